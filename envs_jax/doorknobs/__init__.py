"""Doorknobs: rooms, clutter and doors whose knobs must be turned (the authors' env code)."""
from envs_jax.doorknobs.distractor import DoorknobsDistractor
from envs_jax.doorknobs.env import Doorknobs

__all__ = ["Doorknobs", "DoorknobsDistractor"]
