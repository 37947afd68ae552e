"""The Python API (jaxbridge/api.py): make_train is train.py's run as one jitted (and vmapped) function, and
docs/API.md covers every public name (tests/test_quickstart.py: train, load, evaluate, render)."""
import csv
import dataclasses
import io
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxbridge
from jaxbridge.run.artifacts import metrics_csv
from run_helpers import train as train_cli

ROOT = Path(__file__).resolve().parents[1]
RATES = ("0.001", "0.0003")  # 0.001 is the default
CONFIG = jaxbridge.make_config("light_switch_door", seeds=4, cycles=5, updates_per_cycle=20, episodes_per_cycle=2,
                               checkpoint_every=5)


@pytest.fixture(scope="module")
def cli_metrics(tmp_path_factory):
    """train.py's metrics.csv of LSD ours, 4 seeds x 5 cycles, at each learning rate (one sweep)."""
    out = tmp_path_factory.mktemp("runs")
    proc = train_cli("--env", "light_switch_door", "--approaches", "ours", "--num-seeds", "4", "--cycles", "5",
                     "--updates-per-cycle", "20", "--episodes-per-cycle", "2", "--checkpoint-every", "5",
                     "--sweep", f"learning_rate={','.join(RATES)}", "--no-progress", "--out", str(out), "--name", "cli")
    assert proc.returncode == 0, proc.stderr
    return {rate: (out / "cli" / f"ours@learning_rate={rate}" / "metrics.csv").read_text() for rate in RATES}


def as_csv(metrics) -> str:
    """make_train's metrics ([seeds, cycles] fields) written as train.py writes metrics.csv."""
    metrics = jax.tree.map(np.asarray, metrics)
    return metrics_csv([jax.tree.map(lambda x: x[:, c], metrics) for c in range(CONFIG.cycles)], CONFIG.seeds)


def rows(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text)))


def test_make_train_is_train_py_as_one_jitted_function_and_vmaps_over_hyperparameters(cli_metrics):
    # One jitted function of the whole run, vmapped over two learning rates (one compile serves both
    # checks): each rate's runs are the plain run's program, so each gives train.py's numbers at that rate.
    train = jaxbridge.make_train(CONFIG)
    hypers = jax.tree.map(lambda *v: jnp.stack(v), *(jaxbridge.Hyper.of(dataclasses.replace(CONFIG, learning_rate=float(r)))
                                                      for r in RATES))
    out = jax.jit(jax.vmap(train, in_axes=(None, 0)))(None, hypers)
    for i, rate in enumerate(RATES):
        mine, theirs = rows(as_csv(jax.tree.map(lambda x: x[i], out.metrics))), rows(cli_metrics[rate])
        assert mine == theirs
    assert rows(cli_metrics["0.001"]) != rows(cli_metrics["0.0003"])  # the two rates learn differently
    assert out.learners.updates.tolist() == [[5 * 20] * 4] * 2


def test_docs_api_md_documents_every_public_name_and_help_explains_the_calls():
    text = (ROOT / "docs" / "API.md").read_text()
    assert [name for name in jaxbridge.__all__ if f"**`{name}" not in text and f"**`jaxbridge.{name}" not in text] == []
    for name in jaxbridge.__all__:
        assert getattr(jaxbridge, name).__doc__, name
    assert "learning_rate = 0.001" in jaxbridge.TrainConfig.__doc__ and "Adam step size" in jaxbridge.TrainConfig.__doc__


def test_a_training_builds_each_programs_setup_once(monkeypatch, tmp_path):
    """prepare builds the setups; the memory estimate, the network check, the learner contract and the
    training read them (before them, the estimate's lower bound builds a learner on the first seed's tasks,
    no setup)."""
    from jaxbridge.learn.setup import Setup

    built, init = [], Setup.__init__

    def counted(self, config, *args, **kwargs):
        built.append((config.approach, config.num_seeds))
        init(self, config, *args, **kwargs)
    monkeypatch.setattr(Setup, "__init__", counted)
    whole = lambda: sorted(approach for approach, seeds in built if seeds == 2)
    training = jaxbridge.prepare("light_switch_door", ["pure_planning", "random"], seeds=2, cycles=1, out=tmp_path)
    assert sorted(built) == [("pure_planning", 2), ("random", 2)]  # one setup each, none for the memory estimate
    experiment = training.run()
    assert whole() == ["pure_planning", "random"] and set(experiment.summaries) == {"pure_planning", "random"}
    # a sweep over a leaf hyperparameter: one program per approach, one setup each
    built.clear()
    jaxbridge.prepare("light_switch_door", ["random"], seeds=2, cycles=1, out=tmp_path, name="sweep",
                      sweep={"gamma": (0.8, 0.9)}).release()
    assert whole() == ["random"]


class FirstCycle(Exception):
    """Raised where the first cycle would start: what came before it is the training's preparation."""


def test_train_py_to_its_first_cycle_resolves_the_env_checks_the_config_draws_each_seeds_tasks_compiles_each_task_and_builds_each_setup_once(
        monkeypatch, tmp_path):
    import train
    from envs_jax.coffee.env import Coffee  # no plan_bound: the memory estimate compiles tasks as well
    from jaxbridge.api import config as api_config, training as api_training
    from jaxbridge.core import tasks
    from jaxbridge.learn.online import Cycle
    from jaxbridge.learn.setup import Setup

    counts: dict = {}

    def counting(key, fn):
        def counted(*args, **kwargs):
            counts[key(*args)] = counts.get(key(*args), 0) + 1
            return fn(*args, **kwargs)
        return counted
    monkeypatch.setattr(api_config, "load_env", counting(lambda env: "env resolved", api_config.load_env))
    monkeypatch.setattr(api_training, "load_env", counting(lambda env: "env resolved", api_training.load_env))
    monkeypatch.setattr(api_config, "_check_fits_env", counting(lambda *a: "config checked", api_config._check_fits_env))
    draw = Coffee.train_tasks.__func__
    monkeypatch.setattr(Coffee, "train_tasks", classmethod(counting(lambda cls, seed, _: seed, draw)))
    monkeypatch.setattr(tasks, "compile_task", counting(lambda env, spec: ("compiled", spec), tasks.compile_task))
    monkeypatch.setattr(Setup, "__init__", counting(lambda setup, config, *rest: ("setup", config.approach), Setup.__init__))
    tasks._drawn_train_tasks.cache_clear()  # earlier tests of this process drew and compiled these seeds' tasks too
    tasks.compiled_task.cache_clear()
    def first_cycle(self, learners):
        raise FirstCycle()
    monkeypatch.setattr(Cycle, "__call__", first_cycle)
    with pytest.raises(FirstCycle):
        train.main(["--env", "coffee", "--approaches", "ours,random,no_callplanner", "--num-seeds", "2", "--first-seed", "3",
                    "--cycles", "1", "--episodes-per-cycle", "2", "--num-test-tasks", "2", "--test-protocol", "authors",
                    "--workers", "1", "--no-progress", "--out", str(tmp_path)])
    specs = tasks.training_specs(Coffee, [3, 4], 2)[0] + tasks.evaluation_specs(Coffee, [3, 4], 2, "authors")[0]
    assert counts == {"env resolved": 1, "config checked": 1, 3: 1, 4: 1, **{("compiled", spec): 1 for spec in specs},
                      **{("setup", approach): 1 for approach in ("ours", "random", "no_callplanner")}}
