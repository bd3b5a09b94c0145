"""How often the estimator's extent range holds the true footprint, on ray-cast frames of the simulated shelf
(the shelf simulator's camera mode: label segmentation), per density, clean or with the L515 noise model.

    python benchmarks/extent_ranges.py [--scenes 10] [--width 160] [--noise]

Scenes: ``sim_configs/sim_shelf.yaml``, 4, 6, 8 and 10 objects, seeds 1000..1000+N-1. A seen object counts as
held when at most 1 cm^2 of its true footprint lies outside the range's farthest rectangle grown by 5 mm. Also
printed: the mean reach of the range beyond the observed part along the axis nearest the viewing direction (m),
and the true depth beyond the observed part, for the objects held.
"""

import argparse
from pathlib import Path

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.perception.estimator import estimate_objects
from slax_drake.perception.observation import Observation, occluder_segmentation
from slax_drake.perception.sensor_noise import l515_depth_noise
from slax_drake.scene import sample_scene
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.raycast import SceneRaycaster

REPO = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=10, help="scenes per density (seeds 1000..)")
    parser.add_argument("--width", type=int, default=160, help="image width (px); the height keeps the aspect")
    parser.add_argument("--noise", action="store_true", help="the L515 noise model on the depth")
    args = parser.parse_args(argv)
    if args.scenes < 1 or args.width < 16:
        parser.error("--scenes must be at least 1 and --width at least 16")
    scenario = load_scenario(REPO / "sim_configs" / "sim_shelf.yaml")
    print(f"width {args.width} px, {'L515 noise' if args.noise else 'clean'}, {args.scenes} scenes per density")
    print(f"{'objects':>7} {'seen':>5} {'held':>5} {'share':>6} {'reach m':>8} {'true m':>7}")
    for n in (4, 6, 8, 10):
        seen = held = 0
        reach, true_depth = [], []
        for seed in range(1000, 1000 + args.scenes):
            scene = sample_scene(scenario, n, seed)
            camera = scene.camera.with_resolution(args.width, int(round(scene.camera.height * args.width
                                                                         / scene.camera.width)))
            depth, labels = SceneRaycaster(scene, include_target=True).render(camera)
            if args.noise:
                depth = l515_depth_noise(depth, camera, seed, 0)
            target = labels == n + 1
            segments = occluder_segmentation(np.where((labels >= 1) & (labels <= n), labels, 0), target)
            frame = Observation(depth, segments, target, camera, min_valid_fraction=0.0)
            for h in estimate_objects(frame, scene.shelf):
                truth = Footprint.of(scene.objects[h.segment_id - 1])
                extent = h.uncertainty.extent
                seen += 1
                if truth.polygon().difference(extent.most().polygon().buffer(0.005)).area > 1e-4:
                    continue
                held += 1
                c, s = np.cos(extent.yaw), np.sin(extent.yaw)
                axes = np.array([[c, s], [-s, c]])
                view = np.array([truth.x, truth.y]) - camera.position[:2]
                k = int(np.argmax(np.abs(axes @ view)))
                far = 1 if (axes @ view)[k] > 0 else 0  # the far edge along that axis: hi when it points away
                corners = truth.polygon().exterior.coords
                along = np.array(corners) @ axes[k]
                if far:
                    reach.append(extent.most_hi[k] - extent.least_hi[k])
                    true_depth.append(max(along.max() - extent.least_hi[k], 0.0))
                else:
                    reach.append(extent.least_lo[k] - extent.most_lo[k])
                    true_depth.append(max(extent.least_lo[k] - along.min(), 0.0))
        share = held / max(seen, 1)
        print(f"{n:>7} {seen:>5} {held:>5} {share:>6.3f} {np.mean(reach):>8.3f} {np.mean(true_depth):>7.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
