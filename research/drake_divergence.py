"""Where each Drake trial of a physics benchmark leaves the path of the shelf-simulator trial beside it, and why.
Prints Markdown.

    python research/drake_divergence.py PHYSICS_FOLDER [--policy slax-belief]

PHYSICS_FOLDER is a physics benchmark's result folder with its trial files (``physics_trials/POLICY/*.json``).
Both simulators start from the same scene with the same policy; the shelf simulator's actions name true objects
("push object_2 d=-0.085") and each Drake action records the true object it moved (``true_object``). The two paths
agree while each step moves the same object by the same kind of action, the displacement within 1 cm along x and
the suction's placement depth within 3 cm. The first step where they do not is the divergence, and its cause is
read from the Drake record at that step:

- "planner refused": the motion planner rejected one or more candidates before the executed action (the policy
  decided again without them; the shelf simulator has no motion planner), with the refusals' kinds and waypoints
  where the run recorded them (``rejected``, since the physics records keep them);
- "last action off prediction (KIND)": the Drake action before it ended off the action model's prediction (slid,
  turned, put back, ...), so the two simulators decide on different shelves;
- "first decision differs": step 0 with no rejection: the two frames of the same scene led to another choice;
- "same predicted state, other decision": every action so far matched its prediction, yet the policy chose
  otherwise (the estimated poses, within the match tolerance, or the tracker's hypotheses differ);
- "Drake stopped" / "shelf stopped": one path is a prefix of the other (its ending: revealed, no feasible action,
  ...); "same actions": no divergence.

Counted per (shelf outcome, Drake outcome with nothing lost); the scenes the shelf simulator revealed and Drake did
not are listed with their cause; and, where the records keep them, the motion planner's refusals of the whole run
by kind and waypoint.
"""

from __future__ import annotations

import argparse
import collections
import enum
import re
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.physics import clean_success
from slax_drake.evaluation.trial_records import analyse_trial_records

DX_TOLERANCE_M = 0.011  # 1 cm along x, and the rounding of the shelf record's 3 decimals
DZ_TOLERANCE_M = 0.03  # the placement depth: Drake plans it on the estimated pose
_SHELF_ACTION = re.compile(r"(push|suction) (\S+) (?:d|dx)=([+-]?[\d.]+)(?: dz=([+-]?[\d.]+))?")


def shelf_step(described: str) -> tuple:
    """(kind, true object, displacement along x (m), placement depth move (m; 0 for a push)) of a shelf-simulator
    action as its record describes it ("suction object_4 dx=+0.400 dz=-0.206 yaw=+4deg")."""
    m = _SHELF_ACTION.match(described)
    if m is None:
        raise UserError(f"not a described action: {described!r}")
    return m.group(1), m.group(2), float(m.group(3)), float(m.group(4) or 0.0)


def drake_step(action: dict) -> tuple:
    """The same four of a Drake action record (its ``true_object``)."""
    if action["type"] == "push":
        return "push", action.get("true_object"), float(action["d"]), 0.0
    return "suction", action.get("true_object"), float(action["dx"]), float(action["dz"])


def same_step(a: tuple, b: tuple) -> bool:
    return (a[0] == b[0] and a[1] == b[1] and abs(a[2] - b[2]) <= DX_TOLERANCE_M
            and abs(a[3] - b[3]) <= DZ_TOLERANCE_M)


class Cause(enum.StrEnum):
    """Why the Drake trial leaves the shelf trial's path at the divergence (module docstring)."""

    SAME = "same actions"
    DRAKE_STOPPED = "Drake stopped"
    SHELF_STOPPED = "shelf stopped"
    PLANNER_REFUSED = "planner refused"
    OFF_PREDICTION = "last action off prediction"
    FIRST_DECISION = "first decision differs"
    OTHER_DECISION = "same predicted state, other decision"


# the causes counted with their detail in the table (the others by kind; the scene list keeps the detail)
COUNTED_WITH_DETAIL = (Cause.OFF_PREDICTION,)


