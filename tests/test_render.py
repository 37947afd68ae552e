"""Episode rendering: path segments by actor, doors opened by the bridge, the re-run being the evaluated
episode, the ground skills it records, a valid PNG, eval.py's --render flags; and animation: frame
captions, which frames are kept, and for each env a GIF of an oracle episode whose frames are all there,
all of one size, not blank, and move with the robot (one file, so the episodes compile once)."""
import io
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from envs_jax.coffee.env import Coffee
from envs_jax.doorknobs.env import Doorknobs
from envs_jax.light_switch_door.env import LightSwitchDoor
from jaxbridge.viz.animate import (
    FRAME_DPI,
    _caption_and_target,
    control_changes,
    frame_caption,
    frame_pixels,
    frame_steps,
    render_gif,
)
from jaxbridge.core.bridges import make_bridge
from envs_jax.base import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER
from envs_jax.drawing import ACTORS, EpisodeTrace, actor_segments, draw_path
from jaxbridge.run.evaluate import run_bridge
from jaxbridge.viz.episodes import bridge_choices, pick_episode, skill_label
from jaxbridge.viz.render import EpisodeFigure, drawer_for, render_episode, trace_episodes
from jaxbridge.core.tasks import make_batch

P, B, C = ACTOR_PLANNER, ACTOR_BRIDGE, ACTOR_CALL_PLANNER
ROOT = Path(__file__).resolve().parents[1]


def trace(actor, opens, success=True, xy=None):
    """A hand-made trace: opens[d] = step on which door d opens (-1: never)."""
    steps = len(actor)
    opened = np.array([[0 <= at < t for at in opens] for t in range(steps + 1)], bool).reshape(steps + 1, len(opens))
    xy = np.zeros((steps + 1, 2), np.float32) if xy is None else np.asarray(xy, np.float32)
    return EpisodeTrace(spec=None, seed=0, task=0, success=success, bridge_decisions=0,
                        actor=np.asarray(actor, np.int32), xy=xy, open=opened)


def test_actor_segments_are_maximal_runs_sharing_their_end_points():
    assert actor_segments(np.array([P, P, B, C, P, P])) == [(P, 0, 2), (B, 2, 3), (C, 3, 4), (P, 4, 6)]
    assert actor_segments(np.array([B])) == [(B, 0, 1)]
    assert actor_segments(np.array([], np.int32)) == []


def test_drawn_path_is_coloured_by_actor_with_markers_for_acting_in_place():
    xy = [(0, 0), (1, 0), (1, 0), (1, 0), (2, 0), (2, 1)]  # the bridge and CallPlanner act on the spot
    actor = np.array([P, B, C, B, P])
    ax = Figure().add_subplot()
    handles = draw_path(ax, np.asarray(xy, float), actor)
    drawn = [(line.get_color(), line.get_xydata().tolist()) for line in ax.lines]
    assert drawn == [(ACTORS[P][1], [[0, 0], [1, 0]]), (ACTORS[B][1], [[1, 0], [1, 0]]),
                     (ACTORS[C][1], [[1, 0], [1, 0]]), (ACTORS[B][1], [[1, 0], [2, 0]]),
                     (ACTORS[P][1], [[2, 0], [2, 1]])]
    markers = [c.get_offsets().tolist() for c in ax.collections]
    assert markers == [[[1, 0]], [[1, 0]]]  # the bridge's in-place step, then CallPlanner
    assert [h.get_label() for h in handles] == ["path: planner in control", "path: bridge in control",
                                                "bridge acts in place (turns a knob)", "bridge calls CallPlanner"]


def test_doors_opened_by_the_bridge_and_the_default_pick():
    t = trace([P, B, C, B, P, P], opens=[1, -1, 3])
    assert t.opened_at.tolist() == [1, -1, 3] and t.opened_by_bridge.tolist() == [True, False, True]
    assert trace([P, P], opens=[0]).opened_by_bridge.tolist() == [False]  # opened on a planner step
    assert trace([], opens=[-1]).opened_by_bridge.tolist() == [False]
    one, two, two_again = trace([B], [0]), trace([B, B], [0, 1]), trace([B, B], [1, 0])
    assert pick_episode([one, two, two_again]) is two
    unsolved = trace([B, B, B], [0, 1, 2], success=False)
    assert pick_episode([unsolved, one]) is one and pick_episode([unsolved]) is unsolved


@pytest.fixture(scope="module")
def oracle_episode():
    """Seed 0's test task 6 (3 doors to the goal), evaluated with the oracle bridge, then re-run recorded."""
    spec = Doorknobs.test_tasks(0)[6]
    batch = make_batch(Doorknobs, [spec], [0])
    bridge = make_bridge("oracle", batch.env)
    result = run_bridge(batch, bridge, seed=0)
    return batch, bridge, result, trace_episodes(batch, bridge, None, [0], seed=0, expected=result)[0]


