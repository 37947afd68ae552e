"""Pure-functional JAX environments with novelties, and their planner models."""
from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv, SkillCall, SkillSpec
from envs_jax.coffee.env import Coffee
from envs_jax.doorknobs.env import Doorknobs
from envs_jax.light_switch_door.env import LightSwitchDoor

ENVS = {LightSwitchDoor.name: LightSwitchDoor, Doorknobs.name: Doorknobs, Coffee.name: Coffee}


def env_class(name: str) -> type[NoveltyEnv]:
    """The env class registered under `name`; ValueError naming the choices otherwise."""
    if name not in ENVS:
        raise ValueError(f"unknown env {name!r}; choose from {', '.join(sorted(ENVS))}")
    return ENVS[name]

__all__ = ['BridgeAction', 'BridgeObs', 'NoveltyEnv', 'SkillCall', 'SkillSpec', 'LightSwitchDoor', 'Doorknobs', 'Coffee', 'ENVS', 'env_class']
