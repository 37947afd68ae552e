"""Env names: the built-ins, names that packages register, and `package.module:Class` for any importable
env class (`train.py --env my_package.my_module:MyEnv`)."""
from __future__ import annotations

import importlib
import importlib.metadata
from typing import Callable, Union

from envs_jax.base import NoveltyEnv

EnvFactory = Union[type[NoveltyEnv], Callable[[], type[NoveltyEnv]]]
_REGISTRY: dict[str, EnvFactory] = {}
ENTRY_POINTS = "jaxbridge.envs"  # an installed package's `[project.entry-points."jaxbridge.envs"]` name = "module:Class"


def register(name: str, factory: EnvFactory) -> None:
    """Give an env class a short name: `factory` is the class, or a function returning it (so that the
    module defining it is imported only when the name is used)."""
    if not name or ":" in name:
        raise ValueError(f"an env name is a non-empty string without ':', got {name!r}")
    _REGISTRY[name] = factory


def registered() -> list[str]:
    """The registered names, sorted: the built-ins, `register`ed ones and installed packages' entry points."""
    return sorted(set(_REGISTRY) | {e.name for e in importlib.metadata.entry_points(group=ENTRY_POINTS)})


def env_class(spec: str) -> type[NoveltyEnv]:
    """The env class named by `spec`: a registered name or `package.module:Class`. ValueError in one line
    otherwise (unknown name, module that does not import, missing attribute, not a NoveltyEnv)."""
    entry_points = {e.name: e for e in importlib.metadata.entry_points(group=ENTRY_POINTS)}
    if spec in _REGISTRY:
        found = _REGISTRY[spec]
        found = found if isinstance(found, type) else found()
    elif spec in entry_points:
        try:
            found = entry_points[spec].load()
        except (ImportError, AttributeError) as err:
            raise ValueError(f"env {spec!r}: its entry point {entry_points[spec].value!r} does not load ({err})") from None
    elif ":" in spec:
        module_name, _, attribute = spec.partition(":")
        try:
            module = importlib.import_module(module_name)
        except ImportError as err:
            raise ValueError(f"env {spec!r}: cannot import module {module_name!r} ({err})") from None
        if not hasattr(module, attribute):
            raise ValueError(f"env {spec!r}: module {module_name!r} has no attribute {attribute!r}")
        found = getattr(module, attribute)
    else:
        raise ValueError(f"unknown env {spec!r}; choose from {', '.join(registered())}, or give package.module:Class")
    if not (isinstance(found, type) and issubclass(found, NoveltyEnv)):
        raise ValueError(f"env {spec!r} is {found!r}, not a subclass of envs_jax.NoveltyEnv")
    return found


def is_builtin(spec: str) -> bool:
    """A name this package registers itself (checked by its own tests, not at every run)."""
    return spec in BUILTIN + VARIANTS + KNOBS + WORLDS


BUILTIN = ("light_switch_door", "doorknobs", "coffee")  # the paper's envs
VARIANTS = ("light_switch_panel", "coffee_distractor", "doorknobs_distractor")  # ours, built to test one argument (docs/DESIGN.md says which)
KNOBS = ("light_switch_sequence",)  # ours, with a task parameter that measures one limitation (docs/DESIGN.md)
WORLDS = ("multi_novelty",)  # ours, built to ask one limitation's question in a world of its own (docs/DESIGN.md)
