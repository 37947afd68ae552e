"""What one env's episodes look like: a `Drawer` per env in `DRAWERS` (Doorknobs: the room map from above;
Light Switch Door: the row of cells over time; Coffee: the table from above plus the arm's height, tilt
and wrist over time), and the robot's path coloured by who was in control, which all envs share.

A drawer draws the world in two layers: its fixed parts (`draw_background`: rooms, walls, the machine,
the axes' limits) and its state after some number of steps (`draw_state`: doors, the robot, the jug). A
still picture draws both at the end of the episode; an animation draws the background once and the state
of every frame over it.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Arc, Circle, Patch, Polygon, Rectangle

from envs_jax import coffee_world as coffee
from envs_jax import geometry
from envs_jax.base import NoveltyEnv
from envs_jax.doorknobs_maps import ROBOT_RADIUS
from jaxbridge.episode_trace import EpisodeTrace, actor_segments
from jaxbridge.meta_policy import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER

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


def _robot_marks(ax, trace: EpisodeTrace, upto: int, when: str, radius: float) -> list:
    """The robot, to scale, at the start (white) and after `upto` steps (grey)."""
    handles = []
    for xy, fc, label in ((trace.xy[0], "white", "robot at the start"), (trace.xy[upto], "#555555", f"robot {when}")):
        ax.add_patch(Circle(xy, radius, fc=fc, ec="black", lw=1.0, zorder=7))
        handles.append(Line2D([], [], ls="", marker="o", markersize=8, markerfacecolor=fc, markeredgecolor="black",
                              label=label))
    return handles


def _bridge_badges(ax, points: np.ndarray, order: np.ndarray) -> list:
    """Numbered discs, in the order the bridge opened the doors; a legend handle if any."""
    for k, (x, y) in zip(order, points):
        ax.annotate(str(k), (x, y), ha="center", va="center", fontsize=7, fontweight="bold", color="white",
                    zorder=8, bbox={"boxstyle": "circle,pad=0.25", "fc": ACTORS[ACTOR_BRIDGE][1], "ec": "black",
                                    "lw": 0.6})
    return [Line2D([], [], ls="", marker="o", markersize=9, color=ACTORS[ACTOR_BRIDGE][1], markeredgecolor="black",
                   label="door opened by the bridge (in order)")] if len(order) else []


def _bridge_order(trace: EpisodeTrace, upto: int) -> np.ndarray:
    """int[D]: 1, 2, ... for the doors the bridge opened in the first `upto` steps, in the order it opened
    them (the same numbers whatever `upto`); 0 for the others."""
    mine = trace.opened_by_bridge
    rank = np.argsort(np.argsort(np.where(mine, trace.opened_at, np.iinfo(np.int64).max), kind="stable"))
    return np.where(mine & (trace.opened_at < upto), rank + 1, 0)


class DoorknobsDrawer(Drawer):
    """The map from above: rooms (start and goal tinted), walls, clutter, doors closed or swung open, the
    robot at its start and now (at the end of the episode in a still picture)."""

    def snapshot(self, env, state):
        return state.robot, state.door_open

    def object_xy(self, env, trace, kind, slot, upto):
        x, y, width, _, theta = env.task_arrays(trace.spec).door_rect[slot]
        return np.array([x, y]) + width / 2 * np.array([np.cos(theta), np.sin(theta)]) if kind == "door" else None

    def draw_background(self, ax, env, trace):
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
        lo, hi = task.room_xy[rooms].min(0) - 0.05, task.room_xy[rooms].max(0) + 1.05
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_axis_off()  # the walls frame the map
        return [Patch(fc=START_ROOM, ec="grey", label="start room"), Patch(fc=GOAL_ROOM, ec="grey", label="goal room"),
                Patch(fc=CLUTTER, label="clutter"), Patch(fc=WALL, label="wall")]

    def draw_state(self, ax, env, trace, upto):
        upto, when = moment(trace, upto)
        task, now, order = env.task_arrays(trace.spec), trace.open[upto], _bridge_order(trace, upto)
        badges, badge_order = [], []
        for d in np.flatnonzero(task.door_mask):
            x, y, width, _, theta = task.door_rect[d]
            along = np.array([np.cos(theta), np.sin(theta)])
            hinge, end = np.array([x, y]), np.array([x, y]) + width * along
            if now[d]:  # swung open about its hinge, a quarter turn
                leaf = hinge + width * np.array([-along[1], along[0]])
                ax.plot(*np.stack([hinge, leaf]).T, color=OPENED, lw=2.0, zorder=3)
                ax.add_patch(Arc(hinge, 2 * width, 2 * width, theta1=np.degrees(theta), theta2=np.degrees(theta) + 90,
                                 color=OPENED, lw=0.8, ls=":", zorder=3))
            else:
                ax.plot(*np.stack([hinge, end]).T, color=CLOSED, lw=4.0, solid_capstyle="butt", zorder=3)
            if order[d]:  # on the wall just past the doorway, off the robot's way
                badges.append(hinge + (width + 0.09) * along)
                badge_order.append(order[d])
        return [Line2D([], [], color=CLOSED, lw=4, label=f"door closed ({when})"),
                Line2D([], [], color=OPENED, lw=2, label=f"door open ({when})"),
                *_bridge_badges(ax, np.array(badges).reshape(-1, 2), np.array(badge_order)),
                *_robot_marks(ax, trace, upto, when, ROBOT_RADIUS)]


class LightSwitchDoorDrawer(Drawer):
    """The row of cells across, time down: the robot's cell at every step, each door a bar on its cell's
    right edge (where it blocks) that turns from closed to open at the step it opened."""

    figsize = (9.5, 6.0)

    def snapshot(self, env, state):
        return jnp.stack([state.robot_x, jnp.float32(0.0)]), env.door_open(state)

    def path(self, trace):
        return np.stack([trace.xy[:, 0], np.arange(trace.steps + 1)], axis=-1)

    def object_xy(self, env, trace, kind, slot, upto):
        return np.array([slot + 0.5, upto]) if kind == "cell" else None

    def draw_background(self, ax, env, trace):
        cells, end = int(env.task_arrays(trace.spec).num_cells), max(trace.steps, 1)
        for c in range(cells):
            ax.add_patch(Rectangle((c, 0), 1.0, end, fc=GOAL_ROOM if c == cells - 1 else ROOM if c % 2 else "white",
                                   ec="#dddddd", lw=0.5, zorder=0))
        ax.text(cells - 0.5, -0.3, "light", ha="center", va="bottom", fontsize=8, color="#1b5e20")
        ax.set_xlim(0, cells)
        ax.set_ylim(end + 0.5, -0.8)
        ax.set_xlabel("robot position (cells)")
        ax.set_ylabel("env step")
        return [Patch(fc=GOAL_ROOM, ec="grey", label="light's cell (goal)")]

    def draw_state(self, ax, env, trace, upto):
        (upto, when), task, end = moment(trace, upto), env.task_arrays(trace.spec), max(trace.steps, 1)
        now = end if upto == trace.steps else upto  # how far down the time axis the doors are drawn
        order, opened_at = _bridge_order(trace, upto), trace.opened_at
        badges, badge_order = [], []
        for d in np.flatnonzero(task.door_cell >= 0):
            x = task.door_cell[d] + 1.0
            switch = opened_at[d] + 1 if opened_at[d] >= 0 else end
            ax.plot([x, x], [0, min(switch, now)], color=CLOSED, lw=3.5, solid_capstyle="butt", zorder=3)
            if now > switch:
                ax.plot([x, x], [switch, now], color=OPENED, lw=1.5, ls="--", zorder=3)
            if order[d]:
                badges.append((x + 0.25, switch))
                badge_order.append(order[d])
        ax.scatter(*self.path(trace)[upto], s=70, color="#555555", edgecolor="black", zorder=7)
        return [Line2D([], [], color=CLOSED, lw=3.5, label="door closed"),
                Line2D([], [], color=OPENED, lw=1.5, ls="--", label="door open"),
                *_bridge_badges(ax, np.array(badges).reshape(-1, 2), np.array(badge_order)),
                Line2D([], [], ls="", marker="o", markersize=8, markerfacecolor="#555555", markeredgecolor="black",
                       label=f"robot {when}")]


def _limits(values: np.ndarray) -> tuple[float, float]:
    """The range of `values` with matplotlib's default 5% margins."""
    lo, hi = float(np.min(values)), float(np.max(values))
    pad = 0.05 * (hi - lo) if hi > lo else 0.5
    return lo - pad, hi + pad


