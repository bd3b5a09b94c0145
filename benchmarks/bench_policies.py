"""Prints (1) how the policies' coarse ground-truth 1D support (1 cm lattice, 1 cm surface samples, 160 px)
agrees with the fine one (5 mm, 5 mm, 640 px), as the fraction of image width, and (2) the mean decision
time per step of each policy on one core (one process, torch and BLAS limited to one thread), over a few
seeded scenes of each density.

    python benchmarks/bench_policies.py [--scenes 2] [--densities 4,6,8,10] [--policies dar,bluction-la2]
"""

import argparse
import os
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.occupancy import compute_occupancy
from slax_drake.shelf.distribution import GroundTruthDistribution, support
from slax_drake.policies.registry import POLICY_NAMES, make_policy
from slax_drake.shelf.simulator import run_trial
from slax_drake.scene import sample_scene


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, default=2, help="scenes per density")
    ap.add_argument("--densities", default="4,6,8,10")
    ap.add_argument("--policies", default=",".join(POLICY_NAMES))
    ap.add_argument("--skip-support", action="store_true", help="skip the coarse-vs-fine support comparison")
    args = ap.parse_args()
    densities = [int(v) for v in args.densities.split(",")]
    sc = load_scenario("sim_configs/table1.yaml")
    size = tuple(sc.target.sizes[0])
    diffs = []
    for seed in range(0 if args.skip_support else args.scenes * 4):
        scene = sample_scene(sc, [4, 6, 8, 10][seed % 4], seed, target_size=size)
        fine = compute_occupancy(scene, size, 0.005).p1d
        coarse = GroundTruthDistribution(size).distribution(scene)
        diffs.append(abs(support(fine) / len(fine) - support(coarse) / len(coarse)))
    if diffs:
        print(f"support as a fraction of image width, |coarse - fine| over {len(diffs)} scenes: "
              f"mean {np.mean(diffs):.3f}, max {np.max(diffs):.3f}")
    print(f"mean decision time per step, one core, {args.scenes} scenes each of {densities} objects, H = 2n")
    for name in args.policies.split(","):
        times = []
        for density in densities:
            for seed in range(args.scenes):
                scene = sample_scene(sc, density, 100 + seed, target_size=size)
                r = run_trial(scene, make_policy(name, sc, horizon=2 * density), 2 * density)
                times += r.decision_seconds
        print(f"{name:>18}: {np.mean(times):.3f} s (max {np.max(times):.3f} s) over {len(times)} steps")


if __name__ == "__main__":
    t = time.time()
    main()
    print(f"total {time.time() - t:.1f} s")
