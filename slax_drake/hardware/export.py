"""A trial's ``trial.json`` -> :class:`~slax_drake.hardware.trajectory_file.ExportedTrajectory`.

The trial records ``executed_trajectory``: the commanded joint trajectory over the whole trial (holds between
motions), every ``stride``-th 1 ms sample (10 ms by default), rounded to 1e-6. Each action's motion starts at its
decision time (``steps_log[*].time`` of the entries with an action) and lasts ``actions[*].motion.duration_s``;
its suction command is on over ``actions[*].motion.suction_intervals`` (seconds from the motion's start). Each
motion's ``action`` carries ``estimate``, the hypothesis the planner acted on (shape, size, x, y, yaw in the shelf
frame, from the decision's ``hypotheses``), and ``scene_object``, the scene object the trial associated the
segment with; the checker matches the estimate to its own scene and checks the association.

A guarded suction's motion carries ``guarded_push_in`` in its action (its push-in window, s from the motion's start,
and the stop force); when the trial's guard stopped it on contact, the action is exported as two motions: the
motion up to the stop (``guarded_push_in.stopped_at_s``; it ends moving, where the controller's guard stops it) and
the stop motion the planner made from the measured pose (``guard_stop_motion``: hold, lower, release, back off, the
way back), which starts at rest. A lifted object's push-in that the guard stopped at the support board's front edge
(``guard.edge_stop``) was pushed in again higher by the motion the planner made from there (``edge_retry_motion``;
it starts at rest and carries its own ``guarded_push_in``), followed, when the guard stopped that too, by its stop
motion: three motions. An unguarded lift's push-in is watched likewise while a stop would be the board's edge
(``guard.edge_only``): when it stopped there, its motion up to the stop (``edge_watch.stopped_at_s``, ending moving)
and the push-in again higher (``edge_retry_motion``, not watched). A lift the trial weighed and put back (too heavy, not hanging free, or nothing
held) is exported likewise: the motion up to the weighing (``put_back_at_s``; at rest at the lift) and the put-back
motion (``put_back_motion``: its own motion played backward, lowered, released where it was sealed, the way back).

Export cuts the record into motions: the samples from the motion's start to its end; when the start or the end
(multiples of 1 ms) falls between two records, the point is added from the record before the start or after the
end (the robot holds still there, so its position is exact, velocity and acceleration zero). With ``rate=None`` the points are the trial's own
samples (nothing is interpolated: a replay feeds exactly what the trial recorded). With a rate (Hz) each motion
is resampled at t = k / rate from its start, plus its end point (:func:`slax_drake.hardware.interpolation.resample`):
positions by quintic Hermite interpolation of the recorded positions, velocities and accelerations (on a Ruckig
profile recorded every 10 ms, within 2e-7 rad of the exact profile); accelerations linearly between records (the
jerk-limited profile's acceleration is piecewise linear: this never exceeds the records' accelerations nor their
jerk, and is off by at most j_max * dt / 2 at a jerk switch); velocities as the integral of that acceleration,
corrected linearly to meet the next record. At rate 100 and the trial's default 10 ms
records the samples coincide with the records and are copied exactly.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from slax_drake.hardware.fetch_limits import FETCH_JOINTS
from slax_drake.hardware.interpolation import resample
from slax_drake.hardware.trajectory_file import ExportedTrajectory, Motion
from slax_drake.errors import TrialFileError
from slax_drake.systems.guard import dragged_after_weighing

TIME_EPS = 1e-6  # s: trial.json rounds its times to 1e-6


def read_trial(path: str | Path) -> dict:
    """The trial record ``path`` (a trial.json, or the folder 'slax-drake trial' wrote it to); a missing, corrupt or
    foreign file is a TrialFileError."""
    path = Path(path)
    if path.is_dir():
        path = path / "trial.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise TrialFileError(f"{path}: no such file") from None
    except json.JSONDecodeError as e:
        raise TrialFileError(f"{path}: not valid JSON (truncated or corrupt): {e.msg} at line {e.lineno}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise TrialFileError(f"{path}: cannot read ({e})") from None
    for key in ("executed_trajectory", "actions", "steps_log"):
        if not isinstance(data, dict) or key not in data:
            raise TrialFileError(f"{path}: not a trial record (no {key!r}; written by 'slax-drake trial')")
    return data


def trial_scene(data: dict):
    """The trial's initial scene, sampled again from its config, object count and seed (the trial does the same),
    checked against the trial's recorded initial object poses (1e-4 m, 1e-4 rad)."""
    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene

    for key in ("objects", "seed"):
        value = data.get(key)
        if isinstance(value, bool) or not isinstance(value, int):
            raise TrialFileError(f"the trial's {key!r} must be an integer (got {value!r}); pass --scene")
    if not isinstance(data.get("config"), str):
        raise TrialFileError(f"the trial's 'config' must be a scenario path (got {data.get('config')!r}); pass --scene")
    scene = sample_scene(load_scenario(data["config"]), data["objects"], seed=data["seed"])
    recorded = data.get("initial_objects") or {}
    for o in scene.objects:
        r = recorded.get(o.name)
        if r is None or abs(r["x"] - o.center[0]) > 1e-4 or abs(r["y"] - o.center[1]) > 1e-4 or abs(r["yaw"] - o.yaw) > 1e-4:
            raise TrialFileError(f"the scene sampled from {data['config']} (objects {data['objects']}, seed "
                                 f"{data['seed']}) differs from the trial's initial objects at {o.name}: pass --scene")
    return scene