def test_oracle_episode_reports_the_doors_the_bridge_opened(oracle_episode):
    batch, _, result, t = oracle_episode
    assert t.success and t.steps == result.steps[0] and t.spec.doors_to_goal == 3
    assert not t.open[0].any()
    # Every door open at the end was opened by the bridge: one per stuck event, one per door on the way.
    np.testing.assert_array_equal(t.opened_by_bridge, t.open[-1])
    assert t.opened_by_bridge.sum() == result.stuck_events[0] == 3
    # The oracle turns a knob (one bridge step, in place) and calls CallPlanner (one step) per door.
    assert (t.actor == B).sum() == (t.actor == C).sum() == 3
    assert np.all(t.xy[1:][t.actor != P] == t.xy[:-1][t.actor != P])
    np.testing.assert_allclose(t.xy[0], batch.specs[0].robot)


def test_rerun_that_is_not_the_evaluated_episode_is_refused(oracle_episode):
    batch, bridge, result, _ = oracle_episode
    with pytest.raises(RuntimeError, match="steps"):
        trace_episodes(batch, bridge, None, [0], seed=0, expected=result.replace(steps=result.steps + 1))


def test_rendered_png_is_a_valid_image(oracle_episode):
    batch, _, _, t = oracle_episode
    png = render_episode(batch.env, t, "oracle bridge")
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    image = matplotlib.image.imread(io.BytesIO(png), format="png")
    assert image.shape[0] > 400 and image.shape[1] > 600 and image.std() > 0.05


@pytest.fixture(scope="module")
def coffee_episode():
    """Seed 0's test task 1 (3 cups), evaluated with the oracle bridge, then re-run recorded."""
    batch = make_batch(Coffee, [Coffee.test_tasks(0)[1]], [0])
    bridge = make_bridge("oracle", batch.env)
    result = run_bridge(batch, bridge, seed=0)
    return batch, bridge, result, trace_episodes(batch, bridge, None, [0], seed=0, expected=result)[0]


@pytest.fixture(scope="module")
def light_switch_door_episode():
    """Seed 0's test task 0 (11 cells, 3 doors) with the oracle bridge, recorded (not evaluated first)."""
    batch = make_batch(LightSwitchDoor, [LightSwitchDoor.test_tasks(0)[0]], [0])
    bridge = make_bridge("oracle", batch.env)
    return batch, bridge, None, trace_episodes(batch, bridge, None, [0], seed=0)[0]


def test_coffee_oracle_episode_shows_the_bridge_twisting_the_jug_and_renders(coffee_episode):
    batch, _, _, t = coffee_episode
    spec = batch.specs[0]
    assert t.success and t.details.shape == (t.steps + 1, 10 + batch.env.max_cups)
    # The jug turns graspable on a bridge step (TwistJug), which twists in place.
    assert not t.open[0, 0] and t.opened_by_bridge.tolist() == [True]
    twist = t.opened_at[0]
    np.testing.assert_allclose(t.xy[twist + 1], t.xy[twist])
    assert drawer_for(batch.env).bridge_summary(t) == "the bridge twisted the jug from rot 1.50 to 0.88"
    liquid = t.details[-1, 10:13]  # every cup ends above its target
    assert np.all(liquid > 0.75 * np.array([c[2] for c in spec.cups]))
    png = render_episode(batch.env, t, "oracle bridge")
    image = matplotlib.image.imread(io.BytesIO(png), format="png")
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and image.shape[0] > 800 and image.shape[1] > 600 and image.std() > 0.05


