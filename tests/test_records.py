"""The docs' numbers are their records': every generated block of README.md, docs/RESULTS.md,
docs/PERFORMANCE.md and docs/results/generalisation.md re-renders from docs/results/ to what is
committed, and a number edited by hand is caught."""
import json
import re

import pytest

from bench import study
from bench.pages import render
from bench.records import ROOT


@pytest.mark.parametrize("doc", render.DOCS)
def test_the_docs_are_what_their_records_render(doc):
    text = (ROOT / doc).read_text()
    assert render.BLOCK.search(text), f"{doc} has no generated block"
    assert render.stale_blocks(text) == [], f"{doc} differs from its records: run python -m bench.pages.render"


def test_a_number_edited_by_hand_is_caught():
    text = (ROOT / "docs" / "RESULTS.md").read_text()
    block = next(m for m in render.BLOCK.finditer(text) if re.search(r"\d", m["body"]))
    digit = re.search(r"\d", block["body"])
    edited_body = block["body"][:digit.start()] + str((int(digit[0]) + 1) % 10) + block["body"][digit.end():]
    edited = text[:block.start("body")] + edited_body + text[block.end("body"):]
    assert render.stale_blocks(edited) == [block["name"]]
    assert render.rendered(edited) == text  # rendering puts the record's number back


def test_an_unknown_block_is_refused():
    with pytest.raises(SystemExit, match="unknown generated block 'no such'"):
        render.rendered("<!-- generated: no such -->\nx\n<!-- end generated: no such -->\n")


def test_the_headline_quotes_the_authors_logged_numbers():
    rows = render.results.authors_rows("light_switch_door")
    cells = render.results.authors_test_cells(rows["ours"], (10, 25, 50, 100))
    assert cells == ["0.33 [0, 1]", "0.72 [0, 1]", "0.57 [0, 1]", "0.64 [0, 1]"]
    single = render.results.authors_test_cells(rows["pure_planning"], (10, 25))
    assert single == ["0 (single evaluation)", ""]


def test_a_finished_step_is_not_run_again_and_keeps_the_commit_it_ran_at(tmp_path):
    calls = []
    steps = study.Steps(tmp_path / "steps.json")
    first = steps.run("train", lambda: calls.append(1) or {"wall_s": 1.0})
    assert first["wall_s"] == 1.0 and first["commit"] == study.git_commit()
    again = study.Steps(tmp_path / "steps.json")  # a later call of the command
    assert again.run("train", lambda: calls.append(2) or {"wall_s": 9.0}) == first
    assert calls == [1]
    assert json.loads((tmp_path / "steps.json").read_text()) == {"train": first}


def test_a_step_restarted_after_a_stop_shows_its_time_as_a_lower_bound():
    # study.train_step marks a training resumed from its checkpoints: its seconds count from the restart
    seconds_text = render.results.seconds_text
    whole = {"wall_s": 1234.0, "steps": {"train": {"wall_s": 1000.0}, "sweep": {"wall_s": 234.0}}}
    assert seconds_text(whole) == "1,234 s" and seconds_text(whole["steps"]["train"]) == "1,000 s"
    restarted = {**whole, "steps": {**whole["steps"], "train": {"wall_s": 600.0, "resumed": True}}}
    assert seconds_text(restarted).startswith("at least 1,234 s")
    assert seconds_text(restarted["steps"]["train"]).startswith("at least 600 s")
    assert seconds_text(restarted["steps"]["sweep"]) == "234 s"


def test_a_claims_verdict_follows_its_stated_rule():
    from bench.pages import claims
    row = lambda mean, low, high: {"test_solve_rate_mean": mean, "test_solve_rate_mean_low": low, "test_solve_rate_mean_high": high}
    steady = {c: row(0.95, 0.85, 1.0) for c in range(1, 101)}
    assert claims.converges(steady).holds
    assert not claims.converges({**steady, 60: row(0.95, 0.75, 1.0)}).holds  # an interval dips below 0.8 after 40
    assert claims.converges({**steady, 39: row(0.2, 0.1, 0.3)}).holds  # before cycle 40 it may still learn
    apart, overlapping = {c: row(0.3, 0.2, 0.4) for c in steady}, {c: row(0.8, 0.7, 0.9) for c in steady}
    assert claims.above(steady, {"random": apart}, (100,)).holds and not claims.above(steady, {"random": overlapping}, (100,)).holds
    # an efficiency claim needs ours apart at every early cycle, not only at the end
    late = {**steady, 10: row(0.3, 0.2, 0.4)}
    assert claims.above(late, {"maple_q": apart}, (100,)).holds and not claims.above(late, {"maple_q": apart}, (10, 25)).holds
    # "gets stuck": beaten and low; beaten but not low is partly
    assert claims.stuck(steady, apart, "no_callplanner", 100) == (claims.stuck(steady, apart, "no_callplanner", 100).text, True, False)
    beaten_not_stuck = {c: row(0.6, 0.5, 0.7) for c in steady}
    partly = claims.stuck(steady, beaten_not_stuck, "no_callplanner", 100)
    assert not partly.holds and partly.partly
    yes, no, part = claims.Outcome("", True), claims.Outcome("", False), claims.Outcome("", False, True)
    pairs = ((yes, yes), (yes, no), (no, yes), (part, yes), (yes, None), (None, yes), (None, None))
    assert [claims.verdict(*pair) for pair in pairs] == [
        "reproduced", "reproduced with our departures", "not reproduced", "partly", "not measured", "not measured",
        "not measured"]


def test_no_claim_is_reproduced_where_the_preset_is_not_measured():
    from bench.pages import claims
    rows = [line.split(" | ") for line in claims.claims_table().splitlines()[2:]]
    assert rows and all(not (r[3] == "not measured" and "**reproduced" in r[4]) for r in rows)
    coffee_stuck = next(r for r in rows if "gets stuck" in r[0] and "Coffee" in r[1])
    assert "**partly**" in coffee_stuck[4]  # no CallPlanner solves most of Coffee's test tasks
