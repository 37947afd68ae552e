"""Where the committed records live and what every headline is computed on: shared by the commands that
write records (bench.studies.paper, bench) and the one that renders docs from them (bench.pages.render)."""
from __future__ import annotations

import contextlib
import csv
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

ROOT = Path(__file__).resolve().parents[1]
ENVS = ("light_switch_door", "doorknobs", "coffee")  # the built-in envs every record covers
DISTRACTOR_ENVS = ("coffee_distractor", "doorknobs_distractor")  # variants where an object nearer the stuck robot is the wrong one (bench.studies.selection)
RECORDS = ROOT / "docs" / "results"
QUICKSTART = RECORDS / "quickstart.json"  # bench.timings.quickstart: the README's first command per env
SUITE = RECORDS / "suite.json"  # bench.timings.suite: the README's second command
SUITE_CLAIMS = RECORDS / "suite_claims.json"  # bench.timings.suite --claims: the claim tests (-m claims)
BENCH = ROOT / "bench" / "results.json"  # python -m bench.timings.table: the benchmark table
# Every test-seed set {first: count}: 200-231 the paper envs' headlines, 300-331 the studies past the paper,
# 400-431 this round's new studies (and the learned selector's next verdict: 200-231 and 300-331 are spent
# for it, the ledger's rows say why). Each run on them gets a ledger row (bench.ledger).
TEST_SETS = {200: 32, 300: 32, 400: 32}
PRESET_RUN = "ours_authors_preset"  # the records' name for ours with --preset authors (bench.studies.paper)
CYCLES = (10, 25, 50, 100)  # the cycles the tables show, whose checkpoints the studies keep
# {approach: the test-seed sets spent for it}: a result seen there motivated a change to it, so its records
# there are history, judged against no bar (each has a spent row in the ledger: bench.ledger --spent).
SPENT = {"ours_learned_selection": ("200-231", "300-331")}


def on_test_seeds(seeds: list[int]) -> bool:
    """Whether any of `seeds` lies in a test-seed set."""
    return any(first <= s < first + size for first, size in TEST_SETS.items() for s in seeds)


def seed_list(text: str) -> list[int]:
    """FIRST-LAST (or one seed) as the list of its seeds."""
    first, _, last = text.partition("-")
    return list(range(int(first), int(last or first) + 1))


# Records written before bench/ was split by kind name their commands by the modules of then: each old
# name's module today, so that a page shows a command that runs.
RENAMED = {
    **{name: f"studies.{name}" for name in ("paper", "plan_repair", "learners", "selection", "multi_novelty", "fix_length")},
    **{name: f"timings.{name}" for name in (
        "ab", "approaches", "cold_start", "devices", "doorknobs", "evaluation", "identical", "maple_q", "meta_policy",
        "pytest_compile_time", "quickstart", "refusal", "scaling", "suite", "training", "update_parts", "updates")},
    **{name: f"probes.{name}" for name in (
        "bridge_steps", "decisions", "knob_offsets", "stuck_objects", "sweep", "low_level", "departures")},
    "render": "pages.render", "results_blocks": "pages.results", "claims": "pages.claims",
    "performance_blocks": "pages.performance", "fix_length_page": "pages.fix_length",
    "multi_novelty_page": "pages.multi_novelty", "report": "pages.report",
}

# The timings whose --num-seeds N became --seeds FIRST-LAST (bench/command.py), as recorded commands are shown.
SEED_COUNTED = ("approaches", "cold_start", "devices", "evaluation", "identical", "training", "updates")


def current_command(command: str) -> str:
    """A recorded command with today's module names (`RENAMED`; the old `python -m bench`: the table) and
    today's seed flag (a timing's old --num-seeds N counted from seed 0: --seeds 0-LAST)."""
    command = re.sub(r"python -m bench(?=\s|$)", "python -m bench.timings.table", command)
    command = re.sub(r"\bbench\.(\w+)\b", lambda m: "bench." + RENAMED.get(m[1], m[1]), command)
    return re.sub(rf"(python -m bench\.timings\.(?:{'|'.join(SEED_COUNTED)})\b.*?)--num-seeds (\d+)",
                  lambda m: f"{m[1]}--seeds 0-{int(m[2]) - 1}", command)


