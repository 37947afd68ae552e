"""The one parser of a bench command, a study's, a page's, a probe's or a timing's: `python -m MODULE` and
the module's docstring, --env where the command takes one (a registered env, or one of a study's), --seeds
FIRST-LAST where it trains on seeds, then the command's own flags.

    parser = CommandParser(__spec__.name, __doc__, env="coffee", seeds="0-7")
    parser.add_argument("--cycles", type=int, default=40)
    args = parser.parse_args()  # args.seeds as typed, args.seed_list its seeds

An unreadable or empty --seeds is a flag error (one line, exit 2, as every flag's), and so is a test-seed set unless the
parser allows them: only a study runs on test seeds, since only it appends the run's ledger row
(bench/study.py); probes and timings are development tools.
"""
from __future__ import annotations

import argparse

import jaxbridge
from bench.records import on_test_seeds, seed_list
from jaxbridge.utils.cli import ArgumentParser


class CommandParser(ArgumentParser):  # errors in one line, exit 2, as train.py's
    def __init__(self, module: str, doc: str | None, *, env: str | None = None, envs: tuple[str, ...] | None = None,
                 env_help: str = "a registered env", seeds: str | None = None, test_seeds: bool = False,
                 dirty_records: str | None = None):
        """--env defaults to `env` among every registered env, or is required among `envs`; --seeds defaults to
        `seeds`; --allow-dirty where the command writes records, those of uncommitted code to `dirty_records`."""
        super().__init__(prog=f"python -m {module}", description=doc,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
        self.test_seeds = test_seeds
        if env or envs:
            names = list(envs or jaxbridge.env_names())
            self.add_argument("--env", default=env, required=env is None, choices=names, metavar="ENV",
                              help=f"{env_help}: {', '.join(names)}" + (" (default: %(default)s)" if env else ""))
        if seeds:
            self.add_argument("--seeds", default=seeds, help=(
                "consecutive seeds, FIRST-LAST (default: %(default)s); a test-seed set or part of one needs --change "
                "and --chosen-on (its ledger row)" if test_seeds else
                "development seeds, FIRST-LAST (default: %(default)s; the test-seed sets are the studies')"))
        if dirty_records:
            self.add_argument("--allow-dirty", action="store_true", help=(
                f"run on code with uncommitted changes (a local try): the records go to {dirty_records}/, not docs/"
                + ("; on test seeds the ledger row is written all the same" if test_seeds else "")))

    def parse_args(self, args=None, namespace=None) -> argparse.Namespace:
        parsed = super().parse_args(args, namespace)
        if getattr(parsed, "seeds", None) is not None:
            parsed.seed_list = self.seed_list(parsed.seeds)
        return parsed

    def seed_list(self, text: str) -> list[int]:
        """FIRST-LAST's seeds; a parser error (exit 2) when unreadable, empty or, unless allowed, on test seeds."""
        try:
            seeds = seed_list(text)
        except ValueError:
            seeds = []
        if not seeds:
            self.error(f"--seeds takes FIRST-LAST with FIRST <= LAST, got {text!r}")
        if not self.test_seeds and on_test_seeds(seeds):
            self.error(f"--seeds {text}: development seeds only (a test-seed set is a study's, which writes its "
                       "ledger row)")
        return seeds
