"""compute_occupancy timing on one core: ms per call at the policies' coarse settings and the dataset's, and
ms per dataset sample (the three target ratios of one scene through compute_occupancies, sharing their work).

Wall-clock (time.perf_counter) and CPU (time.process_time) figures, each the median over repeats; the CPU
figure varies less when other processes share the core.

    python benchmarks/bench_occupancy.py [--scenes 30] [--repeats 3]
"""

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.occupancy import compute_occupancy  # noqa: E402
from slax_drake.scene import sample_scene  # noqa: E402

try:
    from slax_drake.occupancy import compute_occupancies  # noqa: E402
except ImportError:  # a checkout from before compute_occupancies (for before/after figures): one call per size

    def compute_occupancies(scene, sizes, grid_step, camera, spacing):
        return [compute_occupancy(scene, s, grid_step, camera, spacing) for s in sizes]


TARGET_SIZES = ((0.06, 0.06, 0.03), (0.06, 0.06, 0.06), (0.06, 0.06, 0.12))
SETTINGS = [  # (label, grid step, camera resolution, surface spacing, sizes per call)
    ("coarse: grid 0.01, 160x120, spacing 0.005 (default)", 0.01, (160, 120), None, 1),
    ("coarse: grid 0.01, 160x120, spacing 0.01", 0.01, (160, 120), 0.01, 1),
    ("dataset: grid 0.005, 256x192, spacing 0.005", 0.005, (256, 192), 0.005, 1),
    ("dataset sample: the 3 ratios in one call", 0.005, (256, 192), 0.005, 3),
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
    print(f"one core; load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"{'N':>3}  {'setting':<52} {'wall ms/call':>13} {'CPU ms/call':>12} {'hidden K (mean)':>16}")
    for n in (4, 8, 12):
        scenes = [sample_scene(scenario, n, 1000 + s) for s in range(args.scenes)]
        for label, step, res, spacing, count in SETTINGS:
            camera = scenes[0].camera.with_resolution(*res)
            sizes = TARGET_SIZES if count == 3 else ((0.06, 0.06, 0.06),)
            compute_occupancies(scenes[0], sizes, step, camera, spacing)  # warm caches
            figures, ks = {}, []
            for name, clock in (("wall", time.perf_counter), ("cpu", time.process_time)):
                times = []
                for _ in range(args.repeats):
                    t0 = clock()
                    for scene in scenes:
                        ks.extend(o.num_hidden for o in compute_occupancies(scene, sizes, step, camera, spacing))
                    times.append((clock() - t0) / len(scenes))
                figures[name] = statistics.median(times)
            print(f"{n:>3}  {label:<52} {1000 * figures['wall']:>13.2f} {1000 * figures['cpu']:>12.2f} "
                  f"{statistics.mean(ks):>16.0f}")
    print(f"load average now {' '.join(f'{v:.2f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
