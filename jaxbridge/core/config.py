"""Settings of a training run. The defaults are ours; each field says where the paper or the authors'
code differ, and docs/DESIGN.md lists every departure. The experiment's settings are TrainConfig's own;
the learner's are its settings class's (core/learner_settings.py), held as `config.learner`."""
from __future__ import annotations

import dataclasses
import enum
import typing
from dataclasses import dataclass

from jaxbridge.core.learner_settings import (DQNSettings, LearnerSettings, PQNSettings, named, settings_class)
from jaxbridge.core.settings import Settings, declared, described, setting
from jaxbridge.core.token_settings import TokenSettings

# 2: `approach` (version 1 configs were all "ours" and still load); 3: `split_task_state` (older runs
# stored whole observations and load with it off); 4: `preset`, `test_protocol`, `activation`,
# `target_init`, `reset_optimizer`, `explore_ground_operators` (older runs were the jaxbridge preset,
# which their defaults are); 5: `output_init` (older runs started their output layer at zero); 6:
# `env_quirks`, `normalise`, `fit_patience`, `param_samples` (older runs had none of them: their defaults);
# 7: `loop_guard` (older runs had none); 8: `low_level_budget` (older runs had no low-level baselines);
# 9: `feature_noise` (older runs had none); 10: `step_gamma` (older runs had none); 11: `learner`, `q_lambda`,
# `pqn_epochs`, `pqn_minibatches` (older runs were double DQN); 12: the learner's settings nested under
# `learner` with its `name` (older configs were flat: a learner reads its fields from the top level, and
# the other learner's fields, which it never read, are dropped); 13: `attention_distance`,
# `attention_preference` (older learned selectors read the distance now, with a preference bound of 4),
# `keep_cycles` (older runs kept the latest two checkpoints alone); 14: `attention_robot_features` (older
# learned selectors' Q-networks read the robot's own features), `attention_fixed_penalty`,
# `attention_log_scale` (older ones had neither: their defaults); 15: `attention_kind_noise` (older learned
# selectors' feature noise perturbed every token entry), `attention_fixed_penalty` on (older ones learned it);
# 16: the `attention_*` settings under `tokens`, the object-token network's (older configs held them in `learner`)
CONFIG_VERSION = 16
NESTED_SINCE = 12


class ParamSamples(enum.StrEnum):
    """How a skill's parameter samples in an argmax are drawn (TrainConfig.param_samples)."""

    STRATIFIED = "stratified"
    IID = "iid"


