"""Weighing a lifted object at the cup from the arm's joint efforts, and undoing a lift that is too heavy (the Drake
trials: tests/systems/test_weigh_drake.py)."""

import dataclasses

import numpy as np
import pytest

from slax_drake.planning.trajectory import JointTrajectory
from slax_drake.planning.waypoints import DWELL, WEIGH_DWELL
from slax_drake.shelf.actions import Push, Suction
from slax_drake.systems.guard import GRAVITY, WEIGH_EARLY, Payload, weigh_time


@pytest.fixture(scope="module")
def effort_model():
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.guard import EffortModel

    return EffortModel(load_station_scenario("sim_configs/station_sim_shelf.yaml"))


def _wrench_efforts(model, q, weight, offset):
    """The efforts (9,) with which the arm at rest at q holds a weight ``weight`` (N) whose centre lies ``offset``
    (world, m) from the cup tip: J^T (torque, force), the torque r x F about the tip."""
    from pydrake.multibody.tree import JacobianWrtVariable

    model._set(q)
    world = model.plant.world_frame()
    J = model.plant.CalcJacobianSpatialVelocity(model.context, JacobianWrtVariable.kV, model._cup, np.zeros(3),
                                                world, world)[:, model._iv]
    force = np.array([0.0, 0.0, weight])
    return J.T @ np.concatenate([np.cross(offset, force), force])


@pytest.mark.parametrize("offset", [(0.0, 0.06, -0.01), (0.04, -0.03, 0.02), (0.0, 0.0, -0.05)])
def test_the_cup_s_payload_is_its_weight_and_the_moment_it_hangs_off_the_cup(effort_model, offset):
    """Efforts that hold a 7 N weight whose centre lies off the cup tip read back as 7 N and 7 N times the centre's
    horizontal distance (the vertical offset makes no moment), at two arm configurations."""
    from slax_drake.station import robot as robot_model
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    q_obs = np.array([station.observation_configuration[n] for n in robot_model.PLANNED_JOINTS])
    for q in (q_obs, q_obs + np.linspace(-0.2, 0.2, 9) * np.r_[0.0, np.ones(8)]):
        residual = _wrench_efforts(effort_model, q, 7.0, np.asarray(offset))
        payload = effort_model.payload(q, residual)
        assert payload.weight_n == pytest.approx(7.0, abs=1e-6)
        assert payload.moment_nm == pytest.approx(7.0 * np.hypot(offset[0], offset[1]), abs=1e-6)


def test_the_mass_a_weighed_object_is_reckoned_with_explains_its_moment_at_the_believed_lever():
    weighed = Payload(weight_n=4.905, moment_nm=0.3)  # 0.5 kg hanging 6.1 cm off the cup
    assert weighed.mass_at(0.061) == pytest.approx(0.5, rel=0.01)  # the lever believed right: its own mass
    assert weighed.mass_at(0.03) == pytest.approx(0.3 / (GRAVITY * 0.03))  # believed shallower: heavier, so that
    # mass x g x lever is the moment weighed
    assert weighed.mass_at(0.2) == pytest.approx(0.5)  # never lighter than its weight
    assert weighed.mass_at(0.0) == pytest.approx(0.5)


def _motion(action, labels_times):
    from slax_drake.planning.planner import PlannedMotion

    n = 9
    times = np.arange(0, 8001) * 0.001
    q = np.outer(np.sin(times), np.arange(1, n + 1))  # distinct positions along the way
    v = np.outer(np.cos(times), np.arange(1, n + 1))
    a = np.outer(-np.sin(times), np.arange(1, n + 1))
    traj = JointTrajectory(tuple(f"j{k}" for k in range(n)), times, q, v, a)
    return PlannedMotion(action, traj, [(1.0, 7.0)], labels_times, 0.0, {}, [])


LIFT = Suction("object_0", (0.0, -0.2, 0.05), 0.1, 0.2)
TIMES = [("pre-approach", 0.5), ("approach", 0.8), ("seal", 1.2), ("lift", 2.0), ("pull out", 3.0),
         ("translate", 4.0), ("push in", 5.0), ("lower", 5.5), ("release", 5.5), ("back off", 6.5),
         ("retract", 7.0)]


