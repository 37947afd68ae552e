"""How an env draws its episodes: the recorded `EpisodeTrace` a drawer reads, the `Drawer` base an env
subclasses (beside the env: e.g. envs_jax/doorknobs/drawer.py, returned by `NoveltyEnv.drawer()`), and the
parts every drawer shares (the path coloured by who was in control, the robot, the bridge's badges).

A drawer draws the world in two layers: its fixed parts (`draw_background`) and its state after some
number of steps (`draw_state`). A still picture draws both at the end of the episode; an animation draws
the background once and the state of every frame over it. jaxbridge/viz turns traces into PNGs and GIFs.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import matplotlib.colors
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Circle

from envs_jax.base import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, NoveltyEnv

@dataclass(frozen=True)
class EpisodeTrace:
    """One recorded episode: what the pictures need, nothing more. Arrays over steps describe each env
    step; arrays over steps + 1 describe the states before each step, then after the last."""

    spec: Any  # the task's host-side spec
    seed: int
    task: int  # index among its seed's tasks
    success: bool
    bridge_decisions: int
    actor: np.ndarray  # int32[steps]: ACTOR_* of each step
    xy: np.ndarray  # float32[steps + 1, 2]: the robot
    open: np.ndarray  # bool[steps + 1, D]: the open doors (Coffee: the jug graspable)
    details: np.ndarray | None = None  # float[steps + 1, K]: whatever else the env's drawer records
    # The ground skill each step ran (None in hand-made traces that do not need them).
    skill: np.ndarray | None = None  # int32[steps]: skill id; env.num_skills is CallPlanner
    slot: np.ndarray | None = None  # int32[steps]: the object it acts on (the env's slot)
    param: np.ndarray | None = None  # float32[steps]: its continuous parameter
    decided: np.ndarray | None = None  # bool[steps]: the bridge chose that skill (or CallPlanner) then
    # A learned object selector's attention at each of its decisions (zeros elsewhere), over the object view's
    # slots, and each slot's type id (an index into the env's object_types); None for other bridges.
    attention: np.ndarray | None = None  # float[steps, N]
    object_type: np.ndarray | None = None  # int[N]

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



ACTORS = {ACTOR_PLANNER: ("planner in control", "#1f77b4"), ACTOR_BRIDGE: ("bridge in control", "#ff7f0e"),
          ACTOR_CALL_PLANNER: ("CallPlanner", "#9467bd")}
CLOSED, OPENED, WALL, CLUTTER = "#c62828", "#2e7d32", "#303030", "#8d7b68"
ROOM, START_ROOM, GOAL_ROOM = "#f5f2eb", "#dce9f7", "#d8f0cf"


class Drawer:
    """How one env's episodes look. Subclasses draw the world; the path and legend are shared.

    State is drawn after `upto` steps, within limits that the background fixes for the whole episode, so
    that the frames of an animation line up; upto=None is the end of the episode in a still picture (the
    legend says "at the end" rather than "now")."""

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

    def path(self, trace: EpisodeTrace) -> np.ndarray:
        """float[steps + 1, 2]: where the path runs in the picture."""
        return trace.xy

    def draw_background(self, ax, env: NoveltyEnv, trace: EpisodeTrace) -> list:
        """Draw the world's fixed parts and set the axes' limits; return legend handles for what was drawn."""
        raise NotImplementedError

    def draw_state(self, ax, env: NoveltyEnv, trace: EpisodeTrace, upto: int | None) -> list:
        """Draw what changes (but the path), after `upto` steps; return legend handles for what was drawn."""
        raise NotImplementedError

    def object_xy(self, env: NoveltyEnv, trace: EpisodeTrace, kind: str, slot: int, upto: int) -> np.ndarray | None:
        """float[2]: where object `slot` of type `kind` (what a skill acts on) is in the picture after `upto`
        steps; None where the picture does not show it."""
        return None

    def draw_panels(self, fig, env: NoveltyEnv, trace: EpisodeTrace) -> list:
        """Extra axes beside the world, their fixed parts (none by default); returns them."""
        return []

    def draw_panel_state(self, panels: list, env: NoveltyEnv, trace: EpisodeTrace, upto: int | None) -> None:
        """Draw into the extra axes what changes, after `upto` steps."""


def moment(trace: EpisodeTrace, upto: int | None) -> tuple[int, str]:
    """(steps taken, how the legend says when): upto=None is the end of the episode in a still picture."""
    return (trace.steps, "at the end") if upto is None else (upto, "now")


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


def robot_marks(ax, trace: EpisodeTrace, upto: int, when: str, radius: float) -> list:
    """The robot, to scale, at the start (white) and after `upto` steps (grey)."""
    handles = []
    for xy, fc, label in ((trace.xy[0], "white", "robot at the start"), (trace.xy[upto], "#555555", f"robot {when}")):
        ax.add_patch(Circle(xy, radius, fc=fc, ec="black", lw=1.0, zorder=7))
        handles.append(Line2D([], [], ls="", marker="o", markersize=8, markerfacecolor=fc, markeredgecolor="black",
                              label=label))
    return handles


ATTENTION = "#00897b"


def attention_marks(ax, drawer: "Drawer", env: NoveltyEnv, trace: EpisodeTrace, upto: int) -> list:
    """At each of the bridge's decisions in the first `upto` steps, a ring around every object it attended
    to, as opaque as its weight (those under 5% left out), where the picture shows the object; a legend
    handle if any."""
    types, names = trace.object_type, list(type(env).object_types)
    points, weights = [], []
    for step, slot in zip(*np.nonzero(trace.attention[:upto] >= 0.05)):
        first = int(np.argmax(types == types[slot]))  # the slot's index among its type's: the drawer's slot
        xy = drawer.object_xy(env, trace, names[types[slot]], int(slot - first), int(step))
        if xy is not None:
            points.append(xy)
            weights.append(float(trace.attention[step, slot]))
    if not points:
        return []
    colours = [matplotlib.colors.to_rgba(ATTENTION, w) for w in weights]
    ax.scatter(*np.asarray(points).T, s=260, facecolors="none", edgecolors=colours, linewidths=2.0, zorder=6)
    return [Line2D([], [], ls="", marker="o", markersize=12, markerfacecolor="none", markeredgecolor=ATTENTION,
                   markeredgewidth=2.0, label="attended at a bridge decision (opacity: weight)")]


def bridge_badges(ax, points: np.ndarray, order: np.ndarray) -> list:
    """Numbered discs, in the order the bridge opened the doors; a legend handle if any."""
    for k, (x, y) in zip(order, points):
        ax.annotate(str(k), (x, y), ha="center", va="center", fontsize=7, fontweight="bold", color="white",
                    zorder=8, bbox={"boxstyle": "circle,pad=0.25", "fc": ACTORS[ACTOR_BRIDGE][1], "ec": "black",
                                    "lw": 0.6})
    return [Line2D([], [], ls="", marker="o", markersize=9, color=ACTORS[ACTOR_BRIDGE][1], markeredgecolor="black",
                   label="door opened by the bridge (in order)")] if len(order) else []


def bridge_order(trace: EpisodeTrace, upto: int) -> np.ndarray:
    """int[D]: 1, 2, ... for the doors the bridge opened in the first `upto` steps, in the order it opened
    them (the same numbers whatever `upto`); 0 for the others."""
    mine = trace.opened_by_bridge
    rank = np.argsort(np.argsort(np.where(mine, trace.opened_at, np.iinfo(np.int64).max), kind="stable"))
    return np.where(mine & (trace.opened_at < upto), rank + 1, 0)
