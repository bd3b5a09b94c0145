"""The full station: point contact, the scene's objects at rest where the JSON puts them, the tool camera equal
to the scene camera, the exported ports, and bad station files."""

import math

import numpy as np
import pytest

from slax_drake.config import REPO_ROOT
from slax_drake.errors import ConfigError
from slax_drake.scene.sampling import sample_scene
from slax_drake.station import robot as robot_model
from slax_drake.station.scenario import DEFAULT_STATION, load_station_scenario, observation_positions
from slax_drake.systems.station import MakeStation

DEFAULT_STATION_PATH = REPO_ROOT / DEFAULT_STATION


@pytest.fixture(scope="module")
def station(sim_scenario):
    scenario = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    scene = sample_scene(sim_scenario, 6, seed=3)
    return scenario, scene, MakeStation(scenario, scene, camera=False)


def _simulator(diagram, seconds):
    from pydrake.systems.analysis import Simulator

    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    q = diagram.GetOutputPort("measured_state").Eval(context)[:9]
    diagram.GetInputPort("desired_state").FixValue(context, np.concatenate([q, np.zeros(9)]))
    diagram.GetInputPort("suction_command").FixValue(context, [0.0])
    simulator.AdvanceTo(seconds)
    return simulator


def test_contact_model_is_point(station):
    from pydrake.multibody.plant import ContactModel

    plant = station[2].GetSubsystemByName("plant")
    assert plant.get_contact_model() == ContactModel.kPoint
    assert plant.time_step() > 0


def test_objects_rest_at_their_json_poses_and_the_arm_holds(station):
    scenario, scene, diagram = station
    simulator = _simulator(diagram, 0.6)
    context = simulator.get_context()
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = plant.GetFrameByName("shelf_body").CalcPoseInWorld(plant_context).inverse()
    for obj in scene.objects + (scene.target.as_object(),):
        X_SO = X_SW @ plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName(obj.name))
        assert np.linalg.norm(X_SO.translation() - obj.X_SO[:3, 3]) < 1e-3, obj.name
        assert np.allclose(X_SO.rotation().matrix(), obj.X_SO[:3, :3], atol=1e-2), obj.name
    q = diagram.GetOutputPort("measured_state").Eval(context)[:9]
    assert np.abs(q - observation_positions(scenario)).max() < 1e-3


def test_the_measured_efforts_at_rest_are_the_gravity_torques(station):
    """Holding the observation pose, the joint controllers apply what gravity needs (the PD part is ~0): the
    efforts of the planned joints equal the robot's gravity torques there, in PLANNED_JOINTS order."""
    scenario, _, diagram = station
    simulator = _simulator(diagram, 0.6)
    context = simulator.get_context()
    efforts = diagram.GetOutputPort("measured_efforts").Eval(context)
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    tau_g = plant.CalcGravityGeneralizedForces(plant_context)  # generalized forces gravity applies
    robot = plant.GetModelInstanceByName(scenario.robot_model)
    expected = [-tau_g[plant.GetJointByName(n, robot).velocity_start()] for n in robot_model.PLANNED_JOINTS]
    assert np.abs(np.asarray(expected)).max() > 1.0  # the arm is held against gravity
    assert np.allclose(efforts, expected, atol=0.05 + 0.02 * np.abs(expected))


def test_tool_camera_is_the_scene_camera_at_the_observation_pose(station):
    scenario, scene, diagram = station
    plant = diagram.GetSubsystemByName("plant")
    context = plant.CreateDefaultContext()
    X_SC = plant.GetFrameByName(robot_model.CAMERA_FRAME).CalcPose(context, plant.GetFrameByName("shelf_body"))
    assert np.allclose(X_SC.GetAsMatrix4(), scene.camera.X_SC, atol=1e-9)
    X_WS = plant.GetFrameByName("shelf_body").CalcPoseInWorld(context)
    assert X_WS.rotation().matrix()[2, 2] > np.cos(1e-3)  # the shelf stands level


def test_ports(station):
    diagram = station[2]
    inputs = {diagram.get_input_port(i).get_name() for i in range(diagram.num_input_ports())}
    outputs = {diagram.get_output_port(i).get_name() for i in range(diagram.num_output_ports())}
    assert inputs == {"desired_state", "suction_command"}
    assert {"measured_state", "measured_efforts", "robot_state", "query_object", "body_poses", "contact_results",
            "suction_force"} <= outputs
    assert diagram.GetOutputPort("measured_efforts").size() == len(robot_model.PLANNED_JOINTS)
    assert diagram.GetInputPort("desired_state").size() == 18