BYTES_PER_JOINT_POINT = 200  # one joint at one resampled point: q, v, a as float64, Python floats, text output


def export_trial(data: dict, rate: float | None = None, source: str | None = None, scene=None) -> ExportedTrajectory:
    """Cuts the trial's executed trajectory into motions (module docstring); ``rate`` in Hz or None."""
    from slax_drake.scene.io import scene_to_dict

    if rate is not None and not rate > 0:
        raise TrialFileError(f"--rate must be positive (got {rate})")
    et = data["executed_trajectory"]
    try:
        names = tuple(et["joint_names"])
        times = np.asarray(et["times"], float)
        q = np.asarray(et["positions"], float)
        v = np.asarray(et["velocities"], float)
        a = np.asarray(et["accelerations"], float)
    except (KeyError, TypeError, ValueError) as e:
        raise TrialFileError(f"{source or 'trial'}: executed_trajectory is malformed ({e})") from None
    if names != FETCH_JOINTS:
        raise TrialFileError(f"{source or 'trial'}: executed_trajectory joints {list(names)} are not {list(FETCH_JOINTS)}")
    if times.ndim != 1 or len(times) < 2 or any(x.shape != (len(times), len(names)) for x in (q, v, a)):
        raise TrialFileError(f"{source or 'trial'}: executed_trajectory arrays have inconsistent shapes")
    for label, x in (("times", times), ("positions", q), ("velocities", v), ("accelerations", a)):
        if not np.all(np.isfinite(x)):
            where = np.argwhere(~np.isfinite(x))[0]
            raise TrialFileError(f"{source or 'trial'}: executed_trajectory.{label} holds a non-finite value "
                                 f"({float(x[tuple(where)])!r} at index {', '.join(map(str, where))})")
    if not np.all(np.diff(times) > 0):
        raise TrialFileError(f"{source or 'trial'}: executed_trajectory times are not strictly increasing")
    starts = [e for e in data["steps_log"] if "action" in e]
    if len(starts) != len(data["actions"]):
        raise TrialFileError(f"{source or 'trial'}: {len(data['actions'])} actions but {len(starts)} decisions with one")
    if rate is not None:
        from slax_drake.resources import check_memory

        points = sum(float(action["motion"]["duration_s"]) for action in data["actions"]) * rate
        check_memory(points * len(names) * BYTES_PER_JOINT_POINT, f"--rate {rate:g} Hz ({points:.3g} points)",
                     "use a lower rate")
    motions = []
    for entry, action in zip(starts, data["actions"]):
        act = {k: action[k] for k in ("type", "object", "d", "dx", "dz", "yaw") if k in action}
        estimate = (entry.get("hypotheses") or {}).get(action.get("object"))
        if isinstance(estimate, dict):  # what the planner believed of the object it acts on
            act["estimate"] = {k: estimate[k] for k in ("shape", "size", "x", "y", "yaw") if k in estimate}
        if action.get("true_object") is not None:  # the simulator's association of the segment to a scene object
            act["scene_object"] = action["true_object"]
        for t0, duration, intervals, motion_act, after_stop in _segments(entry, action, act, source):
            mt, mq, mv, ma = _cut(times, q, v, a, t0, duration, names, source, after_stop)
            if rate is not None:
                count = max(1, int(np.ceil(duration * rate - 1e-6)))  # samples k / rate < duration, then the end
                new_t = np.append(np.arange(count) / rate, duration)
                stopped = "stopped_at_s" in (motion_act.get("guarded_push_in") or {})
                q_end = mq[-1].copy()
                v_end, a_end = (mv[-1].copy(), ma[-1].copy()) if stopped else (0.0, 0.0)
                mq, mv, ma = resample(mt, mq, mv, ma, new_t)
                mq[-1], mv[-1], ma[-1] = q_end, v_end, a_end  # the end exactly: at rest, or where a guard stopped it
                mt = new_t
            events = []
            for on, off in intervals:
                events += [(float(on), True), (float(off), False)]
            motions.append(Motion(t0, mt, mq, mv, ma, events, motion_act,
                                  None if after_stop else entry.get("poses_before"),
                                  [] if after_stop else list(entry.get("lost", []))))
    metadata = {
        "source": source, "config": data.get("config"), "station": data.get("station"),
        "objects": data.get("objects"), "seed": data.get("seed"), "policy": data.get("policy"),
        "rate_hz": rate, "samples": "trial records" if rate is None else f"resampled at {rate} Hz (quintic Hermite)",
        "initial_positions": q[0].tolist(), "end_time": float(times[-1]),
        "final_objects": data.get("final_objects"),
    }
    if scene is not None:
        metadata["scene"] = scene_to_dict(scene)
    return ExportedTrajectory(motions, metadata)


