"""Render the docs' numbers from the committed records: every generated block of README.md, docs/RESULTS.md,
docs/PERFORMANCE.md and the pages under docs/results/ (DOCS) is rebuilt from docs/results/ (bench.studies.paper,
bench.timings.quickstart, bench.timings.suite), docs/results/authors*.csv (the authors' logged numbers) and
bench/results.json (python -m bench.timings.table). A block is what lies between

    <!-- generated: NAME -->
    ...
    <!-- end generated: NAME -->

and text outside the blocks is left as it is.

    python -m bench.pages.render            # rewrite the blocks
    python -m bench.pages.render --check    # exit 1, naming the blocks, where a doc differs from its records
"""
from __future__ import annotations

import re
import sys

from bench.command import CommandParser
from bench.pages import claims, fix_length, model_repair, multi_novelty, performance, results, selection_history
from bench.records import ROOT

DOCS = ("README.md", "docs/RESULTS.md", "docs/PERFORMANCE.md", "docs/results/generalisation.md", "docs/results/plan_repair.md",
        "docs/results/learners.md", "docs/results/selection.md", "docs/results/fix_length.md",
        "docs/results/multi_novelty.md", "docs/results/model_repair.md", "docs/results/ledger.md")
BLOCKS = {**results.BLOCKS, **performance.BLOCKS, "claims": claims.claims_table, "claims rule": claims.rule_text,
          "fix length": fix_length.block, "multi novelty": multi_novelty.block, "model repair": model_repair.block,
          "selection history": selection_history.block}
BLOCK = re.compile(r"(<!-- generated: (?P<name>[\w ]+) -->\n)(?P<body>.*?)(<!-- end generated: (?P=name) -->)", re.S)


# ---------------------------------------------------------------- the docs

def rendered(text: str) -> str:
    """`text` with every generated block rebuilt from the records."""
    def replace(match: re.Match) -> str:
        name = match["name"]
        if name not in BLOCKS:
            raise SystemExit(f"bench.pages.render: unknown generated block {name!r}")
        return match.group(1) + BLOCKS[name]() + match.group(4)
    return BLOCK.sub(replace, text)


def stale_blocks(text: str) -> list[str]:
    """The names of the blocks of `text` that differ from what the records render."""
    fresh = {m["name"]: m["body"] for m in BLOCK.finditer(rendered(text))}
    return [m["name"] for m in BLOCK.finditer(text) if fresh[m["name"]] != m["body"]]


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 where a doc differs from its records")
    args = parser.parse_args(argv)
    stale = {}
    for doc in DOCS:
        path = ROOT / doc
        text = path.read_text()
        stale[doc] = stale_blocks(text)
        if stale[doc] and not args.check:
            path.write_text(rendered(text))
    for doc, names in stale.items():
        if names:
            print(f"{doc}: {'stale' if args.check else 'rendered'}: {', '.join(names)}")
    return 1 if args.check and any(stale.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