def test_depth_image_agrees_with_the_scene_raycaster(sim_scenario):
    from slax_drake.scene.raycast import SceneRaycaster

    scenario = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    scene = sample_scene(sim_scenario, 4, seed=5)
    small = scene.camera.with_resolution(160, 120)
    scene = type(scene)(scene.shelf, small, scene.objects, scene.target, scene.seed)
    diagram = MakeStation(scenario, scene)
    context = diagram.CreateDefaultContext()
    depth = diagram.GetOutputPort("depth_image").Eval(context).data[:, :, 0]
    labels = diagram.GetOutputPort("label_image").Eval(context).data[:, :, 0]
    ref_depth, ref_labels = SceneRaycaster(scene, include_target=True).render(small)
    both = np.isfinite(ref_depth) & (ref_depth > 0) & np.isfinite(depth) & (depth > 0)
    assert both.mean() > 0.5
    # Measured: 99.94 % of pixels within 1 mm and 99.99 % of labels equal (the rest lie on silhouettes).
    close = np.abs(depth[both] - ref_depth[both]) < 0.001
    assert close.mean() > 0.995
    same = labels[both].astype(int) == ref_labels[both].astype(int)
    assert same.mean() > 0.995


def test_bad_station_file(tmp_path):
    bad = tmp_path / "station.yaml"
    bad.write_text("observation_configuration: {torso_lift_joint: 0.1}\n")
    with pytest.raises(ConfigError, match="observation_configuration"):
        load_station_scenario(bad)
    with pytest.raises(ConfigError, match="no such station file"):
        load_station_scenario(tmp_path / "missing.yaml")
    text = DEFAULT_STATION_PATH.read_text().replace("max_held_moment: 0.4", "max_held_moment: 0.0")
    bad.write_text(text)
    with pytest.raises(ConfigError, match="suction.max_held_moment"):
        load_station_scenario(bad)
    bad.write_text(DEFAULT_STATION_PATH.read_text().replace("max_seal_angle_deg: 10.0", "max_seal_angle_deg: 120"))
    with pytest.raises(ConfigError, match="suction.max_seal_angle_deg"):
        load_station_scenario(bad)


def test_the_station_cup_limits_are_planning_rules_that_overrides_replace():
    """A trial plans with the station cup's limits, reach map, guarded placement and push model unless a tool rule
    says otherwise; .inf / 90 lift the limits."""
    import dataclasses
    import math

    from slax_drake.systems.trial import station_tool_rules

    shipped = load_station_scenario(DEFAULT_STATION_PATH)
    # the station's reach map is one of its planning rules too
    # and so is its guarded placement (the station profile's "placement" otherwise), which an override replaces
    assert station_tool_rules(shipped) == {"max_suction_moment": 0.4, "max_drag_pull": 42.412, "max_drag_twist": 0.6362, "max_seal_angle_deg": 10.0,
                                           "reach_map": "models/reach/station_sim_shelf.json",
                                           "suction_hidden_rule": "guarded", "push_turn": "quasi-static"}
    assert "suction_hidden_rule" not in station_tool_rules(shipped, {"suction_hidden_rule": "placement"})
    assert "push_turn" not in station_tool_rules(shipped, {"push_turn": "none"})  # the profile's value
    assert station_tool_rules(shipped, {"suction_hidden_rule": "path"})["suction_hidden_rule"] == "path"
    station = dataclasses.replace(shipped, reach_map="", guarded_placement=False, push_turn="none")
    assert station.suction.max_held_moment == pytest.approx(0.4)
    assert station.suction.max_seal_angle_deg == pytest.approx(10.0)
    assert station_tool_rules(station) == {"max_suction_moment": 0.4, "max_drag_pull": 42.412, "max_drag_twist": 0.6362, "max_seal_angle_deg": 10.0}
    assert station_tool_rules(station, {"max_suction_moment": 0.3, "blade_gap": 0.05}) == {
        "max_suction_moment": 0.3, "max_drag_pull": 42.412, "max_drag_twist": 0.6362, "max_seal_angle_deg": 10.0, "blade_gap": 0.05}
    # The first-order defaults are no variant: a run under them is recorded as one under no rules.
    assert station_tool_rules(station, {"max_suction_moment": math.inf, "max_seal_angle_deg": 90.0}) == {}
    unlimited = dataclasses.replace(station, suction=dataclasses.replace(
        station.suction, max_held_moment=math.inf, max_seal_angle_deg=90.0))
    assert station_tool_rules(unlimited) == {}


