"""How a Coffee episode looks: the table from above, and the arm's height, tilt and wrist over time."""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Rectangle

from envs_jax.coffee import world as coffee
from envs_jax.base import ACTOR_PLANNER
from envs_jax.drawing import ACTORS, CLOSED, CLUTTER, OPENED, ROOM, WALL, Drawer, actor_segments, moment, robot_marks


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
        if kind == "jug":
            return trace.details[upto, self.JUG:self.JUG + 2]
        if kind == "machine":
            return coffee.DISPENSE[:2]
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
        return [*robot_marks(ax, trace, upto, when, 0.12),
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


DRAWER = CoffeeDrawer()