def test_a_lift_is_weighed_at_the_end_of_its_rest_at_the_lift_and_nothing_else_is_weighed():
    assert weigh_time(_motion(LIFT, TIMES)) == pytest.approx(2.0 + WEIGH_DWELL - WEIGH_EARLY)
    higher = TIMES[:3] + [("weigh", 1.8)] + TIMES[3:]  # lifted over a tall object: weighed 1 cm up first
    assert weigh_time(_motion(LIFT, higher)) == pytest.approx(1.8 + WEIGH_DWELL - WEIGH_EARLY)
    assert weigh_time(_motion(dataclasses.replace(LIFT, drag=True), TIMES)) is None
    assert weigh_time(_motion(Push("object_0", (0.0, -0.2, 0.04), 0.1), TIMES)) is None


def test_a_lift_put_back_plays_its_motion_backward_and_releases_where_it_sealed():
    from slax_drake.planning.planner import MotionPlanner

    motion = _motion(LIFT, TIMES)
    t_from = 2.0 + WEIGH_DWELL - WEIGH_EARLY
    back = MotionPlanner.put_back(motion, t_from)
    traj, k = motion.trajectory, int(round(t_from / 0.001))
    assert back.trajectory.times[0] == 0.0 and back.trajectory.duration == pytest.approx(t_from)
    np.testing.assert_allclose(back.trajectory.q[0], traj.q[k])  # from where the cup holds the object
    np.testing.assert_allclose(back.trajectory.q[-1], traj.q[0])  # back to where the motion started
    np.testing.assert_allclose(back.trajectory.v[1], -traj.v[k - 1])  # the same path, the other way
    (on, off), = back.suction_intervals
    assert on == 0.0 and off == pytest.approx(t_from - (1.2 + DWELL))  # released on arriving at the seal
    q_off, _ = back.trajectory.value(off)
    np.testing.assert_allclose(q_off, traj.q[int(round((1.2 + DWELL) / 0.001))], atol=1e-9)
    assert [label for label, _ in back.waypoint_times] == ["lower", "release", "back off", "retract", "return"]
    assert dict(back.waypoint_times)["back off"] == pytest.approx(t_from - 0.8)


def test_a_lift_put_back_is_its_own_mismatch_kind():
    from slax_drake.evaluation.physics import mismatch_kind

    before = {"x": 0.0, "y": -0.2, "yaw": 0.0}
    action = {"type": "suction", "matched": False, "outcome": before, "before": before, "lost_after": False,
              "predicted": {"x": 0.1, "y": 0.0, "yaw": 0.0}}
    assert mismatch_kind(action, 0.8, 0.6) == "seal never formed"
    assert mismatch_kind({**action, "weighed": {"put_back": True}}, 0.8, 0.6) == "put back"
    assert mismatch_kind({**action, "weighed": {"put_back": True}, "lost_after": True}, 0.8, 0.6) == "toppled"


def test_a_lift_is_put_back_when_the_cup_holds_nothing_too_much_or_an_object_the_floor_still_carries():
    from slax_drake.systems.guard import weigh_verdict

    assert weigh_verdict(Payload(4.0, 0.2), 0.4, 0.05) is None  # 5 cm lever, as the camera allows
    assert weigh_verdict(Payload(0.1, 0.0), 0.4, 0.05) == "nothing held"
    assert weigh_verdict(Payload(6.0, 0.42), 0.4, 0.05) == "too heavy"
    assert weigh_verdict(Payload(7.8, 0.37), 0.4, 0.0675) == "not hanging free"  # 4.7 cm of a 6.75 cm radius
    assert weigh_verdict(Payload(7.8, 0.37), 0.4, 0.0) is None  # no least lever: not judged


def test_the_least_lever_of_a_box_keeps_only_the_depth_the_camera_measured():
    from types import SimpleNamespace

    from slax_drake.scene.model import SceneObject, planar_pose
    from slax_drake.systems.guard import least_lever

    box = SceneObject("track_1", "box", (0.10, 0.12, 0.10), planar_pose(0.0, 0.0, 0.05, 0.0))
    seen = SimpleNamespace(object=box, uncertainty=SimpleNamespace(depth=(0.06, 0.2)))
    assert least_lever(seen, (0.0, -0.06)) == pytest.approx(0.03)  # half of the 6 cm measured
    whole = SimpleNamespace(object=box, uncertainty=SimpleNamespace(depth=(0.12, 0.12)))
    assert least_lever(whole, (0.0, -0.06)) == pytest.approx(0.06)
    assert least_lever(box, (0.0, -0.06)) == 0.0  # no uncertainty: not known
    can = SceneObject("track_2", "cylinder", (0.1, 0.1, 0.1), planar_pose(0.0, 0.0, 0.05, 0.0))
    assert least_lever(can, (0.0, -0.05)) == pytest.approx(0.05)  # the fitted radius
