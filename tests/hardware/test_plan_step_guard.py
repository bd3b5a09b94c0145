"""plan-step tells the arm's controller which part of a guarded suction to run as a guarded move: the push-in's
time window and the stop force, as the Drake trial's guard uses them (the guard itself: tests/systems/test_guard.py,
tests/systems/test_guarded_drake.py)."""

import dataclasses

import pytest

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

pytestmark = pytest.mark.slow  # plans a motion


def _box(name, x, y, size, mass):
    return SceneObject(name, "box", size, planar_pose(x, y, size[2] / 2, 0.0), mass=mass)


def test_a_guarded_suction_s_push_in_window_and_stop_force_go_into_the_step_file(sim_scenario):
    from slax_drake.hardware.plan_step import StepPlanner
    from slax_drake.systems.guard import push_in_forces, push_in_window

    step = StepPlanner("sim_configs/station_sim_shelf.yaml", policy="slax-belief")
    assert step.tool_rules["suction_hidden_rule"] == "guarded"  # the shipped station places by guarded moves
    wall = _box("object_0", -0.12, -0.15, (0.30, 0.06, 0.30), 0.3)
    carried = _box("object_1", 0.20, -0.10, (0.08, 0.08, 0.10), 0.3)
    believed = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (wall, carried), None, 0)
    model = step.policy.action_model
    action = next(a for a in model.enumerate(believed.objects, pushes=False, only=("object_1",)).feasible
                  if a.guarded and a.grip == "lift" and abs(a.dx) < 1e-9 and abs(a.dz - 0.25) < 1e-9)
    motion = step.motion_planner.plan(action, believed)
    assert motion.feasible, motion.reason
    record = step._guarded_push_in(action, motion, believed.objects)
    t0, t1 = push_in_window(motion)
    assert (record["t_start_s"], record["t_end_s"]) == (round(t0, 4), round(t1, 4))
    assert 0.0 < t0 < t1 <= motion.trajectory.duration
    stop, expected = push_in_forces(action, carried, model, step.station.guarded_stop_force,
                                    step.station.suction.lip_moment)
    assert record["stop_force_n"] == round(stop, 3) and record["expected_resistance_n"] == 0.0
    assert 0.0 < stop <= step.station.guarded_stop_force
    # the window is the push into the shelf: the cup moves in (S +y) by most of the placement's depth
    world = step.motion_planner.world(believed)
    frame = motion.waypoints[0].frame
    y = [float(world.tool_pose_S(motion.trajectory.value(t)[0], frame).translation()[1]) for t in (t0, t1)]
    assert y[1] - y[0] > 0.1
    plain = dataclasses.replace(motion, action=dataclasses.replace(action, guarded=False))
    assert step._guarded_push_in(plain.action, plain, believed.objects) is None


def test_a_lifted_suction_s_weighing_goes_into_the_step_file(sim_scenario):
    """A lift's weighing (when, against which limit, weight and least lever) for the controller; none for a drag."""
    from types import SimpleNamespace

    from slax_drake.hardware.plan_step import StepPlanner
    from slax_drake.systems.guard import FREE_HANG_SHARE, MIN_HELD_WEIGHT, weigh_time

    step = StepPlanner("sim_configs/station_sim_shelf.yaml", policy="slax-belief")
    carried = _box("object_1", 0.20, -0.10, (0.08, 0.08, 0.10), 0.3)
    believed = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (carried,), None, 0)
    model = step.policy.action_model
    action = next(a for a in model.enumerate(believed.objects, pushes=False, only=("object_1",)).feasible
                  if a.grip == "lift")
    motion = step.motion_planner.plan(action, believed)
    assert motion.feasible, motion.reason
    seen = SimpleNamespace(object=carried, uncertainty=SimpleNamespace(depth=(0.04, 0.2)))
    record = step._weigh_at_lift(action, motion, SimpleNamespace(hypotheses=[seen]))
    assert record["t_s"] == round(weigh_time(motion), 4) and 0.0 < record["t_s"] < motion.trajectory.duration
    assert record["limit_nm"] == model.tool.rules.max_suction_moment == 0.4
    assert record["min_weight_n"] == MIN_HELD_WEIGHT and record["free_hang_share"] == FREE_HANG_SHARE
    assert record["least_lever_m"] == pytest.approx(0.5 * (carried.center[1] - action.q[1]), abs=2e-3)
    drag = dataclasses.replace(motion, action=dataclasses.replace(action, drag=True))
    assert step._weigh_at_lift(drag.action, drag, SimpleNamespace(hypotheses=[seen])) is None


def test_a_sideways_drag_s_weighing_along_its_pull_goes_into_the_step_file(sim_scenario):
    """Under the ``weigh_drag_pull`` rule a sideways drag's pull weighing (when, and the friction over which the arm
    pushes the object back) for the controller; none for a straight drag or with the rule off."""
    from types import SimpleNamespace

    from slax_drake.hardware.plan_step import StepPlanner
    from slax_drake.policies.registry import make_policy
    from slax_drake.systems.drag_weigh import END_MARGIN, SLIDING_TRAVEL, pull_window

    step = StepPlanner("sim_configs/station_sim_shelf.yaml", policy="slax-belief")
    heavy = _box("object_1", 0.0, -0.10, (0.10, 0.16, 0.10), 0.7)  # 0.55 N m held: dragged, 0.36 N m of twist
    believed = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (heavy,), None, 0)
    known = SimpleNamespace(known=[heavy])
    step.tool_rules = {**step.tool_rules, "weigh_drag_pull": True}
    step.policy = make_policy("slax-belief", step.scenario, tool_overrides=step.tool_rules)
    rules = step.policy.action_model.tool.rules
    drags = [a for a in step.policy.action_model.enumerate(believed.objects, pushes=False).feasible if a.drag]
    sideways = next(a for a in drags if abs(a.dx) > 1e-9)
    motion = step.motion_planner.plan(sideways, believed)
    assert motion.feasible, motion.reason
    record = step._weigh_along_pull(sideways, motion, known)
    t_base, t0, t1, t_decide = pull_window(motion)
    assert (record["t_base_s"], record["t_start_s"], record["t_end_s"], record["t_decide_s"]) == tuple(
        round(t, 4) for t in (t_base, t0, t1, t_decide))
    assert 0.0 < t_base < t0 < t1 < t_decide < motion.trajectory.duration
    lever = ((heavy.center[0] - sideways.q[0]) ** 2 + (heavy.center[1] - sideways.q[1]) ** 2) ** 0.5
    assert record["lever_m"] == pytest.approx(lever, abs=1e-4)
    assert record["max_friction_n"] == pytest.approx(rules.max_drag_twist / (rules.drag_safety_factor * lever),
                                                     abs=1e-3)
    assert (record["sliding_after_m"], record["end_margin_m"]) == (SLIDING_TRAVEL, END_MARGIN)
    straight = next(a for a in drags if abs(a.dx) < 1e-9)
    assert step._weigh_along_pull(straight, step.motion_planner.plan(straight, believed), known) is None
    step.policy = make_policy("slax-belief", step.scenario, tool_overrides={**step.tool_rules,
                                                                           "weigh_drag_pull": False})
    assert step._weigh_along_pull(sideways, motion, known) is None
