"""Draw one episode of the meta-policy as a PNG: the env's world, the robot's path coloured by who was in
control (planner, bridge, CallPlanner), and the doors the bridge opened, so a user can see the bridge work.

`trace_episodes` re-runs chosen episodes of an evaluation with recording on. It uses the evaluation's
per-episode keys, so these are the very episodes that were scored (checked against the evaluation's
results), and keeps only a small view of each recorded state (a recorded state carries its whole task).
`render_episode` draws one trace; what the world looks like is the env's business, a `Drawer` per env
in `DRAWERS` (Doorknobs: the room map from above; Light Switch Door: the row of cells over time; Coffee:
the table from above plus the arm's height, tilt and wrist over time).
"""
from __future__ import annotations

import io
from dataclasses import dataclass
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Arc, Circle, Patch, Polygon, Rectangle

from envs_jax import coffee_world as coffee
from envs_jax import geometry
from envs_jax.base import NoveltyEnv
from envs_jax.doorknobs_maps import ROBOT_RADIUS
from jaxbridge.bridges import Bridge
from jaxbridge.meta_policy import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, Controls, EpisodeResult, rollout
from jaxbridge.tasks import TaskBatch

ACTORS = {ACTOR_PLANNER: ("planner in control", "#1f77b4"), ACTOR_BRIDGE: ("bridge in control", "#ff7f0e"),
          ACTOR_CALL_PLANNER: ("CallPlanner", "#9467bd")}
CLOSED, OPENED, WALL, CLUTTER = "#c62828", "#2e7d32", "#303030", "#8d7b68"
ROOM, START_ROOM, GOAL_ROOM = "#f5f2eb", "#dce9f7", "#d8f0cf"


# ---- the episode, host side ------------------------------------------------------------------------
@dataclass(frozen=True)
class EpisodeTrace:
    """One recorded episode: what the picture needs, nothing more."""

    spec: Any  # the task's host-side spec
    seed: int
    task: int  # index among its seed's tasks
    success: bool
    bridge_decisions: int
    actor: np.ndarray  # int32[steps]: ACTOR_* of each step
    xy: np.ndarray  # float32[steps + 1, 2]: the robot before each step, then after the last
    open: np.ndarray  # bool[steps + 1, D]: the open doors (Coffee: the jug graspable), at the same times
    details: np.ndarray | None = None  # float[steps + 1, K]: whatever else the env's drawer records

    @property
    def steps(self) -> int:
        return len(self.actor)

    @property
    def opened_at(self) -> np.ndarray:
        """int[D]: the step on which each door opened; -1 if it did not open during the episode."""
        change = self.open[1:] & ~self.open[:-1]
        first = np.argmax(np.concatenate([change, np.ones((1, change.shape[1]), bool)]), axis=0)  # steps: never
        return np.where(first < self.steps, first, -1)

    @property
    def opened_by_bridge(self) -> np.ndarray:
        """bool[D]: doors that opened on a step the bridge took (only the bridge's skills turn knobs)."""
        actor = np.append(self.actor, -1)  # index -1 (never opened) reads the pad
        return actor[self.opened_at] == ACTOR_BRIDGE


def actor_segments(actor: np.ndarray) -> list[tuple[int, int, int]]:
    """Maximal runs of steps with one actor, as (actor, first step, end step). Run (a, i, j) moved the robot
    along path points i..j: consecutive runs share a point, so the drawn path has no gaps."""
    actor = np.asarray(actor)
    cuts = np.flatnonzero(np.diff(actor)) + 1
    starts, ends = np.concatenate([[0], cuts]), np.concatenate([cuts, [len(actor)]])
    return [(int(actor[i]), int(i), int(j)) for i, j in zip(starts, ends) if j > i]


def pick_episode(traces: list[EpisodeTrace]) -> EpisodeTrace:
    """The solved episode on which the bridge opened the most doors (the first if tied), else the first."""
    solved = [t for t in traces if t.success]
    return max(solved, key=lambda t: int(t.opened_by_bridge.sum())) if solved else traces[0]


