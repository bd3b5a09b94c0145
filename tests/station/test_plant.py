"""One plant builder: the simulated station, the planning world, the checker's world and the controller plant all
load the robot that the station scenario's directives name, and nothing else names it."""

from pathlib import Path

import numpy as np
import pytest

from slax_drake.config import REPO_ROOT
from slax_drake.errors import ConfigError
from slax_drake.hardware.collision import CollisionWorld
from slax_drake.planning.planner import MotionPlanner
from slax_drake.planning.world import PlanningWorld
from slax_drake.scene.sampling import sample_scene
from slax_drake.station.plant import PlantPurpose, controller_plant, make_station_plant, station_joint_limits
from slax_drake.station import robot as robot_model
from slax_drake.station.robot import PLANNED_JOINTS
from slax_drake.station.scenario import DEFAULT_STATION, load_station_scenario, observation_positions
from slax_drake.systems.station import MakeStation

SHIPPED_URL = "package://slax_drake_models/fetch_bluction.urdf"
ELBOW = "elbow_flex_joint"
SHIPPED_ELBOW_UPPER = 2.251  # rad, models/fetch_bluction.urdf
CHANGED_ELBOW_UPPER = 2.0  # rad, the copy's
FOREARM_LONGER = 0.05  # m added to the elbow -> forearm-roll offset of the copy (0.197 m shipped)


@pytest.fixture(scope="module")
def changed_station(tmp_path_factory):
    """A copy of the default station whose directives load a copy of the robot with a lower elbow limit and a
    5 cm longer forearm (given by an absolute file URL)."""
    folder = tmp_path_factory.mktemp("changed_robot")
    urdf = (REPO_ROOT / "models" / "fetch_bluction.urdf").read_text()
    elbow_limit = '<limit lower="-2.251" upper="2.251" velocity="1.521"'
    forearm = '<child link="forearm_roll_link"/><origin xyz="0.197 0 0"'
    assert urdf.count(elbow_limit) == 1 and urdf.count(forearm) == 1
    urdf = urdf.replace(elbow_limit, f'<limit lower="-2.251" upper="{CHANGED_ELBOW_UPPER}" velocity="1.521"')
    urdf = urdf.replace(forearm, f'<child link="forearm_roll_link"/><origin xyz="{0.197 + FOREARM_LONGER} 0 0"')
    (folder / "fetch_changed.urdf").write_text(urdf)
    station_yaml = (REPO_ROOT / DEFAULT_STATION).read_text()
    assert station_yaml.count(SHIPPED_URL) == 1
    (folder / "station.yaml").write_text(station_yaml.replace(SHIPPED_URL, f"file://{folder / 'fetch_changed.urdf'}"))
    return load_station_scenario(folder / "station.yaml")


@pytest.fixture(scope="module")
def scene(sim_scenario):
    return sample_scene(sim_scenario, 3, seed=3)


def _elbow_upper(plant) -> float:
    return float(plant.GetJointByName(ELBOW).position_upper_limits()[0])


def _shelf_in_world(plant):
    return plant.GetFrameByName("shelf_body").CalcPoseInWorld(plant.CreateDefaultContext())


@pytest.mark.parametrize("changed", [False, True], ids=["shipped robot", "changed robot"])
def test_simulator_planner_checker_and_controller_load_the_scenarios_robot(changed, changed_station, scene):
    scenario = changed_station if changed else load_station_scenario(DEFAULT_STATION)
    expected = CHANGED_ELBOW_UPPER if changed else SHIPPED_ELBOW_UPPER

    station = MakeStation(scenario, scene, camera=False)
    simulated = station.GetSubsystemByName("plant")
    world = PlanningWorld(scenario, scene)
    checker = CollisionWorld(scenario, scene)
    planner = MotionPlanner(scenario)

    assert _elbow_upper(simulated) == pytest.approx(expected)
    assert _elbow_upper(world.plant) == pytest.approx(expected)
    assert _elbow_upper(checker.plant) == pytest.approx(expected)
    # Gravity compensation runs on the controller plant of the same robot: -tau_g(q) of that robot.
    context = station.CreateDefaultContext()
    gravity = station.GetSubsystemByName("gravity_compensation")
    tau = gravity.get_output_port_generalized_force().Eval(gravity.GetMyContextFromRoot(context))
    robot_alone = controller_plant(scenario)
    robot_context = robot_alone.CreateDefaultContext()
    robot_alone.SetPositionsAndVelocities(robot_context, station.GetOutputPort("robot_state").Eval(context))
    assert np.allclose(tau, -robot_alone.CalcGravityGeneralizedForces(robot_context), rtol=1e-12, atol=1e-12)
    assert planner.limits.position_upper[PLANNED_JOINTS.index(ELBOW)] == pytest.approx(expected)
    # The shelf is placed from the camera of this robot at q_obs: the same X_WS in all three worlds.
    X_WS = _shelf_in_world(simulated)
    for other in (world.X_WS, checker.X_WS, _shelf_in_world(world.plant)):
        assert np.allclose(other.GetAsMatrix4(), X_WS.GetAsMatrix4(), atol=1e-12)


