"""Sharding the seeds over devices does not change a single bit: a short training on 2 virtual CPU
devices (3 seeds: one padded slot) gives the metrics and parameters of 1 device. (Seed blocks on 1 and
2 devices: tests/test_optim.py.) (Checkpoints hold the
unpadded state on one device whatever the count, so a run also resumes on another device count to the
same numbers: checked by hand, see docs/PERFORMANCE.md; not in the suite, for time.)"""
import json
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest

from jaxbridge.run import checkpoint
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import SeedMesh, device_count_arg
from jaxbridge.learn.setup import make_setup
from run_helpers import cli_in_process, with_fusion_emitters

ROOT = Path(__file__).resolve().parents[1]
SHORT = ["--num-seeds", "3", "--cycles", "3", "--updates-per-cycle", "20", "--checkpoint-every", "1",
         "--approaches", "ours", "--no-progress"]


def train(*args, env=None):
    return subprocess.run([sys.executable, "train.py", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=600, env=env or with_fusion_emitters())


def start(*args):
    return subprocess.Popen([sys.executable, "train.py", *args], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=with_fusion_emitters())


def exact(run_dir: Path):
    """What must match bit for bit: the latest checkpoint's step, its whole learner state (networks,
    target, optimizer, replay buffer, keys, counters), the metrics as it records them (float32, exact)
    and the metrics.csv text."""
    config = TrainConfig.from_dict(json.loads((run_dir / "config.json").read_text()))
    state, record, step = checkpoint.restore(run_dir / "checkpoints", make_setup(config).init_learners())
    leaves = [np.asarray(x) for x in jax.tree.leaves(state.replace(key=jax.random.key_data(state.key)))]
    return step, leaves, record["history"], (run_dir / "metrics.csv").read_text()


def same(a, b) -> bool:
    step_a, leaves_a, *rest_a = a
    step_b, leaves_b, *rest_b = b
    return (step_a == step_b and len(leaves_a) == len(leaves_b) and rest_a == rest_b
            and all(x.dtype == y.dtype and np.array_equal(x, y) for x, y in zip(leaves_a, leaves_b)))


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    # Both at once (each compiles its program on one core for most of its time).
    procs = [start(*SHORT, "--devices", str(n), "--out", str(out), "--name", f"dev{n}") for n in (1, 2)]
    for proc in procs:
        _, err = proc.communicate(timeout=600)
        assert proc.returncode == 0, err
    return out


def test_two_devices_give_the_metrics_and_parameters_of_one(runs):
    one, two = runs / "dev1" / "ours", runs / "dev2" / "ours"
    assert json.loads((two / "summary.json").read_text())["devices"] == "2 cpu"
    assert json.loads((one / "summary.json").read_text())["devices"] == "1 cpu"
    a, b = exact(one), exact(two)
    assert a[0] == 3 and len(a[2]) == 3
    assert same(a, b)


def test_a_run_widened_onto_a_second_device_mid_run_gives_the_numbers_of_one(runs, tmp_path):
    # What the experiment's scheduler does when a worker frees its device (run/scheduling.py).
    proc = subprocess.run([sys.executable, str(ROOT / "tests" / "widened_train.py"), str(tmp_path)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600, env=with_fusion_emitters())
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["2", "True"]  # asked after cycles 1 and 2, not after the last
    assert json.loads((tmp_path / "ours" / "summary.json").read_text())["devices"] == "2 cpu"
    assert same(exact(runs / "dev1" / "ours"), exact(tmp_path / "ours"))


def test_bad_device_counts_are_one_line_errors():
    for value, message in (("0", "expected auto or a positive integer, got 0"),
                           ("foo", "expected auto or a positive integer, got 'foo'")):
        proc = cli_in_process("train.py", "--devices", value, "--cycles", "1")
        assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr
    # More devices than the machine has (here: a CPU fixed at one device by XLA_FLAGS, as a GPU box is
    # fixed at its GPUs).
    env = {**__import__("os").environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=1",
           "JAX_PLATFORMS": "cpu"}
    proc = train("--devices", "3", "--cycles", "1", env=env)
    assert proc.returncode == 2 and "--devices 3: only 1 CPU device(s) here" in proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_seed_padding_round_trips():
    assert device_count_arg("auto") is None and device_count_arg("4") == 4
    device = jax.local_devices()[0]
    assert SeedMesh(3, (device,) * 2).pad(np.arange(3)).tolist() == [0, 1, 2, 2]  # padding only needs the count
    assert SeedMesh(4, (device,) * 2).padded == 4 and SeedMesh(3, (device,) * 4).padded == 4
    assert SeedMesh(3, (device,), block=2).padded == 4 and SeedMesh(5, (device,) * 2, block=2).padded == 8
    with pytest.raises(ValueError, match="seed block must be at least 1"):
        SeedMesh(3, (device,), block=0)
    mesh = SeedMesh(3, (device,))
    tree = {"a": np.arange(6.0).reshape(3, 2), "k": jax.random.split(jax.random.key(0), 3)}
    back = mesh.unpad(mesh.place(tree))
    assert np.array_equal(back["a"], tree["a"])
    assert np.array_equal(jax.random.key_data(back["k"]), jax.random.key_data(tree["k"]))


def test_concurrent_approaches_split_the_devices_between_them():
    from jaxbridge.learn.devices import split_devices
    devices = ["d0", "d1", "d2", "d3"]  # only their identity matters here
    assert split_devices(devices, 2) == [["d0", "d2"], ["d1", "d3"]]
    assert split_devices(devices, 3) == [["d0", "d3"], ["d1"], ["d2"]]
    assert split_devices(devices, 1) == [devices]
    assert split_devices(devices[:1], 2) == [["d0"], ["d0"]]  # fewer devices than workers: all share them
    assert split_devices(None, 2) == [None, None]
