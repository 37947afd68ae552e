"""How a Multi Novelty episode looks: Light Switch Door's picture (the row across, time down, each door a
bar on its cell's right edge until it opens), with each keycard door's card marked where it lies."""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from envs_jax.light_switch_door.drawer import LightSwitchDoorDrawer

CARD = "#6a1b9a"


class MultiNoveltyDrawer(LightSwitchDoorDrawer):
    def object_xy(self, env, trace, kind, slot, upto):
        task = env.task_arrays(trace.spec)
        cell = {"cell": slot, "door": task.door_cell[slot] if kind == "door" else -1,
                "key": task.key_cell[slot] if kind == "key" else -1, "light": task.num_cells - 1}.get(kind, -1)
        return np.array([cell + 0.5, upto]) if cell >= 0 else None

    def draw_background(self, ax, env, trace):
        legend = super().draw_background(ax, env, trace)
        spec = trace.spec
        for door, key in zip(spec.door_cells, spec.key_cells):
            if key >= 0:  # the card at its cell's top, a thin line to the door it opens
                ax.plot([key + 0.5], [-0.3], marker="s", color=CARD, markersize=6, zorder=4)
                ax.plot([key + 0.5, door + 1.0], [-0.3, -0.3], color=CARD, lw=0.8, ls=":", zorder=3)
        if spec.fuse_blown:
            ax.text(spec.num_cells - 0.5, max(trace.steps, 1) / 2, "fuse blown at the start", ha="center", va="center",
                    rotation=90, fontsize=8, color="#b71c1c")
        return legend + [Line2D([], [], ls="", marker="s", color=CARD, label="a keycard door's card")]


DRAWER = MultiNoveltyDrawer()
