"""Perception-to-belief latency on one core: depth-only segmentation + the observation's validation + the
estimator (segments -> object hypotheses), per frame, at 128x96 (the network's resolution) and 640x480, on
frames of the simulated shelf rendered by Drake, clean and with the L515 noise model. Prints the median and
90th percentile per resolution (issue 16's budget for perception + estimator + decision is 0.3 s median).

    python benchmarks/bench_estimator.py [--scenes 20] [--repeats 3]

Rendering and the noise model are not timed. One core: the process is pinned to one CPU and numpy's, OpenCV's
threads are set to one before anything runs.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.perception.estimator import estimate_objects  # noqa: E402
from slax_drake.perception.observation import (  # noqa: E402
    Observation, occluder_segmentation, target_mask_from_labels,
)
from slax_drake.perception.segmentation import segment_depth  # noqa: E402
from slax_drake.perception.sensor_noise import l515_depth_noise  # noqa: E402
from slax_drake.scene import sample_scene  # noqa: E402
from slax_drake.station.renderer import SceneRenderer  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=20, help="scenes (4 to 12 objects, seeds 0..N-1)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per frame (the fastest counts)")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    cv2.setNumThreads(1)
    scenario = load_scenario(REPO / "sim_configs" / "sim_shelf.yaml")
    scenes = [sample_scene(scenario, 4 + (k % 5) * 2, k) for k in range(args.scenes)]
    print(f"{args.scenes} scenes of 4-12 objects; segmentation + observation + estimator per frame, one core")
    print(f"{'resolution':>10} {'noise':>6} {'median ms':>10} {'p90 ms':>8} {'hypotheses/frame':>17}")
    for width, height in ((128, 96), (640, 480)):
        renderer = SceneRenderer(scenes[0].camera.with_resolution(width, height))
        camera = renderer.camera
        for noisy in (False, True):
            times, counts = [], []
            for k, scene in enumerate(scenes):
                depth, label = renderer.render(scene)
                if noisy:
                    depth = l515_depth_noise(depth, camera, seed=k)
                target = target_mask_from_labels(label, len(scene.objects) + 1)

                def step():
                    labels = occluder_segmentation(segment_depth(depth, camera, scene.shelf), target)
                    return estimate_objects(Observation(depth, labels, target, camera), scene.shelf)

                best = float("inf")
                for _ in range(args.repeats):
                    t = time.perf_counter()
                    hypotheses = step()
                    best = min(best, time.perf_counter() - t)
                times.append(best)
                counts.append(len(hypotheses))
            p90 = float(np.percentile(times, 90))
            print(f"{width}x{height:<4} {'L515' if noisy else 'off':>6} {1000 * statistics.median(times):10.1f} "
                  f"{1000 * p90:8.1f} {statistics.mean(counts):17.1f}")


if __name__ == "__main__":
    main()
