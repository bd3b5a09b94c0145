"""How depth-only segmentation goes wrong on the Table I scenes' first frames: segments that hold two objects or more
(merged) and objects spread over two segments or more (split), against the render's labels. Prints one line per
density and the totals.

    python research/depth_segment_merges.py [--config sim_configs/table1.yaml] [--scenes 20] [--seed 0]
        [--width 160] [--sensor-noise]

The scenes are the benchmark's (``scene_seed(seed, density, index)``); each is ray-cast at ``width`` px with the
target, optionally with the L515 noise model (seeded by the scene index), and segmented by
:func:`slax_drake.perception.segmentation.segment_depth`. An object is "in" a segment when it holds at least 20 % of
the segment's pixels; a true object is split when two segments each hold at least 20 % of its pixels, and counted as
"split around an occluder" when its own visible region is disconnected (depth alone cannot join such parts). A
fragment is a segment most of whose pixels are an object that has a larger segment (each one becomes a hypothesis
of its own: a small box where there is part of a bigger object). Each
line ends with the mean instance IoU (``segmentation.instance_mean_iou``, target pixels left out, objects with at
least ``MIN_IOU_PIXELS`` visible pixels scored) over the frames.
"""

from __future__ import annotations

import argparse
import collections
import sys

import cv2
import numpy as np

SHARE = 0.2  # of a segment's (or an object's) pixels
MIN_VISIBLE = 6  # px for an object to count as visible
MIN_IOU_PIXELS = 38  # px (0.2 % of a 160 x 120 frame) for an object to be scored by the mean IoU


def frame_counts(depth, labels, seg, n: int) -> collections.Counter:
    """The counts of one frame: ``labels`` the render's (1..n objects, n + 1 the target), ``seg`` the segments."""
    c = collections.Counter()
    visible = [k for k in range(1, n + 1) if (labels == k).sum() >= MIN_VISIBLE]
    c["visible objects"] += len(visible)
    segments = [s for s in np.unique(seg) if s > 0]
    c["segments"] += len(segments)
    main_segment = {}  # object -> (its pixels in its largest segment, that segment)
    majority = {}  # segment -> the object holding most of its pixels
    for s in segments:
        owners = labels[seg == s]
        ids, counts = np.unique(owners[(owners >= 1) & (owners <= n)], return_counts=True)
        big = int(np.sum(counts >= SHARE * len(owners)))
        if big >= 2:
            c["merged segments"] += 1
            c["objects in merged segments"] += big
        if len(ids):
            k = int(ids[counts.argmax()])
            majority[s] = k
            main_segment[k] = max(main_segment.get(k, (0, s)), (int(counts.max()), s))
    c["fragments"] += sum(1 for s, k in majority.items() if main_segment[k][1] != s)
    for k in visible:
        px = seg[labels == k]
        _, counts = np.unique(px[px > 0], return_counts=True)
        if np.sum(counts >= SHARE * len(px)) >= 2:
            c["split objects"] += 1
            parts = cv2.connectedComponents((labels == k).astype(np.uint8), connectivity=4)[0] - 1
            if parts > 1:
                c["split around an occluder"] += 1
    return c


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/table1.yaml")
    parser.add_argument("--scenes", type=int, default=20, help="scenes per density (default 20)")
    parser.add_argument("--seed", type=int, default=0, help="the protocol seed (default 0)")
    parser.add_argument("--width", type=int, default=160, help="image width in px (default 160, the policies')")
    parser.add_argument("--sensor-noise", action="store_true", help="the L515 depth-noise model on every frame")
    args = parser.parse_args(argv)
    if args.scenes < 1 or args.width < 16:
        print("error: --scenes must be at least 1 and --width at least 16", file=sys.stderr)
        return 2
    from slax_drake.config import ConfigError, load_scenario
    from slax_drake.evaluation.table1 import protocol_frame, protocol_scene, scene_seed
    from slax_drake.perception.segmentation import instance_mean_iou, segment_depth

    try:
        scenario = load_scenario(args.config)
    except (OSError, ConfigError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    total, all_ious = collections.Counter(), []
    for density in scenario.protocol.densities:
        per, ious = collections.Counter(), []
        for index in range(args.scenes):
            scene = protocol_scene(scenario, density, scene_seed(args.seed, density, index))
            camera, depth, labels = protocol_frame(scene, args.width, index if args.sensor_noise else None)
            n = len(scene.objects)
            seg = segment_depth(depth, camera, scene.shelf)
            per += frame_counts(depth, labels, seg, n)
            truth = np.where((labels >= 1) & (labels <= n), labels, 0)
            ious.append(instance_mean_iou(np.where(labels == n + 1, 0, seg), truth, min_true_pixels=MIN_IOU_PIXELS))
        print(f"{density} objects: " + ", ".join(f"{k} {v}" for k, v in sorted(per.items()))
              + f", mean IoU {np.mean(ious):.3f}")
        total += per
        all_ious += ious
    print("all: " + ", ".join(f"{k} {v}" for k, v in sorted(total.items())) + f", mean IoU {np.mean(all_ious):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
