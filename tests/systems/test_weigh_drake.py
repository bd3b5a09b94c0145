"""Weighing in a Drake trial: the lift that lost its object in the physics benchmark (Table I household scene 6:13,
slax-belief: a 1.05 kg cylinder sealed 6.75 cm in front of its centre, 0.69 N m against the cup's 0.64 N m lip) is
weighed at the lift, found not hanging free (the floor still carries part of it: its seal is peeling), put back
where it stood and not lost; the trial's export of the lift and its put-back passes the independent checker
(the logic on synthetic efforts: tests/systems/test_weigh.py)."""

import json

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def trial(tmp_path_factory):
    from slax_drake.cli import main

    folder = tmp_path_factory.mktemp("weighed")
    assert main(["trial", "--config", "sim_configs/table1_household.yaml", "--benchmark-scene", "6:13",
                 "--policy", "slax-belief", "--out", str(folder), "--quiet"]) == 0
    return folder


def test_a_lift_the_floor_still_carries_is_put_back_and_nothing_is_lost(trial):
    data = json.loads((trial / "trial.json").read_text())
    lift = next(a for a in data["actions"] if a.get("true_object") == "object_3" and a["type"] == "suction")
    weighed = lift["weighed"]
    assert weighed["put_back"] and weighed["why"] == "not hanging free"
    assert weighed["moment_nm"] < weighed["limit_nm"]  # the moment alone would have let it be carried
    assert weighed["lever_m"] < 0.8 * weighed["least_lever_m"]
    assert weighed["mass_kg"] * 9.81 * weighed["believed_lever_m"] > weighed["limit_nm"]  # not lifted again
    final = data["final_objects"]["object_3"]
    assert final["upright"] and final["inside"]
    later = data["actions"][data["actions"].index(lift) + 1:]
    assert not [a for a in later if a.get("true_object") == "object_3" and a.get("grip") == "lift"]


def test_the_put_back_exports_as_two_motions_that_pass_the_checker(trial, tmp_path, capsys):
    from slax_drake.cli import main
    from slax_drake.hardware.trajectory_file import load_trajectory

    path = tmp_path / "t.json"
    assert main(["export", str(trial / "trial.json"), "--out", str(path)]) == 0
    motions = load_trajectory(path).motions
    k = next(i for i, m in enumerate(motions) if "put_back_at_s" in (m.action or {}))
    assert motions[k + 1].action.get("put_back_motion")
    capsys.readouterr()
    assert main(["check-trajectory", str(path)]) == 0, capsys.readouterr().out
    assert "OK: no violation" in capsys.readouterr().out


def test_the_trial_record_holds_the_policys_decision_log(trial):
    """slax-belief keeps a record of each decision (its plan, the share of its belief the plan reveals, ...); the
    Drake trial writes it per step, one entry per decision made (one more for each candidate the planner
    rejected)."""
    data = json.loads((trial / "trial.json").read_text())
    steps = data["steps_log"]
    assert all(isinstance(step.get("decision_log"), list) for step in steps)
    executed = [step for step in steps if step.get("action")]
    assert executed and all(step["decision_log"] for step in executed)
    for step in executed:
        last = step["decision_log"][-1]
        assert last["plan"][0].startswith(step["action"]["type"])  # the plan it took starts with the executed move
        assert 0.0 <= last["revealed"] <= 1.0
