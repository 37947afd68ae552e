"""Draw one episode of the meta-policy as a PNG: the env's world, the robot's path coloured by who was in
control (planner, bridge, CallPlanner), the doors the bridge opened and the skills it chose, so a user can
see the bridge work.

`trace_episodes` re-runs chosen episodes of an evaluation with recording on. It uses the evaluation's
per-episode keys, so these are the very episodes that were scored (checked against the evaluation's
results), and keeps only a small view of each recorded state (a recorded state carries its whole task)
and the ground skill each step ran; of a learned object selector, also what it saw at each decision, for
its attention. `render_episode` draws one trace through an `EpisodeFigure`, which `animate` also draws
its frames with; what the world looks like is the env's business (`drawers`).
"""
from __future__ import annotations

import io
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from envs_jax.base import NoveltyEnv
from envs_jax.drawing import Drawer, EpisodeTrace, attention_marks, draw_path, moment
from jaxbridge.core.bridges import Bridge
from jaxbridge.core.meta_policy import Controls, EpisodeResult, MetaPolicy, rollout
from jaxbridge.core.tasks import TaskBatch
from jaxbridge.learn.object_q import slot_weights
from jaxbridge.viz.episodes import bridge_choices


def drawer_for(env: NoveltyEnv) -> Drawer:
    """The env's drawer (`NoveltyEnv.drawer`); ValueError for an env that draws nothing."""
    drawer = env.drawer()
    if drawer is None:
        raise ValueError(f"env {env.name!r} has no episode drawer (NoveltyEnv.drawer); it cannot be rendered")
    return drawer


# ---- recording ---------------------------------------------------------------------------------
@partial(jax.jit, static_argnames=("drawer", "max_steps"))
def _recorded_rollout(policy: MetaPolicy, drawer: Drawer, batch, keys, max_steps: int, groups):
    """rollout(record=True), keeping of each recorded state only its snapshot and details (XLA then drops
    the rest), and of each step the ground skill it ran."""
    env, controls = policy.env, policy.controls
    result, records = rollout(policy, batch, keys, max_steps, record=True, groups=groups)
    per_state = lambda state: (*drawer.snapshot(env, state), drawer.details(env, state))
    xy, door_open, details = jax.vmap(jax.vmap(per_state))(records.env_state)  # [T, B, ...]
    per_step = (records.actor, records.skill, records.slot, records.param, records.decided)
    seen = None
    if controls.observation.tokens:  # object tokens, what a learned selector attends to, and each object slot's type
        seen = (records.features, env.objects(jax.tree.map(lambda x: x[0, 0], records.env_state)).type_id)
    return result, per_step, (xy, door_open, details), seen


def trace_episodes(batch: TaskBatch, bridge: Bridge, bridge_params, indices, seed: int = 0,
                   controls: Controls = Controls(), expected: EpisodeResult | None = None) -> list[EpisodeTrace]:
    """Episodes `indices` of `run_bridge(batch, bridge, bridge_params, seed, controls)`, recorded.

    `expected`, that evaluation's results, checks that the re-run episodes are the evaluated ones."""
    wanted = np.asarray(indices, np.int64)
    # Every episode of the wanted episodes' seeds is re-run: an env may share state between a seed's
    # concurrent episodes (`share_between_episodes`); alone, an episode's numbers are its own.
    idx = np.flatnonzero(np.isin(batch.seeds, batch.seeds[wanted]))
    take = lambda tree: jax.tree.map(lambda x: x[idx], tree)
    keys = jax.random.split(jax.random.key(seed), batch.size)[idx]
    params = None if bridge_params is None else take(bridge_params)
    # One step past the longest horizon, so the last record holds the final state. An episode's draws for
    # its first max_steps steps do not depend on how many are drawn (partitionable threefry); the check
    # against `expected` below would catch it if they did.
    result, (actor, skill, slot, param, decided), (xy, door_open, details), seen = jax.tree.map(
        np.asarray, _recorded_rollout(MetaPolicy(batch.env, bridge, params, controls), drawer_for(batch.env),
                                      take(batch.arrays), keys, batch.max_steps + 1,
                                      jnp.asarray(batch.seeds[idx], jnp.int32)))
    if expected is not None:
        for field in ("success", "steps", "planner_calls", "bridge_decisions", "stuck_events"):
            if not np.array_equal(getattr(result, field), np.asarray(getattr(expected, field))[idx]):
                raise RuntimeError(f"the re-run episodes differ from the evaluated ones in {field}")
    attention, object_type = None, None
    if seen is not None:  # at the bridge's decisions only
        tokens, object_type = seen
        attention = slot_weights(batch.env, bridge.net, params.q, tokens) * decided[..., None]
    traces = []
    for i in wanted:
        row = int(np.searchsorted(idx, i))
        n, owner = int(result.steps[row]), int(batch.seeds[i])
        traces.append(EpisodeTrace(
            spec=batch.specs[i], seed=owner, task=int(i - np.argmax(batch.seeds == owner)),
            success=bool(result.success[row]), bridge_decisions=int(result.bridge_decisions[row]),
            actor=actor[:n, row], xy=xy[: n + 1, row], open=door_open[: n + 1, row], details=details[: n + 1, row],
            skill=skill[:n, row], slot=slot[:n, row], param=param[:n, row], decided=decided[:n, row],
            attention=None if attention is None else attention[:n, row], object_type=object_type))
    return traces


