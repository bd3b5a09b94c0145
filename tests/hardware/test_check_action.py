"""slax-drake check-action (issue 17 item 5): one action's verdict on a scene (the action model, then the motion
planner) as a function and a command; --all lists every candidate with its verdict, a table and a picture."""

import json

import pytest

from slax_drake.cli import main
from slax_drake.errors import ActionSpecError
from slax_drake.hardware.check_action import check_action, check_all, parse_action, spec_of
from slax_drake.scene.io import save_scene
from slax_drake.scene.sampling import sample_scene


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory, sim_scenario):
    path = tmp_path_factory.mktemp("check_action") / "scene.json"
    save_scene(sample_scene(sim_scenario, 4, seed=3), path)
    return path


def test_action_specs_parse_and_bad_ones_are_refused():
    assert parse_action("push:object_2:+0.10") == ("push", "object_2", 0.10)
    assert parse_action("suction:object_1:-0.05:0.1") == ("suction", "object_1", -0.05, 0.1)
    for bad in ("push:object_2", "push:object_2:far", "lift:object_2:0.1", "suction:object_1:0.1", "push::0.1"):
        with pytest.raises(ActionSpecError):
            parse_action(bad)


@pytest.mark.parametrize("argv, message", [
    (["--action", "push:object_0:0.05x"], "expected push:OBJECT:D"),
    (["--action", "push:nothing:0.05"], "no object named 'nothing'"),
    (["--action", "push:object_0:0"], "non-zero distance"),
    (["--action", "push:object_0:0.05", "--png", "x.png"], "--png applies to --all only"),
])
def test_bad_input_is_one_line_and_exit_2(scene_file, capsys, argv, message):
    assert main(["check-action", "--scene", str(scene_file), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_missing_scene_file_exits_2(tmp_path, capsys):
    assert main(["check-action", "--scene", str(tmp_path / "none.json"), "--action", "push:object_0:0.1"]) == 2
    assert "cannot read scene file" in capsys.readouterr().err


def test_an_action_the_model_refuses_says_why_without_planning(scene_file, capsys, tmp_path):
    # object_0 of this scene stands behind the others: every push of it is refused by the action model
    check = check_action(scene_file, "push:object_0:+0.05")
    assert not check.feasible and check.stage == "action model" and check.reason and check.timings == {}
    out = tmp_path / "v.json"
    assert main(["check-action", "--scene", str(scene_file), "--action", "push:object_0:+0.05",
                 "--json", str(out)]) == 1
    assert "infeasible (action model)" in capsys.readouterr().out
    assert json.loads(out.read_text())[0]["stage"] == "action model"


@pytest.mark.slow
def test_all_candidates_are_listed_with_verdicts_and_each_one_rechecks_alone(scene_file, tmp_path, capsys):
    checker, checks = check_all(scene_file)
    planned = [c for c in checks if c.planned is not None]
    assert planned and any(c.feasible for c in planned)
    for c in planned:
        if c.feasible:
            assert c.duration_s > 0 and set(c.timings) == {"ik_s", "check_s", "timing_s", "total_s"}
        else:
            assert c.stage == "motion" and c.reason
    # one feasible candidate checked alone through the command gives the same verdict
    first = next(c for c in planned if c.feasible)
    assert main(["check-action", "--scene", str(scene_file), "--action", spec_of(first.planned)]) == 0
    assert capsys.readouterr().out.startswith(f"{spec_of(first.planned)}: feasible, motion ")
    png = tmp_path / "all.png"
    assert main(["check-action", "--scene", str(scene_file), "--all", "--png", str(png)]) == 0
    out = capsys.readouterr().out
    assert f"{len(checks)} candidates: {sum(c.feasible for c in checks)} feasible" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
