"""A trial as a ROS 2 bag (rosbag2 folder, MCAP storage), written with ``rosbags`` (pure Python, no ROS install).

The bag is a folder ``<out>/`` holding ``metadata.yaml`` and ``<out name>.mcap``; Foxglove opens the ``.mcap`` file
directly, ``ros2 bag play <out>`` plays the folder (ROS 2 Jazzy message definitions, rosbag2 metadata version 9,
MCAP chunks compressed with zstd).

The bag's ``metadata.yaml`` names ``ros_distro: jazzy`` (the message definitions it is written with).

Clock: every stamp (each message's ``header.stamp`` and its log time in the bag) is the trial's simulation time,
t = 0 at the start of the simulation, in nanoseconds rounded from the trial's seconds (so the bag starts on
1970-01-01 in tools that show dates). Messages are written in time order; log times never decrease.

Topics (one ``rosbags`` connection each):

- ``/joint_states`` (sensor_msgs/JointState): one per record of the trial's ``executed_trajectory`` (every 10 ms
  and at each motion's first sample): positions (rad; m for torso_lift_joint) and velocities of
  :data:`~slax_drake.hardware.fetch_limits.FETCH_JOINTS`, named as on the real Fetch. They are the *commanded*
  states (the trial records what the planner sent, not the plant's measured state); effort is empty.
- ``/planned_trajectory`` (trajectory_msgs/JointTrajectory): one per motion, stamped at the motion's start (its
  decision time), ``header.frame_id`` ``base_link``, points as ``slax-drake export`` cuts them (the trial's records,
  or resampled with ``--rate``): positions, velocities, accelerations and ``time_from_start``.
- ``/suction_command`` (std_msgs/Bool): ``false`` at t = 0, then ``true``/``false`` at each suction event of each
  motion (the command, on or off, that the planner sends to the cup).
- ``/tf_static`` (tf2_msgs/TFMessage, transient-local QoS), one message at t = 0: ``world`` -> ``base_link`` (the
  robot's base weld) and ``world`` -> ``shelf`` (when the station is known), ``shelf`` -> ``camera_optical_frame``
  (the depth camera at the observation configuration, where every depth image is taken; OpenCV/ROS optical
  axes: z forward, x right, y down) and ``shelf`` -> ``target`` (its initial pose: the trial does not record the
  target per step).
- ``/tf`` (tf2_msgs/TFMessage): at each decision (``steps_log[*].time``) ``shelf`` -> each object, named as in the
  scene (``object_0``, ``object_1``, ...), from the decision's planar poses (x, y, yaw in the shelf frame; z = half
  the object's height, the object standing on the shelf; a toppled or dropped object, listed in the decision's
  ``lost``, keeps this planar pose), and once more at the trial's end from its final poses (x, y, z, yaw) when
  that is later than the last decision.
- ``/robot_description`` (std_msgs/String, transient-local QoS), one message at t = 0: the robot's URDF (the
  station's robot model, ``package://`` mesh paths as in ``models/``), so that RViz and Foxglove draw the robot
  from ``/joint_states`` and ``/tf_static``.
- ``/slax_drake/trajectory`` (std_msgs/String, transient-local QoS), one message at t = 0: the exported
  trajectory's document without its points (JSON, as the CSV's ``# meta`` line: metadata with the scene, and per
  motion its action with the planner's estimate, objects_before, lost and suction events), so that
  ``slax-drake check-trajectory`` and ``replay`` read the bag (:func:`read_trajectory_bag`).
- ``/camera/depth/image`` (sensor_msgs/Image, encoding ``32FC1``, metres along the optical axis, little-endian;
  Drake's values outside the depth range: +inf beyond the far plane, 0 nearer than the near plane) and ``/camera/depth/camera_info`` (sensor_msgs/CameraInfo:
  ``plumb_bob`` with zero distortion, K and P from the scene camera's intrinsics with pixel centres at integer
  coordinates as in OpenCV), one each per decision, from the trial's ``step_depth.npz``, both in
  ``camera_optical_frame``.

Frames: ``shelf`` is the shelf frame S (origin at the centre of the support surface, x right seen from the
camera, y into the shelf, z up); ``world`` is the Drake station's world frame.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from slax_drake.errors import TrialFileError
from slax_drake.hardware.export import export_trial
from slax_drake.hardware.fetch_limits import FETCH_JOINTS

STEP_DEPTH_FILE = "step_depth.npz"  # written by slax_drake.systems.trial.write_trial beside trial.json

TOPIC_JOINT_STATES = "/joint_states"
TOPIC_PLANNED_TRAJECTORY = "/planned_trajectory"
TOPIC_SUCTION = "/suction_command"
TOPIC_TF = "/tf"
TOPIC_TF_STATIC = "/tf_static"
TOPIC_DEPTH = "/camera/depth/image"
TOPIC_CAMERA_INFO = "/camera/depth/camera_info"
TOPIC_ROBOT_DESCRIPTION = "/robot_description"
TOPIC_TRAJECTORY_DOCUMENT = "/slax_drake/trajectory"
ROS_DISTRO = "jazzy"  # the message definitions the bag is written with (rosbags' Stores.ROS2_JAZZY)

FRAME_WORLD = "world"
FRAME_BASE = "base_link"
FRAME_SHELF = "shelf"
FRAME_CAMERA = "camera_optical_frame"
FRAME_TARGET = "target"

MSG_TYPES = {
    TOPIC_JOINT_STATES: "sensor_msgs/msg/JointState",
    TOPIC_PLANNED_TRAJECTORY: "trajectory_msgs/msg/JointTrajectory",
    TOPIC_SUCTION: "std_msgs/msg/Bool",
    TOPIC_TF_STATIC: "tf2_msgs/msg/TFMessage",
    TOPIC_TF: "tf2_msgs/msg/TFMessage",
    TOPIC_DEPTH: "sensor_msgs/msg/Image",
    TOPIC_CAMERA_INFO: "sensor_msgs/msg/CameraInfo",
    TOPIC_ROBOT_DESCRIPTION: "std_msgs/msg/String",
    TOPIC_TRAJECTORY_DOCUMENT: "std_msgs/msg/String",
}
LATCHED = (TOPIC_TF_STATIC, TOPIC_ROBOT_DESCRIPTION, TOPIC_TRAJECTORY_DOCUMENT)  # transient-local QoS


@dataclasses.dataclass
class StepDepth:
    """The depth image the planner saw at each decision: ``times`` (K,) s on the trial clock, ``depth`` (K, H, W)
    float32 metres along the camera's optical axis."""

    times: np.ndarray
    depth: np.ndarray


