"""Where the committed records live and what every headline is computed on: shared by the commands that
write records (bench.paper, bench) and the one that renders docs from them (bench.render)."""
from __future__ import annotations

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RECORDS = ROOT / "docs" / "results"
# The test seeds (first, count): every headline figure and nothing else. If a result on them ever
# motivates a change, they are spent and the next range (300, 32) takes their place (docs/RESULTS.md).
TEST_SEEDS = (200, 32)


def git_commit() -> str:
    """The checkout's commit, with "+changes" when its tracked files differ from it."""
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    commit = git("rev-parse", "HEAD") or "unknown"
    return commit + ("+changes" if git("status", "--porcelain", "--untracked-files=no") else "")