def guarded_window(action: dict) -> tuple[float, float] | None:
    """(start, end), s from the motion's start, of a guarded suction's push-in from its recorded waypoint times
    (the segment arriving at "push in"); None for any other action or a record without them."""
    from slax_drake.systems.guard import push_in_of

    if action.get("type") != "suction" or not action.get("guarded"):
        return None
    return push_in_of((action.get("motion") or {}).get("waypoint_times") or [])


def _segments(entry: dict, action: dict, act: dict, source):
    """[(start s on the trial clock, duration s, suction intervals from the start, the motion's action, whether it
    starts where a guard stopped the motion before)] of one action: its motion; for a guarded suction whose push-in
    the guard stopped (``action["guard"]["stopped"]``), its motion up to the stop (ending where the guard stopped it,
    not at rest; the action's ``guarded_push_in`` says so) and the stop motion planned from there (hold, lower,
    release, back off, the way back; ``guard.stop_motion``); one stopped at the board's front edge
    (``guard.edge_stop``): its motion up to that stop, then the push-in again higher (``edge_stop.stop_motion``, its
    own ``guarded_push_in``), cut likewise when the guard stopped that. A guarded suction's action carries ``guarded_push_in``: its
    push-in window, the stop force and, when stopped, ``stopped_at_s``. A lift weighed and put back
    (``action["weighed"]["put_back"]``): its motion up to the weighing (at rest at the lift; its action carries
    ``put_back_at_s``) and the put-back motion (its own motion played backward: lowered, released, the way back;
    ``put_back_motion``)."""
    t0 = float(entry["time"])
    motion = action["motion"]
    duration = float(motion["duration_s"])
    intervals = [(float(on), float(off)) for on, off in motion.get("suction_intervals") or []]
    weighed = action.get("weighed") if isinstance(action.get("weighed"), dict) else None
    if weighed and weighed.get("put_back"):  # weighed at the lift and put back: the motion up to there, then back
        t_back, back_duration, back_intervals, before = _replaced(
            weighed, "put_back_time", "put_back_motion", t0, duration, intervals, "a put-back lift", source)
        segments = [(t0, t_back, before, {**act, "put_back_at_s": t_back}, False),
                    (t0 + t_back, back_duration, back_intervals, {**act, "put_back_motion": True}, True)]
        if dragged_after_weighing(action):  # then the drag to the same placement, from where the put-back ended
            drag = weighed["drag_after_weighing"]
            try:
                t_drag, motion = float(drag["started_at"]), drag["motion"]
                drag_duration = float(motion["duration_s"])
                drag_intervals = [(float(on), float(off)) for on, off in motion.get("suction_intervals") or []]
                drag_act = {k: drag["drag"][k] for k in ("type", "object", "dx", "dz", "yaw") if k in drag["drag"]}
            except (KeyError, TypeError, ValueError) as e:
                raise TrialFileError(f"{source or 'trial'}: a drag after a put-back lift's record is malformed ({e})"
                                     ) from None
            if t_drag < t0 + t_back + back_duration - TIME_EPS:
                raise TrialFileError(f"{source or 'trial'}: a drag after a put-back lift starts at {t_drag:.3f} s, "
                                     f"before the put-back ends at {t0 + t_back + back_duration:.3f} s")
            segments.append((t_drag, drag_duration, drag_intervals,
                             {**act, **drag_act, "grip": "drag", "dragged_after_weighing": True}, False))
        return segments
    from slax_drake.systems.guard import push_in_of

    guard = action.get("guard") if isinstance(action.get("guard"), dict) else None
    if guard and guard.get("edge_only") and isinstance(guard.get("edge_stop"), dict):  # an unguarded lift's retry
        edge = guard["edge_stop"]
        t_edge, retry_duration, retry_intervals, before = _replaced(
            edge, "stop_time", "stop_motion", t0, duration, intervals, "a stop at the board's edge", source)
        window = push_in_of(motion.get("waypoint_times") or [])
        if window is None:
            raise TrialFileError(f"{source or 'trial'}: a push-in stopped at the board's edge has no 'push in'")
        watch = {"t_start_s": window[0], "t_end_s": window[1], "stopped_at_s": t_edge}
        return [(t0, t_edge, before, {**act, "edge_watch": watch}, False),
                (t0 + t_edge, retry_duration, retry_intervals, {**act, "edge_retry_motion": True}, True)]
    window = guarded_window(action)
    if window is None:
        return [(t0, duration, intervals, act, False)]
    record = {"t_start_s": window[0], "t_end_s": window[1], "stop_force_n": (guard or {}).get("threshold_n")}
    edge = guard.get("edge_stop") if guard else None
    if isinstance(edge, dict):  # stopped at the board's front edge, then pushed in again higher
        t_edge, retry_duration, retry_intervals, before = _replaced(
            edge, "stop_time", "stop_motion", t0, duration, intervals, "a stop at the board's edge", source)
        retry_window = push_in_of(edge["stop_motion"].get("waypoint_times") or [])
        if retry_window is None:
            raise TrialFileError(f"{source or 'trial'}: a push-in retried at the board's edge has no 'push in'")
        first = (t0, t_edge, before, {**act, "guarded_push_in": {**record, "stopped_at_s": t_edge}}, False)
        t0, duration, intervals = t0 + t_edge, retry_duration, retry_intervals
        act = {**act, "edge_retry_motion": True}
        record = {"t_start_s": retry_window[0], "t_end_s": retry_window[1], "stop_force_n": record["stop_force_n"]}
    else:
        first = None
    segments = [] if first is None else [first]
    if not (guard and guard.get("stopped")):
        return segments + [(t0, duration, intervals, {**act, "guarded_push_in": record}, first is not None)]
    t_stop, stop_duration, stop_intervals, before = _replaced(
        guard, "stop_time", "stop_motion", t0, duration, intervals, "a guard stop", source)
    return segments + [(t0, t_stop, before, {**act, "guarded_push_in": {**record, "stopped_at_s": t_stop}},
                        first is not None),
                       (t0 + t_stop, stop_duration, stop_intervals,
                        {k: v for k, v in act.items() if k != "edge_retry_motion"} | {"guard_stop_motion": True}, True)]


