"""Envs by name: the built-in names are their classes' names, and an installed package's env entry point
(docs/NEW_ENV.md, "A short name") is found by `import envs_jax` and trained by name from the command line."""
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import envs_jax
from envs_jax import BUILTIN, VARIANTS, env_class, is_builtin

ROOT = Path(__file__).resolve().parents[1]


def test_the_builtin_names_are_their_classes_names():
    classes = (envs_jax.LightSwitchDoor, envs_jax.Doorknobs, envs_jax.Coffee, envs_jax.LightSwitchPanel,
               envs_jax.CoffeeDistractor, envs_jax.DoorknobsDistractor)
    assert sorted(c.name for c in classes) == sorted(BUILTIN + VARIANTS)
    assert all(env_class(c.name) is c and is_builtin(c.name) for c in classes)
    assert set(BUILTIN + VARIANTS) <= set(envs_jax.registered())


# A package of one thin subclass of the example env, declaring the entry point as docs/NEW_ENV.md says.
PYPROJECT = """\
[build-system]
requires = ["setuptools>=61"]
build-backend = "setuptools.build_meta"

[project]
name = "jaxbridge-test-plugin-box"
version = "0.1.0"

[project.entry-points."jaxbridge.envs"]
plugin_box = "jaxbridge_test_plugin.box:PluginBox"
"""
MODULE = """\
from examples.locked_box import LockedBox


class PluginBox(LockedBox):
    name = "plugin_box"
"""
# In the child: the entry point is listed once envs_jax is imported, then train.py trains it by name.
CHILD = """\
import runpy, sys
import envs_jax
assert "plugin_box" in envs_jax.registered(), envs_jax.registered()
assert envs_jax.env_class("plugin_box").__module__ == "jaxbridge_test_plugin.box"
sys.argv = ["train.py", *sys.argv[1:]]
runpy.run_path("train.py", run_name="__main__")
"""


def install(source: Path, site: Path) -> None:
    """Install the package at `source` into the directory `site` (not into this Python's site-packages):
    with pip and setuptools offline, as a user would, or where setuptools is missing, the dist-info pip
    would write, by hand (importlib.metadata reads the same two files)."""
    if importlib.util.find_spec("setuptools"):
        proc = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
                               "--no-index", "--no-cache-dir", "--disable-pip-version-check", "--target", str(site),
                               str(source)], capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        return
    (site / "jaxbridge_test_plugin").mkdir(parents=True)
    (site / "jaxbridge_test_plugin" / "__init__.py").write_text("")
    (site / "jaxbridge_test_plugin" / "box.py").write_text(MODULE)
    info = site / "jaxbridge_test_plugin_box-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: jaxbridge-test-plugin-box\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text('[jaxbridge.envs]\nplugin_box = jaxbridge_test_plugin.box:PluginBox\n')


def test_an_installed_packages_env_entry_point_imports_and_trains_by_name(tmp_path):
    """`import envs_jax` once refused any installed env entry point (it asserted that the registered names
    were the built-ins)."""
    source, site = tmp_path / "source", tmp_path / "site"
    (source / "jaxbridge_test_plugin").mkdir(parents=True)
    (source / "pyproject.toml").write_text(PYPROJECT)
    (source / "jaxbridge_test_plugin" / "__init__.py").write_text("")
    (source / "jaxbridge_test_plugin" / "box.py").write_text(MODULE)
    install(source, site)
    assert [p.name for p in site.glob("*.dist-info")] == ["jaxbridge_test_plugin_box-0.1.0.dist-info"]

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")]))}
    proc = subprocess.run([sys.executable, "-c", CHILD, "--env", "plugin_box", "--approaches", "pure_planning",
                           "--num-seeds", "1", "--cycles", "1", "--episodes-per-cycle", "1", "--no-progress",
                           "--out", str(tmp_path / "runs")], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    run = tmp_path / "runs" / "plugin_box" / "pure_planning"
    assert json.loads((run / "config.json").read_text())["env"] == "plugin_box"  # what --resume loads again
    assert (run / "metrics.csv").read_text().count("\n") == 2  # the header and seed 0's cycle 1
    assert importlib.util.find_spec("jaxbridge_test_plugin") is None  # nothing installed for this Python