def test_the_longer_forearm_moves_the_camera_and_so_the_shelf(changed_station, scene):
    shipped = make_station_plant(load_station_scenario(DEFAULT_STATION), scene, PlantPurpose.CHECKING).X_WS
    changed = make_station_plant(changed_station, scene, PlantPurpose.CHECKING).X_WS
    moved = np.linalg.norm(changed.translation() - shipped.translation())
    assert moved == pytest.approx(FOREARM_LONGER, abs=1e-9)  # the forearm is straight in line with the wrist
    assert np.allclose(changed.rotation().matrix(), shipped.rotation().matrix(), atol=1e-9)
    # ... and weighs on the shoulder differently (the controller plant's gravity torques at q_obs).
    torques = []
    for scenario in (load_station_scenario(DEFAULT_STATION), changed_station):
        plant = controller_plant(scenario)
        context = plant.CreateDefaultContext()
        q = plant.GetPositions(context)
        q[robot_model.planned_joint_indices(plant)] = observation_positions(scenario)
        plant.SetPositions(context, q)
        torques.append(plant.CalcGravityGeneralizedForces(context))
    shoulder_lift = controller_plant(changed_station).GetJointByName("shoulder_lift_joint").velocity_start()
    assert abs(torques[1][shoulder_lift] - torques[0][shoulder_lift]) > 0.1  # N m


def test_purposes_hold_what_the_table_says(scene):
    scenario = load_station_scenario(DEFAULT_STATION)
    n_items = len(scene.objects) + 1
    sim = make_station_plant(scenario, scene, PlantPurpose.SIMULATION)
    plan = make_station_plant(scenario, scene, PlantPurpose.PLANNING)
    check = make_station_plant(scenario, scene, PlantPurpose.CHECKING)
    ctrl = make_station_plant(scenario, purpose=PlantPurpose.CONTROLLER)
    robot_q = ctrl.plant.num_positions()
    assert sim.plant.time_step() == scenario.plant_config.time_step and plan.plant.time_step() == 0.0
    assert list(sim.objects) == [o.name for o in scene.objects] + ["target"]  # the target is simulated
    assert list(plan.objects) == list(check.objects) == [o.name for o in scene.objects]
    assert sim.plant.num_positions() == robot_q + 7 * n_items  # free objects
    assert check.plant.num_positions() == robot_q + 7 * len(scene.objects)  # free, placed per motion
    assert plan.plant.num_positions() == robot_q  # objects welded where they stand
    assert ctrl.scene_graph is None and ctrl.shelf is None and not ctrl.plant.HasBodyNamed("shelf_body")
    assert [ctrl.plant.get_joint(i).name() for i in ctrl.plant.GetJointIndices()] == \
        [plan.plant.get_joint(i).name() for i in plan.plant.GetJointIndices(plan.robot)]
    with_target = make_station_plant(scenario, scene, PlantPurpose.PLANNING, include_target=True)
    assert "target" in with_target.objects


def test_joint_limits_of_the_default_station(changed_station):
    shipped = station_joint_limits(load_station_scenario(DEFAULT_STATION))
    changed = station_joint_limits(changed_station)
    k = PLANNED_JOINTS.index(ELBOW)
    assert shipped.position_upper[k] == pytest.approx(SHIPPED_ELBOW_UPPER)
    assert changed.position_upper[k] == pytest.approx(CHANGED_ELBOW_UPPER)
    assert np.array_equal(np.delete(shipped.position_upper, k), np.delete(changed.position_upper, k))
    assert controller_plant(changed_station).num_positions() == controller_plant(
        load_station_scenario(DEFAULT_STATION)).num_positions()


def test_directives_without_the_robot_are_refused(tmp_path):
    text = (REPO_ROOT / DEFAULT_STATION).read_text().replace("child: fetch::base_link", "child: fetch::torso_lift_link")
    (tmp_path / "station.yaml").write_text(text)
    scenario = load_station_scenario(tmp_path / "station.yaml")
    with pytest.raises(ConfigError, match="must weld fetch::base_link to 'world'"):
        make_station_plant(scenario, purpose=PlantPurpose.CONTROLLER)
    scenario.robot_model = "no_such_robot"
    with pytest.raises(ConfigError, match="exactly one model named 'no_such_robot'"):
        make_station_plant(scenario, purpose=PlantPurpose.PLANNING)


def test_station_for_finds_by_name_then_by_shelf_and_refuses_an_unknown_shelf(tmp_path):
    """One lookup for every command: station_<stem>.yaml first, else a shipped station with the same shelf."""
    from slax_drake.config import REPO_ROOT
    from slax_drake.errors import StationNotFoundError
    from slax_drake.scene.model import Shelf
    from slax_drake.station.scenario import station_for

    assert Path(station_for("sim_configs/sim_shelf.yaml")).name == "station_sim_shelf.yaml"
    # table1.yaml has no station of its own: the shipped station with its shelf (the sim shelf)
    assert Path(station_for(REPO_ROOT / "sim_configs" / "table1.yaml")).name == "station_sim_shelf.yaml"
    # a copy elsewhere under another name (written out flat: the shipped file is an overlay) is found by its shelf
    from pydrake.common.yaml import yaml_dump_typed

    from slax_drake.config import load_scenario

    copy = tmp_path / "my_table.yaml"
    copy.write_text(yaml_dump_typed(load_scenario(REPO_ROOT / "sim_configs" / "physical_shelf.yaml")))
    assert Path(station_for(copy)).name == "station_physical_shelf.yaml"
    with pytest.raises(StationNotFoundError, match="pass --station"):
        station_for(shelf=Shelf(width=1.234, height=0.5, depth=0.5))