def _replaced(record: dict, time_key: str, motion_key: str, t0: float, duration: float, intervals, what: str,
              source):
    """(when, s from the motion's start; the replacing motion's duration, s; its suction intervals; the motion's own
    intervals cut there) of a motion that ``record`` (a guard stop's or a put-back's) says was replaced at
    ``record[time_key]`` (trial clock) by ``record[motion_key]``; TrialFileError (naming ``what``) when malformed."""
    try:
        t_cut = float(record[time_key]) - t0
        motion = record[motion_key]
        after = float(motion["duration_s"])
        after_intervals = [(float(on), float(off)) for on, off in motion.get("suction_intervals") or []]
    except (KeyError, TypeError, ValueError) as e:
        raise TrialFileError(f"{source or 'trial'}: {what}'s record is malformed ({e})") from None
    if not 0.0 < t_cut <= duration + TIME_EPS:
        raise TrialFileError(f"{source or 'trial'}: {what} replaced a motion at {t_cut:.3f} s of its "
                             f"{duration:.3f} s")
    return t_cut, after, after_intervals, [(on, min(off, t_cut)) for on, off in intervals if on < t_cut]


def _cut(times, q, v, a, t0: float, duration: float, names, source, after_stop: bool):
    """The records of [t0, t0 + duration] (module docstring) as (times from t0, q, v, a). A guard's stop motion
    (``after_stop``) starts at rest where the record after the stop holds it (the trial's record at the stop
    instant is the stopped motion's last)."""
    t1 = t0 + duration
    lo = t0 + TIME_EPS if after_stop else t0 - TIME_EPS
    idx = np.flatnonzero((times >= lo) & (times <= t1 + TIME_EPS))
    if len(idx) == 0:
        raise TrialFileError(f"{source or 'trial'}: no record during the motion at {t0} s")
    mt, mq, mv, ma = times[idx] - t0, q[idx], v[idx], a[idx]
    zero = np.zeros((1, len(names)))
    if after_stop:  # it holds still first: the stop pose, at rest
        mt, mq = np.append(0.0, mt), np.vstack([mq[:1], mq])
        mv, ma = np.vstack([zero, mv]), np.vstack([zero, ma])
    elif abs(mt[0]) > TIME_EPS:  # the start falls between records: the robot holds the previous record's pose
        if idx[0] == 0:
            raise TrialFileError(f"{source or 'trial'}: the record starts after the motion at {t0} s")
        mt, mq = np.append(0.0, mt), np.vstack([q[idx[0] - 1], mq])
        mv, ma = np.vstack([zero, mv]), np.vstack([zero, ma])
    if abs(mt[-1] - duration) > TIME_EPS:  # the end falls between records: the next record holds the end pose
        nxt = idx[-1] + 1
        if nxt >= len(times):
            raise TrialFileError(f"{source or 'trial'}: the record ends before the motion at {t0} s does")
        mt = np.append(mt, duration)
        mq = np.vstack([mq, q[nxt]])
        mv = np.vstack([mv, np.zeros(len(names))])
        ma = np.vstack([ma, np.zeros(len(names))])
    else:
        mt[-1] = duration
    mt[0] = 0.0
    return mt, mq, mv, ma
