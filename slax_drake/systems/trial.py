"""A full SLAX-RAY trial as one Drake diagram: the station and the PlannerSystem, optionally drawn in Meshcat.

:class:`TrialOptions` says which trial (config, station, object count, seed, policy, rules, ...);
:func:`build_trial` samples the scene (``slax_drake.scene.sampling.sample_scene``: the same scenes as the shelf
simulator for the same config, object count and seed), makes the policy and the motion planner and builds the
diagram:

    station camera depth_image -> [DepthNoiseSystem, with ``sensor_noise``] -> PerceptionSystem -> PlannerSystem
    -> station (desired_state, suction_command)

The PerceptionSystem also reads the station's ``label_image``, for the target mask only (the stand-in for detecting
the target by its colour) and, with ``segmentation="labels"``, the occluders' segmentation (the idealised option;
"depth": depth-only segmentation). The planner reads only the perception outputs (``observation``, ``hypotheses``,
``occupancy_1d``), the station's ``measured_state`` and the evaluator's ``stop``. Ground truth (``body_poses``, the
label image) goes only to the EvaluatorSystem, which scores the trial (target visible fraction, lost objects,
poses) and tells the planner when the target is revealed. Running it and recording its outputs (trial.json, step
PNGs, HTML replay) is ``slax_drake.evaluation.trial``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.errors import TrialError

DEFAULT_OBJECTS = 3
DEFAULT_SEED = 7


@dataclasses.dataclass
class TrialOptions:
    config: str = "sim_configs/sim_shelf.yaml"
    objects: int = DEFAULT_OBJECTS
    seed: int = DEFAULT_SEED
    policy: str = "bluction-dar"
    perception: str = "ground-truth"
    station: str | None = None  # default: sim_configs/station_<config stem>.yaml
    meshcat: bool = False
    html: str | None = None
    out: str | None = "out/trial"
    max_sim_time: float | None = None  # default: 40 s per allowed action + 5 s
    stride: int = 10  # trial.json keeps every stride-th 1 ms sample of the executed trajectory
    sleep: bool = False  # lock resting objects out of the physics step (slax_drake.systems.sleep.ObjectSleep)
    target_size: tuple | None = None  # (x, y, z) m; default: drawn from the scenario's target sizes
    horizon: int | None = None  # actions at most; default: 2 per object
    sensor_noise: bool = False  # the L515 depth-noise model between the camera and perception (seeded by ``seed``)
    segmentation: str = "labels"  # "labels": the render's object labels (idealised); "depth": depth-only
    tool_rules: dict | None = None  # rule overrides of the profile for the policy and the planner; they
    # take precedence over the station's own limits (see station_tool_rules)
    profile: str = "station"  # the action model's rule profile: a Drake trial plans with the physical tool's
    # rules whatever the scene scenario's profile is (slax_drake.shelf.rules)


@dataclasses.dataclass
class TrialDiagram:
    """A built trial (see :func:`build_trial`): run ``diagram`` until ``planner_system.trial_state(context)`` is
    done."""

    diagram: object  # pydrake Diagram
    station: object  # the station subdiagram (MakeStation)
    plant: object  # its MultibodyPlant
    planner_system: object  # PlannerSystem
    evaluator: object  # EvaluatorSystem
    perception: object  # PerceptionSystem
    scene: object  # the initial Scene
    scenario: object  # the scene Scenario (slax_drake.config)
    station_path: str
    body_indices: list  # BodyIndex per scene object, scene order
    X_WS: object  # RigidTransform, shelf frame S in world
    horizon: int  # actions at most
    tool_rules: dict  # the action-model rules in force (station cup limits and opts.tool_rules)
    step_images: list  # (step, depth, labels, history, p1d), appended by the planner at every decision; labels: the
    # occluder segmentation with the target mask as label n + 1 (at the perception's working resolution)


def station_tool_rules(station, overrides: dict | None = None, profile: str = "station") -> dict:
    """The rule overrides of ``profile`` a trial on ``station`` plans with: the station cup's limits
    (``suction.max_held_moment`` as ``max_suction_moment`` when finite, with the cup's pull,
    ``suction.vacuum_pressure`` x cup area, as ``max_drag_pull`` and its lip moment, that times ``cup_radius``, as
    ``max_drag_twist``; ``suction.max_seal_angle_deg`` when under 90), its reach map (``reach_map`` when given) and, when the station
    places by guarded moves (``guarded_placement``), ``suction_hidden_rule`` "guarded"; its ``push_turn``; then
    ``overrides`` on top;
    entries equal to the profile's values are left out."""
    from slax_drake.shelf.tool import without_defaults

    rules = {}
    if math.isfinite(station.suction.max_held_moment):
        rules["max_suction_moment"] = float(station.suction.max_held_moment)
        # what the cup may drag instead of lifting: its pull, vacuum pressure x cup area (drag_grasp rule)
        rules["max_drag_pull"] = round(float(station.suction.max_force), 3)
        rules["max_drag_twist"] = round(float(station.suction.lip_moment), 4)
    if station.suction.max_seal_angle_deg < 90.0:
        rules["max_seal_angle_deg"] = float(station.suction.max_seal_angle_deg)
    if station.reach_map:
        rules["reach_map"] = station.reach_map
    if station.guarded_placement:
        rules["suction_hidden_rule"] = "guarded"
    if station.push_turn != "none":
        rules["push_turn"] = station.push_turn
    rules.update(overrides or {})
    if not math.isfinite(rules.get("max_suction_moment", math.inf)):
        for name in ("max_drag_pull", "max_drag_twist"):  # nothing is dragged when every object is lifted
            if name not in (overrides or {}):
                rules.pop(name, None)
    return without_defaults(rules, profile)


