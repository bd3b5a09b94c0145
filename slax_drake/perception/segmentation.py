"""Instance segmentation of the occluding objects from a depth image alone (no label image; a real camera).

1. Foreground: every pixel is back-projected with the camera model into the shelf frame S; a point counts as an
   object when it stands above the support surface and inside the bay, away from the side walls, top and back
   panel by ``margin`` metres (the shelf and the camera are static relative to each other, Sec. III).
2. Depth discontinuities: a pixel whose depth differs from a 4-neighbour by more than
   ``max(jump_abs, jump_rel * depth)`` lies on an edge between instances (an occluder in front of another).
3. Connected components (OpenCV, 4-connectivity) of foreground pixels off the edges are the instances; those
   under ``min_pixels`` are dropped, and edge pixels then join the neighbouring instance by dilation.

Objects that touch at the same depth merge into one instance; :func:`instance_mean_iou` measures how often.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from slax_drake.errors import ImageSizeError
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Shelf


def back_project(depth: np.ndarray, camera: Camera) -> np.ndarray:
    """Depth (H, W) metres along the optical axis -> points (H, W, 3) in the shelf frame (NaN where invalid)."""
    h, w = depth.shape
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    z = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float64)
    p_C = np.stack([(u - camera.cx) / camera.fx * z, (v - camera.cy) / camera.fy * z, z], axis=-1)
    return p_C @ camera.X_SC[:3, :3].T + camera.X_SC[:3, 3]


def foreground_mask(depth: np.ndarray, camera: Camera, shelf: Shelf, margin: float = 0.006) -> np.ndarray:
    """Pixels (H, W) bool that see an object rather than the shelf's panels or nothing."""
    p = back_project(depth, camera)
    with np.errstate(invalid="ignore"):
        return (
            (p[..., 2] > margin)
            & (p[..., 2] < shelf.height - margin)
            & (np.abs(p[..., 0]) < shelf.width / 2 - margin)
            & (p[..., 1] < shelf.depth / 2 - margin)
        )


def depth_edges(depth: np.ndarray, jump_abs: float = 0.01, jump_rel: float = 0.02) -> np.ndarray:
    """Pixels (H, W) bool with a depth jump to a 4-neighbour above max(jump_abs, jump_rel * depth) metres."""
    d = np.where(np.isfinite(depth), depth, 0.0).astype(np.float64)
    edges = np.zeros(d.shape, dtype=bool)
    dx = np.abs(np.diff(d, axis=1))
    dy = np.abs(np.diff(d, axis=0))
    limit = np.maximum(jump_abs, jump_rel * d)
    jx = dx > np.minimum(limit[:, 1:], limit[:, :-1])
    jy = dy > np.minimum(limit[1:, :], limit[:-1, :])
    edges[:, 1:] |= jx
    edges[:, :-1] |= jx
    edges[1:, :] |= jy
    edges[:-1, :] |= jy
    return edges


def segment_depth(depth: np.ndarray, camera: Camera, shelf: Shelf, margin: float = 0.006,
                  jump_abs: float = 0.01, jump_rel: float = 0.02, min_pixels: int | None = None) -> np.ndarray:
    """Depth image (H, W) metres -> instance labels (H, W) int32: 0 shelf/background, 1..K objects, numbered
    left to right by their leftmost pixel. ``camera`` must have the image's resolution."""
    depth = np.asarray(depth, dtype=np.float32)
    if depth.shape != (camera.height, camera.width):
        raise ImageSizeError(
            f"depth image of shape {depth.shape} given, camera is {camera.width}x{camera.height} "
            f"(shape ({camera.height}, {camera.width}))"
        )
    if min_pixels is None:  # about a 1 cm x 1 cm patch at 1 m
        min_pixels = max(4, int(round(depth.size * 2e-4)))
    fg = foreground_mask(depth, camera, shelf, margin)
    core = fg & ~depth_edges(depth, jump_abs, jump_rel)
    count, comps, stats, _ = cv2.connectedComponentsWithStats(core.astype(np.uint8), connectivity=4)
    keep = [i for i in range(1, count) if stats[i, cv2.CC_STAT_AREA] >= min_pixels]
    keep.sort(key=lambda i: (stats[i, cv2.CC_STAT_LEFT], stats[i, cv2.CC_STAT_TOP]))
    relabel = np.zeros(count, dtype=np.int32)
    relabel[keep] = np.arange(1, len(keep) + 1, dtype=np.int32)
    labels = relabel[comps]
    # Edge (and dropped) foreground pixels join an adjacent instance, growing one pixel per pass.
    kernel = np.ones((3, 3), np.uint8)
    for _ in range(8):
        todo = fg & (labels == 0)
        if not todo.any():
            break
        grown = cv2.dilate(labels.astype(np.float32), kernel).astype(np.int32)
        fill = todo & (grown > 0)
        if not fill.any():
            break
        labels[fill] = grown[fill]
    return labels


def instance_mean_iou(predicted: np.ndarray, truth: np.ndarray, min_true_pixels: int = 1) -> float:
    """Mean IoU over the true instances (labels > 0 of ``truth``) after a one-to-one matching to predicted
    instances (labels > 0) that maximises the total IoU; an unmatched true instance scores 0. True instances
    with fewer than ``min_true_pixels`` visible pixels are left out of the mean (they still count as area). An
    image with no true instance scores 1 when nothing is predicted either, else 0."""
    ids, areas = np.unique(truth[truth > 0], return_counts=True)
    scored = set(ids[areas >= min_true_pixels].tolist())
    true_ids = ids.tolist()
    pred_ids = [i for i in np.unique(predicted) if i > 0]
    if not scored:
        return 1.0 if not pred_ids else 0.0
    if not pred_ids:
        return 0.0
    t = np.searchsorted(true_ids, truth)
    p = np.searchsorted(pred_ids, predicted)
    tv = (truth > 0)
    pv = (predicted > 0)
    inter = np.zeros((len(true_ids), len(pred_ids)))
    both = tv & pv
    np.add.at(inter, (t[both], p[both]), 1)
    t_area = np.bincount(t[tv], minlength=len(true_ids)).astype(float)
    p_area = np.bincount(p[pv], minlength=len(pred_ids)).astype(float)
    iou = inter / (t_area[:, None] + p_area[None, :] - inter)
    rows, cols = linear_sum_assignment(-iou)
    matched = dict(zip(rows.tolist(), iou[rows, cols].tolist()))
    keep = [k for k, i in enumerate(true_ids) if i in scored]
    return float(sum(matched.get(k, 0.0) for k in keep) / len(keep))
