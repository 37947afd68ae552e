"""jaxbridge: a planner with a learned bridge policy for novelty recovery, vectorised in JAX.

Floors, each importing only those below it (docs/DESIGN.md): `utils` (files, the smooth reward, CLI
plumbing, the compile cache) < `core` (config, the meta-policy, bridges, task batches, `check_env`) <
`learn` (Q-network, double DQN, replay, approaches, the resolved `Setup`, the jitted cycle) < `viz`
(figures and episode pictures) < `run` (training loop, experiments, checkpoints, run files, evaluation,
sweeps) <
`api` (the Python API below, what train.py and eval.py call). The envs (`envs_jax`) and
the planner (`planner`) sit below.

The Python API (jaxbridge/api/, docs/API.md): `train` and `resume` (an `Experiment`), `load` (a `Policy`
to `evaluate` and `draw`), `hand_made` bridges, `sweep_novelties`, `make_env`, `tasks`, `make_config`,
`TrainConfig`, and `make_train`, a whole run as one pure function; the contracts' checks `check_env` and
`check_learner`.
"""
from jaxbridge.api import *  # noqa: F401,F403 -- the public API, one list: jaxbridge/api/__init__.py's __all__
from jaxbridge.api import __all__
