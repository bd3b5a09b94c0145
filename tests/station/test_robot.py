"""The Fetch + bluction model: forward kinematics against the facts sheet and an independent chain, limits,
package:// loading and the shipped shelf models."""

import math
from pathlib import Path

import numpy as np
import pytest

from slax_drake.config import load_scenario
from slax_drake.scene.sampling import shelf_of
from slax_drake.station import robot as robot_model
from slax_drake.station.plant import controller_plant
from slax_drake.station.scenario import DEFAULT_STATION, load_station_scenario
from slax_drake.station.scene_world import shelf_urdf

REPO = Path(__file__).resolve().parents[2]



def _rot(axis, a):
    c, s = math.cos(a), math.sin(a)
    return {
        "x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
        "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
        "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
    }[axis]


def _oracle_wrist_roll(q):
    """wrist_roll_link origin in base_link for q = [torso, 7 arm joints] from the facts table alone."""
    joints = [
        ((-0.086875, 0, 0.37743), "pz"), ((0.119525, 0, 0.34858), "z"), ((0.117, 0, 0.06), "y"),
        ((0.219, 0, 0), "x"), ((0.133, 0, 0), "y"), ((0.197, 0, 0), "x"), ((0.1245, 0, 0), "y"), ((0.1385, 0, 0), "x"),
    ]
    R, p = np.eye(3), np.zeros(3)
    for (origin, axis), value in zip(joints, q):
        p = p + R @ np.array(origin)
        if axis == "pz":
            p = p + R @ np.array([0, 0, value])
        else:
            R = R @ _rot(axis, value)
    return p, R


def _fk(plant, q9, body):
    context = plant.CreateDefaultContext()
    q = np.zeros(plant.num_positions())
    q[robot_model.planned_joint_indices(plant)] = q9
    plant.SetPositions(context, q)
    return plant.GetBodyByName(body).EvalPoseInWorld(context)


@pytest.fixture(scope="module")
def plant():
    return controller_plant(load_station_scenario(DEFAULT_STATION))


def test_fk_all_zero_matches_facts(plant):
    zero = np.zeros(9)
    assert np.allclose(_fk(plant, zero, "shoulder_pan_link").translation(), [0.03265, 0, 0.72601], atol=1e-3)
    X_wrist = _fk(plant, zero, "wrist_roll_link")
    assert np.allclose(X_wrist.translation(), [0.96165, 0, 0.78601], atol=1e-3)
    # gripper_link of the upstream robot sits 0.16645 m along the wrist roll axis
    assert np.allclose(X_wrist.multiply([0.16645, 0, 0]), [1.1281, 0, 0.78601], atol=1e-3)
    raised = zero.copy()
    raised[0] = 0.38615
    assert np.allclose(_fk(plant, raised, "wrist_roll_link").translation(), [0.96165, 0, 0.78601 + 0.38615], atol=1e-3)


def test_fk_tuck_matches_independent_chain(plant):
    tuck = np.array(robot_model.TUCK_CONFIGURATION)
    p_oracle, R_oracle = _oracle_wrist_roll(tuck[:8])
    X = _fk(plant, tuck, "wrist_roll_link")
    assert np.allclose(X.translation(), p_oracle, atol=1e-3)
    assert np.allclose(X.rotation().matrix(), R_oracle, atol=1e-6)
    # the tucked arm stays inside the base's footprint radius plus a hand
    assert np.hypot(*X.translation()[:2]) < 0.45


def test_tool_dimensions(plant):
    context = plant.CreateDefaultContext()
    mount = plant.GetFrameByName("bluction_mount_link")
    cup = plant.GetFrameByName(robot_model.CUP_TIP_FRAME).CalcPose(context, mount)
    shaft = plant.GetJointByName("tool_shaft_joint")
    assert shaft.revolute_axis().tolist() == [1.0, 0.0, 0.0]
    # 0.40 m tube + 0.02 m cup beyond the 0.03 m flange
    assert cup.translation() == pytest.approx([0.03 + 0.42, 0, 0])
    blade = plant.GetFrameByName(robot_model.BLADE_FACE_FRAME).CalcPose(context, mount)
    assert blade.translation()[2] == pytest.approx(-0.0375)  # blade hangs below the tube at shaft = 0
    q = np.zeros(plant.num_positions())
    q[shaft.position_start()] = robot_model.SHAFT_BLADE_UP
    plant.SetPositions(context, q)
    assert plant.GetFrameByName(robot_model.BLADE_FACE_FRAME).CalcPose(context, mount).translation()[2] == pytest.approx(0.0375)


def test_limits_as_data():
    limits = robot_model.joint_limits(controller_plant(load_station_scenario(DEFAULT_STATION)))
    assert limits.names == robot_model.PLANNED_JOINTS
    assert limits.velocity[2] == pytest.approx(1.454) and limits.effort[2] == pytest.approx(131.76)
    assert limits.acceleration.tolist()[:8] == [0.5, 1.5, 1.0, 1.5, 1.5, 1.5, 2.5, 2.5]
    assert np.allclose(limits.jerk[:8], 10 * limits.acceleration[:8])
    assert limits.position_lower[0] == 0 and limits.position_upper[0] == pytest.approx(0.38615)
    assert math.isinf(limits.position_upper[3])  # continuous roll joint
    assert limits.position_lower[6] == pytest.approx(-2.16)


def test_every_actuator_has_effort_limit_and_pd_gains(plant):
    assert plant.num_actuators() == 11
    for index in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(index)
        assert actuator.effort_limit() > 0 and actuator.has_controller()


@pytest.mark.parametrize("name", ["sim", "physical"])
def test_shipped_shelf_models_match_the_scenarios(name):
    shelf = shelf_of(load_scenario(REPO / "sim_configs" / f"{name}_shelf.yaml"))
    assert (REPO / "models" / f"shelf_{name}.urdf").read_text() == shelf_urdf(shelf)


def test_models_load_by_package_url():
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.001)
    parser = Parser(plant)
    robot_model.add_package(parser)
    for url in ("fetch_bluction.urdf", "shelf_sim.urdf", "shelf_physical.urdf"):
        parser.SetAutoRenaming(True)
        assert parser.AddModels(url=f"package://{robot_model.PACKAGE_NAME}/{url}")
