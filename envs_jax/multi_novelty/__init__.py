"""Multi Novelty: a row of cells with keycard doors, latched doors and a blown fuse, several in one task."""
from envs_jax.multi_novelty.env import MultiNovelty
from envs_jax.multi_novelty.tasks import MultiNoveltyTask

__all__ = ["MultiNovelty", "MultiNoveltyTask"]
