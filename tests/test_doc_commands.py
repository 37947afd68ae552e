"""Every command the docs print parses as printed: its script or bench module exists and takes its flags
and values (placeholders such as `--env E` filled in, a usage line's optional [--flag X] given), and no
doc names a temporary path."""
import argparse
import re
import runpy
import shlex
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
CODE = re.compile(r"```[^\n]*\n(.*?)```|`([^`\n]+)`", re.S)  # a fenced block or an inline span
COMMAND = re.compile(r"^(?:\$ )?(python3? (?:-m [\w.]+|[\w/]+\.py)(?: .*)?)$")
# The docs' placeholders, as a reader fills them in: an env, what changed and on which seeds, a number.
PLACEHOLDERS = {"E": "light_switch_door", "CHANGE": "a change", "SEEDS": "0-7", "WHAT": "train.py"}


def printed_commands() -> dict[str, str]:
    """Each distinct command (without a trailing comment) and the first doc that prints it."""
    found = {}
    for doc in DOCS:
        for block, span in CODE.findall(doc.read_text()):
            for line in re.sub(r"\\\n\s*", " ", block or span).splitlines():  # a line continued by a backslash
                match = COMMAND.match(re.split(r"\s+#", line)[0].strip())
                if match:
                    found.setdefault(match.group(1), str(doc.relative_to(ROOT)))
    return found


def filled(word: str) -> str:
    """A placeholder word (E, or the value of name=N) as a reader would fill it in."""
    name, eq, value = word.rpartition("=")
    value = PLACEHOLDERS.get(value, "1" if re.fullmatch(r"[A-Z]", value) else value)
    return f"{name}{eq}{value}"


class Parsed(Exception):
    """Raised by the patched parse_args once the command line parsed: the command is not run."""


@pytest.fixture
def parse_only(monkeypatch):
    parse = argparse.ArgumentParser.parse_args

    def parse_then_stop(self, args=None, namespace=None):
        raise Parsed(parse(self, args, namespace))

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_then_stop)
    monkeypatch.syspath_prepend(str(ROOT))


COMMANDS = printed_commands()
OURS = {c: doc for c, doc in COMMANDS.items() if " -m " not in c or " -m bench" in c}  # not pytest's or pip's


def test_the_docs_print_commands_and_name_no_temporary_path():
    assert len(OURS) > 100  # the pattern still finds them
    temporary = [f"{doc.relative_to(ROOT)}: {m.group(0)}" for doc in DOCS for m in re.finditer(r"/tmp/\S*", doc.read_text())]
    assert not temporary


@pytest.mark.parametrize("command", sorted(OURS))
def test_a_printed_command_parses_as_printed(command, parse_only, monkeypatch):
    words = [filled(w.strip("[]")) for w in shlex.split(command)[1:] if w.strip("[]")]  # usage lines' [--flag X]
    module = words[1] if words[0] == "-m" else None
    monkeypatch.setattr(sys, "argv", words[1:] if module else words)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # runpy: the module was imported by an earlier command
        with pytest.raises((Parsed, SystemExit)) as outcome:
            runpy.run_module(module, run_name="__main__") if module else runpy.run_path(str(ROOT / words[0]), run_name="__main__")
    if outcome.type is SystemExit:  # argparse's error, or a script that exits before parsing
        assert outcome.value.code in (0, None), f"{OURS[command]}: `{command}` exits {outcome.value.code}"