@dataclass(frozen=True)
class TrainConfig(Settings):
    env: str = setting("light_switch_door", swept=False)
    """Environment: a registered name (train.py --help lists them) or package.module:Class for an env of your
    own (checked first; docs/NEW_ENV.md)."""
    approach: str = setting("ours", swept=False)
    """Which approach (jaxbridge/learn/approaches.py): the paper's ours, no_feature_selection,
    no_callplanner, random, pure_planning, maple_q; the plan-repair baselines plan_progress and
    plan_progress_replan; the low-level (brax) baselines low_level_ppo and low_level_sac, each also
    with _callplanner or _full_state."""
    preset: str = setting("jaxbridge", swept=False)
    """The named set of values the run starts from (jaxbridge/core/presets.py): jaxbridge (ours), authors (the
    authors' code where ours differs) or pqn (PQN with its tuned values); the other settings given override
    its values, and every resolved value is in this config."""
    test_protocol: str = setting("jaxbridge", swept=False)
    """Which of the env's test-task distributions (`test_protocols` of the env) the run is evaluated on,
    e.g. Coffee's authors: 4 cups, horizon 100; Light Switch Door's authors: horizon 30."""
    num_seeds: int = setting(8, low=1, swept=False)
    """Independent seeds, trained together in one vectorised computation."""
    seed_block: int = setting(1, low=1, swept=False)
    """Seeds `vmap`ped together on a device (jaxbridge/learn/devices.py). 1: one seed after another, so a
    seed's numbers depend on nothing else; larger blocks fill a GPU, and then the numbers depend on
    the block width (never on the device count)."""
    first_seed: int = setting(0, low=0, swept=False)
    """Seeds are first_seed .. first_seed + num_seeds - 1; each draws its own train and test tasks."""
    cycles: int = setting(100, low=1, swept=False)
    """Online learning cycles (the paper: 100)."""
    episodes_per_cycle: int = setting(5, low=1)
    """Training episodes per cycle on the training task (the paper: 5)."""
    train_steps: int = setting(100, low=1)
    """Env steps per training episode at most (the paper: 100); it also ends at the goal."""
    num_test_tasks: int = setting(10, low=1)
    """Test tasks per seed, evaluated greedily after every cycle (the paper: 10)."""
    explore_ground_operators: bool = False
    """Exploration (and the random bridge) draws a random applicable ground operator, so a skill with more
    groundings is drawn more often (the authors'); ours draws a random applicable skill, then one of its
    ground operators."""
    n_sample: int = setting(100, low=1)
    """Parameter samples per skill in the greedy argmax (the authors: 100 for Light Switch Door, 10 for
    Doorknobs and Coffee; ours: 100 everywhere)."""
    param_samples: ParamSamples = setting(ParamSamples.STRATIFIED, choices=ParamSamples)
    """How the n parameter samples of a skill in an argmax (greedy and TD targets) are drawn: "stratified"
    (ours: the j-th uniform in the j-th n-quantile of the range, so a narrow good interval is never
    missed by chance) or "iid" (the authors': independent uniforms)."""
    call_planner_bonus: float = setting(0.0, leaf=True, low=0)
    """Extra reward when CallPlanner's transition reaches the goal (the authors' code: 0.5; off by default)."""
    epsilon_start: float = setting(1.0, leaf=True, low=0, high=1)
    """Initial exploration rate."""
    epsilon_end: float = setting(0.05, leaf=True, low=0, high=1)
    """Final exploration rate."""
    epsilon_decay: float = setting(3.8e-5, leaf=True, low=0)
    """Linear decrease of epsilon per training bridge decision (the paper: 3.8e-5)."""
    step_gamma: float = setting(1.0, low=0, high=1, above=True)
    """A further discount per env step of every transition (the options framework's semi-MDP discount,
    gamma^decisions x step_gamma^steps): with 1, the paper's, a fix of the novelty is worth the same
    whatever its number of steps. Below 1 the buffer keeps each transition's step count."""
    loop_guard: bool = True
    """At a bridge decision, every skill the bridge already chose at decisions in this same low-level
    state (each of which left it unchanged) is not applicable, whatever its grounding or parameter: a
    greedy bridge cannot repeat a skill that does nothing until the horizon. Training and test
    episodes alike, every approach with a bridge (not in the paper; off in the authors' preset)."""
    low_level_budget: int = setting(1, low=1)
    """Agent steps per cycle of the low-level baselines (low_level_ppo, low_level_sac), in units of ours'
    env steps per cycle (episodes_per_cycle x train_steps): 1 is the paper's budget."""
    env_quirks: tuple[str, ...] = setting((), swept=False)
    """Behaviours of the authors' env that ours departs from, switched back on by name (the env's `quirks`,
    e.g. Coffee's "shared_repeat_flag"); none by default."""
    learner: LearnerSettings = setting(DQNSettings(name="dqn"), swept=False)
    """What fits the bridge's Q-function, with its settings (core/learner_settings.py; its name is
    `learner.name`): "dqn", double DQN with a replay buffer and a target network (the paper's); "pqn", PQN
    (Gallici et al. 2024): no replay buffer and no target network, LayerNorm in the Q-network, Q(lambda)
    targets over each cycle's own decisions; or package.module:Class for a learner of your own
    (docs/NEW_LEARNER.md; train.py --help --learner NAME lists its settings). Given as a name, it takes that
    learner's default settings; a learner's setting given by name to the config (`TrainConfig(batch_size=64)`)
    sets it in these, and is read here (`config.learner.batch_size`)."""
    tokens: TokenSettings = setting(TokenSettings(), swept=False)
    """The object-token Q-network's settings (core/token_settings.py), read by the approaches whose bridge sees
    object tokens (the learned selector); each is given by its name (`TrainConfig(attention_preference=4)`,
    `--set attention_preference=4`) and read here (`config.tokens.attention_preference`)."""
    checkpoint_every: int = setting(10, low=1, swept=False)
    """Save the learner state every this many cycles (and after the last one)."""
    keep_cycles: tuple[int, ...] = setting((), swept=False)
    """Cycles whose checkpoints are kept besides the latest two (each saved, whatever `checkpoint_every`),
    so that `eval.py --cycle N` can evaluate the bridge as it was then."""

    def __post_init__(self):
        super().__post_init__()
        if len(set(self.env_quirks)) != len(self.env_quirks):
            raise ValueError(f"env_quirks names a quirk twice: {', '.join(self.env_quirks)}")
        if any(not 1 <= c <= self.cycles for c in self.keep_cycles):
            raise ValueError(f"keep_cycles must lie in 1..{self.cycles} (the run's cycles), got "
                             f"{','.join(map(str, self.keep_cycles))}")

    def to_dict(self) -> dict:
        """config.json's content: the learner's settings under `learner`, its name first."""
        data = {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)}
        return {**data, "config_version": CONFIG_VERSION}

    @classmethod
    def from_dict(cls, data: dict) -> "TrainConfig":
        """A config.json's config, of any version from 1 on (see the version notes above)."""
        data = dict(data)
        version = data.pop("config_version", None)
        if version == 1:
            data.setdefault("approach", "ours")
        if version in (1, 2):
            data.setdefault("split_task_state", False)
        elif version not in range(3, CONFIG_VERSION + 1):
            raise ValueError(f"config version {version} is not supported (this release reads versions 1 to {CONFIG_VERSION})")
        if version < 7:  # runs before version 7 had no loop guard
            data.setdefault("loop_guard", False)
        if version < NESTED_SINCE:
            data = _nested(data)
        learner = dict(data.pop("learner"))
        settings = settings_class(learner["name"])
        tokens = data.pop("tokens", None) or _older_tokens(version, learner)
        unknown = ((set(data) - set(_OWN)) | {f"learner.{k}" for k in set(learner) - set(_names(settings))}
                   | {f"tokens.{k}" for k in set(tokens) - set(_names(TokenSettings))})
        if unknown:
            raise ValueError(f"unknown config fields: {', '.join(sorted(unknown))}")
        return cls(**_typed(cls, data), learner=settings(**_typed(settings, learner)), tokens=TokenSettings(**tokens))

    def check_buffer_fits(self) -> None:
        """ValueError unless a cycle's training episodes fit a learner's replay buffer in one insert: the
        buffer finds a transition's next_features in the slot after it (learn/transitions.successor_features),
        which an insert larger than the buffer would overwrite. A learner without a buffer always fits."""
        capacity = getattr(self.learner, "buffer_capacity", None)
        if capacity is not None and self.episodes_per_cycle * self.train_steps > capacity:
            raise ValueError(f"{self.episodes_per_cycle} episodes x {self.train_steps} steps per cycle must fit the "
                             f"replay buffer ({capacity} transitions)")

    @property
    def counts_steps(self) -> bool:
        """Transitions keep their env step count: a step discount is on (`step_gamma` below 1)."""
        return self.step_gamma < 1

    @property
    def seeds(self) -> list[int]:
        return list(range(self.first_seed, self.first_seed + self.num_seeds))


