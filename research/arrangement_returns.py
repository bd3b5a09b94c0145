"""The Drake trials of a physics benchmark whose true shelf came back to an arrangement it held before: a cycle.
Prints Markdown.

    python research/arrangement_returns.py PHYSICS_FOLDER [--policy slax-belief] [--tolerance 0.01]
        [--away 0.02]

PHYSICS_FOLDER is a physics benchmark's result folder with its trial files (``physics_trials/POLICY/*.json``). The
true arrangement at each decision is the trial's initial objects (``initial_objects``) with each executed action's
true object (``true_object``) at the pose Drake left it (``outcome``, planar x, y, yaw in the shelf frame S); an
object pushed along by an action on another is not followed. After action k the arrangement *returns* to the one
held before action j (j < k) when every object stands within ``--tolerance`` (m; and 0.05 rad for its yaw, a box
turned by pi the same) of its pose then, and some object stood more than ``--away`` (m) from that pose in between
(an action that moved nothing, or a put-back, is not a return). The issue's "no cycle" is judged on these counts;
the policy's own correction (no return to an observed arrangement) judges estimated poses (``TrialMemory``).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import analyse_trial_records

YAW_TOLERANCE = 0.05  # rad, the trial memory's


def yaw_difference(a: float, b: float) -> float:
    """|a - b| modulo pi (rad): a box turned by pi stands the same; cylinders' yaws are 0."""
    d = (a - b) % math.pi
    return min(d, math.pi - d)


def arrangements(drake: dict) -> list[dict]:
    """The true arrangement before each action and after the last: {object: (x, y, yaw)} (see the docstring)."""
    state = {name: (p["x"], p["y"], p["yaw"]) for name, p in drake["initial_objects"].items()}
    out = [dict(state)]
    for action in drake["actions"]:
        name, pose = action.get("true_object"), action.get("outcome")
        if name is not None and pose is not None:
            state[name] = (pose["x"], pose["y"], pose["yaw"])
        out.append(dict(state))
    return out


def returns(drake: dict, tolerance: float = 0.01, away: float = 0.02) -> list[tuple[int, int]]:
    """(k, j) for each action k (1-based) after which the arrangement returns to the one held before action j + 1
    (j: the index of that arrangement, 0 the initial one), the earliest such j."""
    held = arrangements(drake)
    found = []
    for k in range(1, len(held)):
        now = held[k]
        for j in range(k - 1):
            then = held[j]
            same = all(math.hypot(now[n][0] - then[n][0], now[n][1] - then[n][1]) <= tolerance
                       and yaw_difference(now[n][2], then[n][2]) <= YAW_TOLERANCE for n in then)
            if same and max(math.hypot(held[i][n][0] - then[n][0], held[i][n][1] - then[n][1])
                            for i in range(j + 1, k) for n in then) > away:
                found.append((k, j))
                break
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", type=Path, help="a physics benchmark's result folder (with its trial files)")
    parser.add_argument("--policy", default="slax-belief")
    parser.add_argument("--tolerance", type=float, default=0.01, help="m (default: 0.01, the trial memory's)")
    parser.add_argument("--away", type=float, default=0.02, help="m (default: 0.02)")
    args = parser.parse_args(argv)
    if not (args.tolerance > 0 and args.away > 0):
        print("error: --tolerance and --away take positive lengths in metres", file=sys.stderr)
        return 2
    try:
        records, found = analyse_trial_records(
            args.physics, args.policy, lambda record: returns(record["drake"], args.tolerance, args.away),
            kind="physics_trials")
    except UserError as e:
        print(f"error: {args.physics}: {e}", file=sys.stderr)
        return 2
    cycled = {key: hits for key, hits in found.items() if hits}
    print(f"{args.policy}, {len(records)} Drake trials of `{args.physics}`: {len(cycled)} returned to an arrangement "
          f"held before (within {args.tolerance} m, after an object stood more than {args.away} m away). Made by "
          f"`python research/arrangement_returns.py {args.physics} --policy {args.policy}`.\n")
    if cycled:
        print("| trial | ending | actions | returns: after action k, to the arrangement before action j + 1 (k, j) |")
        print("|---|---|---|---|")
        for key, hits in cycled.items():
            drake = records[key]["drake"]
            print(f"| {key} | {drake['result']} | {len(drake['actions'])} | "
                  f"{', '.join(f'({k}, {j})' for k, j in hits)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
