"""Settings declared once: a frozen dataclass whose every field says, beside its default, what it is.

`setting(default, leaf=..., low=..., high=..., choices=..., swept=...)` declares a field: whether it is a
leaf (a numeric hyperparameter that changes no shape or program, handed to the cycle as a pytree leaf,
learn/hyper.Hyper, so that one compiled program trains every value of a sweep), its range, the enum its
text resolves to, and whether `--sweep` may vary it. The help text is the docstring written under the
field (`field_docs`, utils/cli.py). Everything that checks, parses, sweeps or explains a setting, and
train.py's flags (utils/cli.add_field_flags), reads these, so a field is declared in one place:
TrainConfig's own (core/config.py) and each learner's settings class.
In a cycle a learner is made from its slot's settings with every leaf a traced value (`with_leaves`), so
wherever it reads a leaf, it reads its own slot's: no leaf can stand for a sweep's every setting.
"""
from __future__ import annotations

import dataclasses
import enum
import textwrap
import typing
from dataclasses import dataclass

from jaxbridge.utils.cli import field_docs


def setting(default, *, leaf: bool = False, low=None, high=None, above: bool = False, choices: type[enum.Enum] | None = None,
            swept: bool = True):
    """A settings field with `default`: `leaf`, a traced hyperparameter (see the module); `low`/`high`, its
    range (`above`: low itself excluded); `choices`, the StrEnum its text resolves to; `swept=False`: it
    sets the experiment rather than how it learns, so `--sweep` refuses it."""
    checked = None if low is None and high is None else (low, high, not above)
    return dataclasses.field(default=default, metadata={"leaf": leaf, "range": checked, "choices": choices, "swept": swept})


def made():
    """A field that is no setting: a part a learner's `create` adds (its env, its network, ...)."""
    return dataclasses.field(default=None, metadata={"made": True})


def _meta(field: dataclasses.Field, key: str, absent=None):
    return field.metadata.get(key, absent)


def declared(cls) -> tuple[dataclasses.Field, ...]:
    """The settings fields of a settings class (or of settings): all but what `create` adds (`made`)."""
    return tuple(f for f in dataclasses.fields(cls) if not _meta(f, "made", False))


@dataclass(frozen=True)
class Settings:
    """The base of a settings class: every field's choices resolved to their enum (so the code compares
    members, never text) and its range checked, once, when the settings are made."""

    def __post_init__(self):
        for field in dataclasses.fields(self):
            value, choices, checked = getattr(self, field.name), _meta(field, "choices"), _meta(field, "range")
            if choices is not None:
                if value not in set(choices):
                    raise ValueError(f"{field.name} must be one of {', '.join(choices)}, got {value!r}")
                object.__setattr__(self, field.name, choices(value))  # resolved once: a member from here on
            if checked is not None:
                _check_range(field.name, value, *checked)

    @classmethod
    def leaves(cls) -> tuple[str, ...]:
        """The names of the leaf fields, in declaration order."""
        return tuple(f.name for f in dataclasses.fields(cls) if _meta(f, "leaf", False))

    def leaf_values(self) -> dict:
        """{name: value} of the leaf fields: those of the settings it holds (the learner's), then its own."""
        held = [getattr(self, f.name) for f in dataclasses.fields(self) if isinstance(getattr(self, f.name), Settings)]
        values = {name: value for settings in held for name, value in settings.leaf_values().items()}
        return {**values, **{name: getattr(self, name) for name in self.leaves()}}

    def with_leaves(self, values) -> "Settings":
        """These settings with their leaf fields (and those of the settings they hold) from the mapping
        `values`, unchecked: in a cycle each slot's are traced values, so a learner made from them reads its
        own slot's wherever it reads a leaf."""
        held = {f.name: getattr(self, f.name).with_leaves(values) for f in dataclasses.fields(self)
                if isinstance(getattr(self, f.name), Settings)}
        return self.with_parts(**held, **{name: values[name] for name in self.leaves()})

    def with_parts(self, **changes) -> "Settings":
        """A copy with `changes`, unchecked (not __init__: the range checks cannot read traced values), e.g.
        a learner's settings with the parts its `create` adds."""
        copy = object.__new__(type(self))
        for field in dataclasses.fields(self):
            object.__setattr__(copy, field.name, changes.get(field.name, getattr(self, field.name)))
        return copy

    def static_values(self) -> tuple:
        """Every non-leaf value, those of the settings it holds too: equal for two settings that one compiled
        program can train side by side."""
        return tuple(value.static_values() if isinstance(value, Settings) else value
                     for field in declared(self) if not _meta(field, "leaf", False)
                     for value in [getattr(self, field.name)])


def _check_range(name: str, value, low, high, low_included: bool) -> None:
    if (low is not None and (value < low or (value == low and not low_included))) or (high is not None and value > high):
        where = (f"{'at least' if low_included else 'above'} {low}" if low is not None else "") + (
            f"{' and ' if low is not None else ''}at most {high}" if high is not None else "")
        raise ValueError(f"{name} must be {where}, got {value}")


def fields_of(cls: type) -> dict[str, dataclasses.Field]:
    return {f.name: f for f in declared(cls)}


def is_swept(cls: type, name: str) -> bool:
    return _meta(fields_of(cls)[name], "swept", True)


def parse_value(cls: type, name: str, text: str):
    """`text` as a value of `cls`'s field `name` (booleans: true/false/1/0; a tuple of ints: 64x64; a tuple
    of names: a+b or none); ValueError (one line) if it is not one."""
    kind = typing.get_type_hints(cls)[name]
    expected = {bool: "true or false", int: "an integer", float: "a number", tuple[int, ...]: "widths like 64x64"}
    try:
        if kind is bool:
            if text.lower() not in ("true", "false", "1", "0"):
                raise ValueError
            return text.lower() in ("true", "1")
        if kind in (int, float):
            return kind(text)
        if kind == tuple[int, ...]:  # e.g. 64x64
            return tuple(int(w) for w in text.split("x"))
        if kind == tuple[str, ...]:  # e.g. a+b (a comma would start the next value of a sweep)
            return () if text == "none" else tuple(text.split("+"))
        return text
    except ValueError:
        raise ValueError(f"{name}: expected {expected.get(kind, 'a value')}, got {text!r}") from None


def shown(value) -> str:
    """A default as the docs show it: an enum member as its text, widths as a tuple."""
    return repr(value.value if isinstance(value, enum.Enum) else value)


def described(cls: type, skip: tuple[str, ...] = ()) -> str:
    """Every field of `cls` with its default and its docstring, for help() and `train.py --help`; [leaf]
    marks a leaf (a sweep over it shares one compiled program)."""
    docs = field_docs(cls)
    return "\n".join(f"{f.name} = {shown(f.default)}{' [leaf]' if _meta(f, 'leaf', False) else ''}\n"
                     + textwrap.indent(docs.get(f.name, ""), "    ") for f in declared(cls) if f.name not in skip)
