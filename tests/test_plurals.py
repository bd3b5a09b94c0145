"""Output lines count in words that agree with their number: "1 motion", "2 pushes", never "pushs"."""

from __future__ import annotations

from pathlib import Path

from slax_drake.io import plural
from slax_drake.systems.trial_summary import trial_summary


def test_plural_agrees_with_the_number():
    assert plural(1, "motion") == "1 motion"
    assert plural(0, "motion") == "0 motions"
    assert plural(2, "push") == "2 pushes"
    assert plural(1, "push") == "1 push"
    assert plural(3, "suction event") == "3 suction events"
    assert plural(2, "box") == "2 boxes"
    assert plural(2, "axis", "axes") == "2 axes"


def _action(kind: str) -> dict:
    a = {"type": kind, "object": "segment_1", "true_object": "object_1", "rejected_before": [],
         "motion": {"duration_s": 3.0}, "planning_s": 0.4}
    return {**a, "d": 0.1} if kind == "push" else {**a, "dx": 0.1, "dz": 0.2}


def test_trial_summary_says_pushes_and_one_action():
    data = {"actions": [_action("push"), _action("push")], "steps": 2, "horizon": 12, "result": "revealed",
            "visible_fraction": 1.0, "cost": 2.0, "sim_time_s": 10.0, "wall_s": 20.0}
    text = trial_summary(data, [Path("out/trial.json")])
    assert "2 pushes" in text and "pushs" not in text and "0 suctions" in text
    data = {**data, "actions": [_action("suction")], "steps": 1, "cost": 1.5}
    text = trial_summary(data, [Path("out/trial.json")])
    assert "1 action (0 pushes, 1 suction)" in text