def find_divergence(record: dict) -> tuple[int, Cause, str]:
    """(the first step where the Drake trial of ``record`` leaves the shelf trial's path, its cause, the cause's
    detail or ""): the step is the length of the common path when one path is a prefix of the other; the detail
    is the ending of the path that stopped, the refusals' kinds and waypoints, or the last action's mismatch."""
    shelf = [shelf_step(s) for s in record["shelf"]["actions"]]
    drake = record["drake"]["actions"]
    common = 0
    while common < min(len(shelf), len(drake)) and same_step(shelf[common], drake_step(drake[common])):
        common += 1
    if common == len(shelf) == len(drake):
        return common, Cause.SAME, ""
    if common == len(drake):
        return common, Cause.DRAKE_STOPPED, record["drake"]["result"].split(":")[0]
    if common == len(shelf):
        return common, Cause.SHELF_STOPPED, record["shelf"]["reason"]
    if drake[common].get("rejected_before", 0):
        kinds = sorted({f"{r.get('kind')} at {r.get('waypoint')}" for r in drake[common].get("rejected", [])})
        return common, Cause.PLANNER_REFUSED, "; ".join(kinds)
    if common and not drake[common - 1].get("matched"):
        return common, Cause.OFF_PREDICTION, str(drake[common - 1].get("mismatch"))
    return common, Cause.FIRST_DECISION if common == 0 else Cause.OTHER_DECISION, ""


def described(cause: Cause, detail: str) -> str:
    return f"{cause} ({detail})" if detail else str(cause)


def divergence(record: dict) -> tuple[int, str]:
    """:func:`find_divergence` with its cause described ("Drake stopped (no feasible action)")."""
    step, cause, detail = find_divergence(record)
    return step, described(cause, detail)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", type=Path, help="a physics benchmark's result folder (with its trial files)")
    parser.add_argument("--policy", default="slax-belief")
    args = parser.parse_args(argv)
    try:
        records, found = analyse_trial_records(args.physics, args.policy, find_divergence, kind="physics_trials")
    except UserError as e:
        print(f"error: {args.physics}: {e}", file=sys.stderr)
        return 2
    print(f"{args.policy}, {len(records)} scenes of `{args.physics}`: where the Drake trial leaves the shelf "
          f"simulator's path, and why. Made by `python research/drake_divergence.py {args.physics} --policy "
          f"{args.policy}`.\n")
    counts = collections.Counter()
    for key, record in records.items():
        _, kind, detail = found[key]
        cause = described(kind, detail) if kind in COUNTED_WITH_DETAIL else str(kind)
        counts[(bool(record["shelf"]["success"]), clean_success(record["drake"]), cause)] += 1
    print("| shelf simulator | Drake (nothing lost) | cause at the divergence | scenes |")
    print("|---|---|---|---|")
    for (shelf, drake, cause), n in sorted(counts.items(), key=lambda kv: (not kv[0][0], kv[0][1], -kv[1])):
        print(f"| {'revealed' if shelf else 'not'} | {'revealed' if drake else 'not'} | {cause} | {n} |")
    lost = [(key, found[key]) for key, r in records.items() if r["shelf"]["success"] and not clean_success(r["drake"])]
    print(f"\nRevealed by the shelf simulator, not by Drake with nothing lost: {len(lost)}.\n")
    for key, (step, cause, detail) in lost:
        print(f"- {key}: step {step}, {described(cause, detail)}")
    refusals = collections.Counter((r.get("kind"), r.get("waypoint")) for record in records.values()
                                   for a in record["drake"]["actions"] for r in a.get("rejected", []))
    if refusals:  # runs since the records keep them
        print(f"\nThe motion planner's refusals before the executed actions, by kind and waypoint "
              f"({sum(refusals.values())} in all):\n")
        print("| kind | waypoint | refusals |")
        print("|---|---|---|")
        for (kind, waypoint), n in refusals.most_common():
            print(f"| {kind} | {waypoint} | {n} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
