"""Occupancy from the depth image alone (slax_drake.occupancy.from_depth) against the ray-cast ground truth
(compute_occupancy) at the policies' coarse settings (1 cm lattice, 1 cm target samples, 160x120 image), on the
Table I scenes: agreement of the 1D support (IoU of {u : P(u) > 0}), of the hidden placements (IoU of the sets)
and the time per call of each, on one core.

    taskset -c 0 python benchmarks/bench_occupancy_from_depth.py [--scenes 25] [--width 160]

The depth image is the noise-free ray-cast render of the scene without its target; the known objects are given
as obstacles to both (the camera mode gives the estimator's hypotheses instead). Rendering is not timed.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.evaluation.table1 import scene_seed  # noqa: E402
from slax_drake.occupancy import compute_occupancy  # noqa: E402
from slax_drake.occupancy.from_depth import occupancy_from_depth  # noqa: E402
from slax_drake.scene import sample_scene  # noqa: E402
from slax_drake.scene.raycast import SceneRaycaster  # noqa: E402


def iou(a, b) -> float:
    union = len(a | b) if isinstance(a, set) else int((a | b).sum())
    inter = len(a & b) if isinstance(a, set) else int((a & b).sum())
    return inter / union if union else 1.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/table1.yaml")
    parser.add_argument("--scenes", type=int, default=25, help="scenes per density (Table I seeds)")
    parser.add_argument("--width", type=int, default=160, help="image width (px); height keeps the aspect")
    args = parser.parse_args()
    scenario = load_scenario(args.config)
    size = tuple(scenario.target.sizes[0])
    rows = []
    t_depth, t_truth = [], []
    for density in scenario.protocol.densities:
        for index in range(args.scenes):
            scene = sample_scene(scenario, density, scene_seed(scenario.protocol.seed, density, index), target_size=size)
            cam = scene.camera.with_resolution(args.width, round(scene.camera.height * args.width / scene.camera.width))
            t0 = time.perf_counter()
            truth = compute_occupancy(scene, size, 0.01, camera=cam, surface_spacing=0.01)
            t_truth.append(time.perf_counter() - t0)
            depth, _ = SceneRaycaster(scene).render(cam)
            occupancy_from_depth(depth, cam, scene.shelf, size, obstacles=scene.objects)  # tabulate the camera once
            t0 = time.perf_counter()
            got = occupancy_from_depth(depth, cam, scene.shelf, size, obstacles=scene.objects)
            t_depth.append(time.perf_counter() - t0)
            placements = iou(set(map(tuple, np.round(got.hidden_xy, 3))), set(map(tuple, np.round(truth.hidden_xy, 3))))
            rows.append((density, iou(got.p1d > 0, truth.p1d > 0), placements))
    print(f"{args.width} px wide, {args.scenes} scenes per density")
    print("density  1D-support IoU mean (min)  placement IoU mean (min)")
    for density in scenario.protocol.densities + ["all"]:
        sel = [r for r in rows if density == "all" or r[0] == density]
        s1, s2 = [r[1] for r in sel], [r[2] for r in sel]
        print(f"{density!s:>7}  {np.mean(s1):.3f} ({min(s1):.3f})             {np.mean(s2):.3f} ({min(s2):.3f})")
    print(f"median time per call: from depth {1e3 * statistics.median(t_depth):.2f} ms, "
          f"ray-cast compute_occupancy {1e3 * statistics.median(t_truth):.2f} ms")


if __name__ == "__main__":
    main()
