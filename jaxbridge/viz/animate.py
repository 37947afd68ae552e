"""Animate one episode as a GIF: frame t shows the world after t steps as the env's `Drawer` draws it (the
path so far coloured by who was in control, the robot, the doors open then), captioned with the step, who
is in control and the ground skill it runs, e.g. "step 12/56 · bridge · OpenDoor(param 0.75)".

Long episodes keep at most `max_frames` frames, always the start, the end and the first frame of every
change of control (`frame_steps`), and those changes stay on screen longer so the captions can be read.
"""
from __future__ import annotations

import io
from collections.abc import Iterable, Iterator

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from PIL import Image

from envs_jax.base import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, NoveltyEnv
from envs_jax.drawing import ACTORS, EpisodeTrace
from jaxbridge.viz.episodes import object_type, skill_label
from jaxbridge.viz.render import EpisodeFigure

MAX_FRAMES = 120
FRAME_DPI = 84  # the drawers' figures (9.5 in wide) come out about 800 pixels wide
STEP_MS, CHANGE_MS, END_MS = 120, 900, 3000  # how long a frame shows: any step, a change of control, the end
CONTROLLER = {ACTOR_PLANNER: "planner", ACTOR_BRIDGE: "bridge", ACTOR_CALL_PLANNER: "CallPlanner"}


def frame_caption(env: NoveltyEnv, trace: EpisodeTrace, t: int) -> str:
    """What frame t (the world after t steps) says about step t, the one that led to it: the step, who was
    in control and the ground skill it ran. Frame 0 is the start."""
    if t == 0:
        return f"step 0/{trace.steps} · start"
    i = t - 1
    words = [f"step {t}/{trace.steps}", CONTROLLER[int(trace.actor[i])]]
    if trace.actor[i] != ACTOR_CALL_PLANNER and trace.skill is not None:  # CallPlanner runs no skill
        words.append(skill_label(env, int(trace.skill[i]), int(trace.slot[i]), float(trace.param[i])))
    return " · ".join(words)


def control_changes(actor: np.ndarray) -> np.ndarray:
    """int[]: the frames that first show a new actor in control (frame i + 1 shows step i)."""
    return np.flatnonzero(np.diff(np.asarray(actor))) + 2


def _spread(values: np.ndarray, count: int) -> np.ndarray:
    """`count` of the sorted `values`, evenly spread: the middle of each of `count` equal shares (all of
    them if they are fewer)."""
    if count >= len(values):
        return values
    return values[((2 * np.arange(count) + 1) * len(values)) // (2 * count)]


def frame_steps(actor: np.ndarray, max_frames: int = MAX_FRAMES) -> np.ndarray:
    """int[]: the frames kept of an episode with these actors, ascending (frame t: after t steps).

    Every frame if the episode has at most max_frames - 1 steps. Otherwise exactly max_frames: the start,
    the end and every change of control, the rest evenly spread over the other steps. Should the changes
    alone not fit, they are themselves evenly spread (the start and the end stay)."""
    if max_frames < 2:
        raise ValueError(f"max_frames must be at least 2 (the start and the end), got {max_frames}")
    steps = len(actor)
    if steps + 1 <= max_frames:
        return np.arange(steps + 1)
    ends = np.array([0, steps])
    kept = np.union1d(ends, control_changes(actor))
    if len(kept) > max_frames:
        kept = np.union1d(ends, _spread(np.setdiff1d(kept, ends), max_frames - 2))
    others = np.setdiff1d(np.arange(steps + 1), kept)
    return np.union1d(kept, _spread(others, max_frames - len(kept)))


def _caption_and_target(figure: EpisodeFigure, env: NoveltyEnv, trace: EpisodeTrace, t: int) -> list:
    """Frame t's caption, in the colour of who was in control, and a ring of that colour around the object
    the step's skill acted on (the door, cell or cup its caption names) where the picture shows it."""
    colour = ACTORS[int(trace.actor[t - 1])][1] if t > 0 else "black"
    artists = [figure.fig.text(0.02, 0.99, frame_caption(env, trace, t), ha="left", va="top", fontsize=13,
                               fontweight="bold", color=colour)]
    kind = None
    if t > 0 and trace.skill is not None and trace.actor[t - 1] != ACTOR_CALL_PLANNER:
        kind = object_type(env, int(trace.skill[t - 1]))
    if kind is not None:
        xy = figure.drawer.object_xy(env, trace, kind, int(trace.slot[t - 1]), t)
        if xy is not None:
            artists.append(figure.world.scatter(*xy, s=380, facecolors="none", edgecolors=colour, linewidths=2.2,
                                                zorder=6))
    return artists


def frame_pixels(env: NoveltyEnv, trace: EpisodeTrace, frames: Iterable[int], label: str = "") -> Iterator[np.ndarray]:
    """uint8[H, W, 3] for each frame t in `frames`: the world after t steps under the frame's caption, all
    of one size (the drawer's figure at FRAME_DPI, never cropped to its contents). The background is drawn
    once and each frame's state over a copy of it: redrawing every figure whole is about ten times slower."""
    figure = EpisodeFigure(env, trace, label, dpi=FRAME_DPI, animated=True)
    canvas = FigureCanvasAgg(figure.fig)
    canvas.draw()
    background, renderer = canvas.copy_from_bbox(figure.fig.bbox), canvas.get_renderer()
    for t in frames:
        canvas.restore_region(background)
        artists = figure.draw_state(t) + _caption_and_target(figure, env, trace, t)
        for artist in artists:
            artist.draw(renderer)
        yield np.asarray(canvas.buffer_rgba())[..., :3].copy()
        for artist in artists:
            artist.remove()


def render_gif(env: NoveltyEnv, trace: EpisodeTrace, label: str = "", max_frames: int = MAX_FRAMES) -> bytes:
    """GIF bytes of one episode, looping; `label` says whose bridge it is (e.g. "oracle bridge")."""
    frames = frame_steps(trace.actor, max_frames)
    pixels = list(frame_pixels(env, trace, frames.tolist(), label))
    # One palette for every frame, from a thinned sample of all of them (a colour may show in a few frames
    # only, e.g. the button before the machine is on), so colours neither flicker nor go missing.
    sample = Image.fromarray(np.concatenate([frame[::3, ::3] for frame in pixels]))
    palette = sample.quantize(colors=255, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    images = [Image.fromarray(frame).quantize(palette=palette, dither=Image.Dither.NONE) for frame in pixels]
    changes = set(control_changes(trace.actor).tolist())
    durations = [END_MS if t == trace.steps else CHANGE_MS if t in changes else STEP_MS for t in frames]
    buffer = io.BytesIO()
    images[0].save(buffer, format="GIF", save_all=True, append_images=images[1:], duration=durations, loop=0)
    return buffer.getvalue()
