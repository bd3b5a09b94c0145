"""Running one full Drake trial and recording it: the trial runner of the evaluation stage.

:func:`run_trial` builds the trial's diagram (:func:`slax_drake.systems.trial.build_trial`), simulates until the
planner system is done (or the simulated-time limit), and returns a :class:`TrialRecord`: success, steps, cost,
actions with predicted and physical outcome and timings, supports, the executed joint trajectory, final object
poses. :func:`write_trial` writes ``trial.json``, ``scene.json`` (the initial scene), per-step PNGs,
``step_depth.npz`` (each decision's depth image) and the HTML replay.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import logging
import math
import time
from pathlib import Path

import numpy as np

from slax_drake.systems.guard import dragged_after_weighing
from slax_drake.systems.trial import DEFAULT_OBJECTS, DEFAULT_SEED, TrialOptions  # noqa: F401  (the runner's options)


@contextlib.contextmanager
def drake_info_silenced():
    """Drake's log (pydrake logs through Python's ``logging.getLogger("drake")``) at warnings and above while the
    block runs. Its INFO lines ("Meshcat listening for connections at ...", a localhost address that dies with the
    process; "Allocating contexts to support implicit context parallelism", once per planned action, from each new
    collision checker) say nothing a user of a trial can act on."""
    import pydrake.common  # noqa: F401  (pydrake ties its C++ log level to this logger's level)

    logger = logging.getLogger("drake")
    previous = logger.level
    logger.setLevel(logging.WARNING)
    try:
        yield
    finally:
        logger.setLevel(previous)


@dataclasses.dataclass
class TrialRecord:
    data: dict
    step_images: list  # (step, depth, labels, history, p1d)
    html: str | None = None
    scene: object = None  # the trial's initial Scene (written as scene.json)
    # (times (N,) s, poses (N, K, 7): x, y, z m and quaternion w, x, y, z of the K scene objects in S), every
    # POSE_PERIOD of simulated time, when run_trial was asked to record them (written as object_poses.npz)
    object_poses: tuple | None = None


OBJECT_POSES_FILE = "object_poses.npz"
POSE_PERIOD = 0.1  # s of simulated time between recorded object poses
# The result of a trial whose simulation blew up (a non-finite pose: an unstable contact), followed by ": " and the
# simulator's message; the trial's records up to then are kept, the objects' final poses are not known.
DIVERGED = "simulation diverged"


def run_trial(opts: TrialOptions, meshcat=None, progress=None, record_poses: bool = False) -> TrialRecord:
    """Runs the trial ``opts`` describes (see the module docstring); ``meshcat``: record it there for the HTML
    replay; ``progress``: a stream (e.g. ``sys.stderr``) to write one line per decision to as it happens
    (:class:`slax_drake.evaluation.trial_progress.DecisionPrinter`); ``record_poses``: keep every object's pose
    every ``POSE_PERIOD`` s (``TrialRecord.object_poses``), from which ``slax-drake view-trial`` draws the replay
    later without simulating again. The simulation is the same either way (only where it pauses differs)."""
    from pydrake.systems.analysis import Simulator

    from slax_drake.systems.trial import build_trial

    t0 = time.perf_counter()
    trial = build_trial(opts, meshcat=meshcat)
    scene, scenario, plant, bodies, X_WS = trial.scene, trial.scenario, trial.plant, trial.body_indices, trial.X_WS
    planner_system, horizon, tool_rules, station_path = (trial.planner_system, trial.horizon, trial.tool_rules,
                                                         trial.station_path)
    simulator = Simulator(trial.diagram)
    simulator.set_target_realtime_rate(0.0)
    if opts.sleep:
        from slax_drake.systems.sleep import ObjectSleep

        ObjectSleep(trial.station).install(simulator)
    setup_s = time.perf_counter() - t0
    if meshcat is not None:
        from slax_drake.systems.replay_view import set_replay_camera

        set_replay_camera(meshcat, X_WS, scene.shelf)  # the live view and the HTML replay open looking into the bay
        meshcat.StartRecording(frames_per_second=30.0)
    max_time = opts.max_sim_time or (40.0 * horizon + 5.0)
    t_wall = time.perf_counter()
    printer = None
    if progress is not None:
        from slax_drake.evaluation.trial_progress import DecisionPrinter

        printer = DecisionPrinter(horizon, progress)
    simulator.Initialize()
    context = simulator.get_mutable_context()
    pose_times, poses = [], []
    object_bodies = [plant.get_body(b) for b in bodies]
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = X_WS.inverse()

    def record():
        pose_times.append(context.get_time())
        frame = []
        for body in object_bodies:
            X = X_SW @ plant.EvalBodyPoseInWorld(plant_context, body)
            frame.append(np.concatenate([X.translation(), X.rotation().ToQuaternion().wxyz()]))
        poses.append(frame)

    if record_poses:
        record()
    diverged = None  # the simulator's message when the simulation blew up (a non-finite pose)
    while not planner_system.trial_state(context).done and context.get_time() < max_time:
        t_next = context.get_time() + 1.0
        try:
            if record_poses:
                t0 = context.get_time()
                for k in range(1, round(1.0 / POSE_PERIOD)):
                    simulator.AdvanceTo(t0 + k * POSE_PERIOD)
                    record()
            simulator.AdvanceTo(t_next)
        except RuntimeError as e:
            if "non-finite" not in str(e):
                raise
            diverged = str(e).splitlines()[0][:200]
            if len(pose_times) > len(poses):  # a frame of the blown-up state, half recorded
                pose_times.pop()
            break
        if record_poses:
            record()
        if printer is not None:
            printer.update(planner_system.trial_state(context).log, trial.evaluator.snapshots(context))
    state = planner_system.trial_state(context)
    snapshots = trial.evaluator.snapshots(context)
    wall = time.perf_counter() - t_wall
    html = None
    if meshcat is not None:
        meshcat.StopRecording()
        meshcat.PublishRecording()
        if opts.html:
            html = meshcat.StaticHtml()
    sim_time = context.get_time()
    result = f"{DIVERGED}: {diverged}" if diverged else (state.result or "time limit")
    # where each object ended; unknown (empty) after the simulation blew up
    final = {} if diverged else _final_poses(plant, plant_context, X_WS, scene, bodies)
    target_final = None
    if not diverged and scene.target is not None:
        target_final = _final_poses(plant, plant_context, X_WS, scene.with_objects([scene.target.as_object()]),
                                    [plant.GetBodyByName("target").index()])["target"]
    if printer is not None:
        printer.update(state.log, snapshots)
        printer.finish(final if diverged is None else None)
    log = [_with_ground_truth(entry, snapshots) for entry in state.log]
    actions = []
    for entry in log:
        if "action" not in entry:
            continue
        a = dict(entry["action"])
        pred = entry["predicted_objects"]
        # outcome: where the object ended before the next decision (or at the end)
        a["decision_s"] = entry["decision_s"]
        a["planning_s"] = entry["planning_s"]
        a["planning_cpu_s"] = entry.get("planning_cpu_s")
        a["motion"] = entry["motion"]
        a["rejected_before"] = entry["rejected"]
        if a["type"] == "suction":  # a guarded placement: whether it stopped on contact, where (guard_record)
            a["guard"] = entry.get("guarded")
            if "weighed" in entry:  # a lift weighed by the cup, and whether it was put back (too heavy)
                a["weighed"] = entry["weighed"]
                if dragged_after_weighing(a):  # then dragged to the same placement: executed as a drag
                    a["grip"] = "drag"
        a["predicted"] = pred
        segment = entry.get("segment_of", {}).get(a["object"], a["object"])  # the tracked object's segment
        a["true_object"] = entry.get("segments", {}).get(segment)  # the object the hypothesis was
        a["before"] = entry.get("poses_before", {}).get(a["true_object"]) if a["true_object"] else None
        actions.append(a)
    # actual outcome of each action: the true object's pose at the next decision, and whether it was lost then
    # (toppled or out of the bay, the evaluator's rule; for an action with no next decision, at the trial's end)
    decisions = log
    for k, a in enumerate(actions):
        after = decisions[k + 1] if k + 1 < len(decisions) else None
        a["outcome"] = after.get("poses_before", {}).get(a["true_object"]) if after and a["true_object"] else None
        if a["true_object"] is None:
            a["lost_after"] = None
        elif after is not None and "lost" in after:
            a["lost_after"] = a["true_object"] in after["lost"]
        elif a["true_object"] not in final:  # the simulation blew up during this action: not known
            a["lost_after"] = None
        else:
            end = final[a["true_object"]]
            a["lost_after"] = not (end["upright"] and end["inside"])
    trajectory = executed_trajectory(planner_system.planner, state.motions, sim_time)
    n_push = sum(1 for a in actions if a["type"] == "push")
    n_suction = len(actions) - n_push
    data = {
        "success": result == "revealed",
        "result": result,
        "steps": len(actions),
        "cost": round(n_push + scenario.protocol.suction_cost * n_suction, 6),
        "config": opts.config, "station": station_path, "objects": opts.objects, "seed": opts.seed,
        "policy": opts.policy, "perception": opts.perception, "horizon": horizon, "sleep": opts.sleep,
        "profile": opts.profile, "tool_rules": tool_rules, "mass_model": scenario.physics.mass_model,
        "visible_fraction": round(snapshots[-1].visible_fraction, 4) if snapshots else 0.0,
        "lost_objects": list(snapshots[-1].lost) if snapshots else [],
        "sensor_noise": opts.sensor_noise, "segmentation": opts.segmentation,
        "sim_time_s": round(sim_time, 3), "wall_s": round(wall, 3), "setup_s": round(setup_s, 3),
        "real_time_factor": round(sim_time / wall, 4) if wall > 0 else None,
        "actions": actions,
        "support_per_step": [e.get("support") for e in log if "support" in e],
        "steps_log": [{k: v for k, v in e.items() if k not in ("p1d", "history")} for e in log],
        "initial_objects": {o.name: {"x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                                     "yaw": round(float(o.yaw), 5)} for o in scene.objects},
        "final_objects": final,
        # the target where it ended and how far (m, in the shelf floor's plane) the trial moved it: a move that
        # brushes it can push it deeper or turn it (the evaluator scores it where it stands)
        "target_final": target_final,
        "target_moved_m": None if target_final is None else round(math.hypot(
            target_final["x"] - float(scene.target.center[0]), target_final["y"] - float(scene.target.center[1])), 5),
        "executed_trajectory": trajectory.to_dict(stride=opts.stride, keep_times=[t for t, _ in state.motions]),
        "executed_trajectory_note": f"the commanded (planned) joint trajectory, every {opts.stride} ms and at the "
                                    "first commanded sample of each motion",
    }
    object_poses = (np.array(pose_times), np.array(poses, dtype=np.float32)) if record_poses else None
    return TrialRecord(data, trial.step_images, html, scene, object_poses)


def _final_poses(plant, plant_context, X_WS, scene, bodies) -> dict:
    """{name: x, y, z (m, shelf frame S), yaw (rad), upright (tilted under 20 deg), inside (on or over the shelf
    bay)} of each of the scene's objects (``bodies``: their body indices, in scene order) at the plant's state."""
    X_SW = X_WS.inverse()
    final = {}
    for o, b in zip(scene.objects, bodies):
        X = (X_SW @ plant.EvalBodyPoseInWorld(plant_context, plant.get_body(b))).GetAsMatrix4()
        final[o.name] = {"x": round(float(X[0, 3]), 5), "y": round(float(X[1, 3]), 5), "z": round(float(X[2, 3]), 5),
                         "yaw": round(math.atan2(X[1, 0], X[0, 0]), 5),
                         "upright": bool(abs(X[2, 2]) > math.cos(math.radians(20.0))),
                         "inside": bool(abs(X[0, 3]) < scene.shelf.width / 2 and abs(X[1, 3]) < scene.shelf.depth / 2
                                        and -0.02 < X[2, 3] < scene.shelf.height)}
    return final


def _with_ground_truth(entry: dict, snapshots) -> dict:
    """A planner decision's log entry with what the evaluator saw at that moment (matched by time): the target's
    visible fraction, the lost objects, every object's planar pose in S and which object each segment was."""
    snap = next((s for s in snapshots if abs(s.time - entry["time"]) < 5e-4), None)
    if snap is None:
        return dict(entry)
    return {**entry, "visible_fraction": round(snap.visible_fraction, 4), "lost": list(snap.lost),
            "poses_before": {name: {"x": round(x, 5), "y": round(y, 5), "yaw": round(yaw, 5)}
                             for name, (x, y, yaw) in snap.poses.items()},
            "segments": dict(snap.segments)}


