"""The house's rules: every import points down a floor, and no module outgrows its cap."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# Floors, lowest first: a module may import its own floor's modules and those of the floors below it.
FLOORS = ("planner", "envs_jax", "jaxbridge.utils", "jaxbridge.core", "jaxbridge.learn", "jaxbridge.viz",
          "jaxbridge.run", "jaxbridge.api")
PACKAGES = ("planner", "envs_jax", "jaxbridge")
# Caps by principle, not by today's sizes: a module is one idea read in one sitting (past 500 lines it
# holds two: split it), and a command line is flags and calls of the public API (past 200 lines logic has
# crept in: move it into jaxbridge.api).
MAX_MODULE_LINES, MAX_SCRIPT_LINES = 500, 200
SCRIPTS = ("train.py", "eval.py")


def floor(module: str) -> int | None:
    matches = [i for i, name in enumerate(FLOORS) if module == name or module.startswith(name + ".")]
    return max(matches) if matches else None


def modules():
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
            yield name.removesuffix(".__init__"), path


def imported(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names |= {f"{node.module}.{a.name}" for a in node.names} | {node.module}
    return names


def test_every_import_points_down_a_floor():
    upward = []
    for name, path in modules():
        if path.name == "__init__.py" and floor(name) in (None, FLOORS.index("envs_jax")):
            continue  # a package's front door re-exports what lies below it
        mine = floor(name)
        for target in imported(path):
            theirs = floor(target)
            if theirs is not None and mine is not None and theirs > mine:
                upward.append(f"{name} imports {target}")
    assert not upward, upward


def lines(path: Path) -> int:
    return len(path.read_text().splitlines())


def test_no_module_outgrows_its_cap():
    long = {name: n for name, path in modules() if (n := lines(path)) > MAX_MODULE_LINES}
    long |= {script: n for script in SCRIPTS if (n := lines(ROOT / script)) > MAX_SCRIPT_LINES}
    assert not long, f"split these (caps: {MAX_MODULE_LINES} lines a module, {MAX_SCRIPT_LINES} a script): {long}"


# The pages a reader opens first stay short enough to read whole: the results' headlines, claims and seeds
# (each study on its own page), and each design page one subject.
MAX_PAGE_LINES = {"docs/RESULTS.md": 250, "docs/PERFORMANCE.md": 150, "docs/DESIGN.md": 400, "docs/design/*.md": 400}


def test_no_results_or_design_page_outgrows_its_cap():
    long = {str(path.relative_to(ROOT)): n for pattern, cap in MAX_PAGE_LINES.items() for path in sorted(ROOT.glob(pattern))
            if (n := lines(path)) > cap}
    assert len(list(ROOT.glob("docs/design/*.md"))) >= 2 and not long, long


def test_the_command_lines_call_only_the_public_api():
    """train.py and eval.py are flags, calls of `jaxbridge`'s public names, and printing: they import the
    package root and the command-line plumbing (utils), nothing else of the package, and every name they
    use from the root is in its __all__."""
    import jaxbridge

    for script in (ROOT / name for name in SCRIPTS):
        tree = ast.parse(script.read_text())
        inside = {name for name in imported(script) if name.split(".")[0] in PACKAGES}
        assert inside <= {"jaxbridge"} | {n for n in inside if n.startswith("jaxbridge.utils")}, (script.name, inside)
        used = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name) and node.value.id == "jaxbridge"}
        assert used and used <= set(jaxbridge.__all__), (script.name, used - set(jaxbridge.__all__))


# Where a string setting may be read as text: where it is resolved (a config's choices, presets, --sweep
# values, CLI flags). Everywhere else a setting is a typed value (an enum member, a bool, None).
RESOLUTION = {"jaxbridge.core.config", "jaxbridge.core.settings", "jaxbridge.core.learner_settings",
              "jaxbridge.core.presets", "jaxbridge.core.grid", "jaxbridge.utils.cli"}


def setting_names() -> set[str]:
    import dataclasses

    from jaxbridge.core.config import TrainConfig
    from jaxbridge.core.learner_settings import registered, settings_class
    from jaxbridge.learn.approaches import Approach
    learners = [settings_class(name) for name in registered()]
    names = {f.name for cls in (TrainConfig, Approach, *learners) for f in dataclasses.fields(cls)}
    return (names - {"name", "label", "description"}) | {"request"}  # request: --devices' value


def compared_to_text(node: ast.Compare, settings: set[str]) -> str | None:
    """The setting a comparison reads as text (`config.polyak_per == "update"`, `bridge in ("q", ...)`)."""
    sides = [node.left, *node.comparators]
    texts = [s for s in sides if isinstance(s, ast.Constant) and isinstance(s.value, str)
             or isinstance(s, (ast.Tuple, ast.List, ast.Set)) and s.elts
             and all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in s.elts)]
    named = [s.attr if isinstance(s, ast.Attribute) else s.id for s in sides if isinstance(s, (ast.Attribute, ast.Name))]
    hit = [n for n in named if n in settings]
    return hit[0] if texts and hit else None


def test_no_setting_is_compared_as_text_outside_where_it_is_resolved():
    settings, found = setting_names(), []
    for name, path in modules():
        if not name.startswith("jaxbridge") or name in RESOLUTION:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare) and (setting := compared_to_text(node, settings)):
                found.append(f"{name}:{node.lineno} compares {setting} with text")
    assert not found, found


# A function is read in one screen: in api/ and run/ (the rooms a reader walks through from train.py and
# eval.py) none passes 50 lines. And a function's parameters are what a reader holds in mind at a call: past 8,
# those that travel together become one value that says what they are (core/meta_policy.MetaPolicy). The
# public API's functions and classes (jaxbridge.__all__) are exempt: their keyword options are the user's interface.
MAX_FUNCTION_LINES, LONG_FUNCTION_ROOMS, MAX_PARAMETERS = 50, ("jaxbridge.api", "jaxbridge.run"), 8


def functions(tree: ast.AST):
    """(qualified name, function node) of every function and method, nested ones too."""
    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                name = f"{prefix}{child.name}"
                if not isinstance(child, ast.ClassDef):
                    yield name, child
                yield from walk(child, name + ".")
            else:
                yield from walk(child, prefix)
    yield from walk(tree, "")


def parameters(node: ast.FunctionDef) -> int:
    """Its parameters, *args and **kwargs one each, a method's self or cls not counted."""
    args = node.args
    named = [a.arg for a in (*args.posonlyargs, *args.args, *args.kwonlyargs)]
    if named and named[0] in ("self", "cls"):
        named = named[1:]
    return len(named) + (args.vararg is not None) + (args.kwarg is not None)