def test_resting_objects_fall_asleep_where_the_json_puts_them(sim_scenario):
    from pydrake.systems.analysis import Simulator

    from slax_drake.systems.sleep import ObjectSleep

    scenario = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    scene = sample_scene(sim_scenario, 10, seed=0)
    diagram = MakeStation(scenario, scene, camera=False)
    simulator = Simulator(diagram)
    sleep = ObjectSleep(diagram)
    sleep.install(simulator)
    context = simulator.get_mutable_context()
    q = diagram.GetOutputPort("measured_state").Eval(context)[:9]
    diagram.GetInputPort("desired_state").FixValue(context, np.concatenate([q, np.zeros(9)]))
    diagram.GetInputPort("suction_command").FixValue(context, [0.0])
    simulator.AdvanceTo(0.6)
    assert all(sleep.sleeping(context)), dict(zip(sleep.names(), sleep.sleeping(context)))
    assert sorted(sleep.names()) == sorted(o.name for o in scene.objects + (scene.target.as_object(),))
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = plant.GetFrameByName("shelf_body").CalcPoseInWorld(plant_context).inverse()
    for obj in scene.objects + (scene.target.as_object(),):
        X_SO = X_SW @ plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName(obj.name))
        assert np.linalg.norm(X_SO.translation() - obj.X_SO[:3, 3]) < 1e-3, obj.name
    # Asleep, they stay exactly where they are.
    bodies = [plant.GetBodyByName(name) for name in sleep.names()]
    poses = [plant.EvalBodyPoseInWorld(plant_context, b).GetAsMatrix4() for b in bodies]
    simulator.AdvanceTo(1.0)
    assert all(np.array_equal(plant.EvalBodyPoseInWorld(plant_context, b).GetAsMatrix4(), X) for b, X in zip(bodies, poses))


def test_a_station_names_a_push_model_the_action_model_knows(tmp_path):
    from slax_drake.shelf.rules import RULES
    from slax_drake.station.scenario import PUSH_TURNS

    assert PUSH_TURNS == RULES["push_turn"].choices
    bad = tmp_path / "station.yaml"
    bad.write_text(DEFAULT_STATION_PATH.read_text().replace("push_turn: quasi-static", "push_turn: spin"))
    with pytest.raises(ConfigError, match="push_turn"):
        load_station_scenario(bad)


@pytest.mark.parametrize("value", ["-0.001", ".nan", ".inf"])
def test_a_station_push_compliance_is_a_non_negative_number(tmp_path, value):
    bad = tmp_path / "station.yaml"
    text = DEFAULT_STATION_PATH.read_text()
    assert "\npush_compliance: 0.0 " in text
    bad.write_text(text.replace("\npush_compliance: 0.0 ", f"\npush_compliance: {value} "))
    with pytest.raises(ConfigError, match="push_compliance"):
        load_station_scenario(bad)


def test_an_object_off_the_shelf_lands_on_the_floor_and_rests_there(sim_scenario):
    """A box placed in front of the shelf's opening, in the air, falls onto the room's floor (world z = 0) and rests
    there, as a dropped object does (without the floor it fell until the plant's state was no longer finite); the
    robot, welded to the world, does not touch the floor."""
    from slax_drake.scene.model import Scene, SceneObject, planar_pose

    scenario = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    shelf = sample_scene(sim_scenario, 1, seed=0)
    box = SceneObject("object_0", "box", (0.08, 0.08, 0.12), planar_pose(0.0, -shelf.shelf.depth / 2 - 0.25, 0.06,
                                                                         0.0), mass=0.5)
    scene = Scene(shelf.shelf, shelf.camera, (box,), None, 0)
    diagram = MakeStation(scenario, scene, camera=False)
    simulator = _simulator(diagram, 1.5)
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(simulator.get_context())
    body = plant.GetBodyByName("object_0")
    X_WO = plant.EvalBodyPoseInWorld(plant_context, body)
    assert X_WO.translation()[2] == pytest.approx(0.06, abs=2e-3)  # its centre half its height above the floor
    assert np.linalg.norm(plant.EvalBodySpatialVelocityInWorld(plant_context, body).translational()) < 1e-2
    contacts = plant.get_contact_results_output_port().Eval(plant_context)
    touching = {plant.get_body(i).name() for k in range(contacts.num_point_pair_contacts())
                for i in (contacts.point_pair_contact_info(k).bodyA_index(),
                          contacts.point_pair_contact_info(k).bodyB_index())}
    assert touching == {"world", "object_0"}


