"""The one plant builder of the station: every MultibodyPlant of the project comes from a ``StationScenario``.

``make_station_plant(scenario, scene, purpose)`` (in the manner of Drake's ``MakeMultibodyPlant`` and of
``manipulation``'s hardware station) processes the scenario's model directives, so that the robot is read from
one place only (the station YAML's ``add_model`` of ``robot_model``, welded by its ``add_weld``), and adds, by
``purpose`` (:class:`PlantPurpose`):

==============  ========================  ==========================================  =======================
purpose         plant                     shelf and scene objects                     used by
==============  ========================  ==========================================  =======================
SIMULATION      ``plant_config`` (5 ms    shelf welded at X_WS; objects (and target)  ``systems.station``'s
                discrete), SceneGraph     as free bodies with mass, contact spheres   ``MakeStation``
                                          and visuals; the room's floor at W z = 0
                                          (``scene_world``)
PLANNING        continuous, SceneGraph,   shelf welded at X_WS; objects (target if    ``planning.world``'s
                in a RobotDiagramBuilder  asked) welded where they stand, primitive   ``PlanningWorld``
                                          box/cylinder collision shapes only
CHECKING        continuous, SceneGraph    shelf welded at X_WS; objects as free       ``hardware.collision``'s
                                          bodies, primitive collision shapes only     ``CollisionWorld``
                                          (placed per motion by the checker)
CONTROLLER      continuous, no SceneGraph none: the robot's directives alone          gravity compensation,
                                                                                      joint limits, camera pose
==============  ========================  ==========================================  =======================

Frames: W is the world of the directives (the robot's base welded by its ``add_weld``); S is the shelf frame of
the scene package, welded at X_WS = X_WC(q_obs) * inv(X_SC) (:func:`shelf_pose`): at the observation
configuration q_obs the tool camera's frame is exactly the scene camera's X_SC. The shelf pose is computed on the
controller plant, so it follows the robot of the directives too.

The objects of every purpose are in model instances ``object_<name>`` (body ``<name>``, collision geometry
``<name>_collision``), in scene order and the target last.
"""

from __future__ import annotations

import dataclasses
import enum
import math

import numpy as np

from slax_drake.caches import IdentityMemo
from slax_drake.errors import ConfigError
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene
from slax_drake.station import robot as robot_model
from slax_drake.errors import SceneMismatchError
from slax_drake.station.scenario import SHELF_BODY, StationScenario, observation_positions


class PlantPurpose(enum.Enum):
    """What a station plant is for (see the module docstring's table)."""

    SIMULATION = "simulation"
    PLANNING = "planning"
    CHECKING = "checking"
    CONTROLLER = "controller"


@dataclasses.dataclass
class StationPlant:
    """A finalized station plant and what was added to it.

    ``builder``: the DiagramBuilder (SIMULATION, CHECKING) or RobotDiagramBuilder (PLANNING) holding the plant and
    its SceneGraph; None for CONTROLLER (a plant of its own). ``shelf`` and ``X_WS`` (RigidTransform, the shelf
    frame S in the world) are None for CONTROLLER, and so is ``camera``, the scene camera the shelf was placed from
(the scene's, or the station's scene scenario's when there is no scene). ``objects`` maps each object's name to its body, in scene order
    (target last when added); ``scene_bodies`` lists their indices the way ``scene_world`` does (SIMULATION).
    """

    purpose: PlantPurpose
    plant: object
    scene_graph: object | None
    builder: object | None
    robot: object
    shelf: object | None
    X_WS: object | None
    objects: dict
    camera: Camera | None = None
    scene_bodies: object | None = None


def robot_directives(scenario: StationScenario) -> list:
    """The directives that add the robot: its ``add_model`` (named ``robot_model``) and the ``add_weld`` of its
    base to the world. ConfigError when the directives lack either."""
    child = f"{scenario.robot_model}::{robot_model.BASE_BODY}"
    model = [d for d in scenario.directives if d.add_model is not None and d.add_model.name == scenario.robot_model]
    weld = [d for d in scenario.directives if d.add_weld is not None and d.add_weld.child == child]
    if len(model) != 1:
        raise ConfigError(f"the directives must add exactly one model named {scenario.robot_model!r}")
    if len(weld) != 1 or weld[0].add_weld.parent != "world":
        raise ConfigError(f"the directives must weld {child} to 'world' (one add_weld)")
    return model + weld


