"""Episode rendering: path segments by actor, doors opened by the bridge, the re-run being the evaluated
episode, a valid PNG, and eval.py's --render flags."""
import importlib.util
import io
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from matplotlib.figure import Figure

from envs_jax.coffee import Coffee
from envs_jax.doorknobs import Doorknobs
from jaxbridge.bridges import make_bridge
from jaxbridge.evaluate import run_bridge
from jaxbridge.meta_policy import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER
from jaxbridge.render import (
    ACTORS,
    EpisodeTrace,
    actor_segments,
    draw_path,
    drawer_for,
    pick_episode,
    render_episode,
    trace_episodes,
)
from jaxbridge.tasks import make_batch

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


def test_coffee_oracle_episode_shows_the_bridge_twisting_the_jug_and_renders():
    spec = Coffee.test_tasks(0)[1]  # 3 cups
    batch = make_batch(Coffee, [spec], [0])
    bridge = make_bridge("oracle", batch.env)
    result = run_bridge(batch, bridge, seed=0)
    t = trace_episodes(batch, bridge, None, [0], seed=0, expected=result)[0]
    assert t.success and t.details.shape == (t.steps + 1, 10 + batch.env.max_cups)
    # The jug turns graspable on a bridge step (TwistJug), which twists in place.
    assert not t.open[0, 0] and t.opened_by_bridge.tolist() == [True]
    twist = t.opened_at[0]
    np.testing.assert_allclose(t.xy[twist + 1], t.xy[twist])
    assert drawer_for(batch.env).bridge_summary(t) == "the bridge twisted the jug from rot 1.50 to 0.00"
    liquid = t.details[-1, 10:13]  # every cup ends above its target
    assert np.all(liquid > 0.75 * np.array([c[2] for c in spec.cups]))
    png = render_episode(batch.env, t, "oracle bridge")
    image = matplotlib.image.imread(io.BytesIO(png), format="png")
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and image.shape[0] > 800 and image.shape[1] > 600 and image.std() > 0.05


@pytest.fixture(scope="module")
def eval_main():
    spec = importlib.util.spec_from_file_location("eval_cli", ROOT / "eval.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main


@pytest.mark.parametrize("argv, message", [
    (["--render-task", "3"], "--render-task picks the episode that --render draws"),
    (["--render", "episode.jpg"], "give a path ending in .png"),
    (["--render", "no/such/dir/episode.png"], "directory no/such/dir does not exist"),
    (["--env", "doorknobs", "--num-seeds", "1", "--num-tasks", "2", "--render", "e.png", "--render-task", "2"],
     "--render-task must be below 2"),
])
def test_eval_render_flags_reject_bad_values_in_one_line(eval_main, capsys, argv, message):
    from jaxbridge.cli import run_main
    assert run_main(eval_main, argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and message in err and err.count("\n") == 1
