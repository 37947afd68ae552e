import os

import pytest

from run_helpers import OLDER_EMITTERS, TEST_XLA_FLAGS, script_main

# Tests share compiled programs across processes through JAX's persistent cache, the many small ones too
# (a child train.py finds an earlier one's programs of the same shapes; faster reruns).
os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".jax_cache"))
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
# The paces train.py records (utils/pace.py) go beside it, not into the user's cache: a test's short runs
# are not this machine's training speed.
os.environ.setdefault("JAXBRIDGE_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".jax_cache", "jaxbridge", "jax"))


def pytest_configure(config):
    """Tests check behaviour, not speed: XLA's cheaper code generation cuts the suite's compile time, most
    of its time. The paper's claims (`-m claims`) keep the emitters users' runs compile with: they state
    what users' numbers show (the older emitters' last bits move one seed of a claim). Set before JAX
    starts its backend; child processes inherit it."""
    flags = TEST_XLA_FLAGS.replace(OLDER_EMITTERS, "") if config.getoption("markexpr") == "claims" else TEST_XLA_FLAGS
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {flags}".strip()


@pytest.fixture(scope="module")
def eval_main():
    """eval.py's main(argv), in this process (programs compiled by one call serve the next)."""
    return script_main("eval.py")


# The costliest test files first, by their seconds on a fresh clone (`python -m pytest --durations=0`):
# with `--dist loadfile` each file runs whole on one worker, in this order (`--no-loadscope-reorder`),
# so a long file started last cannot leave the other worker idle at the end.
COSTLIEST_FIRST = ("test_claims.py", "test_learning.py", "test_low_level.py", "test_learners.py", "test_doorknobs.py",
                   "test_reliability.py", "test_object_selection.py", "test_scale_out.py", "test_cli.py", "test_api.py",
                   "test_safety.py", "test_env_contract.py", "test_devices.py", "test_presets.py", "test_sweep.py",
                   "test_optim.py", "test_approaches.py", "test_settings.py", "test_render.py", "test_faults.py",
                   "test_multi_novelty.py", "test_env_plugins.py", "test_plan_repair.py", "test_coffee.py",
                   "test_fix_length.py", "test_quickstart.py", "test_exploration.py", "test_signatures.py",
                   "test_light_switch_door.py", "test_meta_policy.py", "test_distractors.py")


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(COSTLIEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: each file keeps its order