def authors_seed_run_s() -> dict[str, float]:
    """{env: seconds of one seed-run of the authors' "ours" over 100 cycles} (docs/results/authors_times.csv:
    the whole run; Coffee's never finished, so its learning time, a lower bound)."""
    with open(RECORDS / "authors_times.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["approach"] == "ours"]
    return {r["env"]: float(r["whole_run_s"] or r["learning_s"]) for r in rows}


def _git(*args: str, root: Path = ROOT) -> str:
    return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True).stdout.rstrip()  # porcelain lines start with a space


def uncommitted(root: Path = ROOT) -> list[str]:
    """The checkout's paths that differ from its commit (changed, or new and not ignored), leaving out the
    records themselves (docs/results/), which a bench command writes as it goes."""
    lines = _git("status", "--porcelain", "--untracked-files=all", root=root).splitlines()
    paths = [line[3:].split(" -> ")[-1].strip('"') for line in lines]
    return [p for p in paths if not p.startswith(f"{RECORDS.relative_to(ROOT).as_posix()}/")]


def refuse(message: str) -> None:
    """A bench command's refusal: one line on stderr, exit 2."""
    print(message, file=sys.stderr)
    raise SystemExit(2)


def check_clean(module: str, allow_dirty: bool, during: bool = False) -> list[str]:
    """The code's uncommitted paths; a record from them is refused (exit 2) unless `allow_dirty`.
    `during`: the code changed under a run that began clean."""
    changed = uncommitted()
    if changed and not allow_dirty:
        listed = ", ".join(changed[:3]) + (", ..." if len(changed) > 3 else "")
        refuse(f"{module}: the code changed during the run ({listed}); no record written: commit, then run the "
               f"command again (its finished steps are kept)" if during else
               f"{module}: the code has uncommitted changes ({listed}); commit them, or try it out with --allow-dirty")
    return changed


DIRTY_RECORDS = ROOT / "runs" / "dirty_records"  # where --allow-dirty puts the records of uncommitted code


def record_path(module: str, path: Path, allow_dirty: bool) -> Path:
    """Where a timing's record goes, said before it measures: `path`; or, where the code has uncommitted changes
    (refused, exit 2, unless `allow_dirty`), its place under DIRTY_RECORDS (never docs/)."""
    if not check_clean(module, allow_dirty):
        return path
    return DIRTY_RECORDS / (path.relative_to(RECORDS) if path.is_relative_to(RECORDS) else path.name)


def git_commit(changed: list[str] | None = None) -> str:
    """The checkout's full commit, with "+changes" when its code differs from it (`changed`: the
    `uncommitted` paths, when already read)."""
    return (_git("rev-parse", "HEAD") or "unknown") + ("+changes" if (uncommitted() if changed is None else changed) else "")


def shown(path: Path) -> str:
    """A path as the commands show it: relative to the repository root where it lies inside."""
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


@contextlib.contextmanager
def cold_cache() -> Iterator[dict]:
    """The environment of a child that compiles as on a fresh machine: an empty compilation cache of its
    own (removed after), and none of the tests' XLA flags."""
    with tempfile.TemporaryDirectory(prefix="jaxbridge-cold-cache-") as cache:
        env = {k: v for k, v in os.environ.items() if k not in ("JAX_COMPILATION_CACHE_DIR", "XLA_FLAGS")}
        yield {**env, "JAXBRIDGE_CACHE_DIR": cache}


def run_child(command: list[str], keep_stdout: bool = False, cwd: Path = ROOT, env: dict | None = None) -> dict:
    """Run `command` from the repository root (or `cwd`, with `env`) with this process's output; its wall
    time and peak RSS (and, with `keep_stdout`, what it printed, shown here too)."""
    print(f"$ {' '.join(command)}", flush=True)
    start = time.perf_counter()
    child = subprocess.Popen([sys.executable, *command[1:]], cwd=cwd, env=env,  # command[0] is "python", as shown
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
