"""A trial that ends with no action to execute records why: the action model's refusals and the planner's
rejections by typed kind, and its summary names the most frequent and the command that lists every candidate."""

from __future__ import annotations

from pathlib import Path

import pytest

from slax_drake.config import load_scenario
from slax_drake.planning.failures import FailureKind
from slax_drake.policies.registry import make_policy
from slax_drake.scene.sampling import sample_scene
from slax_drake.shelf.actions import RefusalKind
from slax_drake.systems.planner import stop_record
from slax_drake.systems.trial_summary import trial_summary


def test_stop_record_counts_every_refusal_by_kind():
    scenario = load_scenario("sim_configs/table1.yaml")
    scene = sample_scene(scenario, 10, 1, target_size=(0.06, 0.06, 0.06))
    policy = make_policy("bluction-dar", scenario, horizon=4, profile="station")
    planner_rejected = [{"action": "push object_1 d=+0.100", "reason": "insert: tool pose out of reach",
                         "kind": FailureKind.NO_IK_SOLUTION.value, "waypoint": "insert"}]
    record = stop_record(policy, scene.objects, planner_rejected, "no feasible action")
    assert record["stop_reason"] == "no feasible action"
    assert record["refused"], "ten objects on the station's rules: some candidates are refused"
    kinds = {k.value for k in RefusalKind}
    assert all(r["kind"] in kinds for r in record["refused"])
    counts = record["reasons"]
    assert sum(r["count"] for r in counts if r["stage"] == "action model") == len(record["refused"])
    assert {"stage": "motion planner", "kind": "no IK solution", "count": 1} in counts
    assert [r["count"] for r in counts] == sorted((r["count"] for r in counts), reverse=True)
    assert record["excluded"] == []


def _ended(result: str, last: dict) -> dict:
    return {"actions": [], "steps": 0, "horizon": 12, "result": result, "visible_fraction": 0.0, "cost": 0.0,
            "sim_time_s": 1.0, "wall_s": 2.0, "station": "sim_configs/station_sim_shelf.yaml",
            "steps_log": [{"step": 0, "final": True, "result": result, **last}]}


def test_summary_names_the_most_frequent_reason_and_check_action():
    last = {"rejected": [], "refused": [{"candidate": "push:object_1:+x", "kind": "hidden space", "reason": "..."}] * 3,
            "feasible_left": 0, "stop_reason": "no feasible action",
            "reasons": [{"stage": "action model", "kind": "hidden space", "count": 3}]}
    text = trial_summary(_ended("no feasible action", last), [Path("out/trial.json"), Path("out/scene.json")])
    assert "refused 3 candidates" in text
    assert "most frequent: action model: hidden space (3 candidates)" in text
    assert "as it stood at the last decision): slax-drake check-action --from-trial out --all" in text
    motion = {**last, "rejected": [{"action": "push track_5 d=+0.030", "kind": "tool collides"}]}
    assert ("the motion planner rejected 1; then the policy had none left (no feasible action)"
            in trial_summary(_ended("no feasible motion", motion), [Path("out/trial.json")]))
    revealed = trial_summary({**_ended("revealed", last)}, [Path("out/trial.json")])
    assert "check-action" not in revealed


def test_summary_says_the_policy_stopped_when_no_plan_reveals_the_target():
    from slax_drake.policies.protocol import NO_REVEALING_PLAN

    last = {"rejected": [], "refused": [], "feasible_left": 5, "stop_reason": NO_REVEALING_PLAN, "reasons": []}
    text = trial_summary(_ended(NO_REVEALING_PLAN, last), [Path("out/trial.json")])
    assert "outcome: target not revealed: the policy stopped, no plan of it reveals the target" in text
    assert "check-action" not in text  # candidates were left; the policy chose to stop


@pytest.mark.slow
def test_trial_ending_with_no_feasible_action_records_its_reasons(tmp_path):
    """The default station, six objects, seed 2, the density masses (tests/scenarios): the policy has no feasible
    action at its first decision."""
    from slax_drake.cli import main

    assert main(["trial", "--config", "tests/scenarios/sim_shelf_density.yaml", "--objects", "6", "--seed", "2",
                 "--out", str(tmp_path), "--quiet"]) == 0
    import json

    data = json.loads((tmp_path / "trial.json").read_text())
    assert data["result"] in ("no feasible action", "no feasible motion")
    last = data["steps_log"][-1]
    assert last["reasons"] and (last["refused"] or last["rejected"])
    assert all(r["kind"] for r in last["refused"] + last["rejected"])


def test_the_trial_summary_names_the_mass_model_when_the_record_keeps_it():
    """Issue 27's decision: every report names the mass model; a record from before it was kept names none."""
    data = {"actions": [], "steps": 0, "horizon": 6, "result": "revealed", "visible_fraction": 1.0, "cost": 0.0,
            "sim_time_s": 1.0, "wall_s": 1.0}
    assert "masses:" not in trial_summary(data, [Path("out/trial.json")])
    for model, words in (("household", "household goods' masses by shape and volume"),
                         ("density", "objects.density x volume")):
        text = trial_summary({**data, "mass_model": model}, [Path("out/trial.json")])
        assert f"masses:  {words} (physics.mass_model: {model})" in text
