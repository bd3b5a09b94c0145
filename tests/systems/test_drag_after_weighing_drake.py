"""A lift weighed, put back and dragged in the same action in a Drake trial (the ``drag_after_weighing`` rule, on in
the station profile): in Table I household scene 8:6 slax-belief's second action lifts a 0.94 kg cylinder that the
floor still carries (its seal peeling: "not hanging free"); the arm puts it back, and the action model offers the drag to the same
placement at the weighed mass, so the planner plans it from where the put-back ended and the arm drags the
cylinder there. The action is judged where the drag left it, and its export (the lift up to the weighing, the
put-back, the drag) passes the independent checker. The logic on hand-built shelves: tests/shelf/test_weighed_lift.py."""

import json

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def trial(tmp_path_factory):
    from slax_drake.cli import main

    folder = tmp_path_factory.mktemp("dragged")
    # 60 s of simulated time: the first two actions and the start of the third (their outcomes are judged at its
    # decision, 52.6 s)
    assert main(["trial", "--config", "sim_configs/table1_household.yaml", "--benchmark-scene", "8:6",
                 "--policy", "slax-belief", "--max-sim-time", "60",
                 "--out", str(folder), "--quiet"]) == 0
    return folder


def test_the_put_back_lift_is_dragged_to_its_placement_and_lands_as_predicted(trial):
    from slax_drake.evaluation.physics import action_matches

    data = json.loads((trial / "trial.json").read_text())
    lift = data["actions"][1]
    weighed = lift["weighed"]
    assert weighed["put_back"] and weighed["why"] == "not hanging free"
    drag = weighed["drag_after_weighing"]
    assert drag["drag"]["grip"] == "drag" and (drag["drag"]["dx"], drag["drag"]["dz"]) == (lift["dx"], lift["dz"])
    assert drag["started_at"] > weighed["put_back_time"] + weighed["put_back_motion"]["duration_s"]
    assert lift["grip"] == "drag"  # executed as a drag
    assert lift["lost_after"] is False
    assert action_matches(lift["predicted"], lift["outcome"], lift["before"])
    assert abs(lift["outcome"]["x"] - lift["before"]["x"]) > 0.05  # it moved: the drag did, not the put-back


def test_the_lift_the_put_back_and_the_drag_export_as_three_motions_that_pass_the_checker(trial, tmp_path, capsys):
    from slax_drake.cli import main
    from slax_drake.hardware.trajectory_file import load_trajectory

    path = tmp_path / "t.json"
    assert main(["export", str(trial / "trial.json"), "--out", str(path)]) == 0
    motions = load_trajectory(path).motions
    k = next(i for i, m in enumerate(motions) if "put_back_at_s" in (m.action or {}))
    assert motions[k + 1].action.get("put_back_motion")
    assert motions[k + 2].action.get("dragged_after_weighing") and motions[k + 2].action["grip"] == "drag"
    assert motions[k + 2].start_time >= motions[k + 1].end_time
    capsys.readouterr()
    assert main(["check-trajectory", str(path)]) == 0, capsys.readouterr().out
    assert "OK: no violation" in capsys.readouterr().out
