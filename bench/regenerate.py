"""Every record under docs/results/ regenerated at one commit, one bench command after another (the
evidence issue's one regeneration).

    python -m bench.regenerate --change "CHANGE" --chosen-on "SEEDS"   # in a clean clone; hours
    python -m bench.regenerate --dry-run                                # the commands, in order

Each step is a study's command as the docs print it (each study's `regenerate` declares its runs: the
paper's three envs, plan repair, the learners, Multi Novelty and the fix-length study; not the learned
selector, whose test sets are spent), on their test seeds and then on their development seeds. --change and --chosen-on go to every test-seed step's ledger row. A finished
step is not run again (runs/regenerate.json) and each command resumes its own steps, so a regeneration
stopped at any point continues where it left off: a step started before gets its ledger row again, saying
that it was restarted. Uncommitted code is refused before anything runs. Then `python -m bench.pages.render`,
and the records, ledger and docs are committed from the clone.
"""
from __future__ import annotations

import argparse
import json
import sys

from bench.command import CommandParser
from bench.records import ROOT, check_clean, git_commit, refuse, run_child
from bench.studies import studies
from jaxbridge.utils.cli import run_main
from jaxbridge.utils.files import write_atomic



def steps() -> list[tuple[str, list[str], bool]]:
    """(name, the module and its flags, whether it runs on test seeds) of every study's regeneration runs
    (each study's `regenerate`), test seeds first."""
    found = [(f"{study.name} {' '.join(flags)}", [study.module, *flags], study.parse(list(flags)).on_test_seeds)
             for study in studies() for flags in study.regenerate]
    return sorted(found, key=lambda step: not step[2])


STATE = ROOT / "runs" / "regenerate.json"


def command(step: tuple, args: argparse.Namespace, restarted: bool) -> list[str]:
    _, module, on_test_seeds = step
    reasons = []
    if on_test_seeds:
        change = args.change + ("; restarted: it resumes from its checkpoints" if restarted else "")
        reasons = ["--change", change, "--chosen-on", args.chosen_on]
    return ["python", "-m", *module, *reasons]


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--change", help="the ledger's change for every test-seed step: what changed since each set's "
                                         "previous run (required unless --dry-run)")
    parser.add_argument("--chosen-on", help="the ledger's seeds that change was chosen on (required unless --dry-run)")
    parser.add_argument("--dry-run", action="store_true", help="print the steps' commands and which have finished")
    args = parser.parse_args(argv)
    state = json.loads(STATE.read_text()) if STATE.is_file() else {"started": [], "finished": {}}
    if args.dry_run:
        for step in steps():
            mark = "finished" if step[0] in state["finished"] else "started" if step[0] in state["started"] else "to run"
            print(f"{mark:8s}  {' '.join(command(step, argparse.Namespace(change='CHANGE', chosen_on='SEEDS'), False))}")
        return 0
    if not args.change or not args.chosen_on:
        refuse("bench.regenerate: --change and --chosen-on are required (the test-seed steps' ledger rows)")
    check_clean("bench.regenerate", allow_dirty=False)
    commit = git_commit()
    if state.get("commit", commit) != commit:
        refuse(f"bench.regenerate: {STATE.relative_to(ROOT)} began at {state['commit']}, the code is at {commit}: "
               "every record comes from one commit (remove the file to begin again)")
    state["commit"] = commit
    STATE.parent.mkdir(parents=True, exist_ok=True)
    for step in steps():
        name = step[0]
        if name in state["finished"]:
            continue
        restarted = name in state["started"]
        state["started"] = sorted(set(state["started"]) | {name})
        write_atomic(STATE, json.dumps(state, indent=2) + "\n")
        print(f"bench.regenerate: {name}{' (restarted)' if restarted else ''}", flush=True)
        figures = run_child(command(step, args, restarted))
        state["finished"][name] = {"wall_s": figures["wall_s"], "peak_rss_mib": figures["peak_rss_mib"]}
        write_atomic(STATE, json.dumps(state, indent=2) + "\n")
    print(f"bench.regenerate: every step finished at {commit}; now python -m bench.pages.render", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