@pytest.mark.parametrize("argv, message", [
    (["--render-task", "3"], "--render-task picks the episode that --render/--gif draw"),
    (["--render", "episode.jpg"], "give a path ending in .png"),
    (["--gif", "episode.png"], "--gif writes a GIF image: give a path ending in .gif"),
    (["--render", "no/such/dir/episode.png"], "directory no/such/dir does not exist"),
    (["--env", "doorknobs", "--num-seeds", "1", "--num-tasks", "2", "--render", "e.png", "--render-task", "2"],
     "--render-task must be below 2"),
])
def test_eval_render_flags_reject_bad_values_in_one_line(eval_main, capsys, argv, message):
    from jaxbridge.utils.cli import run_main
    assert run_main(eval_main, argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and message in err and err.count("\n") == 1


# ---- the recorded skills, in words ------------------------------------------------------------------
EPISODES = {"light_switch_door": "light_switch_door_episode", "doorknobs": "oracle_episode",
            "coffee": "coffee_episode"}


def env_and_trace(request, name):
    batch, _, _, t = request.getfixturevalue(EPISODES[name])
    return batch.env, t


def test_traces_record_the_ground_skill_of_every_step(light_switch_door_episode):
    batch, _, _, t = light_switch_door_episode
    env = batch.env
    assert t.skill.shape == t.slot.shape == t.param.shape == t.decided.shape == (t.steps,)
    np.testing.assert_array_equal(t.skill == env.num_skills, t.actor == C)  # num_skills is CallPlanner
    assert t.decided.sum() == t.bridge_decisions and np.all(t.actor[t.decided] != P)
    # The planner's MoveRobot steps end in the cell they name (the slot), unless a closed door blocks them.
    moves = (t.actor == P) & (t.skill == env.skill_index("MoveRobot")) & (t.xy[1:, 0] != t.xy[:-1, 0])
    np.testing.assert_allclose(t.xy[1:, 0][moves], t.slot[moves] + 0.5)
    # The oracle per door: MoveKey, TurnKey on the robot's cell, then CallPlanner.
    choices = bridge_choices(env, t)
    assert [label.split("(")[0] for _, label in choices] == ["MoveKey", "TurnKey", "CallPlanner"] * 3
    step, label = choices[0]
    assert t.actor[step - 1] == B and label.startswith(f"MoveKey(cell {int(t.xy[step - 1, 0])}, param ")


def test_skill_labels_name_the_object_and_only_a_sampled_param():
    lsd, doorknobs, coffee = LightSwitchDoor(), Doorknobs(), Coffee()
    assert skill_label(lsd, lsd.skill_index("TurnKey"), 2, 0.7512) == "TurnKey(cell 2, param 0.75)"
    assert skill_label(lsd, lsd.skill_index("TurnOnLight"), 10, 0.75) == "TurnOnLight(cell 10)"  # a constant
    assert skill_label(doorknobs, doorknobs.skill_index("MoveToDoor"), 5, 0.0) == "MoveToDoor(door 5)"
    # OpenDoor turns whatever knob the robot touches: no door of its own.
    assert skill_label(doorknobs, doorknobs.skill_index("OpenDoor"), 5, -0.71) == "OpenDoor(param -0.71)"
    assert skill_label(coffee, coffee.skill_index("Pour"), 1, 0.0) == "Pour(cup 1)"
    assert skill_label(coffee, coffee.skill_index("PickJug"), 0, 0.0) == "PickJug"
    assert skill_label(coffee, coffee.num_skills, 3, 0.4) == "CallPlanner"


def test_frame_captions_say_the_step_who_is_in_control_and_the_skill():
    env = Doorknobs()
    to_door, open_door, through = (env.skill_index(n) for n in ("MoveToDoor", "OpenDoor", "MoveThroughDoor"))
    t = EpisodeTrace(spec=None, seed=0, task=0, success=True, bridge_decisions=2, actor=np.array([P, P, B, C, P]),
                     xy=np.zeros((6, 2)), open=np.zeros((6, 1), bool),
                     skill=np.array([to_door, through, open_door, env.num_skills, to_door]),
                     slot=np.array([5, 5, 0, 0, 14]), param=np.array([0.0, 0.0, 0.71, 0.71, 0.0], np.float32))
    assert [frame_caption(env, t, k) for k in range(6)] == [
        "step 0/5 · start", "step 1/5 · planner · MoveToDoor(door 5)",
        "step 2/5 · planner · MoveThroughDoor(door 5)", "step 3/5 · bridge · OpenDoor(param 0.71)",
        "step 4/5 · CallPlanner", "step 5/5 · planner · MoveToDoor(door 14)"]
    # A trace without skills (made by hand) still says who was in control.
    assert frame_caption(env, trace([P, B, C], opens=[]), 2) == "step 2/3 · bridge"


def test_frame_captions_of_a_real_episode(oracle_episode):
    batch, _, _, t = oracle_episode
    turn = int(np.flatnonzero(t.actor == B)[0])  # the oracle turns the knob it touches to its target
    assert frame_caption(batch.env, t, turn + 1) == f"step {turn + 1}/{t.steps} · bridge · OpenDoor(param 0.75)"
    assert frame_caption(batch.env, t, turn + 2) == f"step {turn + 2}/{t.steps} · CallPlanner"
    assert frame_caption(batch.env, t, turn).startswith(f"step {turn}/{t.steps} · planner · MoveThroughDoor(door ")


def test_still_picture_lists_the_bridges_choices_and_animated_legend_says_now(light_switch_door_episode):
    batch, _, _, t = light_switch_door_episode
    legend = lambda figure: [text.get_text() for text in figure.world.get_legend().get_texts()]
    still = EpisodeFigure(batch.env, t, "oracle bridge")
    still.draw_state()
    texts = legend(still)
    assert texts[texts.index("the bridge chose:") + 1:] == [f"step {k}: {s}" for k, s in bridge_choices(batch.env, t)]
    assert "robot at the end" in texts and "robot now" not in texts
    # An animation draws the whole episode's legend once, saying "now".
    animated = EpisodeFigure(batch.env, t, "oracle bridge", animated=True)
    assert legend(animated) == [text.replace("at the end", "now") for text in texts]


# ---- which frames an animation keeps --------------------------------------------------------------
def test_short_episodes_keep_every_frame():
    np.testing.assert_array_equal(frame_steps(np.array([P, B, C, P]), max_frames=5), np.arange(5))
    np.testing.assert_array_equal(frame_steps(np.array([], np.int32)), [0])


def test_long_episodes_keep_the_ends_and_every_change_of_control_then_spread_the_rest():
    actor = np.array([P] * 10 + [B] * 2 + [C] + [P] * 10)  # control changes on steps 10, 12, 13 (from 0)
    np.testing.assert_array_equal(control_changes(actor), [11, 13, 14])  # frame i + 1 shows step i
    np.testing.assert_array_equal(frame_steps(actor, max_frames=8), [0, 4, 10, 11, 13, 14, 19, 23])
    rng = np.random.default_rng(0)
    for _ in range(200):
        steps, max_frames = int(rng.integers(0, 300)), int(rng.integers(2, 130))
        actor = np.repeat(rng.integers(0, 3, size=steps), rng.integers(1, 30, size=steps))[:steps]
        frames = frame_steps(actor, max_frames)
        assert len(frames) == min(steps + 1, max_frames) and np.all(np.diff(frames) > 0)
        assert frames[0] == 0 and frames[-1] == steps
        if len(control_changes(actor)) + 2 <= max_frames:
            assert set(control_changes(actor)) <= set(frames)
    with pytest.raises(ValueError, match="at least 2"):
        frame_steps(np.array([P, P]), max_frames=1)


def test_when_the_changes_alone_do_not_fit_they_are_spread_too():
    actor = np.array([P, B] * 50)  # 99 changes of control
    frames = frame_steps(actor, max_frames=12)
    assert len(frames) == 12 and frames[0] == 0 and frames[-1] == 100
    assert set(frames[1:-1]) <= set(control_changes(actor)) and np.diff(frames[1:-1]).max() <= 10


# ---- the animation --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(EPISODES))
def test_gif_of_an_oracle_episode(request, name):
    env, t = env_and_trace(request, name)
    max_frames = 30  # fewer than the episodes' steps but Light Switch Door's: subsampled where it must be
    gif = render_gif(env, t, "oracle bridge", max_frames=max_frames)
    image = Image.open(io.BytesIO(gif))
    frames = frame_steps(t.actor, max_frames)
    assert image.format == "GIF" and image.n_frames == len(frames) == min(t.steps + 1, max_frames)
    width, height = (round(inches * FRAME_DPI) for inches in drawer_for(env).figsize)
    pixels = []
    for k in range(image.n_frames):
        image.seek(k)
        frame = image.convert("RGB")
        assert frame.size == (width, height)
        pixels.append(np.asarray(frame, np.int16))
        assert pixels[-1].std() > 10  # not blank
    # The world's part of consecutive frames differs wherever the robot moved in between (visibly: Coffee's
    # robot may drift by a rounding error; Light Switch Door's moves down the time axis every step).
    x0, y0, w, h = drawer_for(env).world_rect
    world = np.s_[round((1 - y0 - h) * height): round((1 - y0) * height), round(x0 * width): round((x0 + w) * width)]
    path = drawer_for(env).path(t)
    for k in range(1, len(frames)):
        if np.abs(path[frames[k]] - path[frames[k - 1]]).max() > 0.05:
            assert np.any(pixels[k][world] != pixels[k - 1][world]), f"frame {k} (step {frames[k]})"
    assert np.any(pixels[-1][world] != pixels[0][world])


def test_frames_drawn_over_the_background_are_the_whole_figure(oracle_episode):
    batch, _, _, t = oracle_episode
    steps = [t.steps // 2, t.steps]
    for k, blitted in zip(steps, frame_pixels(batch.env, t, steps, "oracle bridge")):
        figure = EpisodeFigure(batch.env, t, "oracle bridge", dpi=FRAME_DPI, animated=True)
        figure.draw_state(k)
        _caption_and_target(figure, batch.env, t, k)
        canvas = FigureCanvasAgg(figure.fig)
        canvas.draw()
        np.testing.assert_array_equal(np.asarray(canvas.buffer_rgba())[..., :3], blitted)