_OWN = tuple(f.name for f in dataclasses.fields(TrainConfig))


def _names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in declared(cls))


def _plain(value):
    """A value as JSON keeps it: settings as a dict, tuples as lists, enum members as their text."""
    if isinstance(value, Settings):
        return {f.name: _plain(getattr(value, f.name)) for f in declared(value)}
    return list(value) if isinstance(value, tuple) else value


def _typed(cls: type, data: dict) -> dict:
    """`data` with JSON's lists back as the tuples `cls`'s fields hold."""
    hints = typing.get_type_hints(cls)
    return {k: tuple(v) if typing.get_origin(hints.get(k)) is tuple else v for k, v in data.items()}


def _older_tokens(version: int, learner: dict) -> dict:
    """The token network's settings of a config before version 16: those its learner held (taken out of
    `learner`), over what the versions before each setting ran with."""
    tokens = {name: learner.pop(name) for name in _names(TokenSettings) if name in learner}
    if version < 13:
        tokens = {"attention_distance": "now", "attention_preference": 4.0, **tokens}
    if version < 14:
        tokens = {"attention_robot_features": True, **tokens}
    if version < 15:
        tokens = {"attention_kind_noise": True, "attention_fixed_penalty": False, **tokens}
    return tokens


def _nested(flat: dict) -> dict:
    """A config from before learners had their own settings (a flat dict, `learner` a name or absent: double
    DQN) as a nested one: its learner's fields under `learner`; the fields only another built-in learner
    has, which this run's learner never read, dropped."""
    name = flat.get("learner", TrainConfig.learner.name)
    mine = set(_names(settings_class(name)))
    flat_era = set(_names(DQNSettings)) | set(_names(PQNSettings))  # every learner field a flat config held
    learner = {"name": name, **{k: v for k, v in flat.items() if k in mine and k != "name"}}
    return {**{k: v for k, v in flat.items() if k not in mine | flat_era | {"learner"}}, "learner": learner}


