"""How a Doorknobs episode looks: the room map from above."""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Arc, Patch, Polygon, Rectangle

from envs_jax import geometry
from envs_jax.doorknobs.maps import ROBOT_RADIUS
from envs_jax.drawing import (CLOSED, CLUTTER, GOAL_ROOM, OPENED, ROOM, START_ROOM, WALL, Drawer, bridge_badges,
                              bridge_order, moment, robot_marks)


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
        task, now, order = env.task_arrays(trace.spec), trace.open[upto], bridge_order(trace, upto)
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
                *bridge_badges(ax, np.array(badges).reshape(-1, 2), np.array(badge_order)),
                *robot_marks(ax, trace, upto, when, ROBOT_RADIUS)]


CLOSET = "#7e57c2"


class DoorknobsDistractorDrawer(DoorknobsDrawer):
    """Doorknobs' picture with each closet (inert: drawn once) as a hatched strip on its wall's face and
    its knob as a dot; door slot d + D of the object view is door slot d's closet."""

    def object_xy(self, env, trace, kind, slot, upto):
        task = env.task_arrays(trace.spec)
        doors = task.door_mask.shape[0]
        if kind == "door" and slot >= doors:
            return task.closet_knob[slot - doors]
        return super().object_xy(env, trace, kind, slot, upto)

    def draw_background(self, ax, env, trace):
        handles = super().draw_background(ax, env, trace)
        task = env.task_arrays(trace.spec)
        for d in np.flatnonzero(task.closet_mask):
            ax.plot(*task.closet_door[d].T, color=CLOSET, lw=4.0, solid_capstyle="butt", zorder=3)
            ax.plot(*task.closet_door[d].T, color="white", lw=4.0, ls=(0, (1, 1)), solid_capstyle="butt", zorder=3)
            ax.scatter(*task.closet_knob[d], s=14, color=CLOSET, edgecolor="black", lw=0.4, zorder=4)
        return handles + [Line2D([], [], color=CLOSET, lw=4, marker="o", markevery=[0], markersize=4,
                                 label="closet door and knob (leads nowhere)")]


DRAWER = DoorknobsDrawer()
DISTRACTOR_DRAWER = DoorknobsDistractorDrawer()