@partial(jax.jit, static_argnames=("env", "bridge", "drawer", "max_steps", "controls"))
def _recorded_rollout(env, bridge, drawer, params, tasks, tables, horizons, keys, max_steps, controls):
    """rollout(record=True), keeping of each recorded state only its snapshot and details (XLA then drops
    the rest)."""
    result, records = rollout(env, bridge, params, tasks, tables, horizons, keys, max_steps, record=True,
                              controls=controls)
    per_state = lambda state: (*drawer.snapshot(env, state), drawer.details(env, state))
    xy, door_open, details = jax.vmap(jax.vmap(per_state))(records.env_state)  # [T, B, ...]
    return result, records.actor, xy, door_open, details


def trace_episodes(batch: TaskBatch, bridge: Bridge, bridge_params, indices, seed: int = 0,
                   controls: Controls = Controls(), expected: EpisodeResult | None = None) -> list[EpisodeTrace]:
    """Episodes `indices` of `run_bridge(batch, bridge, bridge_params, seed, controls)`, recorded.

    `expected`, that evaluation's results, checks that the re-run episodes are the evaluated ones."""
    idx = np.asarray(indices, np.int64)
    take = lambda tree: jax.tree.map(lambda x: x[idx], tree)
    keys = jax.random.split(jax.random.key(seed), batch.size)[idx]
    params = None if bridge_params is None else take(bridge_params)
    # One step past the longest horizon, so the last record holds the final state. An episode's draws for
    # its first max_steps steps do not depend on how many are drawn (partitionable threefry); the check
    # against `expected` below would catch it if they did.
    result, actor, xy, door_open, details = jax.tree.map(np.asarray, _recorded_rollout(
        batch.env, bridge, drawer_for(batch.env), params, take(batch.tasks), take(batch.tables),
        take(batch.horizons), keys, batch.max_steps + 1, controls))
    if expected is not None:
        for field in ("success", "steps", "planner_calls", "bridge_decisions", "stuck_events"):
            if not np.array_equal(getattr(result, field), np.asarray(getattr(expected, field))[idx]):
                raise RuntimeError(f"the re-run episodes differ from the evaluated ones in {field}")
    traces = []
    for row, i in enumerate(idx):
        n, owner = int(result.steps[row]), int(batch.seeds[i])
        traces.append(EpisodeTrace(
            spec=batch.specs[i], seed=owner, task=int(i - np.argmax(batch.seeds == owner)),
            success=bool(result.success[row]), bridge_decisions=int(result.bridge_decisions[row]),
            actor=actor[:n, row], xy=xy[: n + 1, row], open=door_open[: n + 1, row], details=details[: n + 1, row]))
    return traces


# ---- drawing ---------------------------------------------------------------------------------------
class Drawer:
    """How one env's episodes look. Subclasses draw the world; the path and legend are shared."""

    figsize = (9.5, 7.0)
    world_rect = (0.03, 0.04, 0.62, 0.82)  # where the world's axes sit in the figure
    in_place = "turns a knob"  # what the bridge does when it acts without moving the robot

    def snapshot(self, env: NoveltyEnv, state) -> tuple[jax.Array, jax.Array]:
        """(float32[2] robot position, bool[D] open doors) of one state; jittable."""
        raise NotImplementedError

    def details(self, env: NoveltyEnv, state) -> jax.Array:
        """float32[K]: anything else of one state the drawing needs (none by default); jittable."""
        return jnp.zeros(0, jnp.float32)

    def bridge_summary(self, trace: EpisodeTrace) -> str:
        """What the bridge fixed in the episode, for the title and eval.py's report."""
        opened = int(trace.opened_by_bridge.sum())
        return f"the bridge opened {opened} door{'s' if opened != 1 else ''}"

    def draw_panels(self, fig, env: NoveltyEnv, trace: EpisodeTrace) -> None:
        """Extra axes beside the world (none by default)."""

    def path(self, trace: EpisodeTrace) -> np.ndarray:
        """float[steps + 1, 2]: where the path runs in the picture."""
        return trace.xy

    def draw_world(self, ax, env: NoveltyEnv, trace: EpisodeTrace) -> list:
        """Draw everything but the path; return legend handles for what was drawn."""
        raise NotImplementedError


