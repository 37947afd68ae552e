"""Each learner's settings: a frozen settings class (core/settings.py) per learner, held by the run's
config as `config.learner`, and which class a learner name takes.

Double DQN's (`DQNSettings`) and PQN's (`PQNSettings`) share the Q-network's and its optimiser's
(`QSettings`). A learner of your own is one class whose fields are its settings (docs/NEW_LEARNER.md); a name is
registered here for each built-in learner and any `register`ed one.
"""
from __future__ import annotations

import dataclasses
import enum
import importlib
from dataclasses import dataclass

from jaxbridge.core.settings import Settings, setting


# The string options, resolved to these typed values when settings are made: each member equals its
# string (config.json and --sweep keep the strings), and the code compares members, not text.
class PolyakPer(enum.StrEnum):
    UPDATE = "update"
    DECISION = "decision"


class Activation(enum.StrEnum):
    LEAKY_RELU = "leaky_relu"
    RELU = "relu"


class TargetInit(enum.StrEnum):
    COPY = "copy"
    APART = "apart"


class OutputInit(enum.StrEnum):
    ZERO = "zero"
    UNIFORM = "uniform"


class Normalise(enum.StrEnum):
    NONE = "none"
    MINMAX = "minmax"


@dataclass(frozen=True)
class LearnerSettings(Settings):
    name: str = setting("", swept=False)
    """The learner these settings are for: a registered name (dqn, pqn) or package.module:Class."""


@dataclass(frozen=True)
class QSettings(LearnerSettings):
    """The Q-network and its optimiser, for learners that fit a learn/q_bridge.QNetwork."""

    learning_rate: float = setting(1e-3, leaf=True, low=0, above=True)
    """Adam step size (the paper: 1e-3; the authors reset Adam every cycle, ours keeps its state)."""
    gamma: float = setting(0.8, leaf=True, low=0, high=1)
    """Discount per bridge decision (the paper: 0.8)."""
    grad_clip: float = setting(5.0, leaf=True, low=0, above=True)
    """Global gradient-norm clip (the paper: 5)."""
    hidden_sizes: tuple[int, ...] = (32, 32)
    """Q-network hidden layers (the paper: [32, 32])."""
    activation: Activation = setting(Activation.LEAKY_RELU, choices=Activation)
    """Hidden units: "leaky_relu" (slope 0.01, ours: keeps units alive under mostly-zero targets) or
    "relu" (the authors')."""
    output_init: OutputInit = setting(OutputInit.ZERO, choices=OutputInit)
    """The Q-network's output layer at the start: "zero" (ours: the untrained Q is 0 everywhere) or
    "uniform" as PyTorch's default nn.Linear, +-1/sqrt(fan_in) (the authors'; the hidden layers start
    so in both)."""
    normalise: Normalise = setting(Normalise.NONE, choices=Normalise)
    """The Q-network's input and output scaling: "none" (ours: features and targets lie in small fixed
    ranges) or "minmax" (the authors'): every cycle, after relabelling, each input entry is shifted by
    its minimum over the replay buffer and divided by its range (at least 1), the targets likewise; the
    network fits the scaled targets and its output is scaled back. The target network shares the scaling."""
    q_ensemble: int = setting(1, low=1)
    """Q-networks fitted side by side, Q = their minimum (2: clipped double Q; the paper: 1)."""
    reset_optimizer: bool = False
    """A new Adam state at the start of every cycle's updates (the authors'); ours keeps one across cycles."""
    n_target_sample: int = setting(10, low=1)
    """Parameter samples per skill when the online net picks the next action of a TD target (the
    authors: 1, which rarely finds a key's +-0.1 window and so undervalues the states before it)."""
    clip_bootstrap: bool = False
    """Clip the bootstrapped next-state value of every TD target to [0, 1 + call_planner_bonus], the range
    every true Q lies in (rewards are 0, or that much at the goal). Stops the max over sampled parameters
    from feeding its upward noise back into the targets (off in the paper)."""
    feature_noise: float = setting(0.0, low=0)
    """Standard deviation of Gaussian noise added to the state features of each minibatch's transitions
    (a fresh draw per update; the TD targets stay those of the clean features): the Q-network is fitted
    to a neighbourhood of every stored state, not to the point, so it varies less with features that
    differ between the training task and the test tasks. 0: none (the paper)."""
    count_bonus: float = setting(0.0, low=0)
    """Exploration by counts (learn/exploration.py): a transition to a bridge observation new in its episode
    earns this much extra reward, divided by the square root of how often the seed has reached that
    observation. 0: none, epsilon-greedy alone (the paper)."""

    def __post_init__(self):
        super().__post_init__()
        if not self.hidden_sizes or min(self.hidden_sizes) < 1:
            raise ValueError(f"hidden_sizes must be one or more positive widths, got {self.hidden_sizes}")