def build_trial(opts: TrialOptions, meshcat=None) -> TrialDiagram:
    """The diagram of the trial ``opts`` describes (see the module docstring); ``meshcat``: draw it there."""
    from pydrake.systems.framework import DiagramBuilder

    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.policies.registry import make_policy
    from slax_drake.shelf.tool import tool_config
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.station.plant import shelf_pose
    from slax_drake.station.scenario import load_station_scenario, station_for
    from slax_drake.perception.belief import make_source
    from slax_drake.scene.model import Scene
    from slax_drake.systems.evaluator import EvaluatorSystem
    from slax_drake.systems.perception_system import PerceptionSystem
    from slax_drake.systems.planner import PlannerSystem
    from slax_drake.systems.station import MakeStation

    if opts.objects < 1:
        raise TrialError(f"--objects must be at least 1 (got {opts.objects})")
    if opts.segmentation not in ("labels", "depth"):
        raise TrialError(f"segmentation must be 'labels' or 'depth' (got {opts.segmentation!r})")
    scenario = load_scenario(opts.config)
    station_path = opts.station or station_for(opts.config)
    station = load_station_scenario(station_path)
    tool_rules = station_tool_rules(station, opts.tool_rules, opts.profile)
    guarded = tool_rules.get("suction_hidden_rule") == "guarded"
    target_size = None if opts.target_size is None else tuple(float(v) for v in opts.target_size)
    scene = sample_scene(scenario, opts.objects, seed=opts.seed, target_size=target_size)
    horizon = opts.horizon if opts.horizon is not None else 2 * opts.objects
    policy = make_policy(opts.policy, scenario, perception=opts.perception, horizon=horizon,
                         tool_overrides=tool_rules, profile=opts.profile)
    if policy.needs_true_scene:
        raise TrialError(f"policy '{opts.policy}' cannot run in a Drake trial (it needs the true scene: an oracle)")
    planner = MotionPlanner(station, tool_config(scenario, opts.profile, **tool_rules))

    builder = DiagramBuilder()
    station_diagram = builder.AddNamedSystem("station", MakeStation(station, scene, meshcat=meshcat))
    plant = station_diagram.GetSubsystemByName("plant")
    bodies = [plant.GetBodyByName(o.name).index() for o in scene.objects]
    X_WS = shelf_pose(station, scene.camera)
    size = scene.target.size if scene.target is not None else tuple(scenario.target.sizes[0])
    source_kind = "network" if opts.perception == "learned" else "depth"
    target_label = len(scene.objects) + 1
    perception = builder.AddNamedSystem("perception", PerceptionSystem(
        scene.camera, scene.shelf, size, source=source_kind, segmentation=opts.segmentation,
        target_label=target_label, input_camera=scene.camera, width=policy.observation_width))
    depth_out = station_diagram.GetOutputPort("depth_image")
    if opts.sensor_noise:
        from slax_drake.systems.depth_noise import DepthNoiseSystem

        noise = builder.AddNamedSystem("depth_noise", DepthNoiseSystem(scene.camera, opts.seed))
        builder.Connect(depth_out, noise.GetInputPort("depth_image"))
        depth_out = noise.GetOutputPort("depth_image")
    builder.Connect(depth_out, perception.GetInputPort("depth_image"))
    builder.Connect(station_diagram.GetOutputPort("label_image"), perception.GetInputPort("label_image"))
    steps = []

    def on_step(entry, depth, segmentation, target_mask, hist, p1d):
        shown = np.where(target_mask, target_label, segmentation)
        steps.append((entry["step"], depth, shown, None if hist is None else np.array(hist),
                      None if p1d is None else np.array(p1d)))

    camera = perception.camera
    guard = None
    # guarded push-ins stop on contact, and lifted objects are weighed, sensed from the arm's joint efforts
    weighed = math.isfinite(policy.action_model.tool.rules.max_suction_moment)
    if guarded or weighed:
        from slax_drake.systems.guard import Guard

        guard = Guard(station, X_WS.rotation().matrix(), station.guarded_stop_force)
    planner_system = builder.AddNamedSystem("planner", PlannerSystem(
        policy, planner, Scene(scene.shelf, scene.camera, (), None), make_source(source_kind, scene.shelf, size),
        horizon, camera.width, camera.height, suction_cost=scenario.protocol.suction_cost, on_step=on_step,
        guard=guard))
    evaluator = builder.AddNamedSystem("evaluator", EvaluatorSystem(
        scene, bodies, X_WS, threshold=scenario.target.visibility_threshold,
        image_size=(scene.camera.width, scene.camera.height),
        target_body_index=plant.GetBodyByName("target").index() if scene.target is not None else None))
    for name in ("observation", "hypotheses", "occupancy_1d"):
        builder.Connect(perception.GetOutputPort(name), planner_system.GetInputPort(name))
    builder.Connect(station_diagram.GetOutputPort("measured_state"), planner_system.GetInputPort("measured_state"))
    builder.Connect(evaluator.GetOutputPort("stop"), planner_system.GetInputPort("stop"))
    if guard is not None:
        builder.Connect(station_diagram.GetOutputPort("measured_efforts"),
                        planner_system.GetInputPort("measured_efforts"))
    builder.Connect(station_diagram.GetOutputPort("label_image"), evaluator.GetInputPort("label_image"))
    builder.Connect(station_diagram.GetOutputPort("body_poses"), evaluator.GetInputPort("body_poses"))
    builder.Connect(planner_system.GetOutputPort("deciding"), evaluator.GetInputPort("deciding"))
    builder.Connect(perception.GetOutputPort("segmentation"), evaluator.GetInputPort("segmentation"))
    builder.Connect(planner_system.GetOutputPort("desired_state"), station_diagram.GetInputPort("desired_state"))
    builder.Connect(planner_system.GetOutputPort("suction_command"), station_diagram.GetInputPort("suction_command"))
    return TrialDiagram(builder.Build(), station_diagram, plant, planner_system, evaluator, perception, scene,
                        scenario, station_path, bodies, X_WS, horizon, tool_rules, steps)