def scene_camera(scenario: StationScenario, scene: Scene | None) -> Camera:
    """The scene's camera, or the camera of the station's scene scenario when there is no scene; SceneMismatchError
    when the scene stands on another shelf than the station's."""
    shelf, camera = _SCENE_CONFIGS(scenario)
    if scene is None:
        return camera
    if scene.shelf != shelf:
        raise SceneMismatchError(
            f"the scene's shelf {scene.shelf} differs from the station's ({scenario.scene_config}: {shelf}); "
            "use the station file made for that shelf"
        )
    return scene.camera


def _scene_config_shelf_and_camera(scenario: StationScenario):
    """(Shelf, Camera) of the station's scene scenario, loaded once per station scenario (the planner builds a
    planning world, and checks its scene against the station's shelf, for every object state it plans in)."""
    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import shelf_of

    config = load_scenario(scenario.scene_config)
    return shelf_of(config), Camera.from_config(config.camera)


_SCENE_CONFIGS = IdentityMemo(_scene_config_shelf_and_camera, limit=8)


def make_station_plant(scenario: StationScenario, scene: Scene | None = None,
                       purpose: PlantPurpose = PlantPurpose.SIMULATION, builder=None,
                       include_target: bool | None = None) -> StationPlant:
    """Builds and finalizes the station's plant for ``purpose`` (module docstring).

    ``builder``: a DiagramBuilder to add the plant and SceneGraph to (SIMULATION, CHECKING) or a
    RobotDiagramBuilder (PLANNING); a new one when None; ignored for CONTROLLER. ``include_target``: add the
    scene's target too (default: True for SIMULATION, False otherwise). ConfigError when the directives lack the
    robot or the shelf; SceneMismatchError when the scene does not stand on the station's shelf.
    """
    from pydrake.multibody.parsing import ModelDirectives, Parser, ProcessModelDirectives
    from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant, MultibodyPlantConfig

    purpose = PlantPurpose(purpose)
    if purpose is PlantPurpose.CONTROLLER:
        plant = MultibodyPlant(0.0)
        parser = Parser(plant)
        robot_model.add_package(parser)
        ProcessModelDirectives(ModelDirectives(directives=robot_directives(scenario)), plant, parser)
        plant.Finalize()
        robot = plant.GetModelInstanceByName(scenario.robot_model)
        return StationPlant(purpose, plant, None, None, robot, None, None, {})

    robot_directives(scenario)  # the robot must be there (ConfigError otherwise)
    camera = scene_camera(scenario, scene)
    X_WS = shelf_pose(scenario, camera)
    if purpose is PlantPurpose.PLANNING:
        from pydrake.planning import RobotDiagramBuilder

        builder = builder if builder is not None else RobotDiagramBuilder(time_step=0.0)
        plant, scene_graph, parser = builder.plant(), builder.scene_graph(), builder.parser()
    else:
        from pydrake.systems.framework import DiagramBuilder

        builder = builder if builder is not None else DiagramBuilder()
        config = scenario.plant_config if purpose is PlantPurpose.SIMULATION else MultibodyPlantConfig(time_step=0.0)
        plant, scene_graph = AddMultibodyPlant(config, builder)
        parser = Parser(plant)
    robot_model.add_package(parser)
    ProcessModelDirectives(ModelDirectives(directives=scenario.directives), plant, parser)
    if not plant.HasModelInstanceNamed(scenario.shelf_model):
        raise ConfigError(f"the directives must add the shelf as a model named {scenario.shelf_model!r}")
    robot = plant.GetModelInstanceByName(scenario.robot_model)
    shelf = plant.GetModelInstanceByName(scenario.shelf_model)
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(SHELF_BODY, shelf), X_WS)

    with_target = (purpose is PlantPurpose.SIMULATION) if include_target is None else include_target
    items = [] if scene is None else list(scene.objects) + (
        [scene.target.as_object()] if with_target and scene.target is not None else [])
    scene_bodies = None
    if purpose is not PlantPurpose.SIMULATION:
        objects = _add_primitive_objects(plant, items, X_WS if purpose is PlantPurpose.PLANNING else None)
    elif scene is None:
        objects = {}
    else:
        from slax_drake.config import load_scenario
        from slax_drake.station.scene_world import add_floor, add_scene_objects

        scene_scenario = load_scenario(scenario.scene_config)
        add_floor(plant)
        scene_bodies = add_scene_objects(plant, scene, scene_scenario.objects.density, include_target=with_target,
                                         friction=scene_scenario.physics.object_friction)
        objects = {name: plant.get_body(index) for name, index in zip(scene_bodies.names, scene_bodies.all())}
    plant.Finalize()
    return StationPlant(purpose, plant, scene_graph, builder, robot, shelf, X_WS, objects, camera, scene_bodies)


