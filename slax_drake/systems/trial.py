"""A full SLAX-RAY trial in one Drake diagram: the station, the PlannerSystem, optional Meshcat recording.

``run_trial(TrialOptions)`` samples the scene (``slax_drake.scene.sampling.sample_scene``: the same scenes as
the shelf simulator for the same config, object count and seed), builds the diagram (station's
``desired_state`` and ``suction_command`` from the planner; the planner reads ``measured_state``,
``depth_image``, ``label_image`` and ``body_poses``), simulates until the planner is done, and returns a
:class:`TrialRecord` (success, steps, cost, actions with outcome and timings, supports, the executed joint
trajectory, final object poses). :func:`write_trial` writes ``trial.json``, ``scene.json`` (the initial scene), per-step PNGs and the HTML replay.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path

import numpy as np

from slax_drake.errors import UserError

DEFAULT_OBJECTS = 3
DEFAULT_SEED = 7


class TrialError(UserError):
    """A trial cannot be set up (bad config, no station for the shelf, unsupported option)."""


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
    tool_rules: dict | None = None  # rule overrides of the profile for the policy and the planner; they
    # take precedence over the station's own limits (see station_tool_rules)
    profile: str = "station"  # the action model's rule profile: a Drake trial plans with the physical tool's
    # rules whatever the scene scenario's profile is (slax_drake.policies.rules)


@dataclasses.dataclass
class TrialRecord:
    data: dict
    step_images: list  # (step, depth, labels, history, p1d)
    html: str | None = None
    scene: object = None  # the trial's initial Scene (written as scene.json)


def station_for(config: str) -> str:
    from slax_drake.config import REPO_ROOT

    path = Path(config)
    candidate = path.parent / f"station_{path.stem}.yaml"
    for c in (candidate, REPO_ROOT / "sim_configs" / f"station_{path.stem}.yaml"):
        if c.is_file():
            return str(c)
    raise TrialError(f"no station file for {config} (expected {candidate}); pass --station")


def station_tool_rules(station, overrides: dict | None = None, profile: str = "station") -> dict:
    """The rule overrides of ``profile`` a trial on ``station`` plans with: the station cup's limits
    (``suction.max_held_moment`` as ``max_suction_moment`` when finite, ``suction.max_seal_angle_deg`` when under
    90), then ``overrides`` on top; entries equal to the profile's values are left out."""
    from slax_drake.policies.registry import without_defaults

    rules = {}
    if math.isfinite(station.suction.max_held_moment):
        rules["max_suction_moment"] = float(station.suction.max_held_moment)
    if station.suction.max_seal_angle_deg < 90.0:
        rules["max_seal_angle_deg"] = float(station.suction.max_seal_angle_deg)
    rules.update(overrides or {})
    return without_defaults(rules, profile)


