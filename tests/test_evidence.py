"""Every sentence true: a number the docs state about a result comes from a record (inside a generated
block, which tests/test_records.py ties to its record), never typed; and the statements a review found
contradicted by the records are gone."""
import re

import pytest

from bench.pages import render
from bench.records import ROOT

PAGES = ("README.md", "docs/RESULTS.md", "docs/PERFORMANCE.md",
         *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs" / "results").glob("*.md")))
CODE = re.compile(r"```.*?```|`[^`\n]+`|^ {4,}python .*$", re.S | re.M)  # commands and settings: tests/test_doc_commands.py runs them
NUMBER = re.compile(r"(?<![\w.])\d+(?:[,.]\d+)*")
# What a number outside a generated block may be, each pattern with why it states no result.
ALLOWED = (
    r"\b\d+-\d+\b|\bc-\d+",  # a seed range or a range of a task's sizes (seeds 0-7, 10-20 cells)
    r"\b\d+-[a-z]+",  # a size in a name (a 5-cell task, the 8-seed training)
    r"\b[0-9a-f]*\d[0-9a-f]*\b(?<=\w{7})",  # a commit hash (seven hex digits or more)
    r"issues? \d+",  # an issue's number
    r"[Vv]ersion \d+|jax \d+\.\d+|Python \d+\.\d+|\(\d+\.\d+\)",  # a version
    r"et al\. \d{4}",  # a citation's year
    r"95%",  # the intervals' level
    r"\d+ (?:online learning )?cycles?|cycles? \d+(?:(?:, | and |/)\d+)*|cycles? [c\d][-+\d ]*\.\. ?c?-?\d+",  # the protocol's cycles
    r"\d[\d,]* (?:tuning |test |validation )?(?:seeds?|test tasks?|training (?:tasks?|episodes)|resamples|seed slots?|"
    r"tasks?|episodes|steps|cells?|doors?|cups?|rooms|maps|devices?|cores?|settings?)\b",  # counts in the protocol and layout
    r"\d+x\d+|\d+x\b|\d+ to [\d,]+",  # a grid's shape, a factor named in a sentence, a range in words
    r"exit(?:s| with)? (?:code )?\d+|process \d+|\(\d+:|\bk \+ \d+",  # exit codes and indices
    r"(?:below|above) [01]\b|divided by \d+|horizon \d+",  # a rate's bounds; the smooth reward's and a task's definition
    r"\d+ (?:and|vs|or) (?=\d+ (?:seed|device|core))",  # the counts a comparison names
    r"the \d+\.\d+ pip",  # a version
    r"within 0\.1 of(?: 0\.75)?|max\(30, h \+ 5\)|fixed 30|their 30|\bh \+ 5",  # the env spec's constants (docs/design/envs.md)
    r"Xeon Gold \d+",  # the authors' machine, per the paper
)
ALLOWED_RE = re.compile("|".join(f"(?:{p})" for p in ALLOWED))


def typed_numbers(text: str) -> list[str]:
    """The numbers of `text` outside generated blocks and code that no ALLOWED pattern covers."""
    prose = re.sub(r"\s+", " ", CODE.sub(" ", render.BLOCK.sub(" ", text)))  # a sentence may wrap anywhere
    covered = [m.span() for m in ALLOWED_RE.finditer(prose)]
    return [f"{m[0]!r} in ...{prose[max(0, m.start() - 40):m.end() + 20]!r}" for m in NUMBER.finditer(prose)
            if not any(start <= m.start() and m.end() <= end for start, end in covered)]


@pytest.mark.parametrize("page", PAGES)
def test_no_page_types_a_number_outside_its_generated_blocks(page):
    assert typed_numbers((ROOT / page).read_text()) == []


def test_a_number_typed_into_results_is_caught():
    text = (ROOT / "docs" / "RESULTS.md").read_text()
    typed = text.replace("## Light Switch Door\n", "## Light Switch Door\n\nOurs reaches 0.93 by the end.\n", 1)
    assert typed != text and len(typed_numbers(typed)) == 1


# Statements a review of the evidence found that the records contradict, by page: none may come back.
CONTRADICTED = {
    "docs/RESULTS.md": ("close to the oracle's ceiling", "no decline", "theirs is higher", "used for nothing else",
                        "run once", "about 97 of the 100 steps"),
    "docs/results/learners.md": ("costs about as much as double DQN", "its peak memory is lower"),
    "docs/results/multi_novelty.md": ("one bridge suffices for the kinds the training task shows",),
    "docs/results/fix_length.md": ("the test seeds ran once",),
}


@pytest.mark.parametrize("page", sorted(CONTRADICTED))
def test_no_statement_the_records_contradict_comes_back(page):
    prose = re.sub(r"\s+", " ", render.BLOCK.sub(" ", (ROOT / page).read_text())).lower()
    assert [s for s in CONTRADICTED[page] if s.lower() in prose] == []


def test_the_typed_pages_are_out_of_docs_and_the_layout_names_every_study():
    assert not (ROOT / "docs" / "results" / "departures.md").exists() and not (ROOT / "docs" / "results" / "low_level.md").exists()
    layout = (ROOT / "README.md").read_text().split("## Layout", 1)[1]
    from bench.studies import NAMES
    assert [s for s in NAMES if s not in layout] == [] and "multi_novelty/" in layout
