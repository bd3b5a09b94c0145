"""Reruns chosen trials of a Table I benchmark folder under another oracle time limit and prints, per trial, the
folder's outcome beside the rerun's. It answers "were these failures for lack of search time?" without rerunning
the whole protocol: the trials are the benchmark's own (`slax-drake benchmark`: the same scene seed per protocol
seed, density and index; the folder's profile, rules, perception and observation mode from its settings.json).

    python benchmarks/rerun_trials.py results/table1_paper100 --policy oracle-p+s --failed --oracle-seconds 120
        [--trials 10:1,8:18] [--config sim_configs/table1.yaml] [--json OUT.json]

``--failed``: every failed trial of the policy in the folder; ``--trials``: density:index pairs (or both).
``--oracle-seconds``: the CPU-time limit per oracle decision of the rerun (the folder's is in its settings).
Exit code 2 for a folder without settings or trials, or a policy the folder does not hold.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import UserError
from slax_drake.evaluation.table1 import run_benchmark_trial, scene_seed
from slax_drake.evaluation.trial_records import read_trial_records
from slax_drake.io import write_text_atomic


def chosen_trials(trials: dict, failed: bool, listed: str | None) -> list[tuple[int, int]]:
    """(density, index) of the trials to rerun (``trials``: the folder's records of the policy), in density then
    index order."""
    chosen = set()
    if listed:
        for part in listed.split(","):
            density, _, index = part.partition(":")
            chosen.add((int(density), int(index)))
    if failed:
        for trial in trials.values():
            if not trial["success"]:
                chosen.add((int(trial["density"]), int(trial["index"])))
    return sorted(chosen)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--policy", required=True)
    ap.add_argument("--failed", action="store_true", help="rerun every failed trial of the policy")
    ap.add_argument("--trials", help="density:index pairs, comma separated")
    ap.add_argument("--oracle-seconds", type=float, default=None, help="CPU s per oracle decision (default: the oracle's)")
    ap.add_argument("--config", default=None, help="the scenario (default: the folder's settings)")
    ap.add_argument("--json", type=Path, help="write the rerun trials here (atomically)")
    args = ap.parse_args(argv)
    settings_path = args.folder / "settings.json"
    if not settings_path.is_file() or not (args.folder / "trials" / args.policy).is_dir():
        print(f"error: {args.folder} has no settings.json or no trials of {args.policy}", file=sys.stderr)
        return 2
    settings = json.loads(settings_path.read_text())
    if settings.get("observation", "privileged") != "privileged" and not args.policy.startswith("oracle"):
        print("error: only privileged folders (or oracles, which read the true scene) are supported", file=sys.stderr)
        return 2
    try:
        folder_trials = read_trial_records(args.folder, args.policy)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    scenario = load_scenario(args.config or settings["config"])
    try:
        trials = chosen_trials(folder_trials, args.failed, args.trials)
    except ValueError:
        print(f"error: --trials {args.trials!r}: density:index pairs, comma separated (e.g. 4:0,10:3)", file=sys.stderr)
        return 2
    if not trials:
        print("error: no trial chosen (use --failed or --trials)", file=sys.stderr)
        return 2
    missing = [f"{density}:{index}" for density, index in trials if f"{density:02d}_{index:04d}" not in folder_trials]
    if missing:
        print(f"error: {args.folder} holds no trial of {args.policy} for {', '.join(missing)}", file=sys.stderr)
        return 2
    profile = settings.get("profile", "station")
    rules = settings.get("tool_rules") or {}
    print(f"{args.policy} in {args.folder} (profile {profile}), rerun with oracle seconds {args.oracle_seconds}")
    print("| trial | folder: success, steps, reason, searches | rerun: success, steps, reason, searches | rerun wall s |")
    print("|---|---|---|---|")
    reruns, revealed = [], 0
    for density, index in trials:
        before = folder_trials[f"{density:02d}_{index:04d}"]
        job = (scenario, args.policy, density, index, scene_seed(settings["seed"], density, index),
               settings.get("perception", "ground-truth"), rules, None, profile, args.oracle_seconds)
        t0 = time.perf_counter()
        after = run_benchmark_trial(job)
        revealed += bool(after["success"])
        reruns.append(after)
        print(f"| {density:02d}_{index:04d} | {before['success']}, {before['steps']}, {before['reason']}, "
              f"{before.get('oracle_status', '-')} | {after['success']}, {after['steps']}, {after['reason']}, "
              f"{after.get('oracle_status', '-')} | {time.perf_counter() - t0:.0f} |", flush=True)
    print(f"\nrevealed {revealed} of {len(trials)} rerun trials")
    if args.json:
        write_text_atomic(args.json, json.dumps({"oracle_seconds": args.oracle_seconds, "trials": reruns}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
