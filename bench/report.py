"""Print a run's results as the markdown table of docs/RESULTS.md, beside the authors' numbers, and
copy its figure into docs/figures/.

    python -m bench.report runs/light_switch_door
"""
from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

# reference/results.md: test solve rate of "ours", mean [min, max] over 8 seeds; smooth reward at 100.
AUTHORS = {"light_switch_door": {"10": "0.33 [0, 1]", "25": "0.72 [0, 1]", "50": "0.57 [0, 1]",
                                 "100": "0.64 [0, 1]", "smooth": "0.74", "time": "17,572 s per seed (about 4.9 h)"}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="a run directory written by train.py")
    args = parser.parse_args()
    summary = json.loads((args.run / "summary.json").read_text())
    config = json.loads((args.run / "config.json").read_text())
    env = config["env"]
    authors = AUTHORS.get(env, {})
    print(f"| {env} | cycle 10 | cycle 25 | cycle 50 | cycle 100 | smooth reward at 100 | run time |")
    print("|---|---|---|---|---|---|---|")
    ours = summary["test_solve_rate_at"]
    cell = lambda c: (f"{ours[c]['mean']:.2f} [{ours[c]['min']:.1f}, {ours[c]['max']:.1f}]" if c in ours else "-")
    print(f"| ours (jaxbridge, {len(summary['seeds'])} seeds) | {cell('10')} | {cell('25')} | {cell('50')} | "
          f"{cell('100')} | {summary['smooth_reward_final']['mean']:.3f} | {summary['elapsed_s']:.0f} s for all seeds |")
    if authors:
        print(f"| authors (8 seeds) | {authors['10']} | {authors['25']} | {authors['50']} | {authors['100']} | "
              f"{authors['smooth']} | {authors['time']} |")
    rates = summary["mean_test_solve_rate_per_cycle"]
    from_30 = rates[29:]
    if from_30:
        print(f"\nmean test solve rate from cycle 30 on: min {min(from_30):.3f}; first cycle with mean >= 0.9: "
              f"{next((i + 1 for i, r in enumerate(rates) if r >= 0.9), None)}")
    figures = Path("docs/figures")
    figures.mkdir(parents=True, exist_ok=True)
    shutil.copy(args.run / "curves.png", figures / f"{env}_curves.png")
    print(f"figure copied to {figures / f'{env}_curves.png'}")


if __name__ == "__main__":
    main()