def draw_path(ax, path: np.ndarray, actor: np.ndarray, in_place: str = "turns a knob") -> list:
    """The path as lines coloured by actor, plus markers where an actor acted without moving the robot
    (the bridge turning a knob, every CallPlanner), which a line alone would not show. Returns legend
    handles for what was drawn."""
    moved = np.any(path[1:] != path[:-1], axis=-1)
    lines = {}
    for a, i, j in actor_segments(actor):
        ax.plot(path[i: j + 1, 0], path[i: j + 1, 1], color=ACTORS[a][1], lw=2.2, solid_capstyle="round", zorder=4)
        if moved[i:j].any():
            lines[a] = Line2D([], [], color=ACTORS[a][1], lw=2.2, label=f"path: {ACTORS[a][0]}")
    handles = [lines[a] for a in sorted(lines)]
    # A CallPlanner usually follows the bridge's last skill on the spot: a small diamond on a larger disc.
    for a, marker, size, label in ((ACTOR_BRIDGE, "o", 110, f"bridge acts in place ({in_place})"),
                                   (ACTOR_CALL_PLANNER, "D", 28, "bridge calls CallPlanner")):
        at = path[:-1][(actor == a) & ~moved]
        if len(at):
            ax.scatter(at[:, 0], at[:, 1], s=size, marker=marker, color=ACTORS[a][1], edgecolor="white", lw=0.6,
                       zorder=5 + (a == ACTOR_CALL_PLANNER))
            handles.append(Line2D([], [], ls="", marker=marker, color=ACTORS[a][1], markeredgecolor="white",
                                  markersize=np.sqrt(size), label=label))
    return handles


def _bridge_badges(ax, points: np.ndarray, order: np.ndarray) -> Line2D:
    """Numbered discs, in the order the bridge opened the doors."""
    for k, (x, y) in zip(order, points):
        ax.annotate(str(k), (x, y), ha="center", va="center", fontsize=7, fontweight="bold", color="white",
                    zorder=8, bbox={"boxstyle": "circle,pad=0.25", "fc": ACTORS[ACTOR_BRIDGE][1], "ec": "black",
                                    "lw": 0.6})
    return Line2D([], [], ls="", marker="o", markersize=9, color=ACTORS[ACTOR_BRIDGE][1], markeredgecolor="black",
                  label="door opened by the bridge (in order)")


def _bridge_order(trace: EpisodeTrace) -> np.ndarray:
    """int[D]: 1, 2, ... for the doors the bridge opened, in the order it opened them; 0 for the others."""
    mine = trace.opened_by_bridge
    rank = np.argsort(np.argsort(np.where(mine, trace.opened_at, np.iinfo(np.int64).max), kind="stable"))
    return np.where(mine, rank + 1, 0)


