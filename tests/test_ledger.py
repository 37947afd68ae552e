"""The evidence's rules: every committed record on a test-seed set has a ledger row with its commit (and
with each of its steps' commits), and a dirty checkout cannot write a record into docs/."""
import json
import re
import subprocess

import pytest

from bench import ledger, records
from bench.studies import paper
from bench.records import RECORDS, TEST_SETS, uncommitted


def records_on_test_seeds():
    """(path, record) of every committed record whose seeds lie in a test-seed set."""
    for path in sorted(RECORDS.glob("*/*.json")):
        record = json.loads(path.read_text())
        if isinstance(record, dict) and str(record.get("seeds", "")).split("-")[0] in map(str, TEST_SETS):
            yield path, record


def on_test_seeds(step) -> bool:
    """A record's step that ran on test seeds: a training from a test set's first seed, an evaluation of
    such a run (bench.timings.training's cost steps train development seeds), or a step without a command, which
    ran in the bench command's own process on the record's seeds (bench.studies.fix_length's)."""
    if not isinstance(step, dict) or "commit" not in step:
        return False
    command = step.get("command")
    first = re.search(r"--first-seed (\d+)", command or "")
    return command is None or command.startswith("python eval.py") or bool(first and int(first[1]) in TEST_SETS)


def test_every_test_seed_record_and_step_has_a_ledger_row_with_its_commit():
    rows = {(row["env"], row["seeds"], row["commit"]) for row in ledger.rows()}
    records = list(records_on_test_seeds())
    assert len(records) >= 3, "the paper envs' headline records are test-seed records"
    for path, record in records:
        steps = [s for s in record.get("steps", {}).values() if on_test_seeds(s)]
        assert steps, f"{path}: no step ran on the test seeds"
        for commit in {record["commit"], *(s["commit"] for s in steps)}:
            assert (record["env"], record["seeds"], commit) in rows, f"{path}: no ledger row for {commit}"


def test_the_ledger_rows_are_complete():
    for row in ledger.rows():
        assert set(row) == set(ledger.FIELDS) and all(row[f] for f in ledger.FIELDS), row
        assert row["seeds"].split("-")[0] in {str(first) for first in TEST_SETS}, row


def git(root, *args):
    subprocess.run(["git", *args], cwd=root, check=True, capture_output=True)


def test_uncommitted_code_counts_and_records_do_not(tmp_path):
    git(tmp_path, "init", "-q")
    (tmp_path / "code.py").write_text("x = 1\n")
    (tmp_path / "docs" / "results").mkdir(parents=True)
    (tmp_path / "docs" / "results" / "run.json").write_text("{}\n")
    git(tmp_path, "add", "-A")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "first")
    assert uncommitted(tmp_path) == []
    (tmp_path / "docs" / "results" / "run.json").write_text('{"a": 1}\n')  # a record written as the run goes
    assert uncommitted(tmp_path) == []
    (tmp_path / "code.py").write_text("x = 2\n")
    (tmp_path / "new.py").write_text("y = 1\n")
    assert sorted(uncommitted(tmp_path)) == ["code.py", "new.py"]


@pytest.fixture
def own_ledger(tmp_path, monkeypatch):
    path = tmp_path / "ledger.csv"
    monkeypatch.setattr(ledger, "LEDGER", path)
    return path


REASON = ["--change", "first run", "--chosen-on", "-"]


def test_a_dirty_checkout_cannot_write_a_record(tmp_path, own_ledger, monkeypatch, capsys):
    monkeypatch.setattr(records, "uncommitted", lambda: ["jaxbridge/core/meta_policy.py"])
    runs = ["--runs", str(tmp_path / "runs")]
    with pytest.raises(SystemExit) as refused:
        paper.STUDY.main(["--env", "coffee", *runs, *REASON])
    assert refused.value.code == 2 and not own_ledger.exists()
    err = capsys.readouterr().err.strip()
    assert "uncommitted changes (jaxbridge/core/meta_policy.py)" in err and "\n" not in err

    args = paper.STUDY.parse(["--env", "coffee", *runs, "--allow-dirty", "--seeds", "200-201", *REASON])
    paper.STUDY.begin(args)
    assert args.records == (tmp_path / "runs").resolve() / "records"  # outside docs/
    (row,) = ledger.rows()
    assert (row["seeds"], row["env"], row["ran"]) == ("200-201", "coffee", "python -m bench.studies.paper --env coffee --seeds 200-201")
    assert row["commit"].endswith("+changes") and row["change"] == "first run"


def test_code_changed_during_a_clean_run_writes_no_record(tmp_path, own_ledger, monkeypatch):
    from bench.studies import selection
    changed = []
    monkeypatch.setattr(records, "uncommitted", lambda: list(changed))

    class Changing(selection.Selection):
        def steps(self, args, steps):  # the code changes while the study runs
            changed.append("jaxbridge/learn/dqn.py")
            return {}

    with pytest.raises(SystemExit) as refused:
        Changing().main(["--env", "coffee", "--seeds", "300-331", "--runs", str(tmp_path), "--records",
                         str(tmp_path / "records"), *REASON])
    assert refused.value.code == 2 and not (tmp_path / "records").exists()
    assert ledger.rows()[0]["seeds"] == "300-331"


