"""Every bench command with a line each: the studies (they write the records under docs/results/), the
pages (they render the docs from those records), the timings and the probes.

    python -m bench
"""
from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
KINDS = {"studies": "train on seeds and write committed records (each a Study, bench/study.py)",
         "pages": "render the docs from the records (python -m bench.pages.render rebuilds every generated block; "
                  "the modules without a command are its blocks)",
         "timings": "seconds and memory of the code's parts and commands",
         "probes": "look inside a trained bridge or a setting's effect, printing what they find"}


def first_sentence(path: Path) -> str:
    """A module's docstring up to its first full stop, on one line."""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return " ".join(doc.split("\n\n")[0].split()).split(". ")[0].rstrip(".")


def modules() -> dict[str, list[tuple[str, Path]]]:
    """{a group's heading: its (module under bench/, file)}: every module of each kind's folder, then the plumbing."""
    groups = {f"{kind}: {what}": [(f"{kind}.{path.stem}", path) for path in sorted((HERE / kind).glob("*.py"))
                                  if path.stem != "__init__"] for kind, what in KINDS.items()}
    groups["plumbing: the test-seed ledger and the one regeneration of every record"] = [
        (name, HERE / f"{name}.py") for name in ("ledger", "regenerate")]
    return groups


def command(module: str, path: Path) -> str:
    """How a module runs: `python -m bench.MODULE` where it has a main; else the command its docstring prints
    that names it (a pytest plugin's); else the module alone (a page's blocks, which bench.pages.render renders)."""
    source = path.read_text()
    if 'if __name__ == "__main__"' in source:
        return f"python -m bench.{module}"
    doc = ast.get_docstring(ast.parse(source)) or ""
    printed = re.search(rf"^\s+(python .*\bbench\.{re.escape(module)}\b.*?)\s*(#.*)?$", doc, re.M)
    return printed[1] if printed else f"bench.{module}"


def listing() -> list[str]:
    """A heading per group, then a line per module: how it runs and its docstring's first sentence."""
    groups = {heading: [(command(module, path), first_sentence(path)) for module, path in found]
              for heading, found in modules().items()}
    width = max(len(run) for rows in groups.values() for run, _ in rows)
    lines = []
    for heading, rows in groups.items():
        lines += ["", heading, *(f"  {run:<{width}}  {sentence}" for run, sentence in rows)]
    return lines[1:]


def main(argv=None) -> int:
    if sys.argv[1:] if argv is None else argv:
        print("python -m bench takes no arguments: it lists the bench commands (each has --help)", file=sys.stderr)
        return 2
    print("\n".join(listing()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