class DoorknobsDrawer(Drawer):
    """The map from above: rooms (start and goal tinted), walls, clutter, doors closed or swung open at the
    end of the episode, the robot at its start and its end."""

    def snapshot(self, env, state):
        return state.robot, state.door_open

    def draw_world(self, ax, env, trace):
        task = env.task_arrays(trace.spec)
        rooms = np.flatnonzero(task.room_mask)
        inside = np.all((task.robot_start >= task.room_xy) & (task.robot_start < task.room_xy + 1), -1)
        start_room = np.argmax(inside & task.room_mask)
        for r in rooms:
            colour = GOAL_ROOM if r == task.goal_room else START_ROOM if r == start_room else ROOM
            ax.add_patch(Rectangle(task.room_xy[r], 1.0, 1.0, fc=colour, ec="none", zorder=0))
            label = "goal" if r == task.goal_room else "start" if r == start_room else None
            if label:
                ax.text(*(task.room_xy[r] + (0.04, 0.96)), label, ha="left", va="top", fontsize=8, zorder=1,
                        color="#1b5e20" if label == "goal" else "#0d47a1", fontweight="bold")
        for rects, colour in ((task.walls[task.wall_mask], WALL), (task.clutter[task.clutter_mask], CLUTTER)):
            for corners in np.asarray(geometry.corners(jnp.asarray(rects))):
                ax.add_patch(Polygon(corners, closed=True, fc=colour, ec=colour, lw=0.8, zorder=2))

        final, order = trace.open[-1], _bridge_order(trace)
        badges, badge_order = [], []
        for d in np.flatnonzero(task.door_mask):
            x, y, width, _, theta = task.door_rect[d]
            along = np.array([np.cos(theta), np.sin(theta)])
            hinge, end = np.array([x, y]), np.array([x, y]) + width * along
            if final[d]:  # swung open about its hinge, a quarter turn
                leaf = hinge + width * np.array([-along[1], along[0]])
                ax.plot(*np.stack([hinge, leaf]).T, color=OPENED, lw=2.0, zorder=3)
                ax.add_patch(Arc(hinge, 2 * width, 2 * width, theta1=np.degrees(theta), theta2=np.degrees(theta) + 90,
                                 color=OPENED, lw=0.8, ls=":", zorder=3))
            else:
                ax.plot(*np.stack([hinge, end]).T, color=CLOSED, lw=4.0, solid_capstyle="butt", zorder=3)
            if order[d]:  # on the wall just past the doorway, off the robot's way
                badges.append(hinge + (width + 0.09) * along)
                badge_order.append(order[d])
        handles = [_bridge_badges(ax, np.array(badges).reshape(-1, 2), np.array(badge_order))] if badges else []

        for xy, fc, label in ((trace.xy[0], "white", "robot at the start"),
                              (trace.xy[-1], "#555555", "robot at the end")):
            ax.add_patch(Circle(xy, ROBOT_RADIUS, fc=fc, ec="black", lw=1.0, zorder=7))
            handles.append(Line2D([], [], ls="", marker="o", markersize=8, markerfacecolor=fc,
                                  markeredgecolor="black", label=label))
        lo, hi = task.room_xy[rooms].min(0) - 0.05, task.room_xy[rooms].max(0) + 1.05
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_axis_off()  # the walls frame the map
        return [Line2D([], [], color=CLOSED, lw=4, label="door closed (at the end)"),
                Line2D([], [], color=OPENED, lw=2, label="door open (at the end)"), *handles,
                Patch(fc=START_ROOM, ec="grey", label="start room"), Patch(fc=GOAL_ROOM, ec="grey", label="goal room"),
                Patch(fc=CLUTTER, label="clutter"), Patch(fc=WALL, label="wall")]


class LightSwitchDoorDrawer(Drawer):
    """The row of cells across, time down: the robot's cell at every step, each door a bar on its cell's
    right edge (where it blocks) that turns from closed to open at the step it opened."""

    figsize = (9.5, 6.0)

    def snapshot(self, env, state):
        return jnp.stack([state.robot_x, jnp.float32(0.0)]), env.door_open(state)

    def path(self, trace):
        return np.stack([trace.xy[:, 0], np.arange(trace.steps + 1)], axis=-1)

    def draw_world(self, ax, env, trace):
        task, end = env.task_arrays(trace.spec), max(trace.steps, 1)
        cells = int(task.num_cells)
        for c in range(cells):
            ax.add_patch(Rectangle((c, 0), 1.0, end, fc=GOAL_ROOM if c == cells - 1 else ROOM if c % 2 else "white",
                                   ec="#dddddd", lw=0.5, zorder=0))
        ax.text(cells - 0.5, -0.3, "light", ha="center", va="bottom", fontsize=8, color="#1b5e20")
        order, opened_at = _bridge_order(trace), trace.opened_at
        badges, badge_order = [], []
        for d in np.flatnonzero(task.door_cell >= 0):
            x = task.door_cell[d] + 1.0
            switch = opened_at[d] + 1 if opened_at[d] >= 0 else end
            ax.plot([x, x], [0, switch], color=CLOSED, lw=3.5, solid_capstyle="butt", zorder=3)
            ax.plot([x, x], [switch, end], color=OPENED, lw=1.5, ls="--", zorder=3)
            if order[d]:
                badges.append((x + 0.25, switch))
                badge_order.append(order[d])
        handles = [_bridge_badges(ax, np.array(badges).reshape(-1, 2), np.array(badge_order))] if badges else []
        ax.set_xlim(0, cells)
        ax.set_ylim(end + 0.5, -0.8)
        ax.set_xlabel("robot position (cells)")
        ax.set_ylabel("env step")
        return [Line2D([], [], color=CLOSED, lw=3.5, label="door closed"),
                Line2D([], [], color=OPENED, lw=1.5, ls="--", label="door open"), *handles,
                Patch(fc=GOAL_ROOM, ec="grey", label="light's cell (goal)")]


