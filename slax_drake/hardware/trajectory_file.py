"""The exported trajectory and its file formats.

An :class:`ExportedTrajectory` is a list of motions. Each :class:`Motion` is one action's trajectory shaped as a
ROS ``trajectory_msgs/JointTrajectory`` (joint names, points with positions, velocities, accelerations and
``time_from_start``), its start time on the trial's clock, and its suction on/off events as timed entries of their
own (the suction valve is not a joint). Between motions the robot holds the last point of the previous motion.
Joints (:data:`~slax_drake.hardware.fetch_limits.FETCH_JOINTS`): torso_lift_joint (m), the seven arm joints and
the bluction tool's tool_shaft_joint (rad), named as on the real robot.

A motion's ``action`` is ``{"type": "push" | "suction", "object": the policy's name for it, "d" | "dx", "dz",
"yaw", "estimate": {"shape", "size", "x", "y", "yaw"} (what the planner believed of it, shelf frame), "scene_object":
the scene object it was associated with (optional)}``.

Formats (chosen by the file's extension; a folder or a ``.mcap`` is the ROS 2 bag of ``export --format mcap``,
read by :func:`slax_drake.hardware.rosbag_export.read_trajectory_bag`):

- ``.json`` (ros-json): ``{"format": "slax-drake-fetch-trajectory", "version": 1, "joint_names": [...],
  "metadata": {...}, "motions": [{"index", "start_time", "action", "objects_before", "lost", "suction_events":
  [{"time_from_start", "suction"}], "trajectory": {"joint_names", "points": [{"positions", "velocities",
  "accelerations", "time_from_start"}]}}]}`` with times in seconds.
- ``.yaml``/``.yml`` (ros-yaml): the same document, but each motion carries ``goal``: a
  ``control_msgs/FollowJointTrajectory`` goal (``trajectory`` with ``header``, ``joint_names`` and points whose
  ``time_from_start`` is a ROS 1 duration ``{secs, nsecs}``; ``path_tolerance``, ``goal_tolerance``,
  ``goal_time_tolerance``) in place of ``trajectory``. Times round to 1 ns there.
- ``.csv``: line 1 ``# slax-drake-fetch-trajectory v1``, line 2 ``# meta <one JSON object: the document without
  the points>``, then a header row and one row per point or suction event: ``motion, start_time,
  time_from_start, event`` (``point``, ``suction_on``, ``suction_off``), then 9 positions, 9 velocities and 9
  accelerations (empty for suction rows). A CSV reader with ``comment='#'`` reads the table.

Floats are written with full precision (Python's repr), so every format parses back to the same numbers
(YAML times to 1 ns). Loading is strict: any malformed or truncated file, wrong joint names, non-finite numbers
(positions, fields, times, objects_before, the action's numbers, initial positions), an unknown action type or
non-monotonic time raise :class:`TrajectoryFileError` naming the file and the problem.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path

import numpy as np

from slax_drake.errors import TrajectoryFileError
from slax_drake.hardware.fetch_limits import FETCH_JOINTS

FORMAT_NAME = "slax-drake-fetch-trajectory"
FORMAT_VERSION = 1
FORMATS = {"ros-json": ".json", "ros-yaml": ".yaml", "csv": ".csv"}
CSV_MAGIC = f"# {FORMAT_NAME} v{FORMAT_VERSION}"
GOAL_TIME_TOLERANCE = 0.5  # s, written into the FollowJointTrajectory goals


@dataclasses.dataclass
class Motion:
    """One action's motion: times (N,) from 0 (s, strictly increasing), q, v, a (N, 9) in ``FETCH_JOINTS`` order,
    its start on the trial clock (s), suction events [(time_from_start, on)], and the trial's context (the action,
    the objects' planar poses {name: {x, y, yaw}} in the shelf frame before it, names of toppled/dropped objects)."""

    start_time: float
    times: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    suction_events: list = dataclasses.field(default_factory=list)
    action: dict | None = None
    objects_before: dict | None = None
    lost: list = dataclasses.field(default_factory=list)

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    @property
    def end_time(self) -> float:
        return self.start_time + self.duration


