"""The studies: each module declares one `Study` (bench/study.py) as STUDY, run as `python -m
bench.studies.NAME`, whose records render into its page."""
from __future__ import annotations

import importlib

NAMES = ("paper", "plan_repair", "learners", "selection", "multi_novelty", "model_repair", "fix_length")


def studies() -> list:
    """Every study's declaration, in NAMES' order (importing them imports jaxbridge)."""
    return [importlib.import_module(f"bench.studies.{name}").STUDY for name in NAMES]
