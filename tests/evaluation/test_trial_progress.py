"""A trial prints one line per decision as it happens: the action on its camera segment, the planning time and,
once the next decision shows it, the outcome against the prediction."""

from __future__ import annotations

import io

import pytest

from slax_drake.evaluation.trial_progress import DecisionPrinter
from slax_drake.systems.evaluator import Snapshot


def _snap(t, x, lost=(), visible=0.0):
    return Snapshot(t, visible, tuple(lost), {"object_4": (x, 0.1, 0.0), "object_1": (0.2, 0.0, 0.0)},
                    {"segment_2": "object_4"})


def _decision(step, t, d=-0.10, rejected=0, predicted_x=-0.05):
    return {"step": step, "time": t, "action": {"type": "push", "object": "segment_2", "d": d},
            "planning_s": 0.42, "rejected": [{}] * rejected,
            "predicted_objects": {"object": "segment_2", "x": predicted_x, "y": 0.1, "yaw": 0.0}}


def test_a_line_opens_at_the_decision_and_closes_with_the_outcome():
    out = io.StringIO()
    printer = DecisionPrinter(12, out)
    log = (_decision(0, 0.5, rejected=1),)
    snaps = (_snap(0.5, 0.05),)
    printer.update(log, snaps)
    assert out.getvalue() == "step 1/12: push segment_2 -0.100 m, planned in 0.4 s after 1 rejected candidate, "
    log += (_decision(1, 20.0, d=+0.05, predicted_x=0.0),)
    snaps += (_snap(20.0, -0.045),)
    printer.update(log, snaps)
    lines = out.getvalue().splitlines()
    assert lines[0].endswith("executed, object_4 moved as predicted")
    assert lines[1] == "step 2/12: push segment_2 +0.050 m, planned in 0.4 s, "
    log += ({"step": 2, "time": 40.0, "final": True, "result": "revealed"},)
    snaps += (_snap(40.0, 0.04, visible=0.96),)
    printer.update(log, snaps)
    lines = out.getvalue().splitlines()
    assert lines[1].endswith("executed, object_4 ended 4.0 cm from the prediction")
    assert lines[2] == "done after 2 actions: target revealed (96% of it visible)"


def test_a_lost_object_and_a_trial_stopped_during_a_motion():
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    printer.update((_decision(0, 0.5),), (_snap(0.5, 0.05),))
    printer.finish({"object_4": {"x": 0.4, "y": 0.1, "yaw": 0.0, "upright": False, "inside": False},
                    "object_1": {"x": 0.2, "y": 0.0, "yaw": 0.0, "upright": True, "inside": True}})
    assert out.getvalue().endswith("executed, object_4 was lost (toppled or off the shelf)\n")


def test_no_feasible_action_says_how_many_candidates_had_no_motion():
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    printer.update(({"step": 0, "time": 0.5, "final": True, "result": "no feasible motion",
                     "rejected": [{}, {}]},), (_snap(0.5, 0.0),))
    assert out.getvalue() == ("done after 0 actions: target not revealed: no candidate action had a collision-free "
                              "motion (0% of it visible); 2 candidates without a motion\n")
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    printer.update(({"step": 0, "time": 0.5, "final": True, "result": "no feasible motion", "rejected": [{}, {}],
                     "reasons": [{"stage": "motion planner", "kind": "no IK solution", "count": 2}]},),
                   (_snap(0.5, 0.0),))
    assert out.getvalue().endswith("2 candidates without a motion; most often motion planner: no IK solution "
                                   "(2 candidates)\n")


@pytest.mark.slow
def test_the_default_trial_prints_its_decisions_on_stderr(tmp_path, capfd):
    from slax_drake.cli import main

    assert main(["trial", "--out", str(tmp_path / "t")]) == 0
    out, err = capfd.readouterr()
    lines = [line for line in err.splitlines() if line.startswith(("step ", "done after"))]
    assert lines[0].startswith("step 1/") and "planned in" in lines[0] and "executed" in lines[0]
    assert lines[-1].startswith("done after")
    assert "== trial summary ==" in out and "step 1/" not in out
    assert (tmp_path / "t" / "object_poses.npz").is_file()  # what view-trial replays the objects from


def test_a_drag_says_so_in_its_line():
    out = io.StringIO()
    printer = DecisionPrinter(8, out)
    entry = {"step": 0, "time": 0.5, "planning_s": 0.2, "rejected": [],
             "action": {"type": "suction", "object": "segment_2", "dx": 0.3, "dz": -0.181, "grip": "drag"},
             "predicted_objects": {"object": "segment_2", "x": 0.2, "y": -0.181, "yaw": 0.0}}
    printer.update((entry,), (_snap(0.5, 0.05),))
    assert out.getvalue() == "step 1/8: suction segment_2 by +0.300 m to y = -0.181 m (dragged), planned in 0.2 s, "


def test_a_tracked_object_is_judged_through_its_segment_in_that_frame():
    """The policy names a tracked object (``track_<k>``); the entry's ``segment_of`` gives its segment in the
    frame, which the referee maps to the true object."""
    out = io.StringIO()
    printer = DecisionPrinter(12, out)
    first = _decision(0, 0.5)
    first["action"]["object"] = "track_3"
    first["segment_of"] = {"track_3": "segment_2"}
    printer.update((first,), (_snap(0.5, 0.05),))
    printer.update((first, {"step": 1, "time": 20.0, "final": True, "result": "horizon"}), (_snap(0.5, 0.05),
                                                                                           _snap(20.0, -0.045)))
    assert out.getvalue().splitlines()[0] == ("step 1/12: push track_3 -0.100 m, planned in 0.4 s, executed, "
                                              "object_4 moved as predicted")


