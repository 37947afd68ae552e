"""The Python API: train, resume, load and evaluate from a script or notebook, and a whole run as one pure
function. train.py and eval.py are these calls behind flags.

    import jax, jaxbridge
    experiment = jaxbridge.train("light_switch_door", approaches="ours", seeds=4, cycles=20)
    experiment.curve("ours")                       # mean test solve rate per cycle
    policy = jaxbridge.load("runs/light_switch_door")
    policy.evaluate(task_size={"cells": 40, "doors": 3}).solve_rate

    config = jaxbridge.make_config("light_switch_door", seeds=4, cycles=10)
    out = jax.jit(jaxbridge.make_train(config))()  # every cycle of every seed, one program, no files

docs/API.md shows each call with what it returns. Bad input raises InputError (a ValueError) in one line.
"""
from jaxbridge.api.config import make_config, preset_values, settings_help
from jaxbridge.api.devices import default_workers, local_devices
from jaxbridge.api.envs import env_names, load_env, make_env, tasks
from jaxbridge.api.models import PlannedEpisodes, learn_model, plan_alone, record_segments
from jaxbridge.api.policies import Bridges, Drawn, Episodes, HandMade, Policy, hand_made, load, side_by_side
from jaxbridge.api.results import read_experiment, run_labels, write_comparison
from jaxbridge.api.sweeps import SWEEP_TASKS, NoveltySweep, sweep_lines, sweep_novelties
from jaxbridge.api.training import (Experiment, Training, all_approaches, default_approaches, make_train, prepare, prepare_resume,
                                    release_locks, resume, train)
from jaxbridge.core.check_env import EnvContractError, check_env
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.presets import PRESETS
from jaxbridge.learn.approaches import APPROACHES, KNOWN as ALL_APPROACHES, LOW_LEVEL, MODEL_REPAIR, PLAN_REPAIR, SELECTION, SIGNATURE
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.learner import LearnerContractError, QLearner, check_learner
from jaxbridge.learn.online import TrainOutput
from jaxbridge.learn.setup import seed_keys
from jaxbridge.run.attention import Attention
from jaxbridge.run.model_repair import LEARNED_CSV
from jaxbridge.run.runner import Interrupted, NumericalFault
from jaxbridge.utils.errors import InputError
from jaxbridge.utils.files import WriteError

__all__ = ["ALL_APPROACHES", "APPROACHES", "Attention", "Bridges", "Drawn", "EnvContractError", "Episodes", "Experiment", "HandMade",
           "Hyper", "InputError", "LearnerContractError", "QLearner", "check_env", "check_learner",
           "Interrupted", "LEARNED_CSV", "LOW_LEVEL", "MODEL_REPAIR", "PlannedEpisodes", "learn_model", "plan_alone", "record_segments", "NoveltySweep", "NumericalFault", "PLAN_REPAIR", "PRESETS", "SELECTION", "SIGNATURE", "Policy", "SWEEP_TASKS",
           "TrainConfig", "TrainOutput", "Training", "WriteError", "all_approaches", "default_approaches", "default_workers", "env_names", "hand_made",
           "load", "load_env", "local_devices", "make_config", "make_env", "make_train", "prepare", "prepare_resume",
           "preset_values", "read_experiment", "release_locks", "resume", "run_labels", "seed_keys", "settings_help", "side_by_side", "sweep_lines", "sweep_novelties", "tasks",
           "train", "write_comparison"]
