"""The station: Fetch with the bluction tool, the shelf with a scene's objects, suction and the tool camera.

``MakeStation(scenario, scene=None, meshcat=None)`` builds one Drake Diagram in the order of Drake's
hardware_sim.py (plant -> controllers -> suction -> camera -> visualization) from a typed ``StationScenario``
whose model directives live in ``sim_configs/station_*.yaml``. The plant (directives, shelf, the scene's objects)
comes from ``slax_drake.station.plant.make_station_plant(..., PlantPurpose.SIMULATION)``, the same builder that
makes the planner's and the checker's worlds and the gravity-compensation controller plant.

Shelf placement: ``slax_drake.station.scenario`` (the tool camera at q_obs is exactly the scene's X_SC).

Ports of the station (all lower_snake_case):

inputs
- ``desired_state`` (18): [q_d, v_d] of ``PLANNED_JOINTS`` (torso m, arm and shaft rad; m/s, rad/s). Feed it a
  TrajectorySource of a joint trajectory (positions and derivatives), or a constant. The head is held at
  ``head_configuration``. Each joint is a PD-controlled actuator of the discrete plant (implicit PD, gains in
  the URDF) with gravity compensation as feed-forward; torques are clamped to the effort limits.
- ``suction_command`` (1): on when > 0.5.

outputs
- ``measured_state`` (18): [q, v] of ``PLANNED_JOINTS``.
- ``measured_efforts`` (9): the effort each joint controller of ``PLANNED_JOINTS`` applies (N for the torso, N m
  for the arm and the shaft): the plant's net actuation (the PD torque plus the gravity feed-forward, clamped to
  the effort limits), what a Fetch's ``joint_states`` reports as ``effort`` (its motor currents times their
  torque constants). Sampled from the last plant step (the discrete plant's output).
- ``robot_state``: the full state of the robot model instance; ``plant_state``: the plant's whole state.
- ``depth_image`` (ImageDepth32F, metres), ``label_image`` (ImageLabel16I: shelf 0, objects[i] i + 1, target
  last, background/robot empty), ``color_image``: the tool camera, rendered only when evaluated (camera=True).
- ``query_object``, ``body_poses``, ``contact_results``, ``suction_force`` (1: the pull in N).

Speed: the plant steps at 5 ms (``plant_config.time_step``); objects stand on small corner/rim spheres only
(scene_world). For long runs, ``slax_drake.systems.sleep.ObjectSleep(station).install(simulator)`` locks resting
objects out of the step until something comes near (about 1.4x faster with 10 objects at rest;
benchmarks/bench_station.py documents the measurements and trade-offs).
"""

from __future__ import annotations

import numpy as np

from slax_drake.scene.model import Scene
from slax_drake.station import robot as robot_model
from slax_drake.station.plant import PlantPurpose, make_station_plant
from slax_drake.station.scenario import StationScenario, camera_render_cameras, observation_positions