def test_a_guarded_placement_says_whether_it_stopped_on_contact():
    """The record the PlannerSystem adds to the action's entry during its motion (a new entry replaces the old one)
    is read when the line closes."""
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    entry = {**_decision(0, 0.5), "action": {"type": "suction", "object": "segment_2", "dx": 0.0, "dz": 0.15,
                                             "grip": "lift", "guarded": True}}
    printer.update((entry,), (_snap(0.5, 0.05),))
    stopped = {**entry, "guarded": {"guarded": True, "stopped": True, "pushed_in_m": 0.212, "short_m": 0.07}}
    printer.update((stopped, {"step": 1, "time": 20.0, "final": True, "result": "horizon"}),
                   (_snap(0.5, 0.05), _snap(20.0, -0.05)))
    assert out.getvalue().splitlines()[0].endswith(
        "planned in 0.4 s, guarded, stopped on contact after 0.212 m, executed, object_4 moved as predicted")
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    printer.update((entry,), (_snap(0.5, 0.05),))
    done = {**entry, "guarded": {"guarded": True, "stopped": False}}
    printer.update((done, {"step": 1, "time": 20.0, "final": True, "result": "horizon"}),
                   (_snap(0.5, 0.05), _snap(20.0, -0.05)))
    assert "planned in 0.4 s, guarded, completed, executed" in out.getvalue()


def test_a_lift_weighed_and_put_back_says_so():
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    lift = {**_decision(0, 0.5), "weighed": {"weight_n": 7.81, "moment_nm": 0.3735, "put_back": True,
                                             "why": "not hanging free"}}
    printer.update((lift, _decision(1, 20.0)), (_snap(0.5, 0.05), _snap(20.0, 0.05)))
    assert out.getvalue().splitlines()[0].endswith(
        "planned in 0.4 s, weighed 7.8 N hanging 0.37 N m off the cup, not hanging free: put back")


def test_a_drag_weighed_along_its_pull_and_pushed_back_says_so():
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    drag = {**_decision(0, 0.5), "weighed": {"along": "pull", "friction_n": 8.497, "twist_nm": 1.0677,
                                             "limit_nm": 0.6362, "put_back": True, "why": "twists off the cup"}}
    printer.update((drag, _decision(1, 20.0)), (_snap(0.5, 0.05), _snap(20.0, 0.05)))
    assert out.getvalue().splitlines()[0].endswith(
        "planned in 0.4 s, weighed along the pull: 8.5 N of friction, a twist of 1.07 N m across > 0.64, "
        "twists off the cup: pushed back")


def test_a_belief_policys_line_says_what_its_plan_reveals_or_that_it_found_none():
    out = io.StringIO()
    printer = DecisionPrinter(8, out)
    first = {**_decision(0, 0.5), "decision_log": [{"revealed": 0.6094, "plan": ["push segment_2 d=-0.100"]}]}
    stalled = {**_decision(1, 20.0), "decision_log": [{"revealed": 0.0, "widened": True}]}
    printer.update((first,), (_snap(0.5, 0.05),))
    printer.update((first, stalled), (_snap(0.5, 0.05), _snap(20.0, -0.05)))
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("step 1/8: push segment_2 -0.100 m (its plan reveals 61% of the belief), planned in")
    assert lines[1].startswith("step 2/8: push segment_2 -0.100 m (no plan reveals any place the target may stand: "
                               "moving on), planned in 0.4 s")
    plain = io.StringIO()  # a policy without a decision log (Bluction-DAR): nothing added
    DecisionPrinter(8, plain).update((_decision(0, 0.5),), (_snap(0.5, 0.05),))
    assert plain.getvalue() == "step 1/8: push segment_2 -0.100 m, planned in 0.4 s, "


def test_a_guarded_placement_retried_at_the_boards_edge_says_so():
    """A push-in stopped at the board's front edge and pushed in again higher: the line names both."""
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    entry = {**_decision(0, 0.5), "action": {"type": "suction", "object": "segment_2", "dx": -0.5, "dz": -0.08,
                                             "grip": "lift", "guarded": True}}
    printer.update((entry,), (_snap(0.5, 0.05),))
    edge = {"guarded": True, "stopped": True, "pushed_in_m": 0.0186, "short_m": 0.21, "edge": True}
    done = {**entry, "guarded": {"guarded": True, "stopped": False, "edge_stop": edge}}
    printer.update((done, {"step": 1, "time": 20.0, "final": True, "result": "horizon"}),
                   (_snap(0.5, 0.05), _snap(20.0, -0.05)))
    assert ("planned in 0.4 s, guarded, stopped at the board's front edge after 0.019 m and pushed in again higher, "
            "completed, executed") in out.getvalue()
    # an unguarded lift's push-in, watched at the edge only: no "guarded"
    out = io.StringIO()
    printer = DecisionPrinter(6, out)
    plain = {**entry, "action": {**entry["action"], "guarded": False}}
    printer.update((plain,), (_snap(0.5, 0.05),))
    done = {**plain, "guarded": {"guarded": False, "edge_only": True, "stopped": False, "edge_stop": edge}}
    printer.update((done, {"step": 1, "time": 20.0, "final": True, "result": "horizon"}),
                   (_snap(0.5, 0.05), _snap(20.0, -0.05)))
    assert ("planned in 0.4 s, stopped at the board's front edge after 0.019 m and pushed in again higher, "
            "executed") in out.getvalue()
