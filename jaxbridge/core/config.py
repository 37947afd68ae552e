"""Hyperparameters of a training run. The defaults are ours; each field says where the paper or the authors'
code differ, and docs/DESIGN.md lists every departure."""
from __future__ import annotations

import ast
import dataclasses
import enum
import inspect
import textwrap
from dataclasses import dataclass

# 2: `approach` (version 1 configs were all "ours" and still load); 3: `split_task_state` (older runs
# stored whole observations and load with it off); 4: `preset`, `test_protocol`, `activation`,
# `target_init`, `reset_optimizer`, `explore_ground_operators` (older runs were the jaxbridge preset,
# which their defaults are); 5: `output_init` (older runs started their output layer at zero); 6:
# `env_quirks`, `normalise`, `fit_patience`, `param_samples` (older runs had none of them: their defaults);
# 7: `loop_guard` (older runs had none); 8: `low_level_budget` (older runs had no low-level baselines);
# 9: `feature_noise` (older runs had none); 10: `step_gamma` (older runs had none); 11: `learner`, `q_lambda`,
# `pqn_epochs`, `pqn_minibatches` (older runs were double DQN)
CONFIG_VERSION = 11


# The numeric hyperparameters that change no shape or program: pytree leaves of the cycle
# (learn/hyper.Hyper), so that one compiled program trains every setting of a sweep. Not polyak_tau:
# XLA fuses a traced tau's products into multiply-adds other than a constant's, so a slot's last bits
# would differ from a plain run's; a sweep over it compiles a program per value.
LEAF_FIELDS = ("learning_rate", "gamma", "grad_clip", "call_planner_bonus", "epsilon_start", "epsilon_end",
               "epsilon_decay", "q_lambda")

# The numeric fields' ranges, checked whenever a config is made: (low, high, low inclusive).
RANGES = {"learning_rate": (0, None, False), "gamma": (0, 1, True), "grad_clip": (0, None, False),
          "polyak_tau": (0, 1, False), "call_planner_bonus": (0, None, True), "epsilon_start": (0, 1, True),
          "epsilon_end": (0, 1, True), "epsilon_decay": (0, None, True), "num_seeds": (1, None, True),
          "cycles": (1, None, True), "episodes_per_cycle": (1, None, True), "train_steps": (1, None, True),
          "num_test_tasks": (1, None, True), "updates_per_cycle": (0, None, True), "fit_patience": (0, None, True),
          "batch_size": (1, None, True), "low_level_budget": (1, None, True), "feature_noise": (0, None, True),
          "step_gamma": (0, 1, False), "q_ensemble": (1, None, True), "n_sample": (1, None, True),
          "n_target_sample": (1, None, True),
          "buffer_capacity": (1, None, True), "checkpoint_every": (1, None, True), "seed_block": (1, None, True),
          "first_seed": (0, None, True), "q_lambda": (0, 1, True), "pqn_epochs": (1, None, True),
          "pqn_minibatches": (1, None, True)}

# The string options, resolved to these typed values when a config is made: each member equals its
# string (config.json and --sweep keep the strings), and the code below compares members, not text.
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


class ParamSamples(enum.StrEnum):
    STRATIFIED = "stratified"
    IID = "iid"


CHOICES = {"polyak_per": PolyakPer, "activation": Activation, "target_init": TargetInit, "output_init": OutputInit,
           "normalise": Normalise, "param_samples": ParamSamples}


