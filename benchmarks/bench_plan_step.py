"""Planning one step from a camera frame, motion planning excluded: perception (frame validation, resampling to
160x120, depth-only segmentation, estimator, P_t from the frame) + the policy's decision (Bluction-DAR by default:
every candidate's distribution from the predicted frame), as ``slax-drake plan-step`` runs them
(slax_drake.hardware.plan_step.StepPlanner.perceive / decide). Issue 16's goal: under 0.3 s median on one core.

    taskset -c 0 python benchmarks/bench_plan_step.py [--scenes 10] [--policy bluction-dar]

Frames: the station camera (640x480) on Table I-like scenes of 4, 6, 8 and 10 objects of the sim shelf, rendered
by the ray caster (equal to Drake's depth to 1e-6 m) with the L515 noise model; rendering is not timed. One
core: numpy's and OpenCV's threads are set to one before anything runs (pin the process with taskset).
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from slax_drake.hardware.plan_step import StepPlanner  # noqa: E402
from slax_drake.perception.sensor_noise import l515_depth_noise  # noqa: E402
from slax_drake.scene.raycast import SceneRaycaster  # noqa: E402
from slax_drake.scene.sampling import sample_scene  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--station", default="sim_configs/station_sim_shelf.yaml")
    parser.add_argument("--scenes", type=int, default=10, help="scenes per object count")
    parser.add_argument("--policy", default="bluction-dar")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    planner = StepPlanner(args.station, policy=args.policy)
    rows = []
    for n in (4, 6, 8, 10):
        for seed in range(args.scenes):
            scene = sample_scene(planner.scenario, n, seed)
            depth, labels = SceneRaycaster(scene, include_target=True).render(planner.camera)
            depth = l515_depth_noise(depth, planner.camera, seed=seed)
            mask = labels == len(scene.objects) + 1
            t0 = time.perf_counter()
            observation, _ = planner.perceive(depth, mask)
            t1 = time.perf_counter()
            planner.decide(observation)
            t2 = time.perf_counter()
            rows.append((n, t1 - t0, t2 - t1, t2 - t0))
    print(f"{args.policy}, {args.scenes} frames per object count, 640x480 noisy frames, working resolution 160x120")
    print("objects  perception median  decision median  total median  total p90")
    for n in (4, 6, 8, 10, "all"):
        sel = [r for r in rows if n == "all" or r[0] == n]
        total = [r[3] for r in sel]
        print(f"{n!s:>7}  {statistics.median(r[1] for r in sel):14.3f} s  {statistics.median(r[2] for r in sel):13.3f} s"
              f"  {statistics.median(total):10.3f} s  {np.percentile(total, 90):7.3f} s")
    print(f"goal: total median < 0.3 s -> {'met' if statistics.median(r[3] for r in rows) < 0.3 else 'NOT met'}")


if __name__ == "__main__":
    main()
