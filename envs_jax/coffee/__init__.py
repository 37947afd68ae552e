"""Coffee: fill cups from a jug whose handle is rotated away from the robot (the authors' env code)."""
from envs_jax.coffee.distractor import CoffeeDistractor
from envs_jax.coffee.env import Coffee

__all__ = ["Coffee", "CoffeeDistractor"]
