"""jaxbridge: a planner with a learned bridge policy for novelty recovery, vectorised in JAX.

Floors, each importing only those below it (docs/DESIGN.md): `utils` (files, the smooth reward, CLI
plumbing, the compile cache) < `core` (config, the meta-policy, bridges, task batches, `check_env`) <
`learn` (Q-network, double DQN, replay, approaches, the resolved `Setup`, the jitted cycle) < `run`
(training loop, experiments, checkpoints, run files, evaluation, sweeps) < `viz` (episode pictures) <
`commands` (what train.py and eval.py call). The envs (`envs_jax`) and the planner (`planner`) sit below.
"""
from jaxbridge.core.check_env import EnvContractError, check_env

__all__ = ["EnvContractError", "check_env"]
