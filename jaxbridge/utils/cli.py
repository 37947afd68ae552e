"""Shared command-line plumbing: argument types, flags made from a dataclass's declarations, and clean
error exits (one line, exit code 2)."""
from __future__ import annotations

import argparse
import ast
import dataclasses
import enum
import functools
import inspect
import sys
import textwrap
import typing

from jaxbridge.utils.errors import InputError


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser, whose errors are one line with a pointer to --help instead of the usage block."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _expected(kind: type, low=None, high=None, low_included: bool = True) -> str:
    """How an error names a number's range: "a positive integer", "a number above 0 and at most 1"."""
    noun = "integer" if kind is int else "number"
    positive = (low == 0 and not low_included) or (kind is int and low == 1 and low_included)
    if high is None and (positive or (low == 0 and low_included)):
        return f"a {'positive' if positive else 'non-negative'} {noun}"
    bounds = ([f"{'at least' if low_included else 'above'} {low}"] if low is not None else []) + (
        [f"at most {high}"] if high is not None else [])
    return " ".join([f"{'an' if kind is int else 'a'} {noun}", " and ".join(bounds)]).strip()


def number_in(kind: type, low=None, high=None, low_included: bool = True, expected: str | None = None):
    """argparse type: an int or float (`kind`) within low..high (`low_included`: low itself allowed); NaN
    is refused wherever a bound is given."""
    expected = expected or _expected(kind, low, high, low_included)

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
        above_low = low is None or value > low or (low_included and value == low)
        if not (above_low and (high is None or value <= high)):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {value}")
        return value
    return parse


positive_int = number_in(int, 1)
non_negative_int = number_in(int, 0)
positive_float = number_in(float, 0, low_included=False)


def positive_int_list(text: str) -> tuple[int, ...]:
    """argparse type: comma-separated positive integers, each once, in increasing order."""
    each = number_in(int, 1, expected="comma-separated positive integers")
    values = tuple(each(part.strip()) for part in text.split(","))
    if list(values) != sorted(set(values)):
        raise argparse.ArgumentTypeError(f"expected increasing positive integers, each once, got {text!r}")
    return values


def names_or_none(text: str) -> tuple[str, ...]:
    """argparse type: comma-separated names; "none" (or nothing) is no names."""
    return tuple(name for name in text.split(",") if name and name != "none")


def true_or_false(text: str) -> bool:
    """argparse type: true/false/1/0, as --set reads a boolean."""
    if text.lower() not in ("true", "false", "1", "0"):
        raise argparse.ArgumentTypeError(f"expected true or false, got {text!r}")
    return text.lower() in ("true", "1")


def auto_or_positive_int(text: str) -> int | None:
    """A positive integer, or None for "auto" (e.g. --devices: every device)."""
    return None if text.strip() == "auto" else number_in(int, 1, expected="auto or a positive integer")(text)


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


@functools.cache
def field_docs(cls: type) -> dict[str, str]:
    """{field: the docstring written under it in the source} for the dataclass `cls` and the dataclasses it
    extends (Python keeps attribute docstrings only in the source)."""
    docs = {}
    for klass in reversed(cls.__mro__):
        if not (dataclasses.is_dataclass(klass) and klass.__dict__.get("__annotations__")):
            continue
        body = ast.parse(textwrap.dedent(inspect.getsource(klass))).body[0].body
        docs.update({a.target.id: inspect.cleandoc(b.value.value) for a, b in zip(body, body[1:])
                     if isinstance(a, ast.AnnAssign) and isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)})
    return docs


def add_field_flags(parser, cls: type, skip: tuple[str, ...] = (), only: tuple[str, ...] | None = None) -> None:
    """One flag per field of the dataclass `cls` (those in `only`, else all but `skip`), made from its
    declaration: --num-seeds for num_seeds, parsed as its type (lists as N[,N]), within the `range` (low,
    high, low included) and among the `choices` (an enum) its metadata holds (core/settings.setting), its
    docstring and default as help. A flag not given is None."""
    hints, docs = typing.get_type_hints(cls), field_docs(cls)
    for field in dataclasses.fields(cls):
        if field.name in skip or (only is not None and field.name not in only):
            continue
        choices = field.metadata.get("choices")
        parse, metavar = _flag_type(hints[field.name], field.metadata.get("range"))
        text = " ".join(docs.get(field.name, "").split()).removesuffix(".").replace("%", "%%")
        parser.add_argument("--" + field.name.replace("_", "-"), type=parse, metavar=None if choices else metavar,
                            choices=None if choices is None else [member.value for member in choices],
                            help=f"{text}; default: {_shown(field.default)}")


def _flag_type(kind, checked: tuple | None):
    """(argparse type, metavar) of a field of type `kind`; `checked`: its (low, high, low included)."""
    if kind == tuple[int, ...]:  # cycles or counts, given as 10,25,50
        return positive_int_list, "N[,N]"
    if kind == tuple[str, ...]:
        return names_or_none, "NAME[,NAME]"
    if kind is bool:
        return true_or_false, "true|false"
    if kind in (int, float):
        return number_in(kind, *(checked or ())), "N" if kind is int else "X"
    return str, "NAME"


def _shown(value) -> str:
    """A default as a flag takes it: a list with commas, a boolean as true/false, an enum member as its text."""
    if isinstance(value, tuple):
        return ",".join(map(str, value)) or "none"
    if isinstance(value, bool):
        return str(value).lower()
    if dataclasses.is_dataclass(value):  # a learner's settings: its name
        return value.name
    return str(value.value if isinstance(value, enum.Enum) else value)


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
