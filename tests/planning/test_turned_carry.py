"""A suctioned object the arm cannot carry straight (its pull-out or translate pose in front of the shoulder has
no IK solution: the wrist would fold into it) is carried turned about the cup's vertical axis, turning back before
it is pushed in: the variants' order, the turned waypoints, the turned sweep, and (slow, Drake) a Table I carry
the planner used to reject is planned, passes the hardware checker and ends where the action model puts it."""

import numpy as np
import pytest

from slax_drake.planning.planner import _midway_rotation
from slax_drake.planning.waypoints import (CARRY_YAWS, TARGET_CLEARANCE, action_waypoints, carried_sweep,
                                           carry_options, pull_out_options, suction_rotation)
from slax_drake.shelf.actions import Suction
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import SceneObject, Shelf, Target, planar_pose

SHELF = Shelf(width=0.6, height=0.6, depth=0.6, wall_thickness=0.02)


def _box(name, x, y, size, yaw=0.0):
    return SceneObject(name, "box", tuple(size), planar_pose(x, y, size[2] / 2.0, yaw))


def _front_box():
    box = _box("object_0", 0.15, -0.22, (0.10, 0.12, 0.16))
    return box, Suction(box.name, (0.15, -0.28, 0.10), -0.25, -0.20)


def test_turned_ways_come_after_every_straight_depth_wrist_side_first():
    box, action = _front_box()
    straight = pull_out_options(action, box, SHELF, None)
    options = carry_options(action, box, SHELF, None, wrist_side=+1.0)
    assert options[:len(straight)] == [(y, 0.0) for y in straight]
    turned = options[len(straight):]
    assert [yaw for _, yaw in turned] == [CARRY_YAWS[0], -CARRY_YAWS[0]]
    assert all(y == straight[0] for y, _ in turned)  # turned only when pulled all the way out
    assert [yaw for _, yaw in carry_options(action, box, SHELF, None, wrist_side=-0.1)[len(straight):]] == \
        [-CARRY_YAWS[0], CARRY_YAWS[0]]


def test_turned_waypoints_keep_the_seal_and_the_placement():
    box, action = _front_box()
    straight = {w.label: w for w in action_waypoints(action, (box,), SHELF)}
    turned = {w.label: w for w in action_waypoints(action, (box,), SHELF, carry_yaw=CARRY_YAWS[0])}
    assert list(straight) == list(turned)
    for label in ("pull out", "translate"):
        assert np.allclose(turned[label].X_SF[:3, :3], suction_rotation(action.yaw + CARRY_YAWS[0]))
        assert np.allclose(turned[label].position, straight[label].position)
    for label in ("pre-approach", "approach", "seal", "lift", "push in", "lower", "release", "back off", "retract"):
        assert np.allclose(turned[label].X_SF[:3, :3], straight[label].X_SF[:3, :3]), label
    for label in ("seal", "lower", "release"):  # the object is held and put down where the action puts it
        assert np.allclose(turned[label].X_SF, straight[label].X_SF), label


def test_the_turned_sweep_turns_the_footprint_about_the_cup():
    box, action = _front_box()
    yaw = CARRY_YAWS[0]
    offsets = [(0.0, 0.0, 0.0), (0.0, -0.1, yaw)]
    sweep = carried_sweep(box, offsets, pivot=action.q[:2])
    end_centres, end_yaw = sweep[-1]
    assert end_yaw == pytest.approx(box.yaw + yaw)
    arm = np.array(box.center[:2]) - np.array(action.q[:2])
    c, s = np.cos(yaw), np.sin(yaw)
    expected = np.array(action.q[:2]) + [0.0, -0.1] + np.array([c * arm[0] - s * arm[1], s * arm[0] + c * arm[1]])
    assert np.allclose(end_centres[-1], expected)
    # no point of the footprint jumps more than the sweep step between samples on the turn
    half_diag = float(np.hypot(*Footprint.of(box).extents()))
    yaws = sorted(y for _, y in sweep)
    assert max(np.diff(yaws)) * (np.linalg.norm(arm) + half_diag) <= 0.005 + 1e-9
    # without a turn the sweep is the straight one of the object's centre
    straight = carried_sweep(box, [(0.0, 0.0), (0.0, -0.1)])
    assert len(straight) == 1 and np.allclose(straight[0][0][-1], np.array(box.center[:2]) + [0.0, -0.1])


def test_a_turned_way_that_would_sweep_over_the_target_is_left_out():
    box, action = _front_box()
    plain = carry_options(action, box, SHELF, None, wrist_side=1.0)
    # a target just right of the object's front corner: the straight way out misses it, a turn swings into it
    fp = Footprint.of(box)
    target = Target((0.04, 0.04, 0.06), planar_pose(fp.x + fp.half_x + TARGET_CLEARANCE + 0.025, -0.26, 0.03, 0.0))
    options = carry_options(action, box, SHELF, target, wrist_side=1.0)
    assert (plain[0][0], 0.0) in options
    assert len([o for o in options if o[1] != 0.0]) < len([o for o in plain if o[1] != 0.0])


def test_midway_rotation_halves_a_turn_and_keeps_an_unturned_segment_exact():
    R0 = suction_rotation(0.2)
    assert np.allclose(_midway_rotation(R0, suction_rotation(0.2 + 0.5)), suction_rotation(0.2 + 0.25))
    assert np.array_equal(_midway_rotation(R0, R0.copy()), R0)


@pytest.mark.slow
def test_a_carry_the_arm_cannot_make_straight_is_planned_turned_and_checks():
    """Table I, 10 objects, scene 0: object_9 stands at the front right, straight ahead of the shoulder; its
    pull-out and translate poses had no IK solution at any carrying depth (research/diagnose_carry.py)."""
    from slax_drake.shelf.actions import apply_action
    from table1_suction_plans import assert_motion_checks, plan_table1_suction

    checker, action, motion = plan_table1_suction(10, 0, "object_9", -0.05)
    assert motion.feasible, motion.reason
    wps = {w.label: w for w in motion.waypoints}
    turn = np.arctan2(wps["pull out"].X_SF[1, 0], wps["pull out"].X_SF[0, 0]) - \
        np.arctan2(wps["seal"].X_SF[1, 0], wps["seal"].X_SF[0, 0])
    assert abs(abs(turn) - CARRY_YAWS[0]) < 1e-9
    world = assert_motion_checks(checker, action, motion)
    traj = motion.trajectory
    # the object, held from the seal, is where the action model puts it at the release
    times = dict(motion.waypoint_times)
    q_seal = traj.value(times["seal"])[0]
    q_release = traj.value(times["release"])[0]
    obj = next(o for o in checker.scene.objects if o.name == action.name)
    world.carry(obj, q_seal)
    X_end = world.carried_pose_S(q_release)
    world.drop()
    placed = next(o for o in apply_action(checker.scene.objects, action) if o.name == action.name)
    assert np.allclose(X_end[:3, 3], placed.X_SO[:3, 3], atol=1e-3)
    assert np.allclose(X_end[:3, :3], placed.X_SO[:3, :3], atol=2e-3)
