"""The planner's variants (approach margins, carrying depths) are tried on after a straight-segment failure:
a Table I suction whose first carrying depths fail and whose last one failed on the approach's straight segment
(the reason that used to end the search) is planned, and its trajectory passes the hardware checker's limits and
the planning world's collision check."""

import pytest

from slax_drake.planning.failures import FailureKind, PlanningFailure
from slax_drake.planning.planner import _another_carry_may_differ, _may_differ


def test_straight_segment_failures_let_the_next_variant_be_tried():
    K = FailureKind
    assert _may_differ((PlanningFailure(K.LEAVES_STRAIGHT_SEGMENT, "approach", deviation=0.0423),), {"pull out"})
    assert _may_differ((PlanningFailure(K.STRAIGHT_SEGMENT_OUT_OF_REACH, "insert"),), {"pre-approach"})
    assert _may_differ((PlanningFailure(K.NO_IK_SOLUTION, "pull out"),), {"pull out"})
    assert not _may_differ((PlanningFailure(K.TOOL_COLLIDES, "insert", hits="wrist_roll_link"),), {"pre-approach"})


def test_a_pose_after_the_placement_with_no_ik_solution_lets_another_carry_be_tried():
    """IK solves the release, back off and retract from where the carry left the arm: with no solution there,
    another carry may have one; a collision of the tool there, or a failure before the carry, does not differ."""
    K = FailureKind
    for waypoint in ("release", "back off", "retract"):
        assert _another_carry_may_differ((PlanningFailure(K.NO_IK_SOLUTION, waypoint),))
        assert not _another_carry_may_differ((PlanningFailure(K.TOOL_COLLIDES, waypoint, hits="track_1"),))
    assert _another_carry_may_differ((PlanningFailure(K.NO_IK_SOLUTION, "translate"),))
    assert not _another_carry_may_differ((PlanningFailure(K.NO_IK_SOLUTION, "approach"),))
    assert not _another_carry_may_differ((PlanningFailure(K.TOOL_COLLIDES, "seal", hits="track_1"),))


@pytest.mark.slow
def test_a_carry_whose_retract_had_no_ik_solution_is_planned_carried_another_way():
    """Table I household scene 4:7, step 5 of its Drake trial (the objects as the camera estimated them): a turned
    suction carried 0.30 m right. Every straight carry ends with no IK solution at the retract (it used to end the
    search there); carried across turned, it plans, and its trajectory passes the checker."""
    import numpy as np

    from slax_drake.config import load_scenario
    from slax_drake.hardware.check import check_trajectory
    from slax_drake.hardware.trajectory_file import ExportedTrajectory, Motion
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.actions import Suction
    from slax_drake.shelf.tool import tool_config
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene, SceneObject, planar_pose
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.trial import station_tool_rules

    scenario = load_scenario("sim_configs/table1_household.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    planner = MotionPlanner(station, tool_config(scenario, "station", **station_tool_rules(station)))

    def obj(name, shape, size, x, y, yaw):
        return SceneObject(name, shape, size, planar_pose(x, y, size[2] / 2, yaw))

    objects = (obj("track_5", "cylinder", (0.155, 0.155, 0.1027), 0.0108, 0.1265, 0.0),
               obj("track_2", "box", (0.1955, 0.1387, 0.1115), -0.0698, -0.1576, 1.295),
               obj("track_3", "box", (0.0803, 0.0849, 0.164), -0.2235, -0.1514, 0.2164),
               obj("track_4", "cylinder", (0.1655, 0.1655, 0.1132), 0.2113, -0.1858, 0.0))
    scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), objects, None, 0)
    action = Suction("track_3", (-0.21438, -0.19291, 0.14400), dx=0.3, dz=-0.001449, yaw=0.216421)
    motion = planner.plan(action, scene)
    assert motion.feasible, motion.reason
    report = check_trajectory(ExportedTrajectory([Motion(start_time=0.0, times=motion.trajectory.times,
                                                         q=motion.trajectory.q, v=motion.trajectory.v,
                                                         a=motion.trajectory.a)]), margin=0.01)
    assert report.ok, report.summary()
    pose = {w.label: w.X_SF for w in motion.waypoints}
    turn = np.degrees(np.arccos(np.clip(pose["seal"][:3, 0] @ pose["translate"][:3, 0], -1.0, 1.0)))
    assert turn == pytest.approx(30.0, abs=0.1)  # carried across turned (CARRY_YAWS), not straight


@pytest.mark.slow
def test_a_suction_that_failed_on_its_approach_segment_is_planned_and_checks():
    from table1_suction_plans import assert_motion_checks, plan_table1_suction

    assert_motion_checks(*plan_table1_suction(10, 1, "object_4", -0.3))