# ---- drawing ---------------------------------------------------------------------------------------
def _choice_entries(env: NoveltyEnv, trace: EpisodeTrace, upto: int, most: int = 10) -> list:
    """Legend lines (no symbol) listing the bridge's decisions so far: the step and the skill it chose."""
    choices = bridge_choices(env, trace, upto)
    lines = [f"step {step}: {label}" for step, label in choices[:most]]
    lines += [f"... and {len(choices) - most} more"] if len(choices) > most else []
    return [Line2D([], [], ls="", label=text) for text in (["the bridge chose:"] if lines else []) + lines]


class EpisodeFigure:
    """One episode's figure in two layers: the background (the world's fixed parts, the title, the axes of
    any panels), drawn on creation, and the state after some number of steps (the path so far, doors,
    robot, legend), which `draw_state` adds. An animation draws the background once, then each frame's
    state over it."""

    def __init__(self, env: NoveltyEnv, trace: EpisodeTrace, label: str = "", dpi: float = 130,
                 animated: bool = False):
        """`label` says whose bridge it is (e.g. "oracle bridge"). `animated`: the legend is the whole
        episode's, drawn with the background (redrawn for every frame it would take most of the time and
        jump about as entries appear)."""
        self.env, self.trace, self.drawer = env, trace, drawer_for(env)
        self.fig = Figure(figsize=self.drawer.figsize, dpi=dpi)  # no pyplot: no global state, nothing to close
        self.world = self.fig.add_axes(self.drawer.world_rect)
        self.fixed_handles = self.drawer.draw_background(self.world, env, trace)
        outcome = f"solved in {trace.steps} steps" if trace.success else f"not solved ({trace.steps} steps)"
        self.world.set_title(f"{env.name}, seed {trace.seed}, task {trace.task}: {trace.spec.describe()}\n"
                             f"{label + ': ' if label else ''}{outcome}; {self.drawer.bridge_summary(trace)} "
                             f"in {trace.bridge_decisions} decisions",
                             loc="left", fontsize=10)  # on the axes, so it follows the map's aspect (no gap)
        self.panels = self.drawer.draw_panels(self.fig, env, trace)
        self.fixed_legend = False
        if animated:  # draw the last frame for its legend, then keep only the legend
            for artist in self.draw_state(trace.steps):
                if artist is not self.world.get_legend():
                    artist.remove()
        self.fixed_legend = animated

    def draw_state(self, upto: int | None = None) -> list:
        """Add the episode's state after `upto` steps (None: at the end, in a still picture); return the
        artists added, in the order to draw them, so that a frame can draw them alone and then remove them."""
        env, trace, drawer, world = self.env, self.trace, self.drawer, self.world
        steps, _ = moment(trace, upto)
        before = {ax: set(ax.get_children()) for ax in self.fig.axes}
        handles = draw_path(world, drawer.path(trace)[: steps + 1], trace.actor[:steps], drawer.in_place)
        handles += drawer.draw_state(world, env, trace, upto) + self.fixed_handles
        if trace.attention is not None:
            handles += attention_marks(world, drawer, env, trace, steps)
        if not self.fixed_legend:
            handles += _choice_entries(env, trace, steps)
            world.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
        drawer.draw_panel_state(self.panels, env, trace, upto)
        added = [[a for a in ax.get_children() if a not in before[ax]] for ax in self.fig.axes]
        return [a for new in added for a in sorted(new, key=lambda a: a.get_zorder())]  # as Figure.draw would


def render_episode(env: NoveltyEnv, trace: EpisodeTrace, label: str = "") -> bytes:
    """PNG bytes of one episode; `label` says whose bridge it is (e.g. "oracle bridge")."""
    figure = EpisodeFigure(env, trace, label)
    figure.draw_state()
    buffer = io.BytesIO()
    figure.fig.savefig(buffer, format="png", bbox_inches="tight", pad_inches=0.15)
    return buffer.getvalue()
