"""Shared command-line plumbing: argument types and clean error exits (one line, exit code 2)."""
from __future__ import annotations

import argparse
import sys

from jaxbridge.utils.errors import InputError


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser, whose errors are one line with a pointer to --help instead of the usage block."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _int_at_least(text: str, low: int, expected: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
    if value < low:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {value}")
    return value


def positive_int(text: str) -> int:
    return _int_at_least(text, 1, "a positive integer")


def positive_int_list(text: str) -> tuple[int, ...]:
    """argparse type: comma-separated positive integers, each once, in increasing order."""
    values = tuple(_int_at_least(part.strip(), 1, "comma-separated positive integers") for part in text.split(","))
    if list(values) != sorted(set(values)):
        raise argparse.ArgumentTypeError(f"expected increasing positive integers, each once, got {text!r}")
    return values


def non_negative_int(text: str) -> int:
    return _int_at_least(text, 0, "a non-negative integer")


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {value}")
    return value


def auto_or_positive_int(text: str) -> int | None:
    """A positive integer, or None for "auto" (e.g. --devices: every device)."""
    return None if text.strip() == "auto" else _int_at_least(text, 1, "auto or a positive integer")


def run_main(main, argv=None) -> int:
    """Run `main(argv)`; turn an InputError (bad input, from the API or the flags) into `error: ...` on
    stderr and exit code 2."""
    try:
        return main(argv) or 0
    except InputError as err:
        print(f"error: {err.as_flag()}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