def _add_primitive_objects(plant, items, X_WS) -> dict:
    """Each object as a body with only its box or cylinder as collision geometry (no mass model of interest):
    welded at X_WS * X_SO when X_WS is given, free otherwise. Returns {name: body}."""
    from pydrake.geometry import Box, Cylinder, ProximityProperties
    from pydrake.math import RigidTransform
    from pydrake.multibody.tree import SpatialInertia

    bodies = {}
    for obj in items:
        instance = plant.AddModelInstance(f"object_{obj.name}")
        body = plant.AddRigidBody(obj.name, instance, SpatialInertia.SolidBoxWithMass(1.0, 0.1, 0.1, 0.1))
        sx, sy, sz = obj.size
        shape = Box(sx, sy, sz) if obj.shape == "box" else Cylinder(sx / 2.0, sz)
        plant.RegisterCollisionGeometry(body, RigidTransform(), shape, f"{obj.name}_collision", ProximityProperties())
        if X_WS is not None:
            plant.WeldFrames(plant.world_frame(), body.body_frame(), X_WS @ RigidTransform(obj.X_SO))
        bodies[obj.name] = body
    return bodies


def controller_plant(scenario: StationScenario):
    """The robot alone (the scenario's robot directives), finalized: for gravity compensation and kinematics."""
    return make_station_plant(scenario, purpose=PlantPurpose.CONTROLLER).plant


def station_joint_limits(scenario: StationScenario) -> robot_model.JointLimits:
    """The limits of ``PLANNED_JOINTS`` of the scenario's robot (:func:`slax_drake.station.robot.joint_limits`)."""
    return robot_model.joint_limits(controller_plant(scenario))


def camera_pose_at(scenario: StationScenario, q_planned: np.ndarray, plant=None):
    """X_WC (RigidTransform) of the tool camera at the planned joint positions (head at head_configuration), on
    ``plant`` (the scenario's controller plant, built when None)."""
    plant = controller_plant(scenario) if plant is None else plant
    context = plant.CreateDefaultContext()
    q = np.zeros(plant.num_positions())
    q[robot_model.planned_joint_indices(plant)] = q_planned
    for name, value in scenario.head_configuration.items():
        q[plant.GetJointByName(name).position_start()] = value
    plant.SetPositions(context, q)
    return plant.GetFrameByName(robot_model.CAMERA_FRAME).CalcPoseInWorld(context)


def base_pose(scenario: StationScenario):
    """X_WB (RigidTransform) of the robot's base_link in the world, from the directives' weld."""
    plant = controller_plant(scenario)
    return plant.GetFrameByName(robot_model.BASE_BODY).CalcPoseInWorld(plant.CreateDefaultContext())


def shelf_pose(scenario: StationScenario, camera: Camera):
    """X_WS = X_WC(q_obs) * inv(X_SC); ConfigError when the shelf would not stand level (> 1 mrad)."""
    from pydrake.math import RigidTransform

    X_WS = camera_pose_at(scenario, observation_positions(scenario)) @ RigidTransform(camera.X_SC).inverse()
    tilt = math.acos(min(1.0, max(-1.0, X_WS.rotation().matrix()[2, 2])))
    if tilt > 1e-3:
        raise ConfigError(
            f"the observation configuration tilts the shelf by {tilt:.4f} rad: at q_obs the camera's roll and pitch "
            "must equal the scene camera's (level roll, pitch_deg down)"
        )
    return X_WS