class CoffeeDrawer(Drawer):
    """The table from above: the machine with its button and dispense area, the cups (green once filled,
    with their liquid / target at the end), the jug at its start and its end (handle drawn), the robot's
    (x, y) path; below, the robot's height, tilt and wrist over time, shaded while the bridge acts."""

    figsize = (9.5, 9.5)
    world_rect = (0.03, 0.36, 0.62, 0.56)
    in_place = "twists the jug"
    Z, TILT, WRIST, JUG, ROT, FILLED, ON, LIQUID = 0, 1, 2, 4, 6, 8, 9, 10  # columns of `details`

    def snapshot(self, env, state):
        return state.robot[:2], (jnp.abs(state.jug_rot) < coffee.PICK_JUG_ROT_TOL)[None]  # graspable

    def details(self, env, state):
        flags = jnp.stack([state.jug_held, state.jug_filled, state.machine_on]).astype(jnp.float32)
        return jnp.concatenate([state.robot[2:], state.jug_xy, state.jug_rot[None], flags, state.cup_liquid])

    def bridge_summary(self, trace):
        rot = trace.details[:, self.ROT]
        if trace.opened_by_bridge.any():
            return f"the bridge twisted the jug from rot {rot[0]:.2f} to {rot[-1]:.2f}"
        return f"the bridge left the jug ungraspable (rot {rot[-1]:.2f})" if not trace.open[-1, 0] else \
            "the bridge did not twist the jug"

    def _jug(self, ax, xy, rot, **style) -> None:
        ax.add_patch(Circle(xy, coffee.JUG_RADIUS, zorder=3, **style))
        handle = xy + coffee.HANDLE_OFFSET * np.array([np.cos(rot - np.pi / 2), np.sin(rot - np.pi / 2)])
        ax.plot(*np.stack([xy, handle]).T, color="black", lw=2.0, zorder=3)

    def draw_world(self, ax, env, trace):
        task, end = env.task_arrays(trace.spec), trace.details[-1]
        ax.add_patch(Rectangle((0, 0), 10, 10, fc=ROOM, ec="#cccccc", zorder=0))
        ax.add_patch(Rectangle(coffee.MACHINE_XY, *coffee.MACHINE_SIZE[:2], fc="#9e9e9e", ec=WALL, zorder=1))
        ax.add_patch(Circle(coffee.DISPENSE[:2], np.sqrt(coffee.DISPENSE_TOL), fc="none", ec="#616161", ls="--",
                            zorder=1))
        button = OPENED if end[self.ON] > 0.5 else CLOSED
        ax.add_patch(Circle(coffee.BUTTON[:2], 0.15, fc=button, ec="black", lw=0.6, zorder=2))
        filled_cup, empty_cup = "#81c784", "white"
        for c in np.flatnonzero(task.cup_mask):
            full = end[self.LIQUID + c] > task.cup_target[c]
            ax.add_patch(Circle(task.cup_xy[c], coffee.CUP_RADIUS, fc=filled_cup if full else empty_cup, ec="black",
                                lw=0.8, zorder=2))
            ax.text(task.cup_xy[c, 0], task.cup_xy[c, 1] - 0.45, f"cup{c}\n{end[self.LIQUID + c]:.2f}/"
                    f"{task.cup_target[c]:.2f}", ha="center", va="top", fontsize=7, zorder=2)
        start = trace.details[0]
        self._jug(ax, start[self.JUG:self.JUG + 2], start[self.ROT], fc="none", ec=CLUTTER, ls="--", lw=1.2)
        self._jug(ax, end[self.JUG:self.JUG + 2], end[self.ROT], fc=CLUTTER if end[self.FILLED] > 0.5 else "white",
                  ec="black", lw=1.0, alpha=0.85)
        handles = []
        for xy, fc, label in ((trace.xy[0], "white", "robot at the start"), (trace.xy[-1], "#555555", "robot at the end")):
            ax.add_patch(Circle(xy, 0.12, fc=fc, ec="black", lw=1.0, zorder=7))
            handles.append(Line2D([], [], ls="", marker="o", markersize=8, markerfacecolor=fc, markeredgecolor="black",
                                  label=label))
        ax.set_xlim(-0.1, 10.1)
        ax.set_ylim(-0.1, 10.1)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        return [*handles, Patch(fc="#9e9e9e", ec=WALL, label="coffee machine"),
                Line2D([], [], ls="", marker="o", color=button, markeredgecolor="black",
                       label=f"button (machine {'on' if end[self.ON] > 0.5 else 'off'} at the end)"),
                Line2D([], [], color="#616161", ls="--", label="dispense area (jug in machine)"),
                Line2D([], [], ls="", marker="o", markersize=9, markerfacecolor="none", markeredgecolor=CLUTTER,
                       label="jug at the start (line: handle)"),
                Line2D([], [], ls="", marker="o", markersize=9, markerfacecolor=CLUTTER, markeredgecolor="black",
                       label="jug at the end (brown: filled)"),
                Patch(fc=filled_cup, ec="black", label="cup filled (liquid/target)"),
                Patch(fc=empty_cup, ec="black", label="cup not filled")]

    def draw_panels(self, fig, env, trace):
        ax = fig.add_axes((0.08, 0.05, 0.57, 0.22))
        steps = np.arange(trace.steps + 1)
        for a, i, j in actor_segments(trace.actor):
            if a != ACTOR_PLANNER:
                ax.axvspan(i, j, color=ACTORS[a][1], alpha=0.25, lw=0)
        lines = ax.plot(steps, trace.details[:, self.Z], color="#37474f", lw=1.6, label="z (left)")
        angles = ax.twinx()
        lines += angles.plot(steps, trace.details[:, self.TILT], color="#8e24aa", lw=1.2, label="tilt (right)")
        lines += angles.plot(steps, trace.details[:, self.WRIST], color="#00897b", lw=1.2, label="wrist (right)")
        lines += angles.plot(steps, trace.details[:, self.ROT], color=CLUTTER, lw=1.2, ls=":", label="jug rot (right)")
        ax.set_xlim(0, max(trace.steps, 1))
        ax.set_xlabel("env step (shaded: bridge, CallPlanner)")
        ax.set_ylabel("height")
        angles.set_ylabel("radians")
        ax.legend(handles=lines, loc="upper left", bbox_to_anchor=(1.12, 1.0), fontsize=8, frameon=False)