@dataclass(frozen=True)
class DQNSettings(QSettings):
    """Double DQN (learn/dqn.py): a replay buffer, a polyak target network, minibatch updates."""

    updates_per_cycle: int = setting(1000, low=0)
    """Double-DQN minibatch updates after each cycle's episodes (the authors: up to 100,000 iterations with
    early stopping, about 5k-21k per cycle; see docs/DESIGN.md)."""
    fit_patience: int = setting(0, low=0)
    """0: every cycle makes exactly `updates_per_cycle` updates (ours). N > 0: the authors' early-stopping
    fit: updates until N in a row found no lower minibatch loss, at most `updates_per_cycle` (theirs:
    N = 5000, at most 100,000), then the weights that scored the lowest loss are restored."""
    batch_size: int = setting(256, low=1)
    """Minibatch size (the paper: 64; 256 learns more reliably at the same number of updates, see
    docs/TUNING.md)."""
    # Not a leaf: XLA fuses a traced tau's products into multiply-adds other than a constant's, so a
    # slot's last bits would differ from a plain run's; a sweep over it compiles a program per value.
    polyak_tau: float = setting(0.0025, low=0, high=1, above=True)
    """Target-network soft update step (the paper: 0.0025)."""
    polyak_per: PolyakPer = setting(PolyakPer.UPDATE, choices=PolyakPer)
    """When the target takes a polyak step: after every minibatch "update" (ours), or per training bridge
    "decision" (the authors' code). docs/TUNING.md gives the comparison."""
    target_init: TargetInit = setting(TargetInit.COPY, choices=TargetInit)
    """The target network at the start: a "copy" of the online one (ours) or initialised "apart" from
    it (the authors'), then tracking it by polyak steps."""
    buffer_capacity: int = setting(32768, low=1)
    """Replay transitions kept per seed (FIFO); the paper's runs stored about 10k."""
    split_task_state: bool = True
    """The full-state ablations store only the entries of the full state that change within a task
    (`full_state_varying` of the env) and multiply the task's constants once per task in the first layer:
    the same network up to float rounding, a fraction of the buffer and the arithmetic (Doorknobs: 152 of
    2027 values)."""


@dataclass(frozen=True)
class PQNSettings(QSettings):
    """PQN (learn/pqn.py): no replay buffer and no target network, Q(lambda) targets."""

    q_lambda: float = setting(0.65, leaf=True, low=0, high=1)
    """The lambda of its Q(lambda) targets (0: one-step targets; 1: Monte Carlo returns)."""
    pqn_epochs: int = setting(4, low=1)
    """Passes over a cycle's decisions, each in `pqn_minibatches` minibatches (a fresh shuffle each)."""
    pqn_minibatches: int = setting(4, low=1)
    """Minibatches per pass over a cycle's decisions."""


# The learners by name: each a `package.module:Class` whose `create(config, env, num_features, full_state)`
# makes the run's learner; imported when first named (the built-ins live a floor above, in learn/).
_REGISTERED = {"dqn": "jaxbridge.learn.dqn:DQN", "pqn": "jaxbridge.learn.pqn:PQN"}


def register(name: str, spec: str) -> None:
    """Give the learner class `package.module:Class` a short name for `--learner`."""
    if not name or ":" in name:
        raise ValueError(f"a learner name is a non-empty string without ':', got {name!r}")
    _REGISTERED[name] = spec


def registered() -> list[str]:
    return list(_REGISTERED)


def learner_class(spec: str) -> type:
    """The learner class `spec` names: a registered name's or `package.module:Class`; ValueError in one line
    for an unknown name, a module that does not import or a class that is not there."""
    if ":" not in spec and spec not in _REGISTERED:
        raise ValueError(f"unknown learner {spec!r}; choose from {', '.join(_REGISTERED)}, or give package.module:Class")
    module_name, _, attribute = _REGISTERED.get(spec, spec).partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise ValueError(f"learner {spec!r}: cannot import module {module_name!r} ({err})") from None
    if not callable(getattr(getattr(module, attribute, None), "create", None)):
        raise ValueError(f"learner {spec!r}: module {module_name!r} has no learner class {attribute!r} (with create)")
    return getattr(module, attribute)


def settings_class(spec: str) -> type[LearnerSettings]:
    """The settings class of the learner `spec` names: the class itself, whose fields are its settings, or
    (a built-in's, declared here) its `settings`."""
    cls = learner_class(spec)
    return cls if issubclass(cls, LearnerSettings) else cls.settings


def named(settings: LearnerSettings) -> LearnerSettings:
    """`settings` with its learner's name: as given, or the registered name of its class."""
    if settings.name:
        return settings
    names = [name for name in _REGISTERED if settings_class(name) is type(settings)]
    if not names:
        raise ValueError(f"{type(settings).__name__}: give the learner's name (name='package.module:Class')")
    return dataclasses.replace(settings, name=names[0])
