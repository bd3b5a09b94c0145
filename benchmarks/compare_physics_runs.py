"""Compares two physics-benchmark runs (``slax-drake benchmark --physics ... --out DIR``) on the scenes both hold:
per density, Drake's trial endings, its success (and with nothing lost), the actions matching the first-order
prediction, the candidate motions the planner refused before each executed action, and the commanded moves back
(undos against the object's previous move, and against its last move along each axis). Made for the question
"what did a code change do to 'no feasible motion'?" on the same scenes (never typed by hand).

    python benchmarks/compare_physics_runs.py results/phys_cam results/phys_s8 [--policy bluction-dar]
        [--new-policy slax-belief-stuck-undo] [--first N]

OLD and NEW are result folders with ``physics_trials/POLICY/DD_NNNN.json`` (their trial files) or, where those
were not kept (the folders under ``docs/results``), their ``physics.json`` (its per-trial rows: endings and
successes, no per-action columns); the scenes are matched by density and index, and a scene whose protocol seed
differs between the runs stops the comparison. ``--new-policy``: NEW's policy when it is another (a variant against
the default). The scenes whose outcome (revealed with nothing lost) differs are listed at the end.
"""

import argparse
import collections
import json
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.physics import clean_success, commanded_undoes
from slax_drake.evaluation.trial_records import read_trial_records

DENSITIES = ("04", "06", "08", "10")


def fail(message: str) -> None:
    """A user error: one line on stderr, exit code 2."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


def load(folder: Path, policy: str) -> dict:
    """{"DD_NNNN": trial record} of ``policy`` in ``folder``: its trial files, else the rows of its physics.json in
    their shape (``drake["actions"]`` None: the rows keep no actions)."""
    trials = read_trial_records(folder, policy, kind="physics_trials", missing_ok=True)
    if trials:
        return trials
    summary_file = folder / "physics.json"
    if not summary_file.is_file():
        fail(f"{folder} holds no trial files of {policy} (physics_trials/{policy}/*.json) and no physics.json")
    try:
        rows = json.loads(summary_file.read_bytes())["trials"]
        out = {f"{int(r['density']):02d}_{int(r['index']):04d}": {
            "seed": r["seed"], "shelf": {"success": bool(r["shelf_success"])},
            "drake": {"result": r["drake_result"], "success": bool(r["drake_success"]), "toppled": r["toppled"],
                      "dropped": r["dropped"], "actions": None}} for r in rows if r.get("policy") == policy}
    except (ValueError, KeyError, TypeError) as e:
        fail(f"{summary_file}: not a physics benchmark summary ({type(e).__name__}: {e})")
    if not out:
        fail(f"{summary_file} holds no trials of {policy}")
    return out



def summary(trials: list[dict]) -> dict:
    endings = collections.Counter(t["drake"]["result"].split(":")[0] for t in trials)  # "simulation diverged: ..."
    kept = all(t["drake"]["actions"] is not None for t in trials)  # physics.json rows keep no actions
    actions = [a for t in trials for a in t["drake"]["actions"]] if kept else None
    lost = sum(bool(t["drake"]["toppled"] or t["drake"]["dropped"]) for t in trials)
    return {
        "scenes": len(trials),
        "success": sum(t["drake"]["success"] for t in trials),
        "nothing_lost": sum(clean_success(t["drake"]) for t in trials),
        "lost_any": lost,
        "matched": sum(bool(a.get("matched")) for a in actions) if kept else None,
        "actions": len(actions) if kept else None,
        "refused_before": sum(a.get("rejected_before", 0) for a in actions) if kept else "-",
        # commanded moves back against the object's previous move / its last move along each axis
        "undoes": (f"{sum(commanded_undoes(t['drake']['actions']) for t in trials)} / "
                   f"{sum(commanded_undoes(t['drake']['actions'], by_axis=True) for t in trials)}") if kept else "-",
        "endings": endings,
        "shelf_success": sum(t["shelf"]["success"] for t in trials),
    }


def row(label: str, density: str, s: dict) -> str:
    endings = ", ".join(f"{k} {v}" for k, v in sorted(s["endings"].items()))
    match = (f"{100 * s['matched'] / s['actions']:.0f} % ({s['matched']}/{s['actions']})" if s["actions"]
             else "-")
    return (f"| {label} | {density} | {s['scenes']} | {s['shelf_success']} | {s['success']} | {s['nothing_lost']} | "
            f"{match} | {s['refused_before']} | {s['undoes']} | {endings} |")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--policy", default="bluction-dar")
    parser.add_argument("--new-policy", default=None, help="NEW's policy, when it is not --policy")
    parser.add_argument("--first", type=int, default=None, metavar="N",
                        help="only the first N scenes per density (e.g. those a run still in progress has finished)")
    args = parser.parse_args(argv)
    try:
        new_policy = args.new_policy or args.policy
        old, new = load(args.old, args.policy), load(args.new, new_policy)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    common = sorted(k for k in set(old) & set(new) if args.first is None or int(k.split("_")[1]) < args.first)
    for key in common:
        if old[key]["seed"] != new[key]["seed"]:
            fail(f"scene {key} has seed {old[key]['seed']} in {args.old} and {new[key]['seed']} in {args.new}")
    policies = args.policy if new_policy == args.policy else f"{args.policy} (old) against {new_policy} (new)"
    print(f"{policies}, the {len(common)} scenes both runs hold; counts of scenes (shelf simulator and Drake "
          f"successes), actions matching the prediction, candidate motions the planner refused before "
          f"the executed actions, and Drake's endings. Made by `python benchmarks/compare_physics_runs.py "
          f"{args.old} {args.new} --policy {args.policy}"
          + (f" --new-policy {new_policy}" if new_policy != args.policy else "")
          + (f" --first {args.first}" if args.first is not None else "") + "`.\n")
    print("| run | objects | scenes | shelf sim. successes | Drake successes | nothing lost | actions matching | "
          "motions refused before an action | commanded moves back: against the previous move / by axis | "
          "Drake endings |")
    print("|---" * 10 + "|")
    for density in DENSITIES + ("all",):
        keys = [k for k in common if density == "all" or k.startswith(density + "_")]
        if not keys:
            continue
        for label, run in (("old", old), ("new", new)):
            print(row(f"{label} ({Path(getattr(args, label)).name})", density.lstrip("0"),
                      summary([run[k] for k in keys])))
    won = [k for k in common if clean_success(new[k]["drake"]) and not clean_success(old[k]["drake"])]
    lost = [k for k in common if clean_success(old[k]["drake"]) and not clean_success(new[k]["drake"])]
    print(f"\nRevealed with nothing lost in new, not in old: {len(won)} ({', '.join(won) or 'none'}); in old, not in "
          f"new: {len(lost)} ({', '.join(lost) or 'none'}).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