DRAWERS: dict[str, Drawer] = {"doorknobs": DoorknobsDrawer(), "light_switch_door": LightSwitchDoorDrawer(),
                              "coffee": CoffeeDrawer()}


def drawer_for(env: NoveltyEnv) -> Drawer:
    if env.name not in DRAWERS:
        raise ValueError(f"no episode drawer for env {env.name!r}; can draw: {', '.join(DRAWERS)}")
    return DRAWERS[env.name]


def render_episode(env: NoveltyEnv, trace: EpisodeTrace, label: str = "") -> bytes:
    """PNG bytes of one episode; `label` says whose bridge it is (e.g. "oracle bridge")."""
    drawer = drawer_for(env)
    fig = Figure(figsize=drawer.figsize, dpi=130)  # no pyplot: no global figure state, nothing to close
    ax = fig.add_axes(drawer.world_rect)
    handles = drawer.draw_world(ax, env, trace)
    handles = draw_path(ax, drawer.path(trace), trace.actor, drawer.in_place) + handles
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    outcome = f"solved in {trace.steps} steps" if trace.success else f"not solved ({trace.steps} steps)"
    ax.set_title(f"{env.name}, seed {trace.seed}, task {trace.task}: {trace.spec.describe()}\n"
                 f"{label + ': ' if label else ''}{outcome}; {drawer.bridge_summary(trace)} "
                 f"in {trace.bridge_decisions} decisions",
                 loc="left", fontsize=10)  # on the axes, so it follows the map's aspect (no gap)
    drawer.draw_panels(fig, env, trace)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", bbox_inches="tight", pad_inches=0.15)
    return buffer.getvalue()
