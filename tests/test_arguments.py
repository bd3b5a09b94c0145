"""Command-line values refused while parsing, before anything is written: one error line naming the argument,
exit code 2 (argparse prints its usage line above it)."""

import argparse

import pytest

from slax_drake import arguments
from slax_drake.cli import main

SEED_ERROR = "argument --seed: must be an integer in [0, 2^63 - 1], got '-1'"


def _refused(argv, capsys) -> str:
    """Runs the command line, expects the parser's refusal (exit code 2, one line) and returns that line less its
    pointer to --help."""
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    (line,) = err.strip().splitlines()
    message, _, see = line.rpartition(" (see ")
    assert see == f"slax-drake {argv[0]} --help)"
    return message


@pytest.mark.parametrize("argv", [
    ["scene", "--out", "out/scene.json"],
    ["dataset", "--scenes", "2", "--out", "out/data"],
    ["benchmark", "--out", "out/table1"],
    ["trial", "--out", "out/trial"],
    ["train", "--data", "out/data", "--out", "out/model"],
])
def test_negative_seed_is_refused_before_anything_is_written(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    line = _refused(argv + ["--seed", "-1"], capsys)
    assert line == f"slax-drake {argv[0]}: error: {SEED_ERROR}"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind, text, message", [
    (arguments.seed, "2.5", "must be an integer, got '2.5'"),
    (arguments.seed, str(2**63), "must be an integer in [0, 2^63 - 1], got '9223372036854775808'"),
    (arguments.non_negative_int, "-3", "must be an integer >= 0, got '-3'"),
    (arguments.positive_int, "0", "must be a positive integer, got '0'"),
    (arguments.positive_float, "0", "must be a positive number, got '0'"),
    (arguments.positive_float, "nan", "must be a finite number, got 'nan'"),
    (arguments.non_negative_float, "-1e-9", "must be a number >= 0, got '-1e-9'"),
    (arguments.non_negative_float, "inf", "must be a finite number, got 'inf'"),
    (arguments.positive_float, "one", "must be a number, got 'one'"),
])
def test_value_types_refuse_with_the_value(kind, text, message):
    with pytest.raises(argparse.ArgumentTypeError) as info:
        kind(text)
    assert str(info.value) == message


def test_value_types_accept_their_range():
    assert arguments.seed("0") == 0 and arguments.seed(str(2**63 - 1)) == 2**63 - 1
    assert arguments.non_negative_int("0") == 0 and arguments.positive_int("7") == 7
    assert arguments.positive_float("1e-3") == 1e-3 and arguments.non_negative_float("0") == 0.0


@pytest.mark.parametrize("argv, error", [
    (["trial", "--max-sim-time", "-1", "--out", "out/trial"],
     "slax-drake trial: error: argument --max-sim-time: must be a positive number, got '-1'"),
    (["trial", "--max-sim-time", "nan", "--out", "out/trial"],
     "slax-drake trial: error: argument --max-sim-time: must be a finite number, got 'nan'"),
    (["check-trajectory", "traj.json", "--margin", "-1"],
     "slax-drake check-trajectory: error: argument --margin: must be a number >= 0, got '-1'"),
    (["check-trajectory", "traj.json", "--collision-step", "-0.1"],
     "slax-drake check-trajectory: error: argument --collision-step: must be a number >= 0, got '-0.1'"),
    (["export", "trial.json", "--rate", "0", "--out", "out/t.json"],
     "slax-drake export: error: argument --rate: must be a positive number, got '0'"),
])
def test_negative_times_and_margins_are_refused(argv, error, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert _refused(argv, capsys) == error
    assert list(tmp_path.iterdir()) == []
