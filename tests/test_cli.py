"""The command lines: a short real training run, evaluating its checkpoint, and clean errors."""
import jaxbridge
import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from jaxbridge.core.config import CONFIG_VERSION
from run_helpers import cli_in_process, read_scalars

ROOT = Path(__file__).resolve().parents[1]


def run(*args, cwd=ROOT):
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    proc = run("train.py", "--num-seeds", "2", "--cycles", "3", "--updates-per-cycle", "10",
               "--checkpoint-every", "2", "--out", str(out), "--name", "tiny",
               "--approaches", "ours,pure_planning", "--preset", "authors", "--tensorboard")
    assert proc.returncode == 0, proc.stderr
    return out / "tiny", proc


def test_train_writes_the_experiment_directory(short_run):
    experiment_dir, proc = short_run
    assert json.loads((experiment_dir / "experiment.json").read_text())["approaches"] == ["ours", "pure_planning"]
    results = list(csv.DictReader((experiment_dir / "results.csv").open()))  # a row per approach and cycle
    assert [(r["approach"], r["cycle"]) for r in results] == [(a, str(c)) for a in ("ours", "pure_planning")
                                                              for c in (1, 2, 3)]
    assert all(r["seeds"] == "2" for r in results)
    planning = results[-1]  # pure planning never passes a door: every statistic is 0
    assert all(float(planning[f"test_solve_rate_{s}"]) == 0.0 for s in ("mean", "mean_low", "iqm_high", "max"))
    for r in results:
        assert float(r["test_solve_rate_mean_low"]) <= float(r["test_solve_rate_mean"]) <= float(r["test_solve_rate_mean_high"])
    table = (experiment_dir / "results.md").read_text()
    assert "over seeds 0-1" in table and "## Interquartile mean (IQM) [95% bootstrap CI]" in table
    assert table.count("| ours | 2 |") == 2  # mean and IQM tables
    assert table.count("| pure planning | 2 |  |  |  |  | 0.00 | 0.00 |") == 2  # no report cycle in 3 cycles
    assert (experiment_dir / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "pure_planning" in proc.stdout and "ours" in proc.stdout


def test_tensorboard_events_hold_each_cycles_statistics_and_the_config(short_run):
    """--tensorboard: per approach, an event file whose scalars are metrics.csv's per-cycle means."""
    run_dir = short_run[0] / "ours"
    rows = list(csv.DictReader((run_dir / "metrics.csv").open()))
    scalars = read_scalars(run_dir / "events")
    for field, tag in (("test_solve_rate", "test/solve_rate/mean"), ("epsilon", "learn/epsilon")):
        means = [sum(float(r[field]) for r in rows if r["cycle"] == str(c)) / 2 for c in (1, 2, 3)]
        assert [step for step, _ in scalars[tag]] == [1, 2, 3]
        assert [v for _, v in scalars[tag]] == pytest.approx(means, abs=1e-6)
    low, high = scalars["train/success_rate/mean_low"], scalars["train/success_rate/mean_high"]
    assert all(a[1] <= b[1] for a, b in zip(low, high))
    assert any(p.name.startswith("events.out.tfevents") for p in (short_run[0] / "pure_planning" / "events").iterdir())
    assert b"config" in next((run_dir / "events").glob("events.out.tfevents.*")).read_bytes()


def test_a_run_records_its_pace_once_compiled(short_run):
    """The pace a run leaves for start-up estimates: its compiling cycles apart from the seed-cycles after
    them (a short run's seconds are mostly compilation: the start line would promise hours for minutes)."""
    from jaxbridge.utils.pace import pace_file
    known = json.loads(pace_file().read_text())
    for approach in ("ours", "pure_planning"):
        measured = known[f"light_switch_door/{approach}"]
        assert 0 < measured["seed_cycle_s"] * 2 < measured["compile_s"]  # a compiled cycle of 2 seeds costs less


def test_progress_into_a_log_is_plain_lines(short_run):
    """stderr is a pipe here, as under nohup or a scheduler: one plain line per reported cycle, no bar frames."""
    lines = [line for line in short_run[1].stderr.splitlines() if " cycles (" in line]
    assert "\r" not in short_run[1].stderr and len(lines) == 6, short_run[1].stderr  # 2 approaches x 3 cycles
    assert lines[-1].startswith("light_switch_door x2 seeds, 2 approaches: 6/6 cycles (100%), ")
    # The time left from each approach's own pace: none before some approach's second cycle (its first
    # compiles); by the fourth cycle one of the two has had its second.
    assert "ETA" not in lines[0] and "ETA" in lines[3] and "test=" in lines[-1]


def test_train_writes_the_run_directory(short_run):
    run_dir, proc = short_run[0] / "ours", short_run[1]
    rows = list(csv.DictReader((run_dir / "metrics.csv").open()))
    assert len(rows) == 2 * 3 and {r["seed"] for r in rows} == {"0", "1"}
    assert {r["cycle"] for r in rows} == {"1", "2", "3"}
    solved = [float(r["test_solve_rate"]) * 10 for r in rows]  # a fraction of the seed's 10 test tasks
    assert all(n == round(n) and 0 <= n <= 10 for n in solved)
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["cycles"] == 3 and summary["seeds"] == [0, 1] and summary["seed_range"] == "0-1"
    final = summary["smooth_reward_final"]
    assert len(final["per_seed"]) == 2 and final["mean"] == pytest.approx(sum(final["per_seed"]) / 2, abs=1e-4)
    assert all(len(v) == 3 for v in summary["per_cycle"]["test_solve_rate"].values())
    config = json.loads((run_dir / "config.json").read_text())
    assert config["config_version"] == CONFIG_VERSION and config["num_seeds"] == 2 and config["approach"] == "ours"
    # --preset authors, resolved: the authors' values in every field they set (jaxbridge/core/presets.py)
    assert config["preset"] == "authors" and config["test_protocol"] == "authors"
    learner = config["learner"]  # the learner's settings, nested with its name
    assert (learner["name"], learner["batch_size"], config["n_sample"], learner["n_target_sample"], learner["polyak_per"],
            config["call_planner_bonus"], learner["updates_per_cycle"]) == ("dqn", 64, 100, 1, "decision", 0.5, 10)
    assert (run_dir / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in (run_dir / "checkpoints").iterdir() if p.name.isdigit()) == ["2", "3"]
    assert "done in" in proc.stdout


def test_eval_loads_the_checkpoint(short_run):
    run_dir = short_run[0]  # the experiment directory: eval.py picks its "ours" run
    proc = cli_in_process("eval.py", str(run_dir), "--num-tasks", "3")
    assert proc.returncode == 0, proc.stderr
    assert "checkpoint of cycle 3" in proc.stdout and "20 cells, 3 doors" not in proc.stdout
    lines = [line for line in proc.stdout.splitlines() if line.strip().startswith(("0 ", "1 "))]
    assert len(lines) == 2
    bigger = cli_in_process("eval.py", str(run_dir), "--task-size", "cells=25,doors=5", "--num-tasks", "2")
    assert bigger.returncode == 0, bigger.stderr
    assert "25 cells, 5 doors" in bigger.stdout


def test_eval_takes_a_runs_seeds_test_tasks_under_another_protocol(short_run):
    """The run trained with --preset authors (horizon 30); --test-protocol jaxbridge evaluates the same
    checkpoints on the same seeds' tasks under the paper's horizons, as train.py would have drawn them."""
    import jaxbridge
    from jaxbridge.core.tasks import evaluation_specs

    policy = jaxbridge.load(short_run[0])
    own, other = policy.tasks(), policy.tasks(test_protocol="jaxbridge")
    specs, _ = evaluation_specs(jaxbridge.load_env("light_switch_door"), [0, 1], 10, "jaxbridge")
    assert other.specs == specs and other.seeds.tolist() == own.seeds.tolist()
    assert other.arrays.horizons.tolist() == [s.horizon for s in specs]
    assert other.arrays.horizons.tolist() != own.arrays.horizons.tolist()  # seed 2's 32-step task aside, longer
    proc = cli_in_process("eval.py", str(short_run[0]), "--test-protocol", "jaxbridge")
    assert proc.returncode == 0, proc.stderr
    assert "test tasks (jaxbridge protocol)" in proc.stdout
    with pytest.raises(jaxbridge.InputError, match="test_protocol 'held_out': light_switch_door has jaxbridge"):
        policy.evaluate(test_protocol="held_out")
    refused = cli_in_process("eval.py", str(short_run[0]), "--test-protocol", "jaxbridge", "--task-size", "cells=25")
    assert refused.returncode == 2 and "does not combine with --sweep or --task-size" in refused.stderr


def all_row(text: str) -> list[str]:
    return next(line.split() for line in text.splitlines() if line.strip().startswith("all "))


def test_side_by_side_matches_the_two_single_evaluations(short_run, eval_main, capsys):
    experiment = short_run[0]
    singles = []
    for approach in ("ours", "pure_planning"):
        assert eval_main([str(experiment), "--approach", approach]) == 0
        row = all_row(capsys.readouterr().out)  # all, tasks, solve rate, mean steps, calls, stuck, decisions
        singles += [row[2], row[3], row[6]]
    assert eval_main([str(experiment / "ours"), str(experiment / "pure_planning")]) == 0
    out = capsys.readouterr().out
    both = all_row(out)[1:]
    assert [float(v) for v in both] == [float(v) for v in singles]
    assert float(singles[3]) == 0.0  # pure planning never passes a door
    seed_rows = [line.split() for line in out.splitlines() if line.strip()[:2] in ("0 ", "1 ")]
    assert len(seed_rows) == 2 and all(len(row) == 7 for row in seed_rows)


def test_sweep_of_an_experiment_has_a_line_per_approach(short_run, eval_main, capsys, tmp_path):
    argv = [str(short_run[0]), "--sweep", "novelties", "--sweep-tasks", "1", "--sweep-out", str(tmp_path)]
    assert eval_main(argv) == 0
    table = (tmp_path / "sweep_novelties.md").read_text()
    assert "| doors | ours | pure planning |" in table
    assert table[table.index("| doors"):] in capsys.readouterr().out  # the same table printed
    rows = [line for line in table.splitlines() if line[:2] == "| " and line[2].isdigit()]
    assert [int(r.split("|")[1]) for r in rows] == list(range(1, 17))
    assert all(r.split("|")[3].strip() == "0.00" for r in rows)  # pure planning: no door passed
    lines = list(csv.DictReader((tmp_path / "sweep_novelties.csv").open()))
    assert len(lines) == 2 * 2 * 16 and {r["line"] for r in lines} == {"ours", "pure planning"}
    assert (tmp_path / "sweep_novelties.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_eval_animates_the_episode_to_a_gif(short_run, eval_main, capsys, tmp_path):
    from PIL import Image

    assert eval_main([str(short_run[0]), "--gif", str(tmp_path / "e.gif"), "--render-task", "1"]) == 0
    assert "drew seed 0, task 1" in capsys.readouterr().out
    with Image.open(tmp_path / "e.gif") as gif:
        assert gif.format == "GIF" and gif.n_frames > 2


@pytest.mark.parametrize("argv, message", [
    (["a", "b", "c"], "give one RUN, or two to compare side by side; got 3"),
    (["--sweep", "novelties"], "--sweep evaluates trained runs"),
    (["--sweep-out", "."], "--sweep-out goes with --sweep"),
    (["RUN", "--sweep-tasks", "3"], "--sweep-tasks goes with --sweep"),
    (["RUN", "--sweep", "novelties", "--gif", "e.gif"], "does not combine with --render/--gif"),
    (["RUN", "RUN", "--render", "e.png"], "draw an episode of one run; give one RUN"),
    (["RUN", "--sweep", "novelties", "--approach", "random"], "holds no random run (it holds: ours, pure_planning)"),
    (["RUN", "--approach", "../ours"], "a run name inside the experiment directory, not a path"),
])
def test_eval_rejects_bad_combinations_in_one_line(short_run, eval_main, capsys, argv, message):
    from jaxbridge.utils.cli import run_main
    argv = [str(short_run[0]) if a == "RUN" else a for a in argv]
    assert run_main(eval_main, argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and message in err and err.count("\n") == 1


def test_an_existing_run_is_not_overwritten(short_run):
    run_dir = short_run[0]
    proc = cli_in_process("train.py", "--cycles", "1", "--out", str(run_dir.parent), "--name", "tiny", "--no-progress")
    assert proc.returncode == 2 and "already exists" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("args,message", [
    (["train.py", "--env", "nowhere"], "unknown env 'nowhere'"),
    (["train.py", "--num-seeds", "0"], "positive integer"),
    (["train.py", "--cycles", "-3"], "positive integer"),
    (["train.py", "--approaches", "ours,clever"], "unknown approach clever"),
    (["train.py", "--approaches", "ours,ours"], "listed twice"),
    (["train.py", "--train-steps", "5"], "--train-steps 5 is too small to ever reach the goal: seed 0's"),
    (["train.py", "--env", "doorknobs", "--first-seed", "1", "--num-seeds", "3", "--train-steps", "11"],
     "seed 2's training task needs at least 12 steps"),
    (["train.py", "--num-seeds", "3", "--seed-block", "4"], "--seed-block 4 is larger than the 3 seeds"),
    (["train.py", "--seed-block", "0"], "positive integer"),
    (["train.py", "--preset", "theirs"], "unknown preset 'theirs'; choose from jaxbridge, authors, pqn"),
    (["train.py", "--env", "doorknobs", "--env-quirks", "raw_offsets,bogus"], "has no quirk 'bogus' (its quirks: raw_offsets"),
    (["train.py", "--env", "doorknobs", "--test-protocol", "authors"], "--test-protocol 'authors': doorknobs has jaxbridge"),
    (["eval.py", "--env", "doorknobs", "--test-protocol", "authors"], "--test-protocol 'authors': doorknobs has jaxbridge"),
    (["eval.py", "--bridge", "clever"], "invalid choice"),
    (["eval.py", "/nonexistent/run"], "not a run directory"),
    (["eval.py", "--num-seeds", "x"], "positive integer"),
])
def test_bad_input_is_one_clear_line_and_exit_code_2(args, message):
    proc = cli_in_process(*args)
    assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr


def test_eval_hand_made_bridges():
    proc = cli_in_process("eval.py", "--bridge", "oracle", "--num-seeds", "2")
    assert proc.returncode == 0, proc.stderr
    last = proc.stdout.strip().splitlines()[-1].split()
    assert last[0] == "all" and float(last[2]) == 1.0  # every task solved


def test_eval_hand_made_bridges_meet_the_test_tasks_train_py_would():
    """Coffee trains on the authors' 4-cup tasks by default; eval.py --bridge evaluates those too, and
    names the protocol only when it is another one."""
    default = cli_in_process("eval.py", "--env", "coffee", "--bridge", "oracle", "--num-seeds", "1")
    variant = cli_in_process("eval.py", "--env", "coffee", "--bridge", "oracle", "--num-seeds", "1", "--test-protocol", "jaxbridge")
    assert default.returncode == variant.returncode == 0, default.stderr + variant.stderr
    sizes = lambda proc: {" ".join(line.split()[1:3]) for line in proc.stdout.splitlines() if line.split()[:1] == ["0"]}
    assert sizes(default) == {"4 cups"} and "protocol" not in default.stdout.splitlines()[0]
    assert "jaxbridge protocol" in variant.stdout.splitlines()[0]


def test_train_runs_the_papers_figure_by_default_and_says_what_it_leaves_out(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXBRIDGE_CACHE_DIR", str(tmp_path / "jax"))  # a machine that has trained nothing
    from envs_jax import env_class
    from jaxbridge.api.training import _start_line as start_line, default_approaches

    doorknobs = env_class("doorknobs")
    approaches = default_approaches(doorknobs)  # the paper's Doorknobs figure: no feature selection timed out
    assert approaches == ["ours", "no_callplanner", "random", "pure_planning", "maple_q"]
    line = start_line(jaxbridge.make_config("doorknobs"), doorknobs, approaches, None)
    assert line.startswith("doorknobs: training ours, no CallPlanner, random bridge, pure planning, Maple Q (pure RL) x 8 seeds")
    assert "not no feature selection" in line and "--approaches all adds it" in line
    assert default_approaches(env_class("coffee")) == ["ours", "no_feature_selection", "no_callplanner", "random",
                                                       "pure_planning", "maple_q"]
    assert "not " not in start_line(jaxbridge.make_config("coffee"), env_class("coffee"), ["ours"], None)
    multi = env_class("multi_novelty")  # its default: the question's approaches, the full-state ones with `all`
    mine = start_line(jaxbridge.make_config("multi_novelty"), multi, default_approaches(multi), None)
    assert "a bridge per signature" in mine and "not no feature selection, Maple Q (pure RL)" in mine
    assert "no time estimate until this machine has trained each of them once" in line


def test_the_start_line_estimates_from_this_machines_own_pace(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXBRIDGE_CACHE_DIR", str(tmp_path / "jax"))
    from envs_jax import env_class
    from jaxbridge.api.training import _start_line as start_line
    from jaxbridge.utils import pace

    at = lambda seed_cycle_s, compile_s: {"seed_cycle_s": seed_cycle_s, "compile_s": compile_s}
    pace.record("coffee", {"ours": at(0.15, 20), "random": at(0.03, 10)})  # measured here
    pace.record("coffee", {"maple_q": at(0.3, 30)})  # a later run adds to what is known
    config, coffee = jaxbridge.make_config("coffee", num_seeds=8), env_class("coffee")
    assert pace.estimate("coffee", ["ours", "random", "maple_q"], 800, workers=2) == 30 + 0.3 * 800  # the longest
    assert pace.estimate("coffee", ["ours", "random"], 800, workers=1) == 20 + 10 + (0.15 + 0.03) * 800
    assert pace.estimate("coffee", ["ours", "no_callplanner"], 800, workers=2) is None  # never trained here
    assert start_line(config, coffee, ["ours", "maple_q"], 2).endswith("; about 4 min at this machine's measured pace")
