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


def name_values(text: str) -> dict[str, int]:
    """argparse type: NAME=N[,NAME=N...] as a dict (e.g. eval.py --task-size cells=40,doors=8)."""
    sizes = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        name, _, value = item.partition("=")
        try:
            sizes[name.strip()] = int(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected NAME=N[,NAME=N...], got {text!r}") from None
    if not sizes:
        raise argparse.ArgumentTypeError(f"expected NAME=N[,NAME=N...], got {text!r}")
    return sizes


def names_from(known, what: str, everything: str = "all"):
    """argparse type: a comma-separated list of `what`s among `known`, each once, or `everything` itself."""
    def names(text: str) -> list[str] | str:
        if text.strip() == everything:
            return everything
        listed = [n.strip() for n in text.split(",") if n.strip()]
        unknown = [n for n in listed if n not in known]
        if not listed or unknown:
            raise argparse.ArgumentTypeError(f"unknown {what} {', '.join(unknown) or repr(text)}; choose from "
                                             f"{everything}, {', '.join(known)}")
        if len(set(listed)) != len(listed):
            raise argparse.ArgumentTypeError(f"an {what} is listed twice in {text!r}")
        return listed
    return names


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
