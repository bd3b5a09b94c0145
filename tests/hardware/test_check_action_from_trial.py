"""``slax-drake check-action --from-trial DIR [--step K]``: the verdicts on a trial's scene as it stood at a decision
(each object where the trial recorded it then, the last decision by default), with the trial's station and rules;
a request it cannot serve is one line and exit code 2."""

from __future__ import annotations

import json

import pytest

from slax_drake.cli import main
from slax_drake.config import load_scenario
from slax_drake.hardware.check_action import make_checker, spec_of
from slax_drake.hardware.plan_step import trial_decision
from slax_drake.scene.io import save_scene
from slax_drake.scene.sampling import sample_scene
from slax_drake.station.scenario import load_station_scenario

STATION = "sim_configs/station_sim_shelf.yaml"
SHIFT = 0.03  # m: how far object_0 stands to the right (+x) at the second decision


@pytest.fixture()
def trial_folder(tmp_path):
    """A trial folder reduced to what --from-trial reads: scene.json and trial.json with two decisions, object_0
    moved SHIFT along x between them, and the rules the trial planned with (a cup that lifts 0.01 N m and drags
    with 0.01 N: it carries nothing)."""
    scene = sample_scene(load_scenario(load_station_scenario(STATION).scene_config), 4, 3)
    save_scene(scene, tmp_path / "scene.json")
    poses = {o.name: {"x": float(o.center[0]), "y": float(o.center[1]), "yaw": float(o.yaw)} for o in scene.objects}
    moved = {**poses, "object_0": {**poses["object_0"], "x": poses["object_0"]["x"] + SHIFT}}
    (tmp_path / "trial.json").write_text(json.dumps({
        "station": STATION, "tool_rules": {"max_suction_moment": 0.01, "max_drag_pull": 0.01},
        "steps_log": [{"step": 0, "time": 0.5, "poses_before": poses}, {"step": 1, "time": 9.0, "poses_before": moved},
                      {"step": 2, "final": True}]}))
    return tmp_path, scene


def test_the_scene_is_the_trials_at_the_decision_the_last_by_default(trial_folder):
    folder, scene = trial_folder
    first, last = trial_decision(folder, 1), trial_decision(folder)
    assert last.step == 2 and len(last.decisions) == 2  # the final entry holds no decision
    x0 = float(scene.objects[0].center[0])
    assert first.scene.objects[0].center[0] == pytest.approx(x0)
    assert last.scene.objects[0].center[0] == pytest.approx(x0 + SHIFT)
    assert [o.center[0] for o in last.scene.objects[1:]] == [o.center[0] for o in scene.objects[1:]]


def test_the_trials_rules_apply(trial_folder, capsys):
    """A suction the station's own rules admit is refused for its held moment under the rules the trial recorded."""
    folder, scene = trial_folder
    lifts = [a for a in make_checker(trial_decision(folder).scene, STATION).candidates().feasible
             if a.kind == "suction" and not getattr(a, "drag", False)]
    assert lifts, "the scene offers a lift under the station's rules"
    assert main(["check-action", "--from-trial", str(folder), "--action", spec_of(lifts[0])]) == 1
    out = capsys.readouterr().out
    assert "at decision 2 of 2" in out and "infeasible (action model)" in out


@pytest.mark.parametrize("argv, message", [
    (["--step", "3", "--all"], "decisions 1 to 2"),
    (["--step", "0", "--all"], "decisions 1 to 2"),
])
def test_a_step_the_trial_does_not_hold_is_refused(trial_folder, capsys, argv, message):
    folder, _ = trial_folder
    assert main(["check-action", "--from-trial", str(folder), *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_step_needs_from_trial_and_a_folder_without_a_trial_is_refused(trial_folder, tmp_path, capsys):
    folder, _ = trial_folder
    assert main(["check-action", "--scene", str(folder / "scene.json"), "--step", "1", "--all"]) == 2
    assert "--step applies to --from-trial only" in capsys.readouterr().err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["check-action", "--from-trial", str(empty), "--all"]) == 2
    assert "no such trial file" in capsys.readouterr().err
    with pytest.raises(SystemExit) as both:  # argparse: --scene and --from-trial are one or the other
        main(["check-action", "--scene", str(folder / "scene.json"), "--from-trial", str(folder), "--all"])
    assert both.value.code == 2
