"""When each object of a Drake trial moved, and during which action and waypoint: the trial's recorded object poses
read against its motions. Prints Markdown.

    python research/object_motion.py TRIAL_FOLDER [--object NAME] [--step 0.002]

TRIAL_FOLDER is a ``slax-drake trial --out`` folder (trial.json and ``object_poses.npz``: every object's pose in the
shelf frame S every 0.1 s of simulated time). A *movement* is a run of samples in which the object's centre moved more
than ``--step`` (m) from one sample to the next, runs less than 0.3 s apart joined; per movement: its time span (s),
how far the centre went (m), its height before and after (z of the centre, m), its tilt from upright after (deg), and
the action that was running when it began (0-based, as the trial's steps) with the last waypoint of that action's
motion it had passed. Read with the trial's step images: an object that moved during another object's action was
taken along by it (collateral), one that ends with its centre below the support surface went through the board.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

JOIN_GAP = 3  # samples (0.3 s): movements closer than this are one


def tilt_deg(quaternion) -> float:
    """The angle (deg) between a body's z axis and the vertical, from its orientation (w, x, y, z)."""
    w, x, y, z = (float(v) for v in quaternion)
    zz = 1.0 - 2.0 * (x * x + y * y)  # the z component of the body's z axis
    return math.degrees(math.acos(max(-1.0, min(1.0, zz))))


def movements(times, positions, step: float) -> list[tuple[int, int]]:
    """(first, last) sample indices of each movement of one object (see the module docstring): the object moved more
    than ``step`` between samples first .. last + 1."""
    moves = np.flatnonzero(np.linalg.norm(np.diff(np.asarray(positions, float), axis=0), axis=1) > step)
    runs = []
    for k in moves:
        if runs and k <= runs[-1][1] + JOIN_GAP:
            runs[-1][1] = int(k)
        else:
            runs.append([int(k), int(k)])
    return [(a, b) for a, b in runs]


def during(t: float, starts: list[tuple[float, list]]) -> str:
    """The action running at time ``t`` (s) and the last waypoint it had passed, from (start time, waypoint times)."""
    k = max((i for i, (t0, _) in enumerate(starts) if t >= t0), default=None)
    if k is None:
        return "before the first action"
    t0, waypoints = starts[k]
    passed = [label for label, tw in waypoints if t - t0 >= tw]
    return f"action {k}, " + (f"after {passed[-1]}" if passed else "before its first waypoint") + f" (+{t - t0:.1f} s)"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trial", type=Path, help="a trial folder (slax-drake trial --out)")
    parser.add_argument("--object", help="one object's movements only (default: every object's)")
    parser.add_argument("--step", type=float, default=0.002, help="m between samples that counts as moving")
    args = parser.parse_args(argv)
    if not args.step > 0:
        print("error: --step takes a positive length in metres", file=sys.stderr)
        return 2
    try:
        record = json.loads((args.trial / "trial.json").read_text())
        with np.load(args.trial / "object_poses.npz") as poses:
            times, samples, names = poses["times"], poses["poses"], [str(n) for n in poses["names"]]
        starts = [(float(s["time"]), (a.get("motion") or {}).get("waypoint_times", []))
                  for s, a in zip((s for s in record["steps_log"] if s.get("action")), record["actions"])]
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"error: {args.trial}: no trial folder with its records and object poses ({type(e).__name__}: {e})",
              file=sys.stderr)
        return 2
    if args.object is not None and args.object not in names:
        print(f"error: --object {args.object}: not an object of the trial ({', '.join(names)})", file=sys.stderr)
        return 2
    print(f"Movements of the objects of `{args.trial}` (more than {args.step} m between 0.1 s samples). Made by "
          f"`python research/object_motion.py {args.trial}" + (f" --object {args.object}" if args.object else "")
          + "`.\n")
    print("| object | from (s) | to (s) | moved (m) | z before, after (m) | tilt after (deg) | during |")
    print("|---|---|---|---|---|---|---|")
    for i, name in enumerate(names):
        if args.object is not None and name != args.object:
            continue
        p = samples[:, i, :3]
        for a, b in movements(times, p, args.step):
            end = b + 1
            print(f"| {name} | {times[a]:.1f} | {times[end]:.1f} | {np.linalg.norm(p[end] - p[a]):.3f} | "
                  f"{p[a, 2]:.3f}, {p[end, 2]:.3f} | {tilt_deg(samples[end, i, 3:]):.0f} | "
                  f"{during(float(times[a]), starts)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
