"""A sideways drag weighed along its pull in a Drake trial (the ``weigh_drag_pull`` rule): in Table I household scene
4:2 slax-belief's first action drags a 1.80 kg cylinder (planned at its class's median mass) 0.20 m across, a twist
the seal does not hold (without the rule it slid 6 cm and turned 25 deg). The arm feels the floor's friction while it
pulls the cylinder out, finds the slide across over the cup's twist limit and pushes it straight back: the cylinder
ends where it stood, and the action's export (the drag up to the pull's end, the push back) passes the independent
checker. The logic on a stand-in arm: tests/systems/test_drag_weigh.py; the shelf simulator's:
tests/shelf/test_drag_pull_weigh.py."""

import json
import math

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def trial(tmp_path_factory):
    from slax_drake.cli import main

    folder = tmp_path_factory.mktemp("pulled")
    # 16 s of simulated time: the drag, its push back, and the second decision (where the first is judged)
    assert main(["trial", "--config", "sim_configs/table1_household.yaml", "--benchmark-scene", "4:2",
                 "--policy", "slax-belief", "--max-sim-time", "16", "--tool-rule", "weigh_drag_pull=true",
                 "--out", str(folder), "--quiet"]) == 0
    return folder


def test_the_drag_is_weighed_along_its_pull_and_pushed_back_where_it_stood(trial):
    from slax_drake.shelf.actions import GRAVITY

    data = json.loads((trial / "trial.json").read_text())
    scene = json.loads((trial / "scene.json").read_text())
    drag = data["actions"][0]
    assert drag["grip"] == "drag" and drag["dx"] == pytest.approx(-0.20)
    weighed = drag["weighed"]
    assert weighed["along"] == "pull" and weighed["put_back"] and weighed["why"] == "twists off the cup"
    mass = next(o["mass"] for o in scene["objects"] if o["name"] == drag["true_object"])
    assert weighed["friction_n"] == pytest.approx(0.44 * mass * GRAVITY, rel=0.25)  # the floor's friction, felt
    assert weighed["twist_nm"] > weighed["limit_nm"]
    before, out = drag["before"], drag["outcome"]
    assert math.hypot(out["x"] - before["x"], out["y"] - before["y"]) < 0.01
    assert abs(math.degrees(math.remainder(out["yaw"] - before["yaw"], 2 * math.pi))) < 5.0
    assert drag["lost_after"] is False


def test_the_drag_and_its_push_back_export_as_two_motions_that_pass_the_checker(trial, tmp_path, capsys):
    from slax_drake.cli import main
    from slax_drake.hardware.trajectory_file import load_trajectory

    path = tmp_path / "t.json"
    assert main(["export", str(trial / "trial.json"), "--out", str(path)]) == 0
    motions = load_trajectory(path).motions
    assert "put_back_at_s" in (motions[0].action or {}) and motions[1].action.get("put_back_motion")
    capsys.readouterr()
    assert main(["check-trajectory", str(path)]) == 0, capsys.readouterr().out
    assert "OK: no violation" in capsys.readouterr().out
