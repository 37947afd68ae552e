"""JAX's persistent compilation cache for the command-line tools, and a counter of compilations.

`enable(...)` points JAX at a cache directory (default `$JAXBRIDGE_CACHE_DIR`, else
`$XDG_CACHE_HOME/jaxbridge/jax`, else `~/.cache/jaxbridge/jax`) so that a later process finds the
compiled programs of an earlier one instead of compiling them again. It must run before JAX compiles
anything (the cache is set up at the first compilation). A `JAX_COMPILATION_CACHE_DIR` already in the
environment (the tests set one) is left as it is.

What the cache cannot hold: JAX does not write programs that contain host callbacks (their Python
function pointers differ between processes), such as the host planner behind the plan tables
(planner/tables.py, a `jax.pure_callback` taken only on a table miss). So the training cycle is first
compiled without it (learn/online.Cycle), and cached; only a cycle that meets a state missing from a
table is run again with it. Evaluation rollouts keep it and are compiled in every process.
"""
from __future__ import annotations

import os
import threading
from contextlib import contextmanager
from pathlib import Path

import jax

# Keep every program: JAX's default (1 s) would keep none of a run's many small ones (docs/PERFORMANCE.md).
MIN_COMPILE_SECS = 0.0

BACKEND_COMPILE = "/jax/core/compile/backend_compile_duration"
TRACE = "/jax/core/compile/jaxpr_trace_duration"
LOWER = "/jax/core/compile/jaxpr_to_mlir_module_duration"
CACHE_HIT = "/jax/compilation_cache/cache_hits"


def default_dir() -> Path:
    if os.environ.get("JAXBRIDGE_CACHE_DIR"):
        return Path(os.environ["JAXBRIDGE_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "jaxbridge" / "jax"


def enable(on: bool = True, path: Path | None = None) -> str | None:
    """Turn JAX's persistent compilation cache on (the directory used) or off (None). Call before
    anything is compiled."""
    if not on:
        jax.config.update("jax_enable_compilation_cache", False)
        return None
    if os.environ.get("JAX_COMPILATION_CACHE_DIR") and path is None:
        return os.environ["JAX_COMPILATION_CACHE_DIR"]
    directory = Path(path) if path is not None else default_dir()
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None  # an unwritable cache must never stop a run: compile as if there were none
    jax.config.update("jax_enable_compilation_cache", True)
    jax.config.update("jax_compilation_cache_dir", str(directory))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_SECS)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return str(directory)


class CacheJanitor:
    """Clears jax's caches between pieces of work that compile programs nobody calls again (brax's
    trainers, anew for every seed), once this process holds half the kernel's memory maps (every
    executable holds some; LLVM aborts when none are left) or has grown by `max_growth` bytes since the
    last clear; always where neither can be read (not Linux). Clearing waits until then because it makes
    every program trace again, and those with host callbacks compile again."""

    def __init__(self, max_growth: int = 1 << 30, proc: Path = Path("/proc/self"),
                 map_limit: Path = Path("/proc/sys/vm/max_map_count")):
        self.max_growth, self.proc, self.map_limit = max_growth, Path(proc), Path(map_limit)
        self.resident_since = self._resident()

    def _use(self) -> tuple[int, int, int] | None:
        """(memory maps held, the kernel's limit on them, resident bytes), or None."""
        try:
            with open(self.proc / "maps", "rb") as lines:
                maps = sum(1 for _ in lines)
            resident = int((self.proc / "statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")
            return maps, int(self.map_limit.read_text()), resident
        except (OSError, ValueError, IndexError):
            return None

    def _resident(self) -> int | None:
        use = self._use()
        return None if use is None else use[2]

    def __call__(self) -> bool:
        """Clear if it is time; True if it cleared."""
        use = self._use()
        if use is not None and self.resident_since is not None:
            maps, limit, resident = use
            if 2 * maps <= limit and resident - self.resident_since <= self.max_growth:
                return False
        jax.clear_caches()
        self.resident_since = self._resident()
        return True


HELP = ("do not use the persistent compilation cache (default: on, in $JAXBRIDGE_CACHE_DIR, else "
        "$XDG_CACHE_HOME/jaxbridge/jax or ~/.cache/jaxbridge/jax; a later run of the same shapes loads its "
        "programs instead of compiling them, the training cycle included)")


class CompileEvents:
    """What JAX compiled while a `with record() as events:` block ran: XLA programs built (`compiles`,
    with their seconds; a program loaded from the persistent cache counts too, and also as a
    `cache_hit`), functions traced and tracing and lowering seconds. Counts every thread's work.
    (A jitted function's `_cache_size()` is no substitute: its dispatch cache can gain an entry
    without any tracing or compiling.)"""

    def __init__(self):
        self.compiles = 0
        self.compile_s = 0.0
        self.programs: list[tuple[str, float]] = []  # (function name, seconds) of each XLA build
        self.traces = 0
        self.trace_s = 0.0
        self.lower_s = 0.0
        self.cache_hits = 0

    def as_dict(self) -> dict:
        return {"compiles": self.compiles, "compile_s": round(self.compile_s, 3), "traces": self.traces, "trace_s": round(self.trace_s, 3),
                "lower_s": round(self.lower_s, 3), "cache_hits": self.cache_hits}

    def slowest(self, n: int = 5) -> list[tuple[str, float]]:
        return sorted(self.programs, key=lambda p: -p[1])[:n]

    @property
    def seconds(self) -> float:
        """Tracing, lowering and XLA compiling: the seconds spent building programs."""
        return self.trace_s + self.lower_s + self.compile_s

    @property
    def fresh(self) -> int:
        """Programs compiled by XLA (not loaded from the persistent cache)."""
        return self.compiles - self.cache_hits


_active: list[CompileEvents] = []
_lock = threading.Lock()
_registered = False


def _on_duration(event: str, duration: float, fun_name: str = "?", **_) -> None:
    with _lock:
        for rec in _active:
            if event == BACKEND_COMPILE:
                rec.compiles += 1
                rec.compile_s += duration
                rec.programs.append((fun_name, duration))
            elif event == TRACE:
                rec.traces += 1
                rec.trace_s += duration
            elif event == LOWER:
                rec.lower_s += duration


def _on_event(event: str, **_) -> None:
    if event == CACHE_HIT:
        with _lock:
            for rec in _active:
                rec.cache_hits += 1


@contextmanager
def record():
    global _registered
    with _lock:
        if not _registered:
            jax.monitoring.register_event_duration_secs_listener(_on_duration)
            jax.monitoring.register_event_listener(_on_event)
            _registered = True
        events = CompileEvents()
        _active.append(events)
    try:
        yield events
    finally:
        with _lock:
            _active.remove(events)
