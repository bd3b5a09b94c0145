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


def test_an_unguarded_lift_from_outside_the_bay_tells_the_controller_to_watch_for_the_boards_edge(sim_scenario):
    """Table I 10:4's tenth decision (tests/systems/test_guarded_drake.py): an unguarded lift carried out of the bay
    and back in. The step file's edge_watch says how far into the push-in a stop is the board's edge; the same
    action guarded has none (its guarded_push_in says it), and so has a push."""
    from tests.systems.test_guarded_drake import SCENE_10_4_BELIEVED

    from slax_drake.hardware.plan_step import StepPlanner
    from slax_drake.planning.planner import EDGE_RETRY_RISE
    from slax_drake.shelf.actions import Push, SEAL_PRESS, Suction
    from slax_drake.systems.guard import EDGE_BAND, push_in_of

    step = StepPlanner("sim_configs/station_sim_shelf.yaml", policy="slax-belief")
    believed = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), tuple(
        SceneObject(name, shape, size, planar_pose(x, y, size[2] / 2, yaw))
        for name, (shape, size, x, y, yaw) in SCENE_10_4_BELIEVED.items()), None, 0)
    action = Suction("track_1", (-0.17887, -0.19682, 0.17183), 0.05, -0.199325, 0.523599)
    motion = step.motion_planner.plan(action, believed)
    assert motion.feasible, motion.reason
    watch = step._edge_watch(action, motion, believed.objects, believed.shelf)
    t0, t1 = push_in_of(motion.waypoint_times)
    assert (watch["t_start_s"], watch["t_end_s"]) == (round(t0, 4), round(t1, 4)) and watch["rise_m"] == EDGE_RETRY_RISE
    # the box's back (its footprint turned 30 deg) is believed 12 cm ahead of the cup's seal
    obj = believed.objects[0]
    back = obj.center[1] + 0.5 * (obj.size[0] * 0.5 + obj.size[1] * 3 ** 0.5 / 2)
    ahead = back - (action.q[1] + SEAL_PRESS * action.axis[1])
    y_start = [w for w in motion.waypoints if w.label == "translate"][0].position[1]
    assert watch["within_m"] == pytest.approx(-believed.shelf.depth / 2 + EDGE_BAND - (y_start + ahead), abs=1e-3)
    assert 0.0 < watch["within_m"] < 0.1
    assert step._edge_watch(dataclasses.replace(action, guarded=True), motion, believed.objects, believed.shelf) is None
    assert step._edge_watch(Push("track_1", (0.0, -0.2, 0.02), 0.05), motion, believed.objects, believed.shelf) is None