def public(module: str, qualified: str) -> bool:
    """A function of the public API: one of jaxbridge.api's named in jaxbridge.__all__, or a method of such a class."""
    import jaxbridge
    return module.startswith("jaxbridge.api") and qualified.split(".")[0] in jaxbridge.__all__


def too_long_and_too_wide(package: str = "jaxbridge") -> tuple[list[str], list[str]]:
    long, wide = [], []
    for name, path in modules():
        if not name.startswith(package):
            continue
        for qualified, node in functions(ast.parse(path.read_text())):
            lines = node.end_lineno - node.lineno + 1
            if name.startswith(LONG_FUNCTION_ROOMS) and lines > MAX_FUNCTION_LINES:
                long.append(f"{name}.{qualified}: {lines} lines")
            if parameters(node) > MAX_PARAMETERS and not public(name, qualified):
                wide.append(f"{name}.{qualified}: {parameters(node)} parameters")
    return long, wide


def test_no_function_outgrows_a_screen_or_takes_more_than_eight_parameters():
    long, wide = too_long_and_too_wide()
    assert not long, f"split these (cap: {MAX_FUNCTION_LINES} lines a function in api/ and run/): {long}"
    assert not wide, f"group what travels together (cap: {MAX_PARAMETERS} parameters outside the public API): {wide}"


def test_the_function_caps_see_what_they_cap():
    """The walk finds nested functions and methods and counts as documented (so the caps above can fail)."""
    tree = ast.parse("class A:\n    def m(self, a, *b, c, **d):\n        def inner(x):\n            return x\n")
    found = dict(functions(tree))
    assert set(found) == {"A.m", "A.m.inner"} and parameters(found["A.m"]) == 4 and parameters(found["A.m.inner"]) == 1
    assert public("jaxbridge.api.training", "prepare") and not public("jaxbridge.core.meta_policy", "rollout")
    assert not public("jaxbridge.api.training", "_plan")


