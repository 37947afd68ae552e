"""Pure-functional JAX environments with novelties, and their planner models.

The public API an env is written against: `NoveltyEnv` (the contract, envs_jax/base.py) and its value
types, `register` and `env_class` (names, envs_jax/registry.py), `envs_jax.drawing` for pictures.
`jaxbridge.check_env` checks an env against the contract; docs/NEW_ENV.md walks through writing one.
"""
from envs_jax.base import (ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, BridgeAction, BridgeObs, NoveltyEnv,
                           NoveltySweep, Objects, SkillCall, SkillSpec, TaskSpec, named_slots)
from envs_jax.coffee import Coffee, CoffeeDistractor
from envs_jax.doorknobs import Doorknobs, DoorknobsDistractor
from envs_jax.light_switch_door import LightSwitchDoor, LightSwitchPanel
from envs_jax.light_switch_door.sequence import LightSwitchSequence
from envs_jax.multi_novelty import MultiNovelty
from envs_jax.registry import BUILTIN, KNOBS, VARIANTS, WORLDS, env_class, is_builtin, register, registered

# The names in BUILTIN + VARIANTS (+ KNOBS, WORLDS); that each is its class's name is checked by tests/test_env_plugins.py
# (tests/test_fix_length.py for KNOBS, tests/test_multi_novelty.py for WORLDS; not here: registered() also lists installed packages' entry points).
for _cls in (LightSwitchDoor, Doorknobs, Coffee, LightSwitchPanel, CoffeeDistractor, DoorknobsDistractor, LightSwitchSequence,
             MultiNovelty):
    register(_cls.name, _cls)

__all__ = ["BUILTIN", "KNOBS", "VARIANTS", "WORLDS", "ACTOR_BRIDGE", "ACTOR_CALL_PLANNER", "ACTOR_PLANNER", "BridgeAction", "BridgeObs", "NoveltyEnv",
           "NoveltySweep", "Objects", "SkillCall", "SkillSpec", "TaskSpec", "LightSwitchDoor", "Doorknobs", "Coffee", "LightSwitchPanel",
           "CoffeeDistractor", "DoorknobsDistractor", "LightSwitchSequence", "MultiNovelty",
           "env_class", "is_builtin", "named_slots", "register", "registered"]
