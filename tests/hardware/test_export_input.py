"""``slax-drake export`` refuses bad input with one line and exit code 2, before writing anything."""

import json

import pytest
from trial_records import fake_trial

from slax_drake.cli import main


@pytest.fixture()
def trial(tmp_path):
    data = {k: v for k, v in fake_trial().items() if k != "full_trajectory"}
    return tmp_path, data


def _write(tmp_path, data, name="trial.json"):
    path = tmp_path / name
    path.write_text(json.dumps(data))  # Python's json writes NaN as the JSON extension token
    return path


def _one_line_error(capsys, *needles):
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    for n in needles:
        assert n in err, err
    return err


def test_a_seed_that_is_not_an_integer(trial, capsys):
    tmp_path, data = trial
    data["seed"] = "seven"
    assert main(["export", str(_write(tmp_path, data)), "--out", str(tmp_path / "t.json")]) == 2
    _one_line_error(capsys, "'seed' must be an integer", "'seven'")
    assert not (tmp_path / "t.json").exists()


@pytest.mark.parametrize("out", ["t.json", "t.yaml", "t.csv"])
@pytest.mark.parametrize("field", ["positions", "velocities", "times"])
def test_nan_in_the_executed_trajectory(trial, capsys, out, field):
    tmp_path, data = trial
    data["executed_trajectory"][field][5] = (float("nan") if field == "times"
                                             else [float("nan")] + data["executed_trajectory"][field][5][1:])
    assert main(["export", str(_write(tmp_path, data)), "--out", str(tmp_path / out), "--scene",
                 str(_scene(tmp_path))]) == 2
    _one_line_error(capsys, f"executed_trajectory.{field} holds a non-finite value")
    assert not (tmp_path / out).exists()


def _scene(tmp_path):
    from slax_drake.config import load_scenario
    from slax_drake.scene.io import save_scene
    from slax_drake.scene.sampling import sample_scene

    path = tmp_path / "scene.json"
    save_scene(sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), 2, seed=3), path)
    return path


@pytest.mark.parametrize("fmt,out,use", [("csv", "t.json", "t.csv"), ("ros-yaml", "t.csv", "t.yaml"),
                                          ("ros-json", "t.yml", "t.json")])
def test_the_extension_must_match_the_format(trial, capsys, fmt, out, use):
    tmp_path, data = trial
    assert main(["export", str(_write(tmp_path, data)), "--format", fmt, "--out", str(tmp_path / out)]) == 2
    _one_line_error(capsys, "the extension must match the format", use)
    assert not (tmp_path / out).exists()


@pytest.mark.parametrize("fmt", [[], ["--format", "mcap"], ["--format", "csv"]])
def test_an_empty_out(trial, capsys, fmt):
    tmp_path, data = trial
    assert main(["export", str(_write(tmp_path, data)), "--out", "", *fmt]) == 2
    err = _one_line_error(capsys, "--out is empty")
    assert "busy" not in err


def test_the_bag_writers_error_names_the_users_path(trial, capsys, tmp_path):
    _, data = trial
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    out = blocker / "bag"  # its parent is a file: nothing can be written under it
    assert main(["export", str(_write(tmp_path, data)), "--format", "mcap", "--out", str(out), "--scene",
                 str(_scene(tmp_path))]) == 2
    err = _one_line_error(capsys, str(out))
    assert ".partial" not in err and ".bag." not in err
