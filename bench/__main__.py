"""Every bench command with a line each: the studies (they write the records under docs/results/), the
pages (they render the docs from those records), the timings and the probes.

    python -m bench
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
KINDS = {"studies": "train on seeds and write committed records (each a Study, bench/study.py)",
         "pages": "render the docs from the records",
         "timings": "seconds and memory of the code's parts and commands",
         "probes": "look inside a trained bridge or a setting's effect, printing what they find"}


def first_sentence(path: Path) -> str:
    """A module's docstring up to its first full stop, on one line."""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return " ".join(doc.split("\n\n")[0].split()).split(". ")[0].rstrip(".")


def listing() -> list[str]:
    lines = []
    for kind, what in KINDS.items():
        lines += ["", f"{kind}: {what}"]
        lines += [row(f"{kind}.{path.stem}", path) for path in sorted((HERE / kind).glob("*.py")) if path.stem != "__init__"]
    lines += ["", "plumbing: the test-seed ledger and the one regeneration of every record"]
    lines += [row(name, HERE / f"{name}.py") for name in ("ledger", "regenerate")]
    return lines[1:]


def row(module: str, path: Path) -> str:
    return f"  {'python -m bench.' + module:<46} {first_sentence(path)}"


def main(argv=None) -> int:
    if sys.argv[1:] if argv is None else argv:
        print("python -m bench takes no arguments: it lists the bench commands (each has --help)", file=sys.stderr)
        return 2
    print("\n".join(listing()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