@pytest.mark.parametrize("station_file, scenario_file", [("sim_configs/station_sim_shelf.yaml", "sim_configs/sim_shelf.yaml"),
                                                          ("sim_configs/station_table2.yaml", "sim_configs/table2.yaml")])
def test_an_object_pressed_deep_into_the_support_board_comes_back_up(station_file, scenario_file):
    """A box whose bottom starts 1.5 cm inside the support board (as a carried object pressed into it) is pushed back
    up onto the board and rests there. With a collision box as thin as the 2 cm panel its corner spheres, past the
    board's middle, met the bottom face nearer than the top and the box fell through the board
    (``SUPPORT_COLLISION_DEPTH``)."""
    from slax_drake.config import load_scenario
    from slax_drake.scene.model import Scene, SceneObject, planar_pose

    scenario = load_station_scenario(station_file)
    shelf = sample_scene(load_scenario(scenario_file), 1, seed=0)
    box = SceneObject("object_0", "box", (0.08, 0.08, 0.12), planar_pose(0.0, 0.0, 0.06 - 0.015, 0.0), mass=0.3)
    scene = Scene(shelf.shelf, shelf.camera, (box,), None, 0)
    diagram = MakeStation(scenario, scene, camera=False)
    simulator = _simulator(diagram, 1.0)
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(simulator.get_context())
    from slax_drake.station.plant import shelf_pose

    X_SO = shelf_pose(scenario, scene.camera).inverse() @ plant.EvalBodyPoseInWorld(
        plant_context, plant.GetBodyByName("object_0"))
    assert X_SO.translation()[2] == pytest.approx(0.06, abs=3e-3)  # resting on the board, not beneath it


@pytest.mark.parametrize("station_file, scenario_file", [("sim_configs/station_sim_shelf.yaml", "sim_configs/sim_shelf.yaml"),
                                                          ("sim_configs/station_table2.yaml", "sim_configs/table2.yaml")])
def test_an_object_over_the_front_edge_rests_on_it_until_its_centre_of_mass_is_past_it(station_file, scenario_file):
    """An 8 cm deep box whose front overhangs the support board's front edge by 1 cm (its centre of mass 3 cm behind
    the edge) rests on the edge and stays upright on the board; one whose centre of mass is 1 cm past the edge tips
    off and falls to the room's floor, not into the board. Before ``support_front_edge`` the first one pivoted about
    its back corner spheres, the edge cutting through its shape, and fell."""
    from slax_drake.config import load_scenario
    from slax_drake.scene.model import Scene, SceneObject, planar_pose
    from slax_drake.station.plant import shelf_pose

    scenario = load_station_scenario(station_file)
    shelf = sample_scene(load_scenario(scenario_file), 1, seed=0)
    front = -shelf.shelf.depth / 2

    def rest(centre_behind_edge):
        box = SceneObject("object_0", "box", (0.08, 0.08, 0.12), planar_pose(0.0, front + centre_behind_edge, 0.06, 0.0),
                          mass=0.3)
        diagram = MakeStation(scenario, Scene(shelf.shelf, shelf.camera, (box,), None, 0), camera=False)
        simulator = _simulator(diagram, 1.5)
        plant = diagram.GetSubsystemByName("plant")
        plant_context = plant.GetMyContextFromRoot(simulator.get_context())
        return shelf_pose(scenario, shelf.camera).inverse() @ plant.EvalBodyPoseInWorld(
            plant_context, plant.GetBodyByName("object_0"))

    X_SO = rest(0.03)
    assert X_SO.translation()[2] == pytest.approx(0.06, abs=3e-3)
    assert X_SO.translation()[1] == pytest.approx(front + 0.03, abs=0.01)
    assert X_SO.rotation().matrix()[2, 2] > math.cos(math.radians(3.0))  # upright
    X_SO = rest(-0.01)
    assert X_SO.translation()[2] < -0.3 and X_SO.translation()[1] < front  # on the floor in front of the shelf
