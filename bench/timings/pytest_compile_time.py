"""Where the test suite's time goes: a pytest plugin that records, per test, its seconds and what JAX
compiled in its process (jaxbridge.utils.compile_cache.record), and prints the totals over every worker
and the costliest tests at the end (docs/PERFORMANCE.md, The test suite). Child processes (train.py,
eval.py) are not seen.

    python -m pytest -p bench.timings.pytest_compile_time
"""
from __future__ import annotations

import csv
import os
import shutil
import tempfile
import time
from pathlib import Path

import pytest

from jaxbridge.utils import compile_cache

RUN_DIR = "JAXBRIDGE_COMPILE_TIME_DIR"  # set by the first process, inherited by pytest-xdist's workers
_rows: list[tuple[str, float, int, float, float, float]] = []


def pytest_configure(config):
    if RUN_DIR not in os.environ:
        os.environ[RUN_DIR] = tempfile.mkdtemp(prefix="compile_time_")


@pytest.fixture(autouse=True)
def _compile_time(request):
    start = time.perf_counter()
    with compile_cache.record() as e:
        yield
    _rows.append((request.node.nodeid, time.perf_counter() - start, e.compiles, e.compile_s, e.trace_s, e.lower_s))


def pytest_sessionfinish(session):
    with open(Path(os.environ[RUN_DIR]) / f"{os.getpid()}.csv", "w", newline="") as f:
        csv.writer(f).writerows(_rows)


def pytest_terminal_summary(terminalreporter, config):
    """Every process's rows (the workers have finished when the controller reports)."""
    if hasattr(config, "workerinput"):  # a worker: the controller reports
        return
    run_dir = Path(os.environ[RUN_DIR])
    rows = [(r[0], *map(float, r[1:])) for path in run_dir.glob("*.csv") for r in csv.reader(path.open())]
    shutil.rmtree(run_dir, ignore_errors=True)
    total = lambda i: sum(r[i] for r in rows)
    write = terminalreporter.write_line
    write(f"compile time: {len(rows)} tests, {total(1):.0f} worker-seconds in tests; XLA compiled {total(2):.0f} "
          f"programs in {total(3):.0f} s, tracing {total(4):.0f} s, lowering {total(5):.0f} s")
    for nodeid, seconds, _, compile_s, *_ in sorted(rows, key=lambda r: -r[3])[:10]:
        write(f"  {compile_s:6.1f} s compiling of {seconds:6.1f} s  {nodeid}")
