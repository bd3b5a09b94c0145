"""Prints (1) how the policies' coarse ground-truth 1D support (1 cm lattice, 1 cm surface samples, 160 px)
agrees with the fine one (5 mm, 5 mm, 640 px), as the fraction of image width, and (2) the mean decision
time per step of each policy on one core (one process), over a few seeded scenes.

    python benchmarks/bench_policies.py [--scenes 3] [--density 6]
"""

import argparse
import time

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.occupancy import compute_occupancy
from slax_drake.policies.distribution import GroundTruthDistribution, support
from slax_drake.policies.registry import POLICY_NAMES, make_policy
from slax_drake.policies.simulator import run_trial
from slax_drake.scene import sample_scene


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, default=3)
    ap.add_argument("--density", type=int, default=6)
    args = ap.parse_args()
    sc = load_scenario("sim_configs/table1.yaml")
    size = tuple(sc.target.sizes[0])
    diffs = []
    for seed in range(args.scenes * 4):
        scene = sample_scene(sc, [4, 6, 8, 10][seed % 4], seed, target_size=size)
        fine = compute_occupancy(scene, size, 0.005).p1d
        coarse = GroundTruthDistribution(size).distribution(scene)
        diffs.append(abs(support(fine) / len(fine) - support(coarse) / len(coarse)))
    print(f"support as a fraction of image width, |coarse - fine| over {len(diffs)} scenes: "
          f"mean {np.mean(diffs):.3f}, max {np.max(diffs):.3f}")
    for name in POLICY_NAMES:
        times = []
        for seed in range(args.scenes):
            scene = sample_scene(sc, args.density, 100 + seed, target_size=size)
            r = run_trial(scene, make_policy(name, sc, horizon=2 * args.density), 2 * args.density)
            times += r.decision_seconds
        print(f"{name:>18}: mean decision time per step {np.mean(times):.3f} s over {len(times)} steps")


if __name__ == "__main__":
    t = time.time()
    main()
    print(f"total {time.time() - t:.1f} s")