@dataclass(frozen=True)
class TrainConfig:
    env: str = "light_switch_door"
    """Environment name."""
    approach: str = "ours"
    """Which approach (jaxbridge/learn/approaches.py): the paper's ours, no_feature_selection,
    no_callplanner, random, pure_planning, maple_q; the plan-repair baselines plan_progress and
    plan_progress_replan; the low-level (brax) baselines low_level_ppo and low_level_sac, each also
    with _callplanner or _full_state."""
    preset: str = "jaxbridge"
    """The named set of values the run started from (jaxbridge/core/presets.py): jaxbridge (ours) or
    authors (the authors' code where ours differs); every resolved value is in this config."""
    test_protocol: str = "jaxbridge"
    """Which of the env's test-task distributions (`test_protocols` of the env) the run is evaluated on,
    e.g. Coffee's authors: 4 cups, horizon 100; Light Switch Door's authors: horizon 30."""
    num_seeds: int = 8
    """Independent seeds, trained together in one vectorised computation."""
    seed_block: int = 1
    """Seeds `vmap`ped together on a device (jaxbridge/learn/devices.py). 1: one seed after another, so a
    seed's numbers depend on nothing else; larger blocks fill a GPU, and then the numbers depend on
    the block width (never on the device count)."""
    first_seed: int = 0
    """Seeds are first_seed .. first_seed + num_seeds - 1; each draws its own train and test tasks."""
    cycles: int = 100
    """Online learning cycles (the paper: 100)."""
    episodes_per_cycle: int = 5
    """Training episodes per cycle on the training task (the paper: 5)."""
    train_steps: int = 100
    """Env steps per training episode at most (the paper: 100); it also ends at the goal."""
    num_test_tasks: int = 10
    """Test tasks per seed, evaluated greedily after every cycle (the paper: 10)."""
    updates_per_cycle: int = 1000
    """Double-DQN minibatch updates after each cycle's episodes (the authors: up to 100,000 iterations with
    early stopping, about 5k-21k per cycle; see docs/DESIGN.md)."""
    fit_patience: int = 0
    """0: every cycle makes exactly `updates_per_cycle` updates (ours). N > 0: the authors' early-stopping
    fit: updates until N in a row found no lower minibatch loss, at most `updates_per_cycle` (theirs:
    N = 5000, at most 100,000), then the weights that scored the lowest loss are restored."""
    batch_size: int = 256
    """Minibatch size (the paper: 64; 256 learns more reliably at the same number of updates, see
    docs/TUNING.md)."""
    learning_rate: float = 1e-3
    """Adam step size (the paper: 1e-3; the authors reset Adam every cycle, ours keeps its state)."""
    gamma: float = 0.8
    """Discount per bridge decision (the paper: 0.8)."""
    grad_clip: float = 5.0
    """Global gradient-norm clip (the paper: 5)."""
    polyak_tau: float = 0.0025
    """Target-network soft update step (the paper: 0.0025)."""
    polyak_per: PolyakPer = PolyakPer.UPDATE
    """When the target takes a polyak step: after every minibatch "update" (ours), or per training bridge
    "decision" (the authors' code). docs/TUNING.md gives the comparison."""
    hidden_sizes: tuple[int, ...] = (32, 32)
    """Q-network hidden layers (the paper: [32, 32])."""
    activation: Activation = Activation.LEAKY_RELU
    """Hidden units: "leaky_relu" (slope 0.01, ours: keeps units alive under mostly-zero targets) or
    "relu" (the authors')."""
    output_init: OutputInit = OutputInit.ZERO
    """The Q-network's output layer at the start: "zero" (ours: the untrained Q is 0 everywhere) or
    "uniform" as PyTorch's default nn.Linear, +-1/sqrt(fan_in) (the authors'; the hidden layers start
    so in both)."""
    normalise: Normalise = Normalise.NONE
    """The Q-network's input and output scaling: "none" (ours: features and targets lie in small fixed
    ranges) or "minmax" (the authors'): every cycle, after relabelling, each input entry is shifted by
    its minimum over the replay buffer and divided by its range (at least 1), the targets likewise; the
    network fits the scaled targets and its output is scaled back. The target network shares the scaling."""
    target_init: TargetInit = TargetInit.COPY
    """The target network at the start: a "copy" of the online one (ours) or initialised "apart" from
    it (the authors'), then tracking it by polyak steps."""
    reset_optimizer: bool = False
    """A new Adam state at the start of every cycle's updates (the authors'); ours keeps one across cycles."""
    explore_ground_operators: bool = False
    """Exploration (and the random bridge) draws a random applicable ground operator, so a skill with more
    groundings is drawn more often (the authors'); ours draws a random applicable skill, then one of its
    ground operators."""
    q_ensemble: int = 1
    """Q-networks fitted side by side, Q = their minimum (2: clipped double Q; the paper: 1)."""
    n_sample: int = 100
    """Parameter samples per skill in the greedy argmax (the authors: 100 for Light Switch Door, 10 for
    Doorknobs and Coffee; ours: 100 everywhere)."""
    param_samples: ParamSamples = ParamSamples.STRATIFIED
    """How the n parameter samples of a skill in an argmax (greedy and TD targets) are drawn: "stratified"
    (ours: the j-th uniform in the j-th n-quantile of the range, so a narrow good interval is never
    missed by chance) or "iid" (the authors': independent uniforms)."""
    n_target_sample: int = 10
    """Parameter samples per skill when the online net picks the next action of a TD target (the
    authors: 1, which rarely finds a key's +-0.1 window and so undervalues the states before it)."""
    epsilon_start: float = 1.0
    """Initial exploration rate."""
    epsilon_end: float = 0.05
    """Final exploration rate."""
    epsilon_decay: float = 3.8e-5
    """Linear decrease of epsilon per training bridge decision (the paper: 3.8e-5)."""
    buffer_capacity: int = 32768
    """Replay transitions kept per seed (FIFO); the paper's runs stored about 10k."""
    call_planner_bonus: float = 0.0
    """Extra reward when CallPlanner's transition reaches the goal (the authors' code: 0.5; off by default)."""
    step_gamma: float = 1.0
    """A further discount per env step of every transition (the options framework's semi-MDP discount,
    gamma^decisions x step_gamma^steps): with 1, the paper's, a fix of the novelty is worth the same
    whatever its number of steps. Below 1 the buffer keeps each transition's step count."""
    clip_bootstrap: bool = False
    """Clip the bootstrapped next-state value of every TD target to [0, 1 + call_planner_bonus], the range
    every true Q lies in (rewards are 0, or that much at the goal). Stops the max over sampled parameters
    from feeding its upward noise back into the targets (off in the paper)."""
    feature_noise: float = 0.0
    """Standard deviation of Gaussian noise added to the state features of each minibatch's transitions
    (a fresh draw per update; the TD targets stay those of the clean features): the Q-network is fitted
    to a neighbourhood of every stored state, not to the point, so it varies less with features that
    differ between the training task and the test tasks. 0: none (the paper)."""
    loop_guard: bool = True
    """At a bridge decision, every skill the bridge already chose at decisions in this same low-level
    state (each of which left it unchanged) is not applicable, whatever its grounding or parameter: a
    greedy bridge cannot repeat a skill that does nothing until the horizon. Training and test
    episodes alike, every approach with a bridge (not in the paper; off in the authors' preset)."""
    low_level_budget: int = 1
    """Agent steps per cycle of the low-level baselines (low_level_ppo, low_level_sac), in units of ours'
    env steps per cycle (episodes_per_cycle x train_steps): 1 is the paper's budget."""
    env_quirks: tuple[str, ...] = ()
    """Behaviours of the authors' env that ours departs from, switched back on by name (the env's `quirks`,
    e.g. Coffee's "shared_repeat_flag"); none by default."""
    split_task_state: bool = True
    """The full-state ablations store only the entries of the full state that change within a task
    (`full_state_varying` of the env) and multiply the task's constants once per task in the first layer:
    the same network up to float rounding, a fraction of the buffer and the arithmetic (Doorknobs: 152 of
    2027 values)."""
    learner: str = "dqn"
    """What fits the bridge's Q-function (jaxbridge/learn/learners.py): "dqn", double DQN with a replay buffer
    and a target network (the paper's); "pqn", PQN (Gallici et al. 2024): no replay buffer and no target
    network, LayerNorm in the Q-network, Q(lambda) targets over each cycle's own decisions; or
    package.module:factory for a learner of your own (docs/NEW_LEARNER.md)."""
    q_lambda: float = 0.65
    """PQN: the lambda of its Q(lambda) targets (0: one-step targets; 1: Monte Carlo returns)."""
    pqn_epochs: int = 4
    """PQN: passes over a cycle's decisions, each in `pqn_minibatches` minibatches (a fresh shuffle each)."""
    pqn_minibatches: int = 4
    """PQN: minibatches per pass over a cycle's decisions."""
    checkpoint_every: int = 10
    """Save the learner state every this many cycles (and after the last one)."""

    def __post_init__(self):
        for field, choice in CHOICES.items():
            if getattr(self, field) not in set(choice):
                raise ValueError(f"{field} must be one of {', '.join(choice)}, got {getattr(self, field)!r}")
            object.__setattr__(self, field, choice(getattr(self, field)))  # resolved once: a member from here on
        for field, (low, high, low_included) in RANGES.items():
            value = getattr(self, field)
            if value < low or (value == low and not low_included) or (high is not None and value > high):
                where = f"{'at least' if low_included else 'above'} {low}" + (f" and at most {high}" if high is not None else "")
                raise ValueError(f"{field} must be {where}, got {value}")
        if len(set(self.env_quirks)) != len(self.env_quirks):
            raise ValueError(f"env_quirks names a quirk twice: {', '.join(self.env_quirks)}")
        if not self.hidden_sizes or min(self.hidden_sizes) < 1:
            raise ValueError(f"hidden_sizes must be one or more positive widths, got {self.hidden_sizes}")

    def to_dict(self) -> dict:
        return {**dataclasses.asdict(self), "hidden_sizes": list(self.hidden_sizes),
                "env_quirks": list(self.env_quirks), "config_version": CONFIG_VERSION}

    @classmethod
    def from_dict(cls, data: dict) -> "TrainConfig":
        data = dict(data)
        version = data.pop("config_version", None)
        if version == 1:
            data.setdefault("approach", "ours")
        if version in (1, 2):
            data.setdefault("split_task_state", False)
        elif version not in (3, 4, 5, 6, 7, 8, 9, 10, CONFIG_VERSION):
            raise ValueError(f"config version {version} is not supported (this release reads versions 1 to {CONFIG_VERSION})")
        if version < 7:  # runs before version 7 had no loop guard
            data.setdefault("loop_guard", False)
        fields = {f.name for f in dataclasses.fields(cls)}
        unknown = set(data) - fields
        if unknown:
            raise ValueError(f"unknown config fields: {', '.join(sorted(unknown))}")
        for field in ("hidden_sizes", "env_quirks"):
            if field in data:
                data[field] = tuple(data[field])
        return cls(**data)

    @classmethod
    def for_env(cls, env: str, preset: str = "jaxbridge", **overrides) -> "TrainConfig":
        """The config for `env`: these defaults, then the preset's values for it (jaxbridge: the env's own
        `train_defaults`, each documented there; jaxbridge/core/presets.py), then `overrides`."""
        from envs_jax import env_class
        from jaxbridge.core.presets import preset_values
        return cls(env=env, **{**preset_values(preset, env_class(env)), **overrides})

    def check_buffer_fits(self) -> None:
        """ValueError unless a cycle's training episodes fit the replay buffer in one insert: the buffer
        finds a transition's next_features in the slot after it (learn/transitions.successor_features),
        which an insert larger than the buffer would overwrite."""
        if self.episodes_per_cycle * self.train_steps > self.buffer_capacity:
            raise ValueError(f"{self.episodes_per_cycle} episodes x {self.train_steps} steps per cycle must fit the "
                             f"replay buffer ({self.buffer_capacity} transitions)")

    @property
    def counts_steps(self) -> bool:
        """Transitions keep their env step count: a step discount is on (`step_gamma` below 1)."""
        return self.step_gamma < 1

    @property
    def seeds(self) -> list[int]:
        return list(range(self.first_seed, self.first_seed + self.num_seeds))


def _documented(cls: type) -> str:
    """The class's docstring for help(): what it is, then every field with its default and the attribute
    docstring written under it in the source (Python keeps those only in the source)."""
    body = ast.parse(textwrap.dedent(inspect.getsource(cls))).body[0].body
    docs = {a.target.id: inspect.cleandoc(b.value.value) for a, b in zip(body, body[1:])
            if isinstance(a, ast.AnnAssign) and isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)}
    shown = lambda value: repr(value.value if isinstance(value, enum.Enum) else value)
    fields = [f"{f.name} = {shown(f.default)}\n" + textwrap.indent(docs.get(f.name, ""), "    ")
              for f in dataclasses.fields(cls)]
    return ("A training run's settings (frozen): `TrainConfig.for_env(env, preset, **overrides)` resolves an env's "
            "and a preset's values.\nEach field, its default, and where the paper or the authors' code differ:\n\n"
            + "\n".join(fields))


TrainConfig.__doc__ = _documented(TrainConfig)
