"""`train.py --preset`: a named set of training values, resolved once into the run's TrainConfig.

* `jaxbridge` (the default, what we recommend): TrainConfig's defaults and the env's `train_defaults`.
* `pqn`: `jaxbridge`'s values with the PQN learner and its values tuned on tuning seeds 0-7 of Light Switch
  Door (docs/RESULTS.md, "Learners").
* `authors`: what the authors' code did where ours differs, per env: the
  values below, then the env's `authors_defaults` (its n_sample, its test tasks, its env quirks). Flags given on the
  command line still override a preset's values.

Departures the preset cannot switch are listed in docs/design/approaches.md, "Departures" (e.g. the stale
relabelling globals, epsilon's per-decision decay).
"""
from __future__ import annotations

PRESETS = {"jaxbridge": "ours: the defaults we recommend (docs/DESIGN.md)",
           "authors": "the authors' code where ours differs, per env",
           "pqn": "ours with the PQN learner and its tuned values (docs/RESULTS.md, Learners)"}
DEFAULT_PRESET = "jaxbridge"

# The authors' values for every env.
AUTHORS = {
    "batch_size": 64,  # their minibatches
    "n_target_sample": 1,  # one parameter sample per ground operator in a TD target's argmax
    "polyak_per": "decision",  # the target's polyak step after every training bridge decision
    "call_planner_bonus": 0.5,  # +0.5 when CallPlanner's transition reaches the goal
    "clip_bootstrap": False,  # no clipping of the bootstrapped value
    "q_ensemble": 1,  # one network
    "loop_guard": False,  # a skill may be chosen again in the state it left unchanged
    "feature_noise": 0.0,  # each minibatch fits the stored features exactly
    "step_gamma": 1.0,  # one discount per bridge decision, whatever its number of env steps
    "activation": "relu",  # plain ReLU hidden units
    "output_init": "uniform",  # PyTorch's default init of the output layer too
    "target_init": "apart",  # the target initialised apart from the online network
    "reset_optimizer": True,  # a new Adam every cycle
    "explore_ground_operators": True,  # epsilon draws uniformly over the applicable ground operators
    "normalise": "minmax",  # per-cycle min-max scaling of the network's inputs and targets
    "fit_patience": 5000,  # fit until 5,000 updates bring no lower minibatch loss ...
    "updates_per_cycle": 100_000,  # ... or 100,000 were made; the best weights restored
    "param_samples": "iid",  # independent parameter samples in the argmax
}

# PQN's values (learn/pqn.py), chosen on Light Switch Door's tuning seeds 0-7 (bench/studies/learners.py says how).
PQN = {
    "learner": "pqn",
    "learning_rate": 1e-4,  # smaller steps: without a buffer each cycle refits on its own decisions
    "q_lambda": 0.3,
    "pqn_epochs": 256,
    "pqn_minibatches": 4,
}


def preset_values(preset: str, env_cls) -> dict:
    """The TrainConfig values `preset` sets for `env_cls` (before command-line flags); ValueError for an
    unknown preset."""
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; choose from {', '.join(PRESETS)}")
    values = {"preset": preset, **env_cls.train_defaults}
    if preset == "authors":
        values.update(AUTHORS, **env_cls.authors_defaults)
    if preset == "pqn":
        values.update(PQN)
    return values


def preset_learner(preset: str | None) -> str | None:
    """The learner `preset` chooses, if it chooses one (pqn: PQN)."""
    return {"authors": AUTHORS, "pqn": PQN}.get(preset, {}).get("learner")