def test_the_ledger_command_appends_a_row_and_refuses_seeds_outside_the_sets(own_ledger, capsys):
    assert ledger.main(["--env", "doorknobs", "--ran", "train.py --env doorknobs --first-seed 300", "--seeds", "300-331",
                        "--change", "a new kind of door", "--chosen-on", "development seeds 0-31", "--commit", "abc"]) == 0
    (row,) = ledger.rows()
    assert (row["seeds"], row["commit"], row["chosen_on"]) == ("300-331", "abc", "development seeds 0-31")
    assert ledger.main(["--env", "doorknobs", "--ran", "x", "--seeds", "100-131", *REASON]) == 2
    assert "not within a test-seed set" in capsys.readouterr().err and len(ledger.rows()) == 1


def test_a_spent_row_records_no_run_and_says_why(own_ledger, capsys):
    assert ledger.main(["--spent", "the learned selector", "--seeds", "300-331", "--change", "a result seen there",
                        "--commit", "abc"]) == 0
    (row,) = ledger.rows()
    assert ledger.is_spent(row) and row["ran"] == "no run: the set is spent for the learned selector"
    assert (row["seeds"], row["change"], row["chosen_on"]) == ("300-331", "spent: a result seen there", "no run: nothing was chosen")
    assert ledger.main(["--spent", "the learned selector", "--seeds", "300-331"]) == 2  # without its reason
    assert ledger.main(["--env", "coffee", "--seeds", "300-331", "--change", "x", "--chosen-on", "y"]) == 2  # a run without --ran
    assert capsys.readouterr().err.count("\n") == 2 and len(ledger.rows()) == 1


def test_every_set_spent_for_an_approach_has_its_spent_row():
    spent = {row["seeds"] for row in ledger.rows() if ledger.is_spent(row)}
    assert records.SPENT and all(set(sets) <= spent for sets in records.SPENT.values())


def test_a_study_on_development_or_test_seeds_writes_a_row_only_for_a_test_set(own_ledger, monkeypatch, capsys):
    """Every study begins the same way (bench/study.py): development seeds leave the ledger alone; test
    seeds need their reasons, and a range leaving its set is refused."""
    from bench.studies import multi_novelty
    monkeypatch.setattr(records, "uncommitted", lambda: [])
    begin = lambda *flags: multi_novelty.STUDY.begin(multi_novelty.STUDY.parse(list(flags)))
    begin("--seeds", "0-7")
    assert not own_ledger.exists()
    for bad in ("7-3", "seven"):  # refused as a flag error, before anything begins
        with pytest.raises(SystemExit) as refused:
            begin("--seeds", bad)
        assert refused.value.code == 2 and "--seeds takes FIRST-LAST" in capsys.readouterr().err
    for flags, message in ((("--seeds", "300-301"), "needs --change and --chosen-on"),
                           (("--seeds", "330-333", *REASON), "not within a test-seed set")):
        with pytest.raises(SystemExit) as refused:
            begin(*flags)
        assert refused.value.code == 2 and message in capsys.readouterr().err and not own_ledger.exists()
    begin("--seeds", "300-331", "--cycles", "50", *REASON)
    (row,) = ledger.rows()
    assert (row["seeds"], row["env"], row["ran"]) == ("300-331", "multi_novelty",
                                                      "python -m bench.studies.multi_novelty --seeds 300-331 --cycles 50")


def test_the_one_regeneration_runs_the_command_of_every_committed_study_record():
    """bench.regenerate's steps are every study's command: a study added without a step fails here
    (performance records are re-measured at HEAD by their own commands, not regenerated; records on a set
    spent for one of their approaches are history, not regenerated)."""
    from bench import regenerate
    performance = ("python -m pytest", "bash bench/gpu.sh", "python -m bench.timings.maple_q")
    steps = regenerate.steps()
    made = {" ".join(["python", "-m", *module]) for _, module, _ in steps}
    for path in sorted(RECORDS.glob("**/*.json")):
        record = json.loads(path.read_text())
        command = records.current_command(record["command"]) if isinstance(record, dict) and "command" in record else None
        spent = any(record.get("seeds") in records.SPENT.get(name, ()) for name in record.get("approaches", ())) if command else False
        if command and not command.startswith(performance) and not spent:
            assert command in made, f"{path}: bench.regenerate has no step '{command}'"
    on_test_seeds = {" ".join(module) for _, module, test in steps if test}
    assert {"bench.studies.paper --env coffee", "bench.studies.multi_novelty --seeds 300-331"} <= on_test_seeds


def test_the_regeneration_refuses_to_start_without_its_ledger_reasons(capsys):
    from bench import regenerate
    with pytest.raises(SystemExit) as stopped:
        regenerate.main(["--change", "a rerun"])
    assert stopped.value.code == 2 and "--chosen-on" in capsys.readouterr().err
