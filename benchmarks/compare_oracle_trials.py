"""Compares the oracles' Table I trial files of two runs of the same scenes (e.g. before and after a change to the
search), trial by trial: outcome, steps, cost, how the search ended, and its CPU seconds.

    python benchmarks/compare_oracle_trials.py OLD_FOLDER NEW_FOLDER [--policies oracle-p,oracle-p+s]

Each folder is a ``slax-drake benchmark --out`` folder (its ``trials/<policy>/<density>_<index>.json``). Prints
one line per trial that differs, a count per policy, and exits 1 when a trial proven optimal in OLD has another
outcome or step count in NEW, or when NEW has more trials cut by time than OLD (the bar for a change that should
make the search faster without changing what it proves). A folder without trial files, or a policy with no trial
in both folders, is refused (one line, exit 2): an empty comparison would pass; so is a policy whose trials record
no oracle search (not an oracle).
"""

import argparse
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import read_trial_records


def search_seconds(trial: dict) -> float:
    return sum(s["seconds"] for s in trial.get("oracle_searches", []))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--policies", default="oracle-p,oracle-p+s")
    args = ap.parse_args(argv)
    for folder in (args.old, args.new):
        if not (folder / "trials").is_dir():
            print(f"error: {folder} holds no trial files (not a slax-drake benchmark --out folder)", file=sys.stderr)
            return 2
    try:  # per policy: (policy, old trials, new trials)
        runs = [(policy, read_trial_records(args.old, policy, missing_ok=True),
                 read_trial_records(args.new, policy, missing_ok=True)) for policy in args.policies.split(",")]
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for policy, old, new in runs:
        if not set(old) & set(new):
            print(f"error: no trial of {policy} in both {args.old} and {args.new}", file=sys.stderr)
            return 2
        unsearched = [key for key in sorted(set(old) & set(new)) if "oracle_status" not in old[key]
                      or "oracle_status" not in new[key]]
        if unsearched:
            print(f"error: trial {unsearched[0]} of {policy} records no oracle search (no oracle_status): this "
                  "script compares the oracles' searches; benchmarks/compare_variant_runs.py compares other policies",
                  file=sys.stderr)
            return 2
    failed = False
    print("| policy | trials in both | proven optimal in old | of those changed | cut by time old -> new | "
          "infeasible old -> new | success old -> new | search CPU s old -> new | the same, trials cut in neither |")
    print("|---|---|---|---|---|---|---|---|---|")
    lines = []
    for policy, old, new in runs:
        both = sorted(set(old) & set(new))
        optimal = changed = 0
        for key in both:
            o, n = old[key], new[key]
            same = (o["success"], o["steps"]) == (n["success"], n["steps"])
            if o["oracle_status"] == "optimal":
                optimal += 1
                if not same:
                    changed += 1
            if not same or o["oracle_status"] != n["oracle_status"] or o["cost"] != n["cost"]:
                lines.append(f"{policy} {key}: {o['oracle_status']} success {o['success']} steps {o['steps']} cost "
                             f"{o['cost']} ({search_seconds(o):.1f} s) -> {n['oracle_status']} success "
                             f"{n['success']} steps {n['steps']} cost {n['cost']} ({search_seconds(n):.1f} s)")

        def count(trials, status):
            return sum(trials[k]["oracle_status"] == status for k in both)

        cut_old, cut_new = count(old, "cut by time"), count(new, "cut by time")
        uncut = [k for k in both if "cut by time" not in (old[k]["oracle_status"], new[k]["oracle_status"])]
        print(f"| {policy} | {len(both)} | {optimal} | {changed} | {cut_old} -> {cut_new} | "
              f"{count(old, 'infeasible')} -> {count(new, 'infeasible')} | "
              f"{sum(old[k]['success'] for k in both)} -> {sum(new[k]['success'] for k in both)} | "
              f"{sum(search_seconds(old[k]) for k in both):.1f} -> {sum(search_seconds(new[k]) for k in both):.1f} | "
              f"{sum(search_seconds(old[k]) for k in uncut):.1f} -> {sum(search_seconds(new[k]) for k in uncut):.1f} "
              f"({len(uncut)}) |")
        failed |= changed > 0 or cut_new > cut_old
    print()
    print("\n".join(lines) if lines else "no trial differs")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
