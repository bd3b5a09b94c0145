"""Dataset throughput on one core: scenes/s for a whole sample (scene sampling, Drake render, three occupancy
distributions, scene JSON) at N = 4, 8, 12, and the worker's peak memory.

Each stage runs exactly as ``SampleMaker.make`` runs it. Wall-clock figures are what one pinned core delivers
under the machine's current load; CPU figures (time.process_time, all threads of this process) are what the
work itself costs, and vary less when other processes share the core. Repeats are timed separately and the
median is printed.

    python benchmarks/bench_dataset.py [--scenes 40] [--repeats 3] [--grid-step 0.005] [--resolution 256x192]
"""

import argparse
import os
import resource
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from slax_drake.dataset.generate import DatasetSpec, SampleMaker  # noqa: E402
from slax_drake.dataset.shards import TARGET_SIZES  # noqa: E402

STAGES = ("sample", "render", "occupancy", "json")

try:
    from slax_drake.occupancy import compute_occupancies  # noqa: E402
except ImportError:  # a checkout from before compute_occupancies (for before/after figures): one call per size
    from slax_drake.occupancy import compute_occupancy  # noqa: E402

    def compute_occupancies(scene, sizes, grid_step, camera, spacing, raycaster):
        return [compute_occupancy(scene, s, grid_step, camera, spacing, raycaster) for s in sizes]


def time_scenes(maker: SampleMaker, n: int, count: int, clock) -> dict:
    """Seconds per stage summed over ``count`` scenes of ``n`` objects, measured with ``clock``."""
    from slax_drake.scene import sample_scene, scene_to_json
    from slax_drake.scene.raycast import SceneRaycaster

    spacing = maker.scenario.target.surface_point_spacing
    totals = dict.fromkeys(STAGES, 0.0)
    for i in range(count):
        t0 = clock()
        scene = sample_scene(maker.scenario, n, 77_000 + 100 * n + i, target_size=TARGET_SIZES[i % 3])
        t1 = clock()
        maker.renderer.render(scene)
        t2 = clock()
        compute_occupancies(scene, TARGET_SIZES, maker.spec.grid_step, maker.camera, spacing,
                            SceneRaycaster(scene))
        t3 = clock()
        scene_to_json(scene)
        t4 = clock()
        for stage, dt in zip(STAGES, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            totals[stage] += dt
    return totals


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/sim_shelf.yaml")
    parser.add_argument("--scenes", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--grid-step", type=float, default=0.005)
    parser.add_argument("--resolution", default="256x192")
    args = parser.parse_args()
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    except (AttributeError, OSError):
        pass
    w, h = (int(v) for v in args.resolution.split("x"))
    spec = DatasetSpec(config=args.config, scenes=args.scenes, resolution=(w, h), grid_step=args.grid_step)
    maker = SampleMaker(spec)
    maker.make(0)  # first VTK frame and caches
    print(f"grid {args.grid_step} m, {w}x{h}, {args.scenes} scenes per N, median of {args.repeats} repeats; "
          f"one core; load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"{'N':>3} {'scenes/s':>9} {'ms/scene':>9} {'CPU scenes/s':>13} {'CPU ms':>7} | CPU ms per stage: "
          + " ".join(f"{s:>9}" for s in STAGES))
    for n in (4, 8, 12):
        walls, cpus = [], []
        for _ in range(args.repeats):
            walls.append(sum(time_scenes(maker, n, args.scenes, time.perf_counter).values()) / args.scenes)
            cpus.append({k: v / args.scenes for k, v in time_scenes(maker, n, args.scenes, time.process_time).items()})
        wall = statistics.median(walls)
        cpu = statistics.median(sum(c.values()) for c in cpus)
        stages = {s: statistics.median(c[s] for c in cpus) for s in STAGES}
        print(f"{n:>3} {1 / wall:>9.1f} {1000 * wall:>9.1f} {1 / cpu:>13.1f} {1000 * cpu:>7.1f} | "
              f"{'':>17}" + " ".join(f"{1000 * stages[s]:>9.1f}" for s in STAGES))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory of this worker: {peak:.0f} MiB; load average now "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
