"""The numeric hyperparameters that change no shape and no program, as pytree leaves (`Hyper`).

A cycle takes them as an input with a leading slot axis, like the seeds' tasks, so one compiled cycle
serves every setting of a sweep (`train.py --sweep`): a slot's numbers are those of a plain run with its
setting, because a plain run passes its one setting the same way. Which settings these are, each field
says where it is declared (`setting(..., leaf=True)`, core/settings.py): the cycle's own in TrainConfig
(the epsilon schedule, call_planner_bonus) and the learner's (learning_rate, gamma, ...); everything else
in the config is static (shapes, programs, switches). The cycle reads its own here and makes each slot's
learner from the config with these values (learn/setup.Setup.learner_for), so a learner reads them as
its settings.
"""
from __future__ import annotations

import jax
import numpy as np

from jaxbridge.core.config import TrainConfig


@jax.tree_util.register_pytree_node_class
class Hyper:
    """float32 scalars (or [slots] arrays) by name, read as attributes (`hyper.gamma`): one per leaf
    setting of the config and its learner (documented where each is declared)."""

    def __init__(self, **values):
        object.__setattr__(self, "values", dict(values))

    def __getattr__(self, name: str):
        try:
            return self.__dict__["values"][name]
        except KeyError:
            raise AttributeError(f"Hyper has no leaf {name!r}; it has {', '.join(self.__dict__['values'])}") from None

    def __setattr__(self, name, value):
        raise AttributeError("Hyper is immutable")

    def __repr__(self) -> str:
        return f"Hyper({', '.join(f'{k}={v!r}' for k, v in self.values.items())})"

    def tree_flatten(self):
        return tuple(self.values.values()), tuple(self.values)

    @classmethod
    def tree_unflatten(cls, names, leaves):
        return cls(**dict(zip(names, leaves)))

    @classmethod
    def of(cls, config: TrainConfig) -> "Hyper":
        return cls(**{name: np.float32(value) for name, value in config.leaf_values().items()})