@dataclasses.dataclass
class ExportedTrajectory:
    """Motions in time order; ``metadata``: where they come from (trial, config, station, scene, rate, end time)."""

    motions: list
    metadata: dict = dataclasses.field(default_factory=dict)
    joint_names: tuple = FETCH_JOINTS

    @property
    def end_time(self) -> float:
        end = self.metadata.get("end_time")
        last = self.motions[-1].end_time if self.motions else 0.0
        return max(float(end), last) if end is not None else last


# -- writing ---------------------------------------------------------------------------------------------------

def _points(m: Motion) -> list:
    return [{"positions": m.q[k].tolist(), "velocities": m.v[k].tolist(), "accelerations": m.a[k].tolist(),
             "time_from_start": float(m.times[k])} for k in range(len(m.times))]


def _motion_header(k: int, m: Motion) -> dict:
    return {"index": k, "start_time": float(m.start_time), "duration": m.duration, "num_points": len(m.times),
            "action": m.action,
            "objects_before": m.objects_before, "lost": list(m.lost),
            "suction_events": [{"time_from_start": float(t), "suction": bool(on)} for t, on in m.suction_events]}


def _document(traj: ExportedTrajectory, points: bool) -> dict:
    motions = []
    for k, m in enumerate(traj.motions):
        entry = _motion_header(k, m)
        if points:
            entry["trajectory"] = {"joint_names": list(traj.joint_names), "points": _points(m)}
        motions.append(entry)
    return {"format": FORMAT_NAME, "version": FORMAT_VERSION, "joint_names": list(traj.joint_names),
            "metadata": traj.metadata, "motions": motions}


def header_document(traj: ExportedTrajectory) -> dict:
    """The document without the points (the CSV's ``# meta`` line, the bag's ``/slax_drake/trajectory``)."""
    return _document(traj, points=False)


def _ros_duration(t: float) -> dict:
    ns = int(round(t * 1e9))
    return {"secs": ns // 1_000_000_000, "nsecs": ns % 1_000_000_000}


def to_ros_json(traj: ExportedTrajectory) -> str:
    return json.dumps(_document(traj, points=True), indent=1, allow_nan=False)


def to_ros_yaml(traj: ExportedTrajectory) -> str:
    import yaml

    doc = _document(traj, points=False)
    for entry, m in zip(doc["motions"], traj.motions):
        entry["goal"] = {
            "trajectory": {
                "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": "base_link"},
                "joint_names": list(traj.joint_names),
                "points": [dict(p, effort=[], time_from_start=_ros_duration(p["time_from_start"])) for p in _points(m)],
            },
            "path_tolerance": [], "goal_tolerance": [],
            "goal_time_tolerance": _ros_duration(GOAL_TIME_TOLERANCE),
        }
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    return "# control_msgs/FollowJointTrajectory goals, one per motion (slax-drake export)\n" + yaml.dump(
        doc, Dumper=dumper, sort_keys=False, default_flow_style=None, width=1000)


def csv_header(names=FETCH_JOINTS) -> list:
    return (["motion", "start_time", "time_from_start", "event"] + [f"{n}_position" for n in names]
            + [f"{n}_velocity" for n in names] + [f"{n}_acceleration" for n in names])


