"""jaxbridge: a planner with a learned bridge policy for novelty recovery, vectorised in JAX.

Floors, each importing only those below it (docs/DESIGN.md): `utils` (files, the smooth reward, CLI
plumbing, the compile cache) < `core` (config, the meta-policy, bridges, task batches, `check_env`) <
`learn` (Q-network, double DQN, replay, approaches, the resolved `Setup`, the jitted cycle) < `run`
(training loop, experiments, checkpoints, run files, evaluation, sweeps) < `viz` (episode pictures) <
`api` (the Python API below) < `commands` (what train.py and eval.py call). The envs (`envs_jax`) and
the planner (`planner`) sit below.

The Python API (jaxbridge/api.py, docs/API.md): `train`, `load` (a `Policy` to `evaluate` and `render`),
`make_env`, `tasks`, `make_config`, `TrainConfig`, and `make_train`, a whole run as one pure function; the
contracts' checks `check_env` and `check_learner`.
"""
from jaxbridge.api import (Episodes, Experiment, Hyper, Policy, TrainConfig, TrainOutput, load, make_config, make_env,
                           make_train, seed_keys, tasks, train)
from jaxbridge.core.check_env import EnvContractError, check_env
from jaxbridge.learn.learner import LearnerContractError, QLearner, check_learner

__all__ = ["EnvContractError", "Episodes", "Experiment", "Hyper", "LearnerContractError", "Policy", "QLearner", "TrainConfig",
           "TrainOutput", "check_env", "check_learner", "load", "make_config", "make_env", "make_train", "seed_keys", "tasks",
           "train"]
