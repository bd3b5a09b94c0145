"""Scene sampling throughput on one core: scenes per second for N = 4, 8, 12 (median of repeats).

    python benchmarks/bench_scene_sampling.py [--scenes 100] [--repeats 3]
"""

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.scene import sample_scene  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/sim_shelf.yaml")
    parser.add_argument("--scenes", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core
    except (AttributeError, OSError):
        pass
    scenario = load_scenario(args.config)
    sample_scene(scenario, 4, 0)  # warm caches (meshes, surface points)
    print(f"{'N':>3} {'scenes/s (median)':>18} {'ms/scene':>9}")
    for n in (4, 8, 12):
        rates = []
        for r in range(args.repeats):
            t0 = time.perf_counter()
            for seed in range(args.scenes):
                sample_scene(scenario, n, 10_000 * r + seed)
            rates.append(args.scenes / (time.perf_counter() - t0))
        rate = statistics.median(rates)
        print(f"{n:>3} {rate:>18.1f} {1000 / rate:>9.2f}")


if __name__ == "__main__":
    main()