def _with_sections(given: dict) -> dict:
    """The keywords of `TrainConfig(...)` with its sections resolved: the learner's name to its settings class
    (its defaults), and a setting of the learner or of the token network given by name at the top level
    set in that section."""
    flat = {k: given.pop(k) for k in list(given) if k not in _OWN}
    learner, tokens = given.get("learner", TrainConfig.learner), given.get("tokens", TrainConfig.tokens)
    if isinstance(learner, str):
        learner = settings_class(learner)(name=learner)
    of_tokens = {k: flat.pop(k) for k in list(flat) if k in _names(TokenSettings)}
    unknown = set(flat) - set(_names(type(learner)))
    if unknown:
        raise ValueError(f"unknown config fields: {', '.join(sorted(unknown))} (not TrainConfig's, nor learner "
                         f"{learner.name or type(learner).__name__}'s, nor the token network's)")
    return {**given, "learner": named(dataclasses.replace(learner, **flat) if flat else learner),
            "tokens": dataclasses.replace(tokens, **of_tokens) if of_tokens else tokens}


def _accepting_section_names(cls: type) -> type:
    """Wrap the generated __init__ so that `TrainConfig(...)` and `dataclasses.replace(config, ...)` take
    the learner by name and its sections' settings by their names (see `_with_sections`)."""
    generated = cls.__init__

    def __init__(self, **given):
        generated(self, **_with_sections(given))

    __init__.__doc__ = generated.__doc__
    cls.__init__ = __init__
    return cls


_accepting_section_names(TrainConfig)
TrainConfig.__doc__ = (
    "A training run's settings (frozen): `jaxbridge.make_config(env, preset=..., **overrides)` resolves an env's "
    "and a preset's values, checked.\nEach field, its default, and where the paper or the authors' code differ ([leaf]: a sweep "
    "over it shares one compiled program):\n\n" + described(TrainConfig, skip=("learner", "tokens"))
    + "\n\nlearner: the learner's settings, `config.learner`; double DQN's by default (PQN's: "
    "help(jaxbridge.core.learner_settings.PQNSettings)):\n\n" + described(DQNSettings)
    + "\n\ntokens: the object-token network's settings, `config.tokens`:\n\n" + described(TokenSettings))
