"""Yawed suction (issue 17 item 1): the tool turns about the shelf's z to meet a turned box face along its normal.

Fast: the action model's ``station`` profile produces a turned suction for a box standing 30 deg turned (the
``paper`` profile and ``max_tool_yaw_deg=0`` keep the tube along y), the turn is clamped by the rule and by the
side walls, and the planner's waypoints approach and seal along the turned axis. Slow: that suction, planned by
the motion planner and executed in the Drake station, seals, carries and places the box where the model says.
"""

import math

import numpy as np
import pytest

from slax_drake.planning.waypoints import CUP_STANDOFF, SEAL_PRESS, action_waypoints
from slax_drake.shelf.actions import ActionModel, Suction, apply_action
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

CUP_LIMITS = dict(max_seal_angle_deg=10.0, max_suction_moment=0.4)  # the station YAML's cup


def _turned_box(yaw_deg, x=0.0, y=-0.12, size=(0.08, 0.10, 0.12)):
    return SceneObject("object_0", "box", size, planar_pose(x, y, size[2] / 2, math.radians(yaw_deg)))


def _model(scenario, profile="station", **rules):
    return ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position[:2],
                       tool_config(scenario, profile, **{**CUP_LIMITS, **rules}))


def test_the_station_profile_turns_the_tool_to_a_box_turned_30_deg(sim_scenario):
    box = _turned_box(30.0)
    suctions = _model(sim_scenario).enumerate((box,), pushes=False).feasible
    assert suctions and {round(math.degrees(s.yaw), 3) for s in suctions} == {30.0}
    # the seal-angle rule refuses the same face with the tube along y
    fixed = _model(sim_scenario, max_tool_yaw_deg=0.0).enumerate((box,), pushes=False)
    assert not fixed.feasible and "turned 30 deg from the tube > 10 deg" in fixed.rejected[0].reason


@pytest.mark.parametrize("face_deg, expected_yaw, sealed", [(-20.0, -20.0, True), (38.0, 30.0, True),
                                                            (44.0, 30.0, False), (0.0, 0.0, True)])
def test_the_turn_is_the_faces_clamped_and_the_seal_rule_takes_the_rest(sim_scenario, face_deg, expected_yaw, sealed):
    model = _model(sim_scenario)
    box = _turned_box(face_deg)
    contact = model.suction_contact(box)
    assert math.degrees(model.tool_yaw(box, contact[:2])) == pytest.approx(expected_yaw, abs=1e-6)
    assert bool(model.enumerate((box,), pushes=False).feasible) is sealed


def test_a_side_wall_limits_the_turn(sim_scenario):
    """A deep box by the left wall whose face looks toward that wall: turned fully, the tube's axis would leave
    the bay through the wall; the turn stops where the axis meets the opening a tube radius inside it."""
    model = _model(sim_scenario)
    shelf = shelf_of(sim_scenario)
    box = _turned_box(-30.0, x=-shelf.width / 2 + 0.10, y=0.10)
    cx, cy, _ = model.suction_contact(box)
    yaw = model.tool_yaw(box, (cx, cy))
    assert -math.radians(30.0) < yaw < 0.0
    x_open = cx + math.tan(yaw) * (cy + shelf.depth / 2)
    assert x_open == pytest.approx(-shelf.width / 2 + 0.015)


def test_waypoints_approach_and_seal_along_the_turned_axis(sim_scenario):
    box = _turned_box(30.0)
    action = next(iter(_model(sim_scenario).enumerate((box,), pushes=False).feasible))
    shelf = shelf_of(sim_scenario)
    wps = {w.label: w for w in action_waypoints(action, (box,), shelf)}
    axis = np.array([*action.axis, 0.0])
    q = np.array(action.q)
    assert np.allclose(wps["approach"].position, q - CUP_STANDOFF * axis)
    assert np.allclose(wps["seal"].position, q + SEAL_PRESS * axis)
    way_in = wps["approach"].position - wps["pre-approach"].position
    assert np.allclose(np.cross(way_in, axis), 0.0, atol=1e-9) and way_in @ axis > 0
    for w in wps.values():  # the cup's axis (cup_tip_frame x) stays turned with the tool all the way
        assert np.allclose(w.X_SF[:3, 0], axis)
    # unturned, the waypoints are the tube-along-y ones
    straight = Suction(action.name, action.q, action.dx, action.dz)
    assert np.allclose(action_waypoints(straight, (box,), shelf)[2].position, q + [0.0, SEAL_PRESS, 0.0])


@pytest.mark.slow
def test_a_box_turned_30_deg_is_sealed_carried_and_placed_in_drake(sim_scenario):
    from slax_drake.evaluation.physics import action_matches
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.motion_run import run_motion

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    box = _turned_box(30.0, x=0.0, y=-0.15)
    scene = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (box,), None, 0)
    model = _model(sim_scenario)
    action = next(a for a in model.enumerate((box,), pushes=False).feasible if abs(a.dx - 0.10) < 1e-9
                  and abs(a.dz - float(box.center[1])) < 1e-9)
    assert math.degrees(action.yaw) == pytest.approx(30.0)
    motion = MotionPlanner(station, tool_config(sim_scenario, "station", **CUP_LIMITS)).plan(action, scene)
    assert motion.feasible, motion.reason

    carried_at = next(t for label, t in motion.waypoint_times if label == "translate")
    poses = run_motion(station, scene, motion, box.name, times=[carried_at])
    held, end = poses[carried_at], poses["end"]
    assert held["z"] > box.size[2] / 2 + 0.005, "the box was not lifted: the seal never formed"
    (predicted,) = [o for o in apply_action((box,), action)]
    expected = {"x": float(predicted.center[0]), "y": float(predicted.center[1]), "yaw": float(predicted.yaw)}
    assert action_matches(expected, end), (end, expected)
    assert end["tilt_deg"] < 5.0 and abs(end["z"] - box.size[2] / 2) < 0.005
