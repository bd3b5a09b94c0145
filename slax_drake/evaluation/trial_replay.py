"""The Meshcat HTML replay of a finished trial, drawn from its records without simulating again
(``slax-drake view-trial``).

The robot follows the trial's ``executed_trajectory`` (the commanded joint positions, every 10 ms). The objects
follow ``object_poses.npz`` beside trial.json (every object's pose in the shelf frame S every 0.1 s of simulated
time, which ``slax-drake trial`` records), linearly interpolated in between. A trial folder without it (written
before trials recorded it) still replays: each object then stands where the trial recorded it at each decision
(``steps_log``, with its height and tilt from the initial scene) and moves there when the motion before the
decision ends; its final pose is that of ``final_objects``. The station is built only to draw the same geometry; no
physics runs.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from slax_drake.errors import TrialFileError

FPS = 30.0  # frames per second of the replay


@dataclasses.dataclass
class TrialReplay:
    html: str
    duration_s: float  # simulated seconds replayed
    objects_from: str  # "recorded poses" or "decision poses"


def trial_replay(trial_json: str | Path, station: str | None = None) -> TrialReplay:
    """The HTML replay of the trial whose ``trial.json`` is at ``trial_json`` (its folder also holds scene.json and,
    for trials that recorded them, object_poses.npz). ``station``: the station YAML (default: the trial's own)."""
    from pydrake.geometry import Meshcat
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RigidTransform

    from slax_drake.evaluation.trial import OBJECT_POSES_FILE, drake_info_silenced
    from slax_drake.scene.io import load_scene
    from slax_drake.station import robot as robot_model
    from slax_drake.station.plant import shelf_pose
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.replay_view import set_replay_camera
    from slax_drake.systems.station import MakeStation

    path = Path(trial_json)
    if path.is_dir():
        path = path / "trial.json"
    data = _read(path)
    scene_path = path.parent / "scene.json"
    if not scene_path.is_file():
        raise TrialFileError(f"{scene_path}: missing (the trial folder's initial scene, which the replay draws)")
    scene = load_scene(scene_path)
    station_scenario = load_station_scenario(station or data.get("station") or "")
    times, q = _trajectory(data, path)
    poses_file = path.parent / OBJECT_POSES_FILE
    names = [o.name for o in scene.objects]
    if poses_file.is_file():
        pose_times, poses = _recorded_poses(poses_file, names)
        objects_from = "recorded poses"
    else:
        pose_times, poses = _decision_poses(data, scene)
        objects_from = "decision poses"

    with drake_info_silenced():
        meshcat = Meshcat()
        diagram = MakeStation(station_scenario, scene, meshcat=meshcat, camera=False)
        context = diagram.CreateDefaultContext()
        plant = diagram.GetSubsystemByName("plant")
        plant_context = plant.GetMyMutableContextFromRoot(context)
        robot = plant.GetModelInstanceByName(station_scenario.robot_model)
        starts = [plant.GetJointByName(n, robot).position_start() for n in robot_model.PLANNED_JOINTS]
        bodies = [plant.GetBodyByName(n) for n in names]
        X_WS = shelf_pose(station_scenario, scene.camera)
        set_replay_camera(meshcat, X_WS, scene.shelf)
        end = float(times[-1])
        meshcat.StartRecording(frames_per_second=FPS, set_visualizations_while_recording=False)
        for t in np.arange(0.0, end + 0.5 / FPS, 1.0 / FPS):
            context.SetTime(float(t))
            q_all = plant.GetPositions(plant_context).copy()
            q_all[starts] = [np.interp(t, times, q[:, j]) for j in range(q.shape[1])]
            plant.SetPositions(plant_context, q_all)
            k = int(np.clip(np.searchsorted(pose_times, t, side="right") - 1, 0, len(pose_times) - 1))
            for i, body in enumerate(bodies):
                pose = poses[k, i]
                if objects_from == "recorded poses" and k + 1 < len(pose_times):
                    s = (t - pose_times[k]) / max(pose_times[k + 1] - pose_times[k], 1e-9)
                    pose = _blend(poses[k, i], poses[k + 1, i], float(np.clip(s, 0.0, 1.0)))
                quat = Quaternion(np.asarray(pose[3:], float) / np.linalg.norm(pose[3:]))
                plant.SetFreeBodyPose(plant_context, body, X_WS @ RigidTransform(quat, np.asarray(pose[:3], float)))
            diagram.ForcedPublish(context)
        meshcat.StopRecording()
        meshcat.PublishRecording()
        html = meshcat.StaticHtml()
    return TrialReplay(html, end, objects_from)


def _read(path: Path) -> dict:
    try:
        data = json.loads(path.read_text())
    except OSError as e:
        raise TrialFileError(f"{path}: cannot read ({e.strerror})") from None
    except json.JSONDecodeError as e:
        raise TrialFileError(f"{path}: not valid JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(data, dict) or "executed_trajectory" not in data:
        raise TrialFileError(f"{path}: not a trial record (no executed_trajectory; trial.json of `slax-drake trial`)")
    return data


def _trajectory(data: dict, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(times (N,) s, positions (N, 9)) of the trial's commanded joint trajectory, in PLANNED_JOINTS order."""
    from slax_drake.station import robot as robot_model

    et = data["executed_trajectory"]
    try:
        names = list(et["joint_names"])
        times = np.asarray(et["times"], float)
        q = np.asarray(et["positions"], float)
    except (KeyError, TypeError, ValueError) as e:
        raise TrialFileError(f"{path}: executed_trajectory is malformed ({e})") from None
    if names != list(robot_model.PLANNED_JOINTS) or q.ndim != 2 or q.shape != (len(times), len(names)) \
            or len(times) < 2 or not np.all(np.isfinite(q)) or not np.all(np.diff(times) > 0):
        raise TrialFileError(f"{path}: executed_trajectory is malformed (joints, shapes, non-finite values or "
                             "times not increasing)")
    return times, q


def _recorded_poses(path: Path, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    try:
        with np.load(path) as f:
            times, poses, recorded = np.asarray(f["times"], float), np.asarray(f["poses"], float), list(f["names"])
    except (OSError, KeyError, ValueError) as e:
        raise TrialFileError(f"{path}: unreadable ({e})") from None
    if [str(n) for n in recorded] != names or poses.shape != (len(times), len(names), 7) or len(times) < 1 \
            or not np.all(np.isfinite(poses)):
        raise TrialFileError(f"{path}: does not hold the poses of the scene's objects ({', '.join(names)})")
    return times, poses


def _decision_poses(data: dict, scene) -> tuple[np.ndarray, np.ndarray]:
    """(times (M,), poses (M, K, 7)): each object where the trial recorded it at each decision, from the end of the
    motion before it; the final poses at the trial's end."""
    from pydrake.math import RollPitchYaw, RotationMatrix

    initial = {o.name: o for o in scene.objects}
    starts = {round(a_t, 4): a for a_t, a in _motion_ends(data)}
    times, frames = [], []

    def frame(planar: dict) -> list:
        out = []
        for name, obj in initial.items():
            p = planar.get(name)
            X = np.asarray(obj.X_SO, float)
            if p is None:
                x, y, z, yaw = X[0, 3], X[1, 3], X[2, 3], math.atan2(X[1, 0], X[0, 0])
            else:
                x, y, z, yaw = p["x"], p["y"], p.get("z", X[2, 3]), p["yaw"]
            R = RotationMatrix(RollPitchYaw(0.0, 0.0, yaw)) @ RotationMatrix(
                RollPitchYaw(0.0, 0.0, -math.atan2(X[1, 0], X[0, 0]))) @ RotationMatrix(X[:3, :3])
            out.append(np.concatenate([[x, y, z], R.ToQuaternion().wxyz()]))
        return out

    times.append(0.0)
    frames.append(frame({}))
    for entry in data.get("steps_log", []):
        poses = entry.get("poses_before")
        if not poses:
            continue
        times.append(starts.get(round(entry["time"], 4), entry["time"]))
        frames.append(frame(poses))
    if data.get("final_objects"):
        times.append(float(data["executed_trajectory"]["times"][-1]))
        frames.append(frame(data["final_objects"]))
    order = np.argsort(times, kind="stable")
    return np.asarray(times)[order], np.asarray(frames)[order]


def _motion_ends(data: dict):
    """(time of the decision after each motion, end time of that motion) pairs: the object poses recorded at a
    decision are shown from the end of the motion before it (the settling time in between)."""
    log = data.get("steps_log", [])
    out = []
    for prev, entry in zip(log[:-1], log[1:]):
        motion = prev.get("motion")
        if motion and "duration_s" in motion:
            out.append((entry["time"], prev["time"] + motion["duration_s"]))
    return out


def _blend(a, b, s: float) -> np.ndarray:
    """The pose ``s`` of the way from ``a`` to ``b`` ([x, y, z, qw, qx, qy, qz]): positions linearly, the
    quaternion by normalised linear interpolation on the shorter arc."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    qb = b[3:] if float(np.dot(a[3:], b[3:])) >= 0 else -b[3:]
    q = (1 - s) * a[3:] + s * qb
    return np.concatenate([(1 - s) * a[:3] + s * b[:3], q / np.linalg.norm(q)])
