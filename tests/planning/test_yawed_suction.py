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


@pytest.mark.parametrize("side", [-1, +1])
def test_a_side_wall_limits_the_turn(sim_scenario, side):
    """A deep box by a side wall whose face looks toward that wall: turned fully, the tube would leave the bay
    through the wall; the turn stops where the tube's surface passes the wall's front edge (at the opening)
    ``TUBE_CLEARANCE`` from it, measured square to the turned axis (before, the axis met the opening a tube
    radius inside the wall, and a 27 deg turn left the tube 1.6 mm into the edge)."""
    from slax_drake.shelf.actions import TUBE_CLEARANCE

    model = _model(sim_scenario)
    shelf = shelf_of(sim_scenario)
    box = _turned_box(side * 30.0, x=side * (shelf.width / 2 - 0.10), y=0.10)
    cx, cy, _ = model.suction_contact(box)
    yaw = model.tool_yaw(box, (cx, cy))
    assert 0.0 < side * yaw < math.radians(30.0)
    edge = np.array([side * shelf.width / 2, -shelf.depth / 2])
    axis_out = np.array([math.sin(yaw), -math.cos(yaw)])
    to_edge = edge - np.array([cx, cy])
    square = abs(to_edge[0] * axis_out[1] - to_edge[1] * axis_out[0])  # the edge's distance from the axis
    assert square == pytest.approx(0.015 + TUBE_CLEARANCE, abs=1e-9)


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
    # it leaves as it came: backs off and retracts along the axis, out to the pre-approach's depth
    way_out = wps["retract"].position - wps["back off"].position
    assert np.allclose(np.cross(way_out, axis), 0.0, atol=1e-9) and way_out @ axis < 0
    assert wps["retract"].position[1] == pytest.approx(wps["pre-approach"].position[1])
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


@pytest.mark.slow
def test_a_turn_the_side_wall_allows_is_one_the_planner_plans(sim_scenario):
    """A box by the right wall turned 33 deg: its face sealed with the tool turned as far as the wall allows (24
    deg, the seal angle within the station's 10) is planned; the turn the old clamp allowed (the axis a tube radius
    inside the wall at the opening, 26 deg) puts the tube against the wall's edge and the planner refuses it."""
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    shelf = shelf_of(sim_scenario)
    box = _turned_box(33.0, x=0.14, y=-0.02, size=(0.10, 0.08, 0.10))
    scene = Scene(shelf, Camera.from_config(sim_scenario.camera), (box,), None, 0)
    action = next(a for a in _model(sim_scenario).enumerate((box,), pushes=False).feasible
                  if not a.drag and abs(a.dx + 0.05) < 1e-9)
    assert 20.0 < math.degrees(action.yaw) < 25.0
    planner = MotionPlanner(station, tool_config(sim_scenario, "station", **CUP_LIMITS))
    motion = planner.plan(action, scene)
    assert motion.feasible, motion.reason
    cx, cy, _ = action.q
    old_yaw = math.atan((shelf.width / 2 - 0.015 - cx) / (cy + shelf.depth / 2))
    assert old_yaw > action.yaw + math.radians(1.0)
    refused = planner.plan(Suction(action.name, action.q, action.dx, action.dz, yaw=old_yaw), scene)
    assert not refused.feasible and "with the shelf" in refused.reason