def executed_trajectory(planner, motions, t_end: float):
    """The commanded trajectory over the whole trial: holds between ``motions`` ((start time s, PlannedMotion)),
    each motion at its start time (a motion cut where the next one starts before its end: a guarded push-in that
    stopped on contact, replaced by its stop motion), from ``planner``'s observation pose."""
    from slax_drake.planning.trajectory import JointTrajectory

    names = planner.limits.names
    q_hold = planner.q_observation
    traj = JointTrajectory.hold(names, q_hold, 0.0)
    for t_start, motion in motions:
        if t_start < traj.times[-1] - 1e-9:  # a motion replaced before its end (a guarded push-in stopped)
            k = int(np.searchsorted(traj.times, t_start - 1e-9))
            traj = JointTrajectory(names, traj.times[:k + 1], traj.q[:k + 1], traj.v[:k + 1], traj.a[:k + 1])
        gap = t_start - traj.times[-1]
        if gap > 0.0015:
            traj = traj.then(JointTrajectory.hold(names, traj.q[-1], gap))
        traj = traj.then(motion.trajectory)
    if t_end - traj.times[-1] > 0.0015:
        traj = traj.then(JointTrajectory.hold(names, traj.q[-1], t_end - traj.times[-1]))
    return traj


def write_trial(record: TrialRecord, out: str | Path, html: str | None = None) -> list[Path]:
    """Writes trial.json, scene.json (the initial scene), step_<k>.png per decision, step_depth.npz (the depth image
    of every decision), and the HTML replay; returns their paths, trial.json first.

    trial.json is written last, after every file it describes, and an older one in ``out`` is removed first: a
    write stopped part-way (Ctrl-C, a full disk) leaves no complete-looking record beside missing or stale files."""
    from slax_drake.io import write_bytes_atomic, write_text_atomic
    from slax_drake.scene.io import save_scene
    from slax_drake.systems.step_figure import step_png_of_record

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "trial.json"]
    (out / "trial.json").unlink(missing_ok=True)
    (out / OBJECT_POSES_FILE).unlink(missing_ok=True)  # an older trial's poses would replay with this one
    if record.scene is not None:
        save_scene(record.scene, out / "scene.json")
        written.append(out / "scene.json")
    for step, depth, labels, history, p1d in record.step_images:
        path = out / f"step_{step:02d}.png"
        write_bytes_atomic(path, step_png_of_record(record, step, depth, labels, history, p1d))
        written.append(path)
    if record.step_images and len(record.step_images) == len(record.data.get("steps_log", ())):
        # the depth image of each decision, for 'slax-drake export --format mcap': times (K,) s, depth (K, H, W) m
        buf = io.BytesIO()
        np.savez_compressed(buf, times=np.array([e["time"] for e in record.data["steps_log"]], float),
                            depth=np.stack([np.asarray(d, np.float32) for _, d, _, _, _ in record.step_images]))
        write_bytes_atomic(out / "step_depth.npz", buf.getvalue())
        written.append(out / "step_depth.npz")
    if record.object_poses is not None:
        times, poses = record.object_poses
        buf = io.BytesIO()
        np.savez_compressed(buf, times=times, poses=poses, names=np.array([o.name for o in record.scene.objects]))
        write_bytes_atomic(out / OBJECT_POSES_FILE, buf.getvalue())
        written.append(out / OBJECT_POSES_FILE)
    if html and record.html:
        Path(html).parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(Path(html), record.html)
        written.append(Path(html))
    write_text_atomic(out / "trial.json", json.dumps(record.data, indent=1))
    return written
