"""The one error kind every refusal of bad input shares, from the Python API and the command lines alike."""
from __future__ import annotations

from contextlib import contextmanager


class InputError(ValueError):
    """Bad input, the caller's to fix, said in one line (the command lines: `error: ...`, exit code 2).

    A message may name the setting it is about as `{setting}`: the Python API shows the keyword
    (`seed_block`), the command lines the flag (`--seed-block`)."""

    def __init__(self, message: str, setting: str | None = None):
        super().__init__(message)
        self.message, self.setting = message, setting

    def __str__(self) -> str:
        return self.naming(self.setting)

    def naming(self, name: str | None) -> str:
        """The message with its setting called `name`."""
        return self.message.replace("{setting}", name or "")

    def as_flag(self) -> str:
        """The message as a command line says it: the setting as its flag."""
        return self.naming(self.setting and "--" + self.setting.replace("_", "-"))


@contextmanager
def refusing(setting: str | None = None, kinds: tuple[type[Exception], ...] = (ValueError,)):
    """Inside, an exception of `kinds` (by default a ValueError: a value given is not one) becomes an
    InputError in its words, about `setting` where one is named ("{setting}: its message"); an InputError
    passes as it is."""
    try:
        yield
    except InputError:
        raise
    except kinds as err:
        raise InputError(f"{{setting}}: {err}" if setting else str(err), setting) from None
