"""Prints the decision time per step of each policy (median, 90th percentile, max; seconds of CPU time of this
process, so that other work on the machine does not inflate it) over the first Table I scenes of each density.
Run it on one core, so that no library spreads a decision over several:

    taskset -c 0 python benchmarks/bench_decision_time.py [--scenes 2] [--densities 4,6,8,10] \\
        [--policies dar,slax-hindsight] [--profile paper|station]

The trials are the Table I protocol's (sim_configs/table1.yaml, protocol seed 0, H = 2n, privileged
observation, ground-truth distributions); the oracles' time per decision includes their search.
"""

import argparse
import os
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import scene_seed
from slax_drake.policies.registry import POLICY_NAMES, make_policy
from slax_drake.shelf.simulator import execute, observation_for
from slax_drake.scene import sample_scene
from slax_drake.scene.sampling import target_visible_fraction


def decision_times(policy, scene, horizon: int, threshold: float) -> list[float]:
    """CPU seconds of each ``decide`` in one rollout (the simulator's own work is not timed)."""
    policy.reset(scene)
    times = []
    for _ in range(horizon):
        if target_visible_fraction(scene) >= threshold:
            break
        obs = observation_for(policy, scene)
        t0 = time.process_time()
        action = policy.decide(obs).best
        times.append(time.process_time() - t0)
        if action is None:
            break
        scene, _ = execute(scene, action, policy.action_model)
    return times


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, default=2, help="scenes per density (the first of the Table I seeds)")
    ap.add_argument("--densities", default="4,6,8,10")
    ap.add_argument("--policies", default=",".join(POLICY_NAMES))
    ap.add_argument("--profile", default=None, help="the action model's profile (default: the scenario's, paper)")
    args = ap.parse_args()
    sc = load_scenario("sim_configs/table1.yaml")
    size = tuple(sc.target.sizes[0])
    densities = [int(v) for v in args.densities.split(",")]
    affinity = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else "?"
    print(f"decision time per step (CPU s), {args.scenes} scene(s) per density {densities}, profile "
          f"{args.profile or sc.profile}, CPUs allowed: {affinity}")
    print("| policy | decisions | median | p90 | max |")
    print("|---|---|---|---|---|")
    for name in args.policies.split(","):
        times = []
        for d in densities:
            for i in range(args.scenes):
                scene = sample_scene(sc, d, scene_seed(0, d, i), target_size=size)
                policy = make_policy(name, sc, horizon=2 * d, profile=args.profile)
                times += decision_times(policy, scene, 2 * d, sc.target.visibility_threshold)
        t = np.array(times) if times else np.zeros(1)
        print(f"| {name} | {len(times)} | {np.median(t):.3f} | {np.percentile(t, 90):.3f} | {t.max():.3f} |",
              flush=True)


if __name__ == "__main__":
    main()
