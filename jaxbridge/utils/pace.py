"""How fast this machine trains: the seconds per seed-cycle of each env and approach it has trained, in
the user's cache (beside JAX's compilation cache), so that train.py's start-up line estimates a run from
this machine's own speed, or from nothing."""
from __future__ import annotations

import json
from pathlib import Path

from jaxbridge.utils.compile_cache import default_dir
from jaxbridge.utils.files import WriteError, write_atomic


def pace_file() -> Path:
    return default_dir().parent / "pace.json"


def _read() -> dict[str, float]:
    try:
        return json.loads(pace_file().read_text())
    except (OSError, ValueError):
        return {}


def record(env: str, paces: dict[str, dict]) -> None:
    """Keep each approach's pace just measured on `env` ({"seed_cycle_s": device-seconds per seed-cycle once
    compiled, "compile_s": its compiling cycles' seconds}; a cache: not written is fine)."""
    measured = {f"{env}/{approach}": {k: round(v, 4) for k, v in p.items()} for approach, p in paces.items()}
    try:
        pace_file().parent.mkdir(parents=True, exist_ok=True)
        write_atomic(pace_file(), json.dumps({**_read(), **measured}, indent=1, sort_keys=True) + "\n")
    except (OSError, WriteError):
        pass


def estimate(env: str, approaches: list[str], seed_cycles: int, workers: int) -> float | None:
    """Seconds for `approaches` x `seed_cycles` on `workers` cores at this machine's recorded paces (each
    approach's compilation, then its seed-cycles): their sum shared by the workers, and at least the longest
    one's; None unless each was measured here."""
    known = _read()
    paces = [known.get(f"{env}/{approach}") for approach in approaches]
    if not all(isinstance(p, dict) for p in paces):  # never trained here (or an older file's entry)
        return None
    each = [p["compile_s"] + p["seed_cycle_s"] * seed_cycles for p in paces]
    return max(max(each), sum(each) / max(1, min(workers, len(each))))
