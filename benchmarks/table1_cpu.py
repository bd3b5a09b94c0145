"""Prints the CPU seconds of Table I trials per policy (this process's CPU time, so that other work on a shared
machine does not inflate it; the trial files' ``trial_seconds`` are wall-clock seconds). Each trial is run exactly
as ``slax-drake benchmark`` runs it (scene sampling, policy construction and the rollout; the oracles with their
per-decision CPU limit), with nothing written. Run it with PYTHONPATH set to the checkout to measure, on one core:

    OMP_NUM_THREADS=1 taskset -c 0 python benchmarks/table1_cpu.py [--profile paper|station] \\
        [--policies dar,oracle-p+s] [--scenes-per-density 4] [--seed 0] [--observation camera] [--json OUT.json]

``--observation camera``: the non-oracle policies see rendered frames with the render's labels (the benchmark's
camera mode, no sensor noise); default privileged.

``--json`` also writes every trial's CPU seconds ({"<policy>/<density>_<index>": seconds}), so two checkouts can
be compared trial by trial.
"""

import argparse
import json
import os
import sys
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.evaluation.table1 import CameraMode, run_benchmark_trial, scene_seed  # noqa: E402
from slax_drake.errors import UserError  # noqa: E402
from slax_drake.policies.registry import POLICY_NAMES  # noqa: E402
from slax_drake.shelf.tool import scenario_profile
from slax_drake.shelf.rules import PROFILES  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    ap.add_argument("--profile", default=None, help="the action model's profile (default: the scenario's)")
    ap.add_argument("--policies", default="dar,der-3,bluction-dar,bluction-la2,slax-hindsight,oracle-p,oracle-p+s")
    ap.add_argument("--scenes-per-density", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None, help="write each trial's CPU seconds here")
    ap.add_argument("--observation", choices=("privileged", "camera"), default="privileged",
                    help="camera: rendered frames with the render's labels for the non-oracle policies")
    args = ap.parse_args(argv)
    unknown = [p for p in args.policies.split(",") if p not in POLICY_NAMES]
    problem = (f"unknown policies {unknown} (known: {', '.join(POLICY_NAMES)})" if unknown else
               f"unknown profile {args.profile!r} (known: {', '.join(PROFILES)})"
               if args.profile is not None and args.profile not in PROFILES else
               "--scenes-per-density must be at least 1" if args.scenes_per_density < 1 else None)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    try:
        scenario = load_scenario(args.config)
        profile = scenario_profile(scenario, args.profile)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    densities = list(scenario.protocol.densities)
    import slax_drake

    camera = CameraMode() if args.observation == "camera" else None
    print(f"Table I trials' CPU seconds (process time), profile {profile}, {args.observation} observation, "
          f"{args.scenes_per_density} scenes per density {densities}, seed {args.seed}, "
          f"package {os.path.dirname(slax_drake.__file__)}")
    print("| policy | trials | CPU s, sum | CPU s, max trial |")
    print("|---|---|---|---|")
    per_trial, total = {}, 0.0
    for policy in args.policies.split(","):
        seconds = []
        for density in densities:
            for index in range(args.scenes_per_density):
                job = (scenario, policy, density, index, scene_seed(args.seed, density, index), "ground-truth", {},
                       camera, profile, None)
                t0 = time.process_time()
                run_benchmark_trial(job)
                seconds.append(time.process_time() - t0)
                per_trial[f"{policy}/{density:02d}_{index:04d}"] = round(seconds[-1], 3)
        total += sum(seconds)
        print(f"| {policy} | {len(seconds)} | {sum(seconds):.1f} | {max(seconds):.1f} |", flush=True)
    print(f"| all | {len(per_trial)} | {total:.1f} | |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(per_trial, f, indent=1, sort_keys=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
