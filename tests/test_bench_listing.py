"""`python -m bench`: every study, page, timing and probe with a line each, saying how it runs (a module
without a command is one page's blocks, which bench.pages.render renders) and its docstring's first sentence."""
import ast
import re

from bench import __main__ as bench
from bench.pages import render


def first_paragraph(path) -> str:
    return (ast.get_docstring(ast.parse(path.read_text())) or "").split("\n\n")[0]


def test_python_m_bench_lists_every_study_page_timing_and_probe_with_a_line_each(capsys):
    assert bench.main([]) == 0
    commands = [re.split(r"\s{2,}", line.strip())[0] for line in capsys.readouterr().out.splitlines() if line.startswith("  ")]
    listed = [next(word for word in command.split() if word.startswith("bench.")) for command in commands]
    assert len(listed) == len(set(listed))
    for kind in bench.KINDS:
        for path in sorted((bench.HERE / kind).glob("*.py")):
            if path.stem == "__init__":
                continue
            module = f"bench.{kind}.{path.stem}"
            runs = bench.command(f"{kind}.{path.stem}", path)
            assert module in listed and runs in commands, module
            if runs == module:  # no command: its blocks are rendered
                assert path.stem in vars(render), f"{module}: neither a command nor a page that bench.pages.render renders"
            paragraph, sentence = " ".join(first_paragraph(path).split()), bench.first_sentence(path)
            assert paragraph[len(sentence):].startswith(".") or sentence.endswith(("?", ")")), f"{module}: a cut sentence"
    assert bench.command("timings.pytest_compile_time", bench.HERE / "timings" / "pytest_compile_time.py") == \
        "python -m pytest -p bench.timings.pytest_compile_time"  # a plugin: the command its docstring prints
    assert {"bench.ledger", "bench.regenerate"} <= set(listed)


def test_python_m_bench_takes_no_arguments(capsys):
    assert bench.main(["--env", "coffee"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
