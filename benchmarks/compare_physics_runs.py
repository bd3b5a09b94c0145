"""Compares two physics-benchmark runs (``slax-drake benchmark --physics ... --out DIR``) on the scenes both hold:
per density, Drake's trial endings, its success (and with nothing lost), the actions matching the first-order
prediction, and the candidate motions the planner refused before each executed action. Made for the question
"what did a code change do to 'no feasible motion'?" on the same scenes (never typed by hand).

    python benchmarks/compare_physics_runs.py results/phys_cam results/phys_s8 [--policy bluction-dar] [--first N]

OLD and NEW are result folders with ``physics_trials/POLICY/DD_NNNN.json`` (their trial files); the scenes are
matched by density and index, and a scene whose protocol seed differs between the runs stops the comparison.
"""

import argparse
import collections
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import read_trial_records

DENSITIES = ("04", "06", "08", "10")


def fail(message: str) -> None:
    """A user error: one line on stderr, exit code 2."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


def load(folder: Path, policy: str) -> dict:
    trials = read_trial_records(folder, policy, kind="physics_trials", missing_ok=True)
    if not trials:
        fail(f"{folder} holds no trial files of {policy} (physics_trials/{policy}/*.json)")
    return trials


def summary(trials: list[dict]) -> dict:
    endings = collections.Counter(t["drake"]["result"] for t in trials)
    actions = [a for t in trials for a in t["drake"]["actions"]]
    lost = sum(bool(t["drake"]["toppled"] or t["drake"]["dropped"]) for t in trials)
    return {
        "scenes": len(trials),
        "success": sum(t["drake"]["success"] for t in trials),
        "nothing_lost": sum(t["drake"]["success"] and not (t["drake"]["toppled"] or t["drake"]["dropped"])
                            for t in trials),
        "lost_any": lost,
        "matched": sum(bool(a.get("matched")) for a in actions),
        "actions": len(actions),
        "refused_before": sum(a.get("rejected_before", 0) for a in actions),
        "endings": endings,
        "shelf_success": sum(t["shelf"]["success"] for t in trials),
    }


def row(label: str, density: str, s: dict) -> str:
    endings = ", ".join(f"{k} {v}" for k, v in sorted(s["endings"].items()))
    match = f"{100 * s['matched'] / s['actions']:.0f} % ({s['matched']}/{s['actions']})" if s["actions"] else "-"
    return (f"| {label} | {density} | {s['scenes']} | {s['shelf_success']} | {s['success']} | {s['nothing_lost']} | "
            f"{match} | {s['refused_before']} | {endings} |")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--policy", default="bluction-dar")
    parser.add_argument("--first", type=int, default=None, metavar="N",
                        help="only the first N scenes per density (e.g. those a run still in progress has finished)")
    args = parser.parse_args()
    try:
        old, new = load(args.old, args.policy), load(args.new, args.policy)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    common = sorted(k for k in set(old) & set(new) if args.first is None or int(k.split("_")[1]) < args.first)
    for key in common:
        if old[key]["seed"] != new[key]["seed"]:
            fail(f"scene {key} has seed {old[key]['seed']} in {args.old} and {new[key]['seed']} in {args.new}")
    print(f"{args.policy}, the {len(common)} scenes both runs hold; counts of scenes (shelf simulator and Drake "
          f"successes), actions matching the first-order prediction, candidate motions the planner refused before "
          f"the executed actions, and Drake's endings. Made by `python benchmarks/compare_physics_runs.py "
          f"{args.old} {args.new} --policy {args.policy}"
          + (f" --first {args.first}" if args.first is not None else "") + "`.\n")
    print("| run | objects | scenes | shelf sim. successes | Drake successes | nothing lost | actions matching | "
          "motions refused before an action | Drake endings |")
    print("|---" * 9 + "|")
    for density in DENSITIES + ("all",):
        keys = [k for k in common if density == "all" or k.startswith(density + "_")]
        if not keys:
            continue
        for label, run in (("old", old), ("new", new)):
            print(row(f"{label} ({Path(getattr(args, label)).name})", density.lstrip("0"),
                      summary([run[k] for k in keys])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