def MakeStation(scenario: StationScenario, scene: Scene | None = None, meshcat=None, camera: bool | None = None):
    """Builds the station Diagram (ports in the module docstring). ``scene``: objects to place (or an empty shelf).

    ``camera`` overrides ``scenario.camera`` (False leaves out the RgbdSensor and its renderer).
    """
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet, MakeRenderEngineVtk, RenderEngineVtkParams
    from pydrake.systems.controllers import InverseDynamics
    from pydrake.systems.framework import DiagramBuilder
    from pydrake.systems.primitives import Adder, ConstantVectorSource, MatrixGain, SharedPointerSystem
    from pydrake.systems.sensors import RgbdSensor

    from slax_drake.station.scene_world import (
        SceneBodies,
        assign_render_labels,
        set_default_object_poses,
        support_by_corner_spheres_only,
    )
    from slax_drake.systems.suction import SuctionCup

    use_camera = scenario.camera if camera is None else camera
    builder = DiagramBuilder()
    station_plant = make_station_plant(scenario, scene, PlantPurpose.SIMULATION, builder)
    cam = station_plant.camera
    plant, scene_graph = station_plant.plant, station_plant.scene_graph
    robot, shelf_instance, X_WS = station_plant.robot, station_plant.shelf, station_plant.X_WS
    bodies = station_plant.scene_bodies
    plant.set_name("plant")

    # The robot never collides with itself in this model (its boxes overlap at the joints).
    robot_geometries = [g for b in plant.GetBodyIndices(robot) for g in plant.GetCollisionGeometriesForBody(plant.get_body(b))]
    scene_graph.collision_filter_manager().Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_geometries)))
    if bodies is not None:
        support_by_corner_spheres_only(scene_graph, plant, shelf_instance, bodies)
    assign_render_labels(scene_graph, plant, shelf_instance, robot, bodies or SceneBodies((), None, ()))
    if scene is not None:
        set_default_object_poses(plant, scene, bodies, X_WS)

    # Default robot pose: the observation configuration.
    q_default = plant.GetDefaultPositions(robot).copy()
    planned_local = _local_position_indices(plant, robot, robot_model.PLANNED_JOINTS)
    q_default[planned_local] = observation_positions(scenario)
    head_names = tuple(scenario.head_configuration)
    q_default[_local_position_indices(plant, robot, head_names)] = [scenario.head_configuration[n] for n in head_names]
    plant.SetDefaultPositions(robot, q_default)

    # Desired state: the planned joints from the input, the head (and any other actuated joint) held still.
    actuated_joints = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices(robot)]
    nu = len(actuated_joints)
    n_planned = len(robot_model.PLANNED_JOINTS)
    D = np.zeros((2 * nu, 2 * n_planned))
    hold = np.zeros(2 * nu)
    for k, name in enumerate(actuated_joints):
        if name in robot_model.PLANNED_JOINTS:
            j = robot_model.PLANNED_JOINTS.index(name)
            D[k, j] = 1.0
            D[nu + k, n_planned + j] = 1.0
        else:
            hold[k] = scenario.head_configuration.get(name, 0.0)
    select = builder.AddNamedSystem("desired_state_to_actuators", MatrixGain(D))
    held = builder.AddNamedSystem("held_joints", ConstantVectorSource(hold))
    desired = builder.AddNamedSystem("desired_actuator_state", Adder(2, 2 * nu))
    builder.Connect(select.get_output_port(), desired.get_input_port(0))
    builder.Connect(held.get_output_port(), desired.get_input_port(1))
    builder.Connect(desired.get_output_port(), plant.get_desired_state_input_port(robot))
    builder.ExportInput(select.get_input_port(), "desired_state")

    # Gravity compensation (feed-forward) from the controller plant: the robot of the same directives, alone. That
    # plant is not a subsystem of the diagram (as one, its 22 continuous states would be integrated every step for
    # nothing, about 17 % of the step time); a SharedPointerSystem owns it (InverseDynamics only keeps a pointer).
    controller_plant = make_station_plant(scenario, purpose=PlantPurpose.CONTROLLER).plant
    builder.AddNamedSystem("controller_plant_owner", SharedPointerSystem(controller_plant))
    gravity = builder.AddNamedSystem(
        "gravity_compensation", InverseDynamics(controller_plant, InverseDynamics.InverseDynamicsMode.kGravityCompensation)
    )
    B = controller_plant.MakeActuationMatrix()  # nv x nu, one 1 per column
    to_actuation = builder.AddNamedSystem("generalized_to_actuation", MatrixGain(B.T))
    builder.Connect(plant.get_state_output_port(robot), gravity.get_input_port_estimated_state())
    builder.Connect(gravity.get_output_port_generalized_force(), to_actuation.get_input_port())
    builder.Connect(to_actuation.get_output_port(), plant.get_actuation_input_port(robot))

    # Measured state of the planned joints.
    nq_robot = plant.num_positions(robot)
    S = np.zeros((2 * n_planned, 2 * nq_robot))
    for j, k in enumerate(planned_local):
        S[j, k] = 1.0
        S[n_planned + j, nq_robot + _local_velocity_index(plant, robot, robot_model.PLANNED_JOINTS[j])] = 1.0
    measured = builder.AddNamedSystem("measured_planned_state", MatrixGain(S))
    builder.Connect(plant.get_state_output_port(robot), measured.get_input_port())
    builder.ExportOutput(measured.get_output_port(), "measured_state")
    # Joint efforts of the planned joints: the net actuation (actuator order) picked in PLANNED_JOINTS order.
    E = np.zeros((n_planned, nu))
    for k, name in enumerate(actuated_joints):
        if name in robot_model.PLANNED_JOINTS:
            E[robot_model.PLANNED_JOINTS.index(name), k] = 1.0
    efforts = builder.AddNamedSystem("measured_planned_efforts", MatrixGain(E))
    builder.Connect(plant.get_net_actuation_output_port(robot), efforts.get_input_port())
    builder.ExportOutput(efforts.get_output_port(), "measured_efforts")
    builder.ExportOutput(plant.get_state_output_port(robot), "robot_state")
    builder.ExportOutput(plant.get_state_output_port(), "plant_state")

    # Suction.
    cup_frame = plant.GetFrameByName(robot_model.CUP_TIP_FRAME, robot)
    suction = builder.AddNamedSystem(
        "suction_cup",
        SuctionCup(plant, scene_graph, cup_frame, scenario.suction, object_bodies=bodies.all() if bodies else []),
    )
    builder.Connect(scene_graph.get_query_output_port(), suction.GetInputPort("query_object"))
    builder.Connect(suction.GetOutputPort("spatial_forces"), plant.get_applied_spatial_force_input_port())
    builder.ExportInput(suction.GetInputPort("suction_command"), "suction_command")
    builder.ExportOutput(suction.GetOutputPort("suction_state"), "suction_force")

    # The tool camera: the scene package's Camera, attached at camera_optical_frame.
    if use_camera:
        renderer = "slax_vtk"
        scene_graph.AddRenderer(renderer, MakeRenderEngineVtk(RenderEngineVtkParams()))
        color_camera, depth_camera = camera_render_cameras(cam, renderer)
        optical = plant.GetFrameByName(robot_model.CAMERA_FRAME, robot)
        sensor = builder.AddNamedSystem(
            "tool_camera",
            RgbdSensor(
                plant.GetBodyFrameIdOrThrow(optical.body().index()),
                optical.GetFixedPoseInBodyFrame(),
                color_camera,
                depth_camera,
            ),
        )
        builder.Connect(scene_graph.get_query_output_port(), sensor.query_object_input_port())
        builder.ExportOutput(sensor.depth_image_32F_output_port(), "depth_image")
        builder.ExportOutput(sensor.label_image_output_port(), "label_image")
        builder.ExportOutput(sensor.color_image_output_port(), "color_image")

    builder.ExportOutput(scene_graph.get_query_output_port(), "query_object")
    builder.ExportOutput(plant.get_body_poses_output_port(), "body_poses")
    builder.ExportOutput(plant.get_contact_results_output_port(), "contact_results")

    if meshcat is not None:
        from pydrake.visualization import AddDefaultVisualization

        AddDefaultVisualization(builder, meshcat)

    diagram = builder.Build()
    diagram.set_name("station")
    return diagram


def _local_position_indices(plant, instance, names) -> list[int]:
    """Indices of the joints' positions within the model instance's position vector."""
    q = np.arange(plant.num_positions(), dtype=float)
    local = plant.GetPositionsFromArray(instance, q).astype(int).tolist()
    return [local.index(plant.GetJointByName(n, instance).position_start()) for n in names]


def _local_velocity_index(plant, instance, name) -> int:
    v = np.arange(plant.num_velocities(), dtype=float)
    local = plant.GetVelocitiesFromArray(instance, v).astype(int).tolist()
    return local.index(plant.GetJointByName(name, instance).velocity_start())