def run_trial(opts: TrialOptions, meshcat=None) -> TrialRecord:
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.policies.registry import make_policy, tool_config
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.systems.planner import PlannerSystem
    from slax_drake.station.scenario import load_station_scenario, shelf_pose
    from slax_drake.systems.station import MakeStation

    if opts.objects < 1:
        raise TrialError(f"--objects must be at least 1 (got {opts.objects})")
    scenario = load_scenario(opts.config)
    station_path = opts.station or station_for(opts.config)
    station = load_station_scenario(station_path)
    tool_rules = station_tool_rules(station, opts.tool_rules, opts.profile)
    t0 = time.perf_counter()
    target_size = None if opts.target_size is None else tuple(float(v) for v in opts.target_size)
    scene = sample_scene(scenario, opts.objects, seed=opts.seed, target_size=target_size)
    horizon = opts.horizon if opts.horizon is not None else 2 * opts.objects
    policy = make_policy(opts.policy, scenario, perception=opts.perception, horizon=horizon,
                         tool_overrides=tool_rules, profile=opts.profile)
    if not hasattr(policy, "decide") or not hasattr(policy, "distribution"):
        raise TrialError(f"policy '{opts.policy}' cannot run in a Drake trial (it needs the true scene: an oracle)")
    policy.reset(scene)
    planner = MotionPlanner(station, tool_config(scenario, opts.profile, **tool_rules))

    builder = DiagramBuilder()
    station_diagram = builder.AddNamedSystem("station", MakeStation(station, scene, meshcat=meshcat))
    plant = station_diagram.GetSubsystemByName("plant")
    bodies = [plant.GetBodyByName(o.name).index() for o in scene.objects]
    target = plant.GetBodyByName("target").index() if scene.target is not None else None
    X_WS = shelf_pose(station, scene.camera)
    steps = []
    planner_system = builder.AddNamedSystem("planner", PlannerSystem(
        policy, planner, scene, bodies, target, X_WS, horizon, threshold=scenario.target.visibility_threshold,
        image_size=(scene.camera.width, scene.camera.height),
        on_step=lambda entry, depth, labels, hist, p1d: steps.append((entry["step"], depth, labels,
                                                                       None if hist is None else np.array(hist),
                                                                       None if p1d is None else np.array(p1d))),
    ))
    for name in ("measured_state", "depth_image", "label_image", "body_poses"):
        builder.Connect(station_diagram.GetOutputPort(name), planner_system.GetInputPort(name))
    builder.Connect(planner_system.GetOutputPort("desired_state"), station_diagram.GetInputPort("desired_state"))
    builder.Connect(planner_system.GetOutputPort("suction_command"), station_diagram.GetInputPort("suction_command"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.set_target_realtime_rate(0.0)
    if opts.sleep:
        from slax_drake.systems.sleep import ObjectSleep

        ObjectSleep(station_diagram).install(simulator)
    setup_s = time.perf_counter() - t0
    if meshcat is not None:
        meshcat.StartRecording(frames_per_second=30.0)
    max_time = opts.max_sim_time or (40.0 * horizon + 5.0)
    t_wall = time.perf_counter()
    simulator.Initialize()
    context = simulator.get_mutable_context()
    while planner_system.result is None and context.get_time() < max_time:
        simulator.AdvanceTo(context.get_time() + 1.0)
    wall = time.perf_counter() - t_wall
    html = None
    if meshcat is not None:
        meshcat.StopRecording()
        meshcat.PublishRecording()
        if opts.html:
            html = meshcat.StaticHtml()
    sim_time = context.get_time()
    result = planner_system.result or "time limit"
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = X_WS.inverse()
    final = {}
    for o, b in zip(scene.objects, bodies):
        X = (X_SW @ plant.EvalBodyPoseInWorld(plant_context, plant.get_body(b))).GetAsMatrix4()
        final[o.name] = {"x": round(float(X[0, 3]), 5), "y": round(float(X[1, 3]), 5), "z": round(float(X[2, 3]), 5),
                         "yaw": round(math.atan2(X[1, 0], X[0, 0]), 5),
                         "upright": bool(abs(X[2, 2]) > math.cos(math.radians(20.0))),
                         "inside": bool(abs(X[0, 3]) < scene.shelf.width / 2 and abs(X[1, 3]) < scene.shelf.depth / 2
                                        and -0.02 < X[2, 3] < scene.shelf.height)}
    actions = []
    for entry in planner_system.log:
        if "action" not in entry:
            continue
        a = dict(entry["action"])
        pred = entry["predicted_objects"]
        # outcome: where the object ended before the next decision (or at the end)
        a["decision_s"] = entry["decision_s"]
        a["planning_s"] = entry["planning_s"]
        a["motion"] = entry["motion"]
        a["rejected_before"] = entry["rejected"]
        a["predicted"] = pred
        actions.append(a)
    # actual outcome of each action: the object's pose at the next decision
    decisions = planner_system.log
    for k, a in enumerate(actions):
        after = decisions[k + 1] if k + 1 < len(decisions) else None
        a["outcome"] = after.get("poses_before", {}).get(a["object"]) if after else None
    trajectory = _executed_trajectory(planner_system, sim_time)
    n_push = sum(1 for a in actions if a["type"] == "push")
    n_suction = len(actions) - n_push
    data = {
        "success": result == "revealed",
        "result": result,
        "steps": len(actions),
        "cost": round(n_push + scenario.protocol.suction_cost * n_suction, 6),
        "config": opts.config, "station": station_path, "objects": opts.objects, "seed": opts.seed,
        "policy": opts.policy, "perception": opts.perception, "horizon": horizon, "sleep": opts.sleep,
        "profile": opts.profile, "tool_rules": tool_rules,
        "visible_fraction": round(planner_system.visible_fraction, 4),
        "sim_time_s": round(sim_time, 3), "wall_s": round(wall, 3), "setup_s": round(setup_s, 3),
        "real_time_factor": round(sim_time / wall, 4) if wall > 0 else None,
        "actions": actions,
        "support_per_step": [e.get("support") for e in planner_system.log if "support" in e],
        "steps_log": [{k: v for k, v in e.items() if k not in ("p1d", "history")} for e in planner_system.log],
        "initial_objects": {o.name: {"x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                                     "yaw": round(float(o.yaw), 5)} for o in scene.objects},
        "final_objects": final,
        "executed_trajectory": trajectory.to_dict(stride=opts.stride,
                                                  keep_times=[t for t, _ in planner_system.motions]),
        "executed_trajectory_note": f"the commanded (planned) joint trajectory, every {opts.stride} ms and at the "
                                    "first commanded sample of each motion",
    }
    return TrialRecord(data, steps, html, scene)


def _executed_trajectory(planner_system, t_end: float):
    """The commanded trajectory over the whole trial: holds between motions, each motion at its start time."""
    from slax_drake.planning.trajectory import JointTrajectory

    names = planner_system.planner.limits.names
    q_hold = planner_system.planner.q_observation
    traj = JointTrajectory.hold(names, q_hold, 0.0)
    for t_start, motion in planner_system.motions:
        gap = t_start - traj.times[-1]
        if gap > 0.0015:
            traj = traj.then(JointTrajectory.hold(names, traj.q[-1], gap))
        traj = traj.then(motion.trajectory)
    if t_end - traj.times[-1] > 0.0015:
        traj = traj.then(JointTrajectory.hold(names, traj.q[-1], t_end - traj.times[-1]))
    return traj


def write_trial(record: TrialRecord, out: str | Path, html: str | None = None) -> list[Path]:
    """Writes trial.json, scene.json (the initial scene), step_<k>.png per decision, and the HTML replay."""
    from slax_drake.io import write_bytes_atomic, write_text_atomic
    from slax_drake.scene.io import save_scene

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "trial.json"]
    write_text_atomic(out / "trial.json", json.dumps(record.data, indent=1))
    if record.scene is not None:
        save_scene(record.scene, out / "scene.json")
        written.append(out / "scene.json")
    for step, depth, labels, history, p1d in record.step_images:
        path = out / f"step_{step:02d}.png"
        write_bytes_atomic(path, _step_png(step, depth, labels, history, p1d))
        written.append(path)
    if html and record.html:
        Path(html).parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(Path(html), record.html)
        written.append(Path(html))
    return written


def _step_png(step, depth, labels, history, p1d) -> bytes:
    import matplotlib

    from slax_drake.io import figure_png

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.4))
    d = np.where(np.isfinite(depth), depth, np.nan)
    axes[0].imshow(d, cmap="viridis")
    axes[0].set_title(f"step {step}: depth (m)")
    axes[1].imshow(labels, cmap="tab20", interpolation="nearest")
    axes[1].set_title("labels (target last)")
    if history is not None:
        if p1d is not None:
            axes[2].plot(p1d, label="P_t")
        axes[2].plot(history, label="P'_t (history min)")
        axes[2].legend()
    axes[2].set_title("1D target distribution")
    for ax in axes[:2]:
        ax.axis("off")
    fig.tight_layout()
    return figure_png(fig, 80)
