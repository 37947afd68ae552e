"""How a Light Switch Door episode looks: the row of cells over time."""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle

from envs_jax.drawing import CLOSED, GOAL_ROOM, OPENED, ROOM, Drawer, bridge_badges, bridge_order, moment


class LightSwitchDoorDrawer(Drawer):
    """The row of cells across, time down: the robot's cell at every step, each door a bar on its cell's
    right edge (where it blocks) that turns from closed to open at the step it opened."""

    figsize = (9.5, 6.0)

    def snapshot(self, env, state):
        return jnp.stack([state.robot_x, jnp.float32(0.0)]), env.door_open(state)

    def path(self, trace):
        return np.stack([trace.xy[:, 0], np.arange(trace.steps + 1)], axis=-1)

    def object_xy(self, env, trace, kind, slot, upto):
        if kind == "cell":
            return np.array([slot + 0.5, upto])
        task = env.task_arrays(trace.spec)
        if kind == "door":  # where its keys turn, as the object view places it
            return np.array([task.keys_cell[slot] + 0.5, upto])
        return np.array([task.num_cells - 0.5, upto]) if kind == "light" else None

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
        order, opened_at = bridge_order(trace, upto), trace.opened_at
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
                *bridge_badges(ax, np.array(badges).reshape(-1, 2), np.array(badge_order)),
                Line2D([], [], ls="", marker="o", markersize=8, markerfacecolor="#555555", markeredgecolor="black",
                       label=f"robot {when}")]


DRAWER = LightSwitchDoorDrawer()
