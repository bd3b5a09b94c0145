"""How far depth-only segmentation moves the object hypotheses from those of the render's labels, on the Table I
scenes' first frames. Per object seen in both modes (a hypothesis belongs to the object most of its segment's pixels
show), the footprint IoU of its depth-only hypothesis against its labels hypothesis; prints per density the objects
compared, those below ``--iou`` (default 0.5), those with no or two hypotheses in depth-only mode, and the cylinders
fitted as boxes.

    python research/depth_hypotheses.py [--config sim_configs/table1.yaml] [--scenes 20] [--seed 0]
        [--densities 8,10] [--iou 0.5] [--width 160] [--sensor-noise]

Seeded like the benchmark (``scene_seed(seed, density, index)``); the noise model is seeded by the scene index.
"""

from __future__ import annotations

import argparse
import collections
import sys

import numpy as np


def footprint_iou(a, b) -> float:
    """IoU of two SceneObjects' footprints on the support surface."""
    from slax_drake.scene.footprint import Footprint

    pa, pb = Footprint.of(a).polygon(), Footprint.of(b).polygon()
    union = pa.union(pb).area
    return float(pa.intersection(pb).area / union) if union > 0 else 0.0


def hypotheses_by_object(depth, labels, segments, camera, shelf, n: int) -> dict:
    """{true object label (1..n): [hypotheses whose segment it mostly shows]} for one frame."""
    from slax_drake.perception.estimator import estimate_objects
    from slax_drake.perception.observation import Observation, occluder_segmentation

    target = labels == n + 1
    segments = occluder_segmentation(segments, target)
    out = {}
    for h in estimate_objects(Observation(depth, segments, target, camera, min_valid_fraction=0.0), shelf):
        owners = labels[segments == h.segment_id]
        owners = owners[(owners >= 1) & (owners <= n)]
        if len(owners):
            out.setdefault(int(np.bincount(owners).argmax()), []).append(h)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/table1.yaml")
    parser.add_argument("--scenes", type=int, default=20, help="scenes per density (default 20)")
    parser.add_argument("--seed", type=int, default=0, help="the protocol seed (default 0)")
    parser.add_argument("--densities", default="8,10", help="comma-separated object counts (default 8,10)")
    parser.add_argument("--iou", type=float, default=0.5, help="count hypotheses below this footprint IoU")
    parser.add_argument("--width", type=int, default=160, help="image width in px (default 160, the policies')")
    parser.add_argument("--sensor-noise", action="store_true", help="the L515 depth-noise model on every frame")
    args = parser.parse_args(argv)
    try:
        densities = [int(d) for d in args.densities.split(",")]
    except ValueError:
        densities = []
    if args.scenes < 1 or args.width < 16 or not densities or not 0 < args.iou <= 1:
        print("error: --scenes must be at least 1, --width at least 16, --densities integers, --iou in (0, 1]",
              file=sys.stderr)
        return 2
    from slax_drake.config import ConfigError, load_scenario
    from slax_drake.evaluation.table1 import protocol_frame, protocol_scene, scene_seed
    from slax_drake.perception.segmentation import segment_depth

    try:
        scenario = load_scenario(args.config)
    except (OSError, ConfigError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    total = collections.Counter()
    for density in densities:
        per = collections.Counter()
        for index in range(args.scenes):
            scene = protocol_scene(scenario, density, scene_seed(args.seed, density, index))
            camera, depth, labels = protocol_frame(scene, args.width, index if args.sensor_noise else None)
            n = len(scene.objects)
            truth = np.where((labels >= 1) & (labels <= n), labels, 0)
            by_labels = hypotheses_by_object(depth, labels, truth, camera, scene.shelf, n)
            by_depth = hypotheses_by_object(depth, labels, segment_depth(depth, camera, scene.shelf), camera,
                                            scene.shelf, n)
            for k, (labelled, *_) in by_labels.items():
                per["objects"] += 1
                mine = by_depth.get(k, [])
                if len(mine) != 1:
                    per["none or two in depth-only"] += 1
                    continue
                if footprint_iou(labelled.object, mine[0].object) < args.iou:
                    per[f"IoU below {args.iou:g}"] += 1
                if labelled.object.shape == "cylinder" and mine[0].object.shape == "box":
                    per["cylinders fitted as boxes"] += 1
        print(f"{density} objects: " + ", ".join(f"{k} {v}" for k, v in sorted(per.items())))
        total += per
    print("all: " + ", ".join(f"{k} {v}" for k, v in sorted(total.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
