"""Light Switch Door: a row of cells, a light at the end, doors with two keys (the authors' env code)."""
from envs_jax.light_switch_door.env import LightSwitchDoor, LightSwitchDoorTask
from envs_jax.light_switch_door.panel import LightSwitchPanel

__all__ = ["LightSwitchDoor", "LightSwitchDoorTask", "LightSwitchPanel"]
