"""Where the committed records live and what every headline is computed on: shared by the commands that
write records (bench.paper, bench) and the one that renders docs from them (bench.render)."""
from __future__ import annotations

import csv
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENVS = ("light_switch_door", "doorknobs", "coffee")  # the built-in envs every record covers
DISTRACTOR_ENVS = ("coffee_distractor",)  # variants where an object nearer the stuck robot is the wrong one (bench.selection)
RECORDS = ROOT / "docs" / "results"
QUICKSTART = RECORDS / "quickstart.json"  # bench.quickstart: the README's first command per env
SUITE = RECORDS / "suite.json"  # bench.suite: the README's second command
SUITE_CLAIMS = RECORDS / "suite_claims.json"  # bench.suite --claims: the claim tests (-m claims)
BENCH = ROOT / "bench" / "results.json"  # python -m bench: the benchmark table
# The test seeds (first, count): every headline figure and nothing else. If a result on them ever
# motivates a change, they are spent and the next range (300, 32) takes their place (docs/RESULTS.md).
TEST_SEEDS = (200, 32)


def authors_seed_run_s() -> dict[str, float]:
    """{env: seconds of one seed-run of the authors' "ours" over 100 cycles} (docs/results/authors_times.csv:
    the whole run; Coffee's never finished, so its learning time, a lower bound)."""
    with open(RECORDS / "authors_times.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["approach"] == "ours"]
    return {r["env"]: float(r["whole_run_s"] or r["learning_s"]) for r in rows}


def git_commit() -> str:
    """The checkout's commit, with "+changes" when its tracked files differ from it."""
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    commit = git("rev-parse", "HEAD") or "unknown"
    return commit + ("+changes" if git("status", "--porcelain", "--untracked-files=no") else "")


def shown(path: Path) -> str:
    """A path as the commands show it: relative to the repository root where it lies inside."""
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def run_child(command: list[str], keep_stdout: bool = False) -> dict:
    """Run `command` from the repository root with this process's output; its wall time and peak RSS (and,
    with `keep_stdout`, what it printed, shown here too)."""
    print(f"$ {' '.join(command)}", flush=True)
    start = time.perf_counter()
    child = subprocess.Popen([sys.executable, *command[1:]], cwd=ROOT,  # command[0] is "python", as shown
                             stdout=subprocess.PIPE if keep_stdout else None, text=True)
    printed = child.stdout.read() if keep_stdout else None  # to its end, before the wait: a full pipe would block it
    if printed is not None:
        print(printed, end="", flush=True)
    _, status, usage = os.wait4(child.pid, 0)  # the child's own resource usage, not all children's
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        raise SystemExit(f"bench: '{' '.join(command)}' failed (exit {code})")
    return {"command": " ".join(command), "wall_s": round(time.perf_counter() - start, 1),
            "peak_rss_mib": round(usage.ru_maxrss / 2**10, 1), "cpu_s": round(usage.ru_utime + usage.ru_stime, 1),
            "load_after": round(os.getloadavg()[0], 2),  # cpu_s / wall_s vs the cores: how much else shared them
            **({"stdout": printed} if keep_stdout else {})}


def cpu_model() -> str:
    """The processor's name (Linux's /proc/cpuinfo), else what the platform module says."""
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def machine() -> dict:
    """What ran a record: Python, jax, the processor, its cores and jax's devices."""
    import jax
    return {"python": platform.python_version(), "jax": jax.__version__, "machine": platform.machine(),
            "processor": cpu_model(), "cpu_cores": os.cpu_count(),
            "devices": f"{jax.device_count()} x {jax.devices()[0].device_kind}"}