class CoffeeDrawer(Drawer):
    """The table from above: the machine with its button and dispense area, the cups (green once filled,
    with their liquid / target), the jug at its start and now (handle drawn), the robot's (x, y) path;
    below, the robot's height, tilt and wrist over time, shaded while the bridge acts."""

    figsize = (9.5, 9.5)
    world_rect = (0.03, 0.36, 0.62, 0.56)
    in_place = "twists the jug"
    Z, TILT, WRIST, JUG, ROT, FILLED, ON, LIQUID = 0, 1, 2, 4, 6, 8, 9, 10  # columns of `details`
    # The panel's curves: (column, on the right-hand axis, colour, width, style, label).
    CURVES = ((Z, False, "#37474f", 1.6, "-", "z (left)"), (TILT, True, "#8e24aa", 1.2, "-", "tilt (right)"),
              (WRIST, True, "#00897b", 1.2, "-", "wrist (right)"), (ROT, True, CLUTTER, 1.2, ":", "jug rot (right)"))

    def snapshot(self, env, state):
        return state.robot[:2], (jnp.abs(state.jug_rot) < coffee.PICK_JUG_ROT_TOL)[None]  # graspable

    def details(self, env, state):
        flags = jnp.stack([state.jug_held, state.jug_filled, state.machine_on]).astype(jnp.float32)
        return jnp.concatenate([state.robot[2:], state.jug_xy, state.jug_rot[None], flags, state.cup_liquid])

    def object_xy(self, env, trace, kind, slot, upto):
        return env.task_arrays(trace.spec).cup_xy[slot] if kind == "cup" else None

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

    def draw_background(self, ax, env, trace):
        ax.add_patch(Rectangle((0, 0), 10, 10, fc=ROOM, ec="#cccccc", zorder=0))
        ax.add_patch(Rectangle(coffee.MACHINE_XY, *coffee.MACHINE_SIZE[:2], fc="#9e9e9e", ec=WALL, zorder=1))
        ax.add_patch(Circle(coffee.DISPENSE[:2], np.sqrt(coffee.DISPENSE_TOL), fc="none", ec="#616161", ls="--",
                            zorder=1))
        ax.set_xlim(-0.1, 10.1)
        ax.set_ylim(-0.1, 10.1)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        return [Patch(fc="#9e9e9e", ec=WALL, label="coffee machine"),
                Line2D([], [], color="#616161", ls="--", label="dispense area (jug in machine)")]

    def draw_state(self, ax, env, trace, upto):
        upto, when = moment(trace, upto)
        task, now, start = env.task_arrays(trace.spec), trace.details[upto], trace.details[0]
        ax.add_patch(Circle(coffee.BUTTON[:2], 0.15, fc=OPENED if now[self.ON] > 0.5 else CLOSED, ec="black", lw=0.6,
                            zorder=2))
        filled_cup, empty_cup = "#81c784", "white"
        for c in np.flatnonzero(task.cup_mask):
            full = now[self.LIQUID + c] > task.cup_target[c]
            ax.add_patch(Circle(task.cup_xy[c], coffee.CUP_RADIUS, fc=filled_cup if full else empty_cup, ec="black",
                                lw=0.8, zorder=2))
            ax.text(task.cup_xy[c, 0], task.cup_xy[c, 1] - 0.45, f"cup{c}\n{now[self.LIQUID + c]:.2f}/"
                    f"{task.cup_target[c]:.2f}", ha="center", va="top", fontsize=7, zorder=2)
        self._jug(ax, start[self.JUG:self.JUG + 2], start[self.ROT], fc="none", ec=CLUTTER, ls="--", lw=1.2)
        self._jug(ax, now[self.JUG:self.JUG + 2], now[self.ROT], fc=CLUTTER if now[self.FILLED] > 0.5 else "white",
                  ec="black", lw=1.0, alpha=0.85)
        return [*_robot_marks(ax, trace, upto, when, 0.12),
                Line2D([], [], ls="", marker="o", color=OPENED, markeredgecolor="black",
                       label="button (green: machine on)"),
                Line2D([], [], ls="", marker="o", markersize=9, markerfacecolor="none", markeredgecolor=CLUTTER,
                       label="jug at the start (line: handle)"),
                Line2D([], [], ls="", marker="o", markersize=9, markerfacecolor=CLUTTER, markeredgecolor="black",
                       label=f"jug {when} (brown: filled)"),
                Patch(fc=filled_cup, ec="black", label="cup filled (liquid/target)"),
                Patch(fc=empty_cup, ec="black", label="cup not filled")]

    def draw_panels(self, fig, env, trace):
        height = fig.add_axes((0.08, 0.05, 0.57, 0.22))
        angles = height.twinx()
        height.set_xlim(0, max(trace.steps, 1))
        height.set_ylim(*_limits(trace.details[:, self.Z]))  # the whole episode's, whatever is drawn yet
        angles.set_ylim(*_limits(trace.details[:, [self.TILT, self.WRIST, self.ROT]]))
        height.set_xlabel("env step (shaded: bridge, CallPlanner)")
        height.set_ylabel("height")
        angles.set_ylabel("radians")
        keys = [Line2D([], [], color=colour, lw=lw, ls=ls, label=label) for _, _, colour, lw, ls, label in self.CURVES]
        height.legend(handles=keys, loc="upper left", bbox_to_anchor=(1.12, 1.0), fontsize=8, frameon=False)
        return [height, angles]

    def draw_panel_state(self, panels, env, trace, upto):
        (upto, _), (height, angles) = moment(trace, upto), panels
        for a, i, j in actor_segments(trace.actor[:upto]):
            if a != ACTOR_PLANNER:
                height.axvspan(i, j, color=ACTORS[a][1], alpha=0.25, lw=0)
        steps = np.arange(upto + 1)
        for column, right, colour, lw, ls, _ in self.CURVES:
            (angles if right else height).plot(steps, trace.details[: upto + 1, column], color=colour, lw=lw, ls=ls)
        if upto < trace.steps:
            height.axvline(upto, color="black", lw=0.8)


DRAWERS: dict[str, Drawer] = {"doorknobs": DoorknobsDrawer(), "light_switch_door": LightSwitchDoorDrawer(),
                              "coffee": CoffeeDrawer()}


def drawer_for(env: NoveltyEnv) -> Drawer:
    if env.name not in DRAWERS:
        raise ValueError(f"no episode drawer for env {env.name!r}; can draw: {', '.join(DRAWERS)}")
    return DRAWERS[env.name]
