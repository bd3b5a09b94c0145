"""One action of a finished Drake trial again, alone: planned by today's planner from the hypotheses the trial's policy
had at that decision, run in the station on the true scene of that moment. Prints Markdown.

    python research/replay_action.py TRIAL_FOLDER --action K [--object NAME] [--every 1.0]

TRIAL_FOLDER is a ``slax-drake trial --out`` folder (trial.json, scene.json and ``object_poses.npz``). Action K
(0-based, as the trial's actions) is rebuilt from its record (type, object, contact, parameters, grip, guarded) and
planned with the trial's station, profile and tool rules in the believed scene of its decision (the recorded
hypotheses as boxes and cylinders standing on the board). The true scene is the trial's initial scene with every
object where ``object_poses.npz`` holds it at the decision's time. The motion then runs in the station: a suction
with the trial's guard (a guarded push-in's stop and retry at the board's edge; an unguarded lift's watch at the
edge), a push open loop (no weighing, no put-back). The moved object's true pose (S; m, rad, deg from upright) is printed every ``--every`` simulated seconds
and at the end, beside the trial's own outcome of that action, so that a change of the planner can be tried on the
very action that went wrong (``docs/research/physics.md``: the way back that knocked a placed box off the shelf).

Bad arguments or an unreadable folder: one line on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.errors import UserError
from slax_drake.scene.io import load_scene
from slax_drake.station.scenario import load_station_scenario


class ReplayError(Exception):
    """The folder or the request cannot be replayed (a user's error: one line, exit code 2)."""


def load_trial(folder: Path) -> tuple[dict, dict]:
    """(trial.json's record, object_poses.npz's arrays) of a trial folder; ReplayError when unreadable."""
    try:
        record = json.loads((folder / "trial.json").read_text())
        with np.load(folder / "object_poses.npz") as poses:
            arrays = {k: poses[k] for k in ("times", "poses", "names")}
    except (OSError, ValueError, KeyError) as e:
        raise ReplayError(f"{folder}: not a readable trial folder ({e})") from None
    return record, arrays


def decision_of(record: dict, k: int) -> tuple[dict, dict]:
    """(the trial's action record k, the decision entry of its steps_log that chose it)."""
    actions = record.get("actions") or []
    if not 0 <= k < len(actions):
        raise ReplayError(f"--action {k}: the trial has {len(actions)} actions (0 .. {len(actions) - 1})")
    chosen = [entry for entry in record.get("steps_log") or [] if entry.get("action")]
    if len(chosen) <= k:
        raise ReplayError(f"--action {k}: the trial's steps_log holds no decision for it")
    return actions[k], chosen[k]


def yaw_of(quaternion) -> float:
    """The heading (rad) of a body's x axis about S z, from its orientation (w, x, y, z)."""
    w, x, y, z = (float(v) for v in quaternion)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def true_scene_at(scene, arrays: dict, t: float):
    """``scene`` (the trial's initial Scene) with each object standing where the recorded poses put it at time ``t``
    (s; the last sample at or before it)."""
    import dataclasses

    from slax_drake.scene.model import planar_pose

    names = [str(n) for n in arrays["names"]]
    i = max(0, int(np.searchsorted(arrays["times"], t, side="right")) - 1)
    moved = []
    for obj in scene.objects:
        x, y, _, *q = arrays["poses"][i, names.index(obj.name)]
        moved.append(dataclasses.replace(obj, X_SO=planar_pose(float(x), float(y), obj.size[2] / 2.0, yaw_of(q))))
    return dataclasses.replace(scene, objects=tuple(moved))


def believed_scene(scene, hypotheses: dict):
    """The believed Scene of a decision: its hypotheses (name -> shape, size, x, y, yaw) standing on the board."""
    from slax_drake.scene.model import Scene, SceneObject, planar_pose

    objects = tuple(SceneObject(name, h["shape"], tuple(h["size"]), planar_pose(h["x"], h["y"], h["size"][2] / 2.0,
                                                                              h["yaw"]))
                    for name, h in hypotheses.items())
    return Scene(scene.shelf, scene.camera, objects, None, 0)


def action_of(entry: dict):
    """The Push or Suction a decision's ``action`` record describes."""
    from slax_drake.shelf.actions import Push, Suction

    a = entry["action"]
    if a["type"] == "push":
        return Push(a["object"], tuple(a["q"]), float(a["d"]), turns=bool(a.get("turns", False)))
    return Suction(a["object"], tuple(a["q"]), float(a["dx"]), float(a["dz"]), float(a.get("yaw", 0.0)),
                   drag=a.get("grip") == "drag", guarded=bool(a.get("guarded", False)))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("trial", type=Path, help="a 'slax-drake trial --out' folder")
    p.add_argument("--action", type=int, required=True, help="the action's index (0-based, as the trial's actions)")
    p.add_argument("--object", help="the true object to follow (default: the one the trial associated the action with)")
    p.add_argument("--every", type=float, default=1.0, help="seconds of simulated time between printed poses")
    args = p.parse_args(argv)
    try:
        if args.every <= 0:
            raise ReplayError("--every: takes a positive number of seconds")
        record, arrays = load_trial(args.trial)
        act, entry = decision_of(record, args.action)
        name = args.object or act.get("true_object")
        if name not in [str(n) for n in arrays["names"]]:
            raise ReplayError(f"--object {name!r}: not an object of the trial")
        if not (isinstance(record.get("config"), str) and isinstance(record.get("station"), str)):
            raise ReplayError(f"{args.trial}: trial.json names no scenario config or station file")
        scenario = load_scenario(record["config"])
        station = load_station_scenario(record["station"])
        scene = load_scene(args.trial / "scene.json")
    except (ReplayError, UserError) as e:  # a config, station or scene file the trial names that cannot be read
        print(f"error: {e}", file=sys.stderr)
        return 2
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.tool import tool_config
    from slax_drake.systems.motion_run import run_guarded_motion, run_motion

    tool = tool_config(scenario, record.get("profile", "station"), **(record.get("tool_rules") or {}))
    believed = believed_scene(scene, entry["hypotheses"])
    true = true_scene_at(scene, arrays, float(entry["time"]))
    action = action_of(entry)
    planner = MotionPlanner(station, tool)
    motion = planner.plan(action, believed)
    print(f"Action {args.action} of `{args.trial}` ({action.describe()}), planned again from its decision's "
          f"hypotheses and run alone on the true scene at t = {float(entry['time']):.1f} s. Made by `python "
          f"research/replay_action.py {args.trial} --action {args.action}`.\n")
    if not motion.feasible:
        print(f"The planner refuses it now: {motion.reason}")
        return 0
    was = (act.get("motion") or {}).get("duration_s")
    print(f"Motion {motion.trajectory.duration:.1f} s (the trial's: {was} s); waypoints: "
          + ", ".join(f"{label} {t:.1f}" for label, t in motion.waypoint_times) + ".\n")
    times = tuple(np.arange(args.every, motion.trajectory.duration, args.every))
    if action.kind == "suction":  # with the trial's guard: a guarded push-in, or an unguarded lift's edge watch
        end, guard = run_guarded_motion(station, true, believed, motion, planner, [name])
        poses = {"end": end[name]}
        print(f"Guard: {json.dumps(guard, default=str) if guard else 'none'}\n")
    else:
        poses = run_motion(station, true, motion, name, times)
    print(f"| t (s) | {name} x | y | z | yaw | tilt (deg) |")
    print("|---|---|---|---|---|---|")
    for t, pose in poses.items():
        label = t if isinstance(t, str) else f"{t:.1f}"
        print(f"| {label} | {pose['x']:+.3f} | {pose['y']:+.3f} | {pose['z']:.3f} | {pose['yaw']:+.3f} | "
              f"{pose['tilt_deg']:.1f} |")
    out = act.get("outcome") or {}
    if out:
        print(f"\nIn the trial it ended at x {out['x']:+.3f}, y {out['y']:+.3f} m (lost after it: "
              f"{bool(act.get('lost_after'))}).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
