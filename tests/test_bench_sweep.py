"""bench.probes.sweep's reliability line (the figures docs/TUNING.md's evidence commands print) and its
config overrides; the probes' and timings' shared parser (bench/command.py) and its development seeds; where a
timing's record of uncommitted code goes."""
import numpy as np
import pytest

from bench import records
from bench.command import CommandParser
from bench.probes.sweep import reliability, swept_config
from bench.timings.training import overrides_parser


def test_the_sweeps_reliability_figures_count_late_dips_and_low_means():
    rates = np.ones((4, 60))
    rates[0, 44] = 0.6  # cycle 45: before 50, only the means count it
    rates[1, 54:56] = 0.7  # cycles 55-56: two seed-cycles below 0.8
    rates[2, 59] = 0.8  # cycle 60: 0.8 is not below 0.8
    line = reliability(rates, 0.93)
    assert "lowest mean from cycle 40 0.900" in line and "cycles from 40 with mean < 0.95: 3;" in line  # cycles 45, 55, 56
    assert "seed-cycles below 0.8 from cycle 50: 2/44" in line and "lowest mean from cycle 50 0.925" in line
    assert "cycles from 50 with mean >= 0.93: 9/11" in line
    assert "mean stays >= 0.93 from cycle 57" in line  # cycles 55-56 are the last below 0.93
    assert "mean stays >= 0.95 from cycle 1" in reliability(np.ones((2, 50)), 0.95)
    assert reliability(rates[:, :49], 0.95) == "reliability: needs 50 cycles or more"


def test_bench_overrides_are_read_as_train_py_sweep_reads_them_and_bad_ones_are_argparse_errors(capsys):
    parser = overrides_parser("bench.probes.sweep", "probe", "doorknobs", "0-0", 1)
    args = parser.parse_args(["feature_noise=0", "loop_guard=false", "hidden_sizes=64x16", "env_quirks=raw_offsets"])
    config, changes = swept_config(args)
    assert changes == {"feature_noise": 0.0, "loop_guard": False, "hidden_sizes": (64, 16), "env_quirks": ("raw_offsets",)}
    assert (config.learner.feature_noise, config.loop_guard, config.learner.hidden_sizes) == (0.0, False, (64, 16))
    assert config.env_quirks == ("raw_offsets",)
    assert swept_config(parser.parse_args(["env_quirks=none"]))[0].env_quirks == ()
    for bad, message in (("feature_noise=abc", "feature_noise: expected a number, got 'abc'"),
                         ("no_such_field=1", "expected a TrainConfig field as name=value, got 'no_such_field=1'"),
                         ("feature_noise", "expected a TrainConfig field as name=value, got 'feature_noise'")):
        with pytest.raises(SystemExit) as exit_:
            parser.parse_args([bad])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and message in err and "Traceback" not in err


def test_a_probes_seeds_are_development_seeds_read_as_a_range_and_anything_else_is_a_one_line_flag_error(capsys):
    parser = CommandParser("bench.probes.example", "probe", env="coffee", seeds="0-7")
    args = parser.parse_args([])
    assert (args.env, args.seeds, args.seed_list) == ("coffee", "0-7", list(range(8)))
    assert parser.parse_args(["--seeds", "100-115"]).seed_list == list(range(100, 116))
    for seeds, message in (("200-231", "--seeds 200-231: development seeds only"),  # a test-seed set
                           ("190-205", "--seeds 190-205: development seeds only"),  # part of one
                           ("7-3", "--seeds takes FIRST-LAST with FIRST <= LAST, got '7-3'"),
                           ("a-b", "--seeds takes FIRST-LAST with FIRST <= LAST, got 'a-b'")):
        with pytest.raises(SystemExit) as exit_:
            parser.parse_args(["--seeds", seeds])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and message in err and err.count("\n") == 1 and "Traceback" not in err
        assert err.startswith("python -m bench.probes.example: error:")
    with pytest.raises(SystemExit):
        parser.parse_args(["--env", "no_such_env"])
    assert "invalid choice: 'no_such_env'" in capsys.readouterr().err
    study = CommandParser("bench.studies.example", "study", envs=("coffee", "doorknobs"), seeds="200-231", test_seeds=True)
    assert study.parse_args(["--env", "coffee"]).seed_list == list(range(200, 232))  # a study may: it writes the ledger's row
    with pytest.raises(SystemExit):
        study.parse_args([])  # a study's --env is required among its envs
    assert "the following arguments are required: --env" in capsys.readouterr().err


def test_a_timings_record_of_uncommitted_code_goes_under_runs_dirty_records_and_only_with_allow_dirty(monkeypatch, capsys):
    record = records.RECORDS / "coffee" / "profile.json"
    monkeypatch.setattr(records, "uncommitted", lambda: ["bench/timings/example.py"])
    assert records.record_path("bench.timings.example", record, True) == records.DIRTY_RECORDS / "coffee" / "profile.json"
    with pytest.raises(SystemExit) as refused:
        records.record_path("bench.timings.example", record, False)
    assert refused.value.code == 2 and "try it out with --allow-dirty" in capsys.readouterr().err
    monkeypatch.setattr(records, "uncommitted", lambda: [])
    assert records.record_path("bench.timings.example", record, False) == record