def read_step_depth(path: str | Path) -> StepDepth | None:
    """``step_depth.npz`` beside a trial.json, or None when the trial has none (written before it was recorded)."""
    path = Path(path)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            times, depth = np.asarray(z["times"], float), np.asarray(z["depth"], np.float32)
    except Exception as e:  # noqa: BLE001 - zip, npy and key errors all mean a damaged file
        raise TrialFileError(f"{path}: not a step depth record ({type(e).__name__}: {e})") from None
    if depth.ndim != 3 or times.shape != (depth.shape[0],) or not np.all(np.isfinite(times)):
        raise TrialFileError(f"{path}: arrays 'times' {times.shape} and 'depth' {depth.shape} do not match")
    return StepDepth(times, depth)


@dataclasses.dataclass
class BagSummary:
    path: Path
    counts: dict  # topic -> messages
    start_s: float
    end_s: float


def _ns(t: float) -> int:
    return int(round(float(t) * 1e9))


def _quaternion(R: np.ndarray) -> tuple:
    """(x, y, z, w) of a rotation matrix (Shepperd's method)."""
    m = np.asarray(R, float)
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        return ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s)
    i = int(np.argmax([m[0, 0], m[1, 1], m[2, 2]]))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
    q = [0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (m[j, i] + m[i, j]) / s
    q[k] = (m[k, i] + m[i, k]) / s
    return (q[0], q[1], q[2], (m[k, j] - m[j, k]) / s)


def _planar(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    X = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    X[:2, :2] = [[c, -s], [s, c]]
    X[:3, 3] = (x, y, z)
    return X


class _Messages:
    """Builds the rosbags message objects of the topics above from one typestore."""

    def __init__(self, typestore):
        self.T = typestore.types

    def header(self, t: float, frame: str):
        ns = _ns(t)
        stamp = self.T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        return self.T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def duration(self, t: float):
        ns = _ns(t)
        return self.T["builtin_interfaces/msg/Duration"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def joint_state(self, t, names, q, v):
        return self.T["sensor_msgs/msg/JointState"](
            header=self.header(t, ""), name=list(names), position=np.asarray(q, np.float64),
            velocity=np.asarray(v, np.float64), effort=np.zeros(0, np.float64))

    def trajectory(self, motion, names):
        point = self.T["trajectory_msgs/msg/JointTrajectoryPoint"]
        points = [point(positions=np.asarray(motion.q[k], np.float64), velocities=np.asarray(motion.v[k], np.float64),
                        accelerations=np.asarray(motion.a[k], np.float64), effort=np.zeros(0, np.float64),
                        time_from_start=self.duration(motion.times[k])) for k in range(len(motion.times))]
        return self.T["trajectory_msgs/msg/JointTrajectory"](
            header=self.header(motion.start_time, FRAME_BASE), joint_names=list(names), points=points)

    def string(self, text: str):
        return self.T["std_msgs/msg/String"](data=text)

    def bool(self, on: bool):
        return self.T["std_msgs/msg/Bool"](data=bool(on))

    def tf(self, t: float, transforms):
        """``transforms``: [(parent, child, X_parent_child 4x4)]."""
        stamped = []
        for parent, child, X in transforms:
            X = np.asarray(X, float)
            qx, qy, qz, qw = _quaternion(X[:3, :3])
            transform = self.T["geometry_msgs/msg/Transform"](
                translation=self.T["geometry_msgs/msg/Vector3"](x=float(X[0, 3]), y=float(X[1, 3]), z=float(X[2, 3])),
                rotation=self.T["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw))
            stamped.append(self.T["geometry_msgs/msg/TransformStamped"](
                header=self.header(t, parent), child_frame_id=child, transform=transform))
        return self.T["tf2_msgs/msg/TFMessage"](transforms=stamped)

    def depth_image(self, t: float, depth: np.ndarray):
        h, w = depth.shape
        data = np.ascontiguousarray(depth, dtype="<f4").view(np.uint8).reshape(-1)
        return self.T["sensor_msgs/msg/Image"](header=self.header(t, FRAME_CAMERA), height=h, width=w,
                                                encoding="32FC1", is_bigendian=0, step=4 * w, data=data)

    def camera_info(self, t: float, camera):
        fx, fy, cx, cy = camera.fx, camera.fy, camera.cx, camera.cy
        roi = self.T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
        return self.T["sensor_msgs/msg/CameraInfo"](
            header=self.header(t, FRAME_CAMERA), height=camera.height, width=camera.width,
            distortion_model="plumb_bob", d=np.zeros(5, np.float64),
            k=np.array([fx, 0, cx, 0, fy, cy, 0, 0, 1], np.float64), r=np.eye(3).reshape(-1),
            p=np.array([fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0], np.float64), binning_x=0, binning_y=0, roi=roi)


def _object_transforms(poses: dict, sizes: dict, what: str) -> list:
    transforms = []
    for name, p in poses.items():
        if name not in sizes:
            raise TrialFileError(f"{what}: object {name!r} is not in the scene (pass the trial's --scene)")
        try:
            x, y, yaw = float(p["x"]), float(p["y"]), float(p["yaw"])
            z = float(p["z"]) if "z" in p else sizes[name][2] / 2.0
        except (KeyError, TypeError, ValueError):
            raise TrialFileError(f"{what}: the pose of {name!r} is malformed ({p!r})") from None
        transforms.append((FRAME_SHELF, name, _planar(x, y, z, yaw)))
    return transforms


def trial_messages(data: dict, msgs: _Messages, *, scene, depth: StepDepth | None = None, X_WS=None, X_WB=None,
                   rate: float | None = None, source: str | None = None, robot_description: str | None = None) -> list:
    """The bag's messages [(time s, topic, message)] in time order (stable: equal times keep topic order)."""
    from slax_drake.hardware.trajectory_file import header_document

    what = source or "trial"
    traj = export_trial(data, rate=rate, source=source, scene=scene)  # validates the executed trajectory and motions
    et = data["executed_trajectory"]
    times = np.asarray(et["times"], float)
    q, v = np.asarray(et["positions"], float), np.asarray(et["velocities"], float)
    out = []
    statics = [(FRAME_SHELF, FRAME_CAMERA, scene.camera.X_SC)]
    if scene.target is not None:
        statics.append((FRAME_SHELF, FRAME_TARGET, scene.target.X_ST))
    if X_WS is not None:
        statics.insert(0, (FRAME_WORLD, FRAME_SHELF, X_WS))
    if X_WB is not None:
        statics.insert(0, (FRAME_WORLD, FRAME_BASE, X_WB))
    out.append((0.0, TOPIC_TF_STATIC, msgs.tf(0.0, statics)))
    if robot_description is not None:
        out.append((0.0, TOPIC_ROBOT_DESCRIPTION, msgs.string(robot_description)))
    out.append((0.0, TOPIC_TRAJECTORY_DOCUMENT, msgs.string(json.dumps(header_document(traj), allow_nan=False))))
    out.append((0.0, TOPIC_SUCTION, msgs.bool(False)))
    for t, qk, vk in zip(times, q, v):
        out.append((float(t), TOPIC_JOINT_STATES, msgs.joint_state(t, FETCH_JOINTS, qk, vk)))
    for m in traj.motions:
        out.append((m.start_time, TOPIC_PLANNED_TRAJECTORY, msgs.trajectory(m, FETCH_JOINTS)))
        for t_rel, on in m.suction_events:
            out.append((m.start_time + t_rel, TOPIC_SUCTION, msgs.bool(on)))
    sizes = {o.name: tuple(o.size) for o in scene.objects}
    last = -math.inf
    for k, entry in enumerate(data["steps_log"]):
        poses = entry.get("poses_before") if isinstance(entry, dict) else None
        if poses is None:
            continue
        try:
            t = float(entry["time"])
        except (KeyError, TypeError, ValueError):
            raise TrialFileError(f"{what}: steps_log[{k}] has no valid time") from None
        if not isinstance(poses, dict):
            raise TrialFileError(f"{what}: steps_log[{k}].poses_before is not a mapping")
        out.append((t, TOPIC_TF, msgs.tf(t, _object_transforms(poses, sizes, f"{what}: steps_log[{k}]"))))
        last = max(last, t)
    end = data.get("sim_time_s")
    final = data.get("final_objects")
    if final and end is not None and float(end) > last:
        out.append((float(end), TOPIC_TF, msgs.tf(float(end), _object_transforms(final, sizes, f"{what}: final_objects"))))
    if depth is not None:
        h, w = depth.depth.shape[1:]
        camera = scene.camera if (scene.camera.width, scene.camera.height) == (w, h) else \
            scene.camera.with_resolution(w, h)
        for t, image in zip(depth.times, depth.depth):
            out.append((float(t), TOPIC_DEPTH, msgs.depth_image(t, image)))
            out.append((float(t), TOPIC_CAMERA_INFO, msgs.camera_info(t, camera)))
    if any(t < 0 or not math.isfinite(t) for t, _, _ in out):
        raise TrialFileError(f"{what}: a time is negative or not finite")
    out.sort(key=lambda m: _ns(m[0]))
    return out


def _tf_static_qos():
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    zero = QosTime(0, 0)
    return Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL, zero, zero,
               QosLiveliness.AUTOMATIC, zero, False)


def write_trial_bag(data: dict, out: str | Path, *, scene, depth: StepDepth | None = None, X_WS=None, X_WB=None,
                    rate: float | None = None, source: str | None = None,
                    robot_description: str | None = None) -> BagSummary:
    """Writes the trial ``data`` (a trial.json) as the bag folder ``out`` (module docstring). ``scene``: the trial's
    initial Scene (object sizes, camera, target); ``X_WS``, ``X_WB``: 4x4 poses of the shelf and of the robot's
    base in the world, or None to leave ``world`` out. The folder is written under a temporary name beside ``out``
    and renamed when complete; an existing ``out`` is refused."""
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer, WriterError
    from rosbags.typesys import Stores, get_typestore

    out = Path(out)
    if not str(out).strip() or out.name in ("", ".", ".."):
        raise TrialFileError(f"--out {str(out)!r} names no bag folder")
    if out.exists() or out.is_symlink():
        raise TrialFileError(f"{out} exists: a bag is never overwritten (remove it or choose another --out)")
    if out.suffix.lower() == ".mcap":
        raise TrialFileError(f"{out}: a ROS 2 bag is a folder (metadata.yaml and <name>.mcap): give --out without .mcap")
    typestore = get_typestore(Stores.ROS2_JAZZY)
    msgs = _Messages(typestore)
    messages = trial_messages(data, msgs, scene=scene, depth=depth, X_WS=X_WS, X_WB=X_WB, rate=rate, source=source,
                              robot_description=robot_description)
    staging = None
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".partial"))
        counts = {}
        writer = Writer(staging / out.name, version=9, storage_plugin=StoragePlugin.MCAP)
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)  # MCAP chunks compressed by zstd
        with writer:
            connections = {}
            for topic, msgtype in MSG_TYPES.items():  # a topic without messages gets no connection
                if any(m[1] == topic for m in messages):
                    qos = (_tf_static_qos(),) if topic in LATCHED else ()
                    connections[topic] = writer.add_connection(topic, msgtype, typestore=typestore,
                                                               offered_qos_profiles=qos)
                    counts[topic] = 0
            for t, topic, message in messages:
                writer.write(connections[topic], _ns(t), typestore.serialize_cdr(message, MSG_TYPES[topic]))
                counts[topic] += 1
        _set_ros_distro(staging / out.name / "metadata.yaml")
        os.rename(staging / out.name, out)
    except (OSError, WriterError) as e:
        text = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
        if staging is not None:
            text = text.replace(str(staging / out.name), str(out)).replace(str(staging), str(out.parent))
        raise TrialFileError(f"{out}: cannot write the bag ({text})") from None
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
    return BagSummary(out, counts, messages[0][0], messages[-1][0])


def _set_ros_distro(metadata: Path) -> None:
    """rosbags writes ``ros_distro: rosbags``; the bag's messages are ROS 2 Jazzy's (``ROS_DISTRO``)."""
    text = metadata.read_text(encoding="utf-8")
    fixed = text.replace("ros_distro: rosbags", f"ros_distro: {ROS_DISTRO}")
    if fixed == text:
        raise RuntimeError(f"{metadata}: no 'ros_distro: rosbags' line to set (rosbags changed its metadata)")
    metadata.write_text(fixed, encoding="utf-8")


def robot_description(station) -> str | None:
    """The URDF text of the station's robot model (``/robot_description``), or None when it is not a URDF."""
    from slax_drake.station.robot import MODELS_DIR

    for d in station.directives:
        model = getattr(d, "add_model", None)
        if model is not None and model.name == station.robot_model and model.file.endswith(".urdf"):
            prefix = "package://slax_drake_models/"
            path = MODELS_DIR / model.file[len(prefix):] if model.file.startswith(prefix) else Path(model.file)
            return path.read_text(encoding="utf-8")
    return None


def read_trajectory_bag(path: str | Path):
    """The motions of a bag written by :func:`write_trial_bag` as an ExportedTrajectory: the points of each
    ``/planned_trajectory`` message, the motions' headers (action, objects, suction events) and the metadata from
    ``/slax_drake/trajectory``. ``path``: the bag folder or the ``.mcap`` file in it. Raises TrajectoryFileError."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    from slax_drake.errors import TrajectoryFileError
    from slax_drake.hardware.trajectory_file import trajectory_from_bag_messages

    path = Path(path)
    folder = path.parent if path.suffix.lower() == ".mcap" else path
    if not (folder / "metadata.yaml").is_file():
        raise TrajectoryFileError(f"{path}: not a ROS 2 bag folder (no metadata.yaml; 'export --format mcap' writes one)")
    typestore = get_typestore(Stores.ROS2_JAZZY)
    document, trajectories = None, []
    try:
        with Reader(folder) as reader:
            wanted = [c for c in reader.connections if c.topic in (TOPIC_TRAJECTORY_DOCUMENT, TOPIC_PLANNED_TRAJECTORY)]
            for connection, _, raw in reader.messages(connections=wanted):
                msg = typestore.deserialize_cdr(raw, connection.msgtype)
                if connection.topic == TOPIC_TRAJECTORY_DOCUMENT:
                    document = msg.data
                else:
                    trajectories.append(msg)
    except TrajectoryFileError:
        raise
    except Exception as e:  # noqa: BLE001 - rosbags raises many kinds for a damaged bag
        raise TrajectoryFileError(f"{path}: cannot read the bag ({type(e).__name__}: {e})") from None
    if document is None:
        raise TrajectoryFileError(f"{path}: the bag has no {TOPIC_TRAJECTORY_DOCUMENT} message (not written by "
                                  "'slax-drake export --format mcap')")
    return trajectory_from_bag_messages(document, trajectories, str(path))