def to_csv(traj: ExportedTrajectory) -> str:
    buf = io.StringIO()
    buf.write(CSV_MAGIC + "\n")
    buf.write("# meta " + json.dumps(_document(traj, points=False), allow_nan=False) + "\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(csv_header(traj.joint_names))
    blank = [""] * (3 * len(traj.joint_names))
    for k, m in enumerate(traj.motions):
        rows = [(float(t), 0, ["point"] + [repr(float(x)) for x in (*m.q[i], *m.v[i], *m.a[i])])
                for i, t in enumerate(m.times)]
        rows += [(float(t), 1, ["suction_on" if on else "suction_off"] + blank) for t, on in m.suction_events]
        for t, _, rest in sorted(rows, key=lambda r: (r[0], r[1])):
            w.writerow([k, repr(float(m.start_time)), repr(t)] + rest)
    return buf.getvalue()


def format_of(path: str | Path) -> str:
    ext = Path(path).suffix.lower()
    for name, e in FORMATS.items():
        if ext == e or (name == "ros-yaml" and ext == ".yml"):
            return name
    raise TrajectoryFileError(f"{path}: unknown trajectory file extension {ext!r} (use .json, .yaml/.yml or .csv, "
                              "or a ROS 2 bag folder written by 'export --format mcap')")


def dumps(traj: ExportedTrajectory, fmt: str) -> str:
    if fmt == "ros-json":
        return to_ros_json(traj)
    if fmt == "ros-yaml":
        return to_ros_yaml(traj)
    if fmt == "csv":
        return to_csv(traj)
    raise TrajectoryFileError(f"unknown format {fmt!r} (choose from {', '.join(FORMATS)})")


def save_trajectory(traj: ExportedTrajectory, path: str | Path, fmt: str | None = None) -> None:
    """Writes ``traj`` atomically; the format follows the extension unless ``fmt`` is given."""
    from slax_drake.io import write_text_atomic

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(Path(path), dumps(traj, fmt or format_of(path)))


# -- reading ---------------------------------------------------------------------------------------------------

def load_trajectory(path: str | Path) -> ExportedTrajectory:
    """Reads a trajectory file of any of the three formats; raises TrajectoryFileError on any problem."""
    path = Path(path)
    if path.is_dir() or path.suffix.lower() == ".mcap":
        from slax_drake.hardware.rosbag_export import read_trajectory_bag

        return read_trajectory_bag(path)
    fmt = format_of(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TrajectoryFileError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise TrajectoryFileError(f"{path}: cannot read ({e})") from None
    if not text.strip():
        raise TrajectoryFileError(f"{path}: the file is empty")
    try:
        if fmt == "ros-json":
            return _from_document(_parse_json(text), source="json")
        if fmt == "ros-yaml":
            return _from_document(_parse_yaml(text), source="yaml")
        return _from_csv(text)
    except _Bad as e:
        raise TrajectoryFileError(f"{path}: {e}") from None


class _Bad(Exception):
    pass


def _parse_json(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise _Bad(f"not valid JSON (truncated or corrupt): {e.msg} at line {e.lineno} column {e.colno}") from None


def _parse_yaml(text: str):
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        return yaml.load(text, Loader=loader)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1} column {mark.column + 1}" if mark is not None else ""
        raise _Bad(f"not valid YAML (truncated or corrupt): {getattr(e, 'problem', None) or e}{where}") from None


def _get(d, key, what, kind=None):
    if not isinstance(d, dict):
        raise _Bad(f"{what} must be a mapping, got {type(d).__name__}")
    if key not in d:
        raise _Bad(f"{what} has no key {key!r}")
    value = d[key]
    if kind is not None and not isinstance(value, kind):
        raise _Bad(f"{what}.{key} must be a {kind.__name__ if isinstance(kind, type) else 'number'}")
    return value


def _number(x, what) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise _Bad(f"{what} must be a number, got {x!r}")
    if not math.isfinite(x):
        raise _Bad(f"{what} is not finite ({x!r})")
    return float(x)


def _vector(x, n, what) -> list:
    if not isinstance(x, list) or len(x) != n:
        raise _Bad(f"{what} must be a list of {n} numbers")
    return [_number(e, what) for e in x]


def _check_names(names, what) -> None:
    if not isinstance(names, list) or list(names) != list(FETCH_JOINTS):
        unknown = [n for n in (names if isinstance(names, list) else []) if n not in FETCH_JOINTS]
        raise _Bad(f"{what} must be exactly {list(FETCH_JOINTS)} in this order"
                   + (f" (unknown: {unknown})" if unknown else f" (got {names!r})"))


def _duration(x, what) -> float:
    if isinstance(x, dict):
        secs, nsecs = x.get("secs"), x.get("nsecs")
        if not isinstance(secs, int) or not isinstance(nsecs, int) or isinstance(secs, bool) or isinstance(nsecs, bool):
            raise _Bad(f"{what} must be {{secs: int, nsecs: int}}")
        return secs + nsecs * 1e-9
    return _number(x, what)


def _from_document(doc, source: str) -> ExportedTrajectory:
    if not isinstance(doc, dict):
        raise _Bad("the document must be a mapping (truncated or not a slax-drake trajectory)")
    if doc.get("format") != FORMAT_NAME:
        raise _Bad(f"not a {FORMAT_NAME} document (format = {doc.get('format')!r})")
    if doc.get("version") != FORMAT_VERSION:
        raise _Bad(f"unsupported version {doc.get('version')!r} (this reader knows {FORMAT_VERSION})")
    _check_names(_get(doc, "joint_names", "document"), "joint_names")
    metadata = doc.get("metadata") or {}
    if not isinstance(metadata, dict):
        raise _Bad("metadata must be a mapping")
    motions_raw = _get(doc, "motions", "document", list)
    motions = []
    for k, entry in enumerate(motions_raw):
        what = f"motions[{k}]"
        if source == "yaml":
            goal = _get(entry, "goal", what, dict)
            msg = _get(goal, "trajectory", f"{what}.goal", dict)
            what_points = f"{what}.goal.trajectory"
        else:
            msg = _get(entry, "trajectory", what, dict)
            what_points = f"{what}.trajectory"
        _check_names(_get(msg, "joint_names", what_points), f"{what_points}.joint_names")
        points = _get(msg, "points", what_points, list)
        if not points:
            raise _Bad(f"{what_points}.points is empty")
        n = len(FETCH_JOINTS)
        times, q, v, a = [], [], [], []
        for i, p in enumerate(points):
            wp = f"{what_points}.points[{i}]"
            times.append(_duration(_get(p, "time_from_start", wp), f"{wp}.time_from_start"))
            q.append(_vector(_get(p, "positions", wp), n, f"{wp}.positions"))
            v.append(_vector(_get(p, "velocities", wp), n, f"{wp}.velocities"))
            a.append(_vector(_get(p, "accelerations", wp), n, f"{wp}.accelerations"))
        events = _events(entry.get("suction_events", []), what)
        motions.append(_motion(entry, what, times, q, v, a, events))
    return _finish(motions, metadata)


def _events(raw, what) -> list:
    if not isinstance(raw, list):
        raise _Bad(f"{what}.suction_events must be a list")
    events = []
    for i, e in enumerate(raw):
        t = _number(_get(e, "time_from_start", f"{what}.suction_events[{i}]"), f"{what}.suction_events[{i}].time_from_start")
        on = _get(e, "suction", f"{what}.suction_events[{i}]")
        if not isinstance(on, bool):
            raise _Bad(f"{what}.suction_events[{i}].suction must be true or false")
        events.append((t, on))
    return events


def _motion(entry, what, times, q, v, a, events) -> Motion:
    start = _number(_get(entry, "start_time", what), f"{what}.start_time")
    times = np.asarray(times, float)
    if abs(times[0]) > 1e-9:
        raise _Bad(f"{what}: the first point's time_from_start must be 0 (got {float(times[0])!r} s)")
    if len(times) > 1 and not np.all(np.diff(times) > 0):
        i = int(np.argmax(~(np.diff(times) > 0)))
        raise _Bad(f"{what}: time_from_start is not strictly increasing at point {i + 1} "
                   f"({float(times[i])!r} then {float(times[i + 1])!r} s)")
    for t, _ in events:
        if not -1e-9 <= t <= times[-1] + 1e-9:
            raise _Bad(f"{what}: suction event at {t} s lies outside the motion (0 to {float(times[-1])!r} s)")
    expected = entry.get("duration")
    if isinstance(expected, (int, float)) and not isinstance(expected, bool) and abs(times[-1] - expected) > 1e-6:
        raise _Bad(f"{what} ends at {float(times[-1])!r} s but its header says {expected} s (truncated?)")
    count = entry.get("num_points")
    if isinstance(count, int) and not isinstance(count, bool) and count != len(times):
        raise _Bad(f"{what} has {len(times)} points but its header says {count} (truncated?)")
    lost = entry.get("lost") or []
    if not isinstance(lost, list) or not all(isinstance(n, str) for n in lost):
        raise _Bad(f"{what}.lost must be a list of object names")
    _check_poses(entry.get("objects_before"), f"{what}.objects_before")
    _check_action(entry.get("action"), f"{what}.action")
    return Motion(start, times, np.asarray(q, float), np.asarray(v, float), np.asarray(a, float),
                  sorted(events, key=lambda e: e[0]), entry.get("action"), entry.get("objects_before"), list(lost))


def _check_poses(poses, what) -> None:
    if poses is None:
        return
    if not isinstance(poses, dict):
        raise _Bad(f"{what} must be a mapping of object names to poses")
    for name, p in poses.items():
        for key in ("x", "y", "yaw"):
            _number(_get(p, key, f"{what}.{name}"), f"{what}.{name}.{key}")


def _check_action(action, what) -> None:
    if action is None:
        return
    if not isinstance(action, dict):
        raise _Bad(f"{what} must be a mapping")
    if action.get("type") not in ("push", "suction"):
        raise _Bad(f"{what}.type must be push or suction (got {action.get('type')!r})")
    if not isinstance(action.get("object"), str):
        raise _Bad(f"{what}.object must be a name")
    for key in ("d", "dx", "dz", "yaw"):
        if key in action:
            _number(action[key], f"{what}.{key}")
    if action["type"] == "push" and "d" not in action:
        raise _Bad(f"{what} is a push without its distance d")
    if "scene_object" in action and not isinstance(action["scene_object"], str):
        raise _Bad(f"{what}.scene_object must be a name")
    for field in ("guarded_push_in", "edge_watch"):  # a guarded push-in; an unguarded lift's watch at the edge
        guarded = action.get(field)
        if guarded is None:
            continue
        if not isinstance(guarded, dict):
            raise _Bad(f"{what}.{field} must be a mapping")
        for key in ("t_start_s", "t_end_s"):
            _number(_get(guarded, key, f"{what}.{field}"), f"{what}.{field}.{key}")
        for key in ("stop_force_n", "stopped_at_s"):
            if guarded.get(key) is not None:
                _number(guarded[key], f"{what}.{field}.{key}")
    est = action.get("estimate")
    if est is not None:
        if not isinstance(est, dict) or est.get("shape") not in ("box", "cylinder"):
            raise _Bad(f"{what}.estimate must be a mapping with shape box or cylinder")
        for key in ("x", "y", "yaw"):
            _number(_get(est, key, f"{what}.estimate"), f"{what}.estimate.{key}")
        size = _vector(_get(est, "size", f"{what}.estimate"), 3, f"{what}.estimate.size")
        if min(size) <= 0:
            raise _Bad(f"{what}.estimate.size must be positive")


def _check_metadata(metadata) -> None:
    initial = metadata.get("initial_positions")
    if initial is not None:
        _vector(initial, len(FETCH_JOINTS), "metadata.initial_positions")


def trajectory_from_bag_messages(document: str, messages: list, source: str) -> ExportedTrajectory:
    """An ExportedTrajectory from a bag's ``/slax_drake/trajectory`` document (JSON, no points) and its
    ``/planned_trajectory`` JointTrajectory messages, one per motion in order."""
    try:
        doc = _parse_json(document)
        if not isinstance(doc, dict) or doc.get("format") != FORMAT_NAME:
            raise _Bad("the /slax_drake/trajectory message is not a slax-drake trajectory header")
        _check_names(doc.get("joint_names"), "joint_names")
        headers = doc.get("motions")
        if not isinstance(headers, list) or len(headers) != len(messages):
            raise _Bad(f"the header lists {len(headers) if isinstance(headers, list) else 'no'} motions but the bag "
                       f"has {len(messages)} /planned_trajectory messages")
        motions = []
        for k, (entry, msg) in enumerate(zip(headers, messages)):
            what = f"motion {k}"
            _check_names(list(msg.joint_names), f"{what}: /planned_trajectory joint_names")
            if not msg.points:
                raise _Bad(f"{what} has no points")
            n = len(FETCH_JOINTS)
            times = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in msg.points]
            q = [_vector([float(x) for x in p.positions], n, f"{what}.positions") for p in msg.points]
            v = [_vector([float(x) for x in p.velocities], n, f"{what}.velocities") for p in msg.points]
            a = [_vector([float(x) for x in p.accelerations], n, f"{what}.accelerations") for p in msg.points]
            if not isinstance(entry, dict):
                raise _Bad(f"{what}'s header must be a mapping")
            entry = dict(entry)
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            if abs(stamp - _number(_get(entry, "start_time", what), f"{what}.start_time")) > 1e-6:
                raise _Bad(f"{what}: the message's stamp {stamp} s is not the header's start_time {entry['start_time']} s")
            entry["duration"] = None if entry.get("duration") is None else round(float(entry["duration"]), 9)
            events = _events(entry.get("suction_events", []), what)
            motions.append(_motion(entry, what, times, q, v, a, events))
        return _finish(motions, doc.get("metadata") or {})
    except _Bad as e:
        raise TrajectoryFileError(f"{source}: {e}") from None


def _finish(motions, metadata) -> ExportedTrajectory:
    _check_metadata(metadata)
    for k in range(1, len(motions)):
        if motions[k].start_time < motions[k - 1].end_time - 1e-9:
            raise _Bad(f"motions[{k}] starts at {motions[k].start_time} s, before motions[{k - 1}] ends "
                       f"({motions[k - 1].end_time} s): time is not monotonic")
    return ExportedTrajectory(motions, metadata)


def _from_csv(text: str) -> ExportedTrajectory:
    lines = text.splitlines()
    if not lines or lines[0].strip() != CSV_MAGIC:
        raise _Bad(f"not a slax-drake trajectory CSV (the first line must be {CSV_MAGIC!r})")
    if len(lines) < 3 or not lines[1].startswith("# meta "):
        raise _Bad("the CSV has no '# meta' line (truncated?)")
    doc = _parse_json(lines[1][len("# meta "):])
    if not isinstance(doc, dict) or doc.get("format") != FORMAT_NAME:
        raise _Bad("the '# meta' line is not a slax-drake trajectory header")
    _check_names(doc.get("joint_names"), "joint_names")
    headers = doc.get("motions")
    if not isinstance(headers, list):
        raise _Bad("the '# meta' line has no motions list")
    rows = list(csv.reader(lines[2:]))
    if not rows or rows[0] != csv_header():
        raise _Bad("the CSV header row must be: " + ",".join(csv_header()[:6]) + ",... (27 joint columns)")
    n = len(FETCH_JOINTS)
    per = {k: ([], [], [], [], []) for k in range(len(headers))}
    starts = {}
    for r, row in enumerate(rows[1:], start=4):
        if len(row) != 4 + 3 * n:
            raise _Bad(f"line {r}: {len(row)} columns, expected {4 + 3 * n} (truncated?)")
        try:
            k = int(row[0])
            start = float(row[1])
            t = float(row[2])
        except ValueError:
            raise _Bad(f"line {r}: motion, start_time and time_from_start must be numbers") from None
        if k not in per:
            raise _Bad(f"line {r}: motion {k} is not in the '# meta' line")
        if not (math.isfinite(start) and math.isfinite(t)):
            raise _Bad(f"line {r}: non-finite time")
        starts.setdefault(k, start)
        times, q, v, a, events = per[k]
        if row[3] == "point":
            try:
                vals = [float(x) for x in row[4:]]
            except ValueError:
                raise _Bad(f"line {r}: joint values must be numbers") from None
            if not all(math.isfinite(x) for x in vals):
                raise _Bad(f"line {r}: non-finite joint value")
            times.append(t)
            q.append(vals[:n])
            v.append(vals[n:2 * n])
            a.append(vals[2 * n:])
        elif row[3] in ("suction_on", "suction_off"):
            events.append((t, row[3] == "suction_on"))
        else:
            raise _Bad(f"line {r}: unknown event {row[3]!r} (point, suction_on or suction_off)")
    motions = []
    for k, header in enumerate(headers):
        times, q, v, a, events = per[k]
        what = f"motion {k}"
        if not times:
            raise _Bad(f"{what} has no points (truncated?)")
        entry = dict(header) if isinstance(header, dict) else {}
        entry["start_time"] = starts[k]
        motions.append(_motion(entry, what, times, q, v, a, events))
    return _finish(motions, doc.get("metadata") or {})
