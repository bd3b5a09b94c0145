"""``benchmark`` refuses a request it cannot run as asked before it writes anything, and a trial file whose fields
are not what a trial writes with one line instead of a traceback."""

from __future__ import annotations

import json

import pytest

from slax_drake.cli import main


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("slax-drake benchmark: error:")
    return err[0]


@pytest.mark.parametrize("physics", [False, True])
def test_too_many_objects_is_refused_before_settings_are_written(tmp_path, capsys, physics):
    out = tmp_path / "b"
    args = ["benchmark", "--densities", "500", "--scenes-per-density", "1", "--policies", "dar", "--out", str(out),
            "--no-progress"] + (["--physics"] if physics else [])
    assert main(args) == 2
    assert "--densities 500" in _one_error_line(capsys)
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("option, value", [("--policies", "dar,dar"), ("--densities", "4,4")])
def test_a_policy_or_density_named_twice_is_refused(tmp_path, capsys, option, value):
    out = tmp_path / "b"
    args = ["benchmark", "--scenes-per-density", "1", "--out", str(out), "--no-progress", "--policies", "dar",
            "--densities", "4"]
    args[args.index(option) + 1] = value
    assert main(args) == 2
    line = _one_error_line(capsys)
    assert option in line and "more than once" in line
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("field, value", [("success", "yes"), ("steps", "3"), ("decision_seconds", None)])
def test_resuming_a_folder_with_a_mistyped_trial_file_is_one_line(tmp_path, capsys, field, value):
    out = tmp_path / "b"
    args = ["benchmark", "--densities", "4", "--scenes-per-density", "1", "--policies", "dar", "--out", str(out),
            "--no-progress"]
    assert main(args) == 0
    capsys.readouterr()
    (path,) = (out / "trials").glob("*/*.json")
    record = json.loads(path.read_text())
    record[field] = value
    path.write_text(json.dumps(record))
    assert main(args) == 2
    line = _one_error_line(capsys)
    assert f"'{field}'" in line and path.name in line
