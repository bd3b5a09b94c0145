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
    record = step._guarded_push_in(action, motion, believed.objects, believed.shelf)
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
    assert step._guarded_push_in(plain.action, plain, believed.objects, believed.shelf) is None
    # carried straight back inside the shelf, the box's back (y -0.06 m, 0.08 m ahead of the cup's seal) never leaves
    # the opening: no stop of this push-in is the board's front edge (the retry's cases: tests/systems/test_guard.py,
    # tests/systems/test_guarded_drake.py)
    from slax_drake.shelf.actions import SEAL_PRESS

    assert y[0] + (-0.06 - (action.q[1] + SEAL_PRESS)) > -believed.shelf.depth / 2.0
    assert record["edge_retry_within_m"] == 0.0 and record["edge_retry_rise_m"] == 0.0