# bench/'s studies and pages (the records and the docs made of them) go through the public API as train.py
# and eval.py do: `jaxbridge` and its utils. These timings and probes time or probe the package's parts,
# so they may import below the API:
BENCH_INSIDE = {
    "timings/table": "the benchmark table's runner: configs and devices for the micro-benchmarks it times",
    "probes/bridge_steps": "counts a trained policy's bridge steps in the jitted cycle's own test rollout",
    "probes/decisions": "records the greedy test rollout's decisions (meta_policy.rollout)",
    "timings/devices": "seconds per jitted cycle on 1 vs 2 devices",
    "timings/doorknobs": "times Doorknobs' skill steps and the oracle's bare rollout",
    "timings/evaluation": "times an evaluation's parts: task batches, plan tables, rollouts",
    "probes/knob_offsets": "probes the Q-network's candidates at Doorknobs' knob offsets",
    "timings/maple_q": "times Maple Q's cycle part by part",
    "timings/meta_policy": "env steps/s of the bare meta-policy",
    "timings/scaling": "seconds as the seed count grows, per seed block",
    "probes/stuck_objects": "the paper's selection rule at the oracle's stuck states (meta_policy.rollout)",
    "probes/sweep": "times a --sweep's programs",
    "timings/training": "seconds for a run's compiled programs",
    "timings/update_parts": "where a learning step's time goes",
    "timings/updates": "times the double-DQN updates alone",
}


def below_the_api(path: Path) -> set[str]:
    """What `path` imports of the package below its public API (jaxbridge's __all__ and jaxbridge.utils)."""
    import jaxbridge

    public = {"jaxbridge"} | {f"jaxbridge.{name}" for name in jaxbridge.__all__}
    return {name for name in imported(path) if name.split(".")[0] in ("jaxbridge", "planner")
            and name not in public and not name.startswith("jaxbridge.utils")}


def test_only_the_listed_micro_benchmarks_import_below_the_public_api():
    found = {path.relative_to(ROOT / "bench").with_suffix("").as_posix(): below
             for path in sorted((ROOT / "bench").rglob("*.py")) if (below := below_the_api(path))}
    assert set(found) <= set(BENCH_INSIDE), {name: found[name] for name in set(found) - set(BENCH_INSIDE)}
    assert set(BENCH_INSIDE) <= set(found), f"these no longer reach inside: strike them off BENCH_INSIDE: {set(BENCH_INSIDE) - set(found)}"


def test_the_settings_and_the_presets_import_nothing_of_each_other():
    """A preset is values for the settings; what combines them is the API's make_config (api/config.py)."""
    config, presets = ROOT / "jaxbridge" / "core" / "config.py", ROOT / "jaxbridge" / "core" / "presets.py"
    assert not any(name.startswith("jaxbridge.core.presets") for name in imported(config))
    assert not any(name.startswith("jaxbridge.core.config") for name in imported(presets))


# Every module that declares, resolves, presets, sweeps or migrates a setting; their code (statements, not
# the docstrings under each field, which are its help) stays small enough to read as one piece.
SETTINGS_MODULES = ("jaxbridge/core/config.py", "jaxbridge/core/settings.py", "jaxbridge/core/learner_settings.py",
                    "jaxbridge/core/token_settings.py", "jaxbridge/core/presets.py", "jaxbridge/core/grid.py",
                    "jaxbridge/learn/hyper.py", "jaxbridge/api/config.py")
MAX_SETTINGS_CODE = 600


def code_lines(path: Path) -> int:
    """Lines holding code: neither blank, nor a comment, nor part of a docstring."""
    source = path.read_text()
    docs = {line for node in ast.walk(ast.parse(source)) if isinstance(node, ast.Expr)
            and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
            for line in range(node.lineno, node.end_lineno + 1)}
    return sum(1 for i, text in enumerate(source.splitlines(), 1)
               if text.strip() and not text.strip().startswith("#") and i not in docs)


def test_the_settings_code_stays_within_its_cap():
    counts = {name: code_lines(ROOT / name) for name in SETTINGS_MODULES}
    assert all(n > 0 for n in counts.values()) and sum(counts.values()) <= MAX_SETTINGS_CODE, counts
    declaring = {str(path.relative_to(ROOT)) for _, path in modules() if any(
        isinstance(node, ast.Call) and getattr(node.func, "id", None) == "setting" for node in ast.walk(ast.parse(path.read_text())))}
    assert declaring and declaring <= set(SETTINGS_MODULES), f"settings declared outside the cap: {declaring - set(SETTINGS_MODULES)}"
