"""Dataset throughput on one core: scenes/s for a whole sample (scene sampling, Drake render, three occupancy
distributions) at N = 4, 8, 12, and the worker's peak memory.

    python benchmarks/bench_dataset.py [--scenes 40] [--grid-step 0.005] [--resolution 256x192]
"""

import argparse
import os
import resource
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from slax_drake.dataset.generate import DatasetSpec, SampleMaker  # noqa: E402
from slax_drake.dataset.shards import TARGET_SIZES  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/sim_shelf.yaml")
    parser.add_argument("--scenes", type=int, default=40)
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
    import numpy as np

    from slax_drake.occupancy import compute_occupancy
    from slax_drake.scene import sample_scene
    from slax_drake.scene.raycast import SceneRaycaster

    print(f"grid {args.grid_step} m, {w}x{h}; one core")
    print(f"{'N':>3} {'scenes/s':>9} {'ms/scene':>9} {'sample ms':>10} {'render ms':>10} {'3 occ ms':>9}")
    for n in (4, 8, 12):
        t_sample = t_render = t_occ = 0.0
        for i in range(args.scenes):
            ratio = i % 3
            t0 = time.perf_counter()
            scene = sample_scene(maker.scenario, n, 77_000 + 100 * n + i, target_size=TARGET_SIZES[ratio])
            t1 = time.perf_counter()
            maker.renderer.render(scene)
            t2 = time.perf_counter()
            rc = SceneRaycaster(scene)
            for size in TARGET_SIZES:
                compute_occupancy(scene, size, args.grid_step, maker.camera,
                                  maker.scenario.target.surface_point_spacing, raycaster=rc)
            t3 = time.perf_counter()
            t_sample += t1 - t0
            t_render += t2 - t1
            t_occ += t3 - t2
        total = t_sample + t_render + t_occ
        k = args.scenes
        print(f"{n:>3} {k / total:>9.1f} {1000 * total / k:>9.1f} {1000 * t_sample / k:>10.1f} "
              f"{1000 * t_render / k:>10.1f} {1000 * t_occ / k:>9.1f}")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory of this worker: {peak:.0f} MiB")
    del np


if __name__ == "__main__":
    main()
