"""Doorknobs: rooms, clutter and doors whose knobs must be turned (reference/envs.md §3)."""
from envs_jax.doorknobs.env import Doorknobs

__all__ = ["Doorknobs"]
