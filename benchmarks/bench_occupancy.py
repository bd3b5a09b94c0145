"""compute_occupancy timing on one core: ms per call at the policies' coarse settings and the dataset's.

    python benchmarks/bench_occupancy.py [--scenes 30]
"""

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.occupancy import compute_occupancy  # noqa: E402
from slax_drake.scene import sample_scene  # noqa: E402

SETTINGS = [  # (label, grid step, camera resolution, surface spacing)
    ("coarse: grid 0.01, 160x120, spacing 0.005 (default)", 0.01, (160, 120), None),
    ("coarse: grid 0.01, 160x120, spacing 0.01", 0.01, (160, 120), 0.01),
    ("dataset: grid 0.005, 256x192, spacing 0.005", 0.005, (256, 192), 0.005),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/sim_shelf.yaml")
    parser.add_argument("--scenes", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    except (AttributeError, OSError):
        pass
    scenario = load_scenario(args.config)
    print(f"{'N':>3}  {'setting':<52} {'ms/call (median of repeats)':>28} {'hidden K (mean)':>16}")
    for n in (4, 8, 12):
        scenes = [sample_scene(scenario, n, 1000 + s) for s in range(args.scenes)]
        for label, step, res, spacing in SETTINGS:
            camera = scenes[0].camera.with_resolution(*res)
            compute_occupancy(scenes[0], (0.06, 0.06, 0.06), step, camera, spacing)  # warm caches
            times, ks = [], []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                for scene in scenes:
                    ks.append(compute_occupancy(scene, (0.06, 0.06, 0.06), step, camera, spacing).num_hidden)
                times.append((time.perf_counter() - t0) / len(scenes))
            print(f"{n:>3}  {label:<52} {1000 * statistics.median(times):>28.2f} {statistics.mean(ks):>16.0f}")


if __name__ == "__main__":
    main()
