"""Instance segmentation of the occluding objects from a depth image alone (no label image; a real camera).

1. Foreground: every pixel is back-projected with the camera model into the shelf frame S; a point counts as an
   object when it stands above the support surface and inside the bay, away from the side walls, top and back
   panel by ``margin`` metres (the shelf and the camera are static relative to each other, Sec. III). The frame's
   range offset, measured on the back panel (:func:`~slax_drake.perception.range_offset.range_calibration`), is
   taken off first: a camera reading 5 mm short made the whole panel foreground, a mosaic of small instances.
2. Depth discontinuities: a pixel whose depth differs from a 4-neighbour by more than
   ``max(jump_abs, jump_rel * depth)`` lies on an edge between instances (an occluder in front of another), and so
   does a pixel at the bottom of a concave crease (:func:`concave_creases`): every object is convex, so a valley in
   the depth image is where two objects meet at the same depth.
3. Connected components (OpenCV, 4-connectivity) of foreground pixels off the edges are the instances; those
   under ``min_pixels`` are dropped.
4. The edge (and dropped) foreground pixels join an instance by depth continuity (:func:`grow_by_depth`): each
   joins the 8-neighbour instance whose depth is nearest its own (or whose surface, continued by its own step
   from the next pixel of that instance, meets it: a receding face), first where that step is within the jump
   limit, then within 3 and 6 times it (``GROWTH_TIERS``); one ring of pixels per pass. So a face seen at a
   grazing angle, all edge pixels (a box's top face seen from just above it can be one row, 4 cm deeper than the
   front face's top row), grows from its own object's pixels, not from whichever neighbour comes first.
5. What no instance reached is a surface of its own (a sliver of an object seen between or above nearer ones is
   all edge pixels): its parts connected over depth steps within three jump limits, of at least ``min_pixels``
   pixels, become instances; then every instance grows again over the same steps. Foreground pixels that none
   reaches (a fragment under ``min_pixels`` of a surface of its own) stay 0: joined to a neighbour over any step,
   three pixels of an object far behind made a box's hypothesis twice as deep.
6. Fragments (instances under ``FRAGMENT_SHARE`` of the image) merge into the larger neighbour whose surface they
   continue along most of their boundary (:func:`merge_fragments`): range noise and missing returns break a
   grazing face into islands of a few pixels.

Objects that touch at the same depth with parallel faces (no crease between them) merge into one instance;
:func:`instance_mean_iou` measures how often, and ``research/depth_segment_merges.py`` counts merged and split
objects and fragments on the Table I scenes.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from slax_drake.errors import ImageSizeError
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Shelf


CREASE_BASELINE = 3  # px on each side of a concave crease's pixel
CREASE_RANGE_SIGMA = 0.0025  # m, the range noise a crease must stand out from (the L515's precision at 1 m)
CREASE_MIN_BEND = 0.35  # the least difference of the tangents of two faces' slopes that makes a crease


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


def jump_limit(depth: np.ndarray, jump_abs: float = 0.01, jump_rel: float = 0.02) -> np.ndarray:
    """The depth step (H, W) metres beyond which two neighbouring pixels lie on different surfaces:
    max(``jump_abs``, ``jump_rel`` * depth), ``jump_abs`` where a pixel has no return."""
    d = np.where(np.isfinite(depth) & (depth > 0), depth, 0.0).astype(np.float64)
    return np.maximum(jump_abs, jump_rel * d)


def depth_edges(depth: np.ndarray, jump_abs: float = 0.01, jump_rel: float = 0.02) -> np.ndarray:
    """Pixels (H, W) bool with a depth jump to a 4-neighbour above max(jump_abs, jump_rel * depth) metres."""
    d = np.where(np.isfinite(depth), depth, 0.0).astype(np.float64)
    edges = np.zeros(d.shape, dtype=bool)
    dx = np.abs(np.diff(d, axis=1))
    dy = np.abs(np.diff(d, axis=0))
    limit = jump_limit(depth, jump_abs, jump_rel)
    jx = dx > np.minimum(limit[:, 1:], limit[:, :-1])
    jy = dy > np.minimum(limit[1:, :], limit[:-1, :])
    edges[:, 1:] |= jx
    edges[:, :-1] |= jx
    edges[1:, :] |= jy
    edges[:-1, :] |= jy
    return edges


def concave_creases(depth: np.ndarray, camera: Camera, jump_abs: float = 0.01, jump_rel: float = 0.02,
                    baseline: int = CREASE_BASELINE, range_sigma: float = CREASE_RANGE_SIGMA,
                    min_bend: float = CREASE_MIN_BEND) -> np.ndarray:
    """Pixels (H, W) bool at the bottom of a concave crease of the depth image: along a row (or a column) the
    surface comes toward the camera on both sides of the pixel. Every occluder is convex (a box or a cylinder),
    and the image of a convex surface is nowhere concave (a plane's depth is a convex function of the pixel
    coordinate; an edge of a box seen from outside is a ridge toward the camera), so such a valley is where two
    objects meet: two boxes side by side, their faces at different angles, touching or nearly so at the same depth.

    With the one-sided slopes s_L = (z[u] - z[u - k]) / k and s_R = (z[u + k] - z[u]) / k (k = ``baseline``
    pixels, metres per pixel), the pixel is a valley where s_L - s_R exceeds both three standard deviations of its
    range noise (sqrt(6) * ``range_sigma`` / k; ``range_sigma`` metres per return) and ``min_bend`` times the
    pixel's footprint z / fx (the two faces' slopes differ by ``min_bend``, a tangent). Every step inside the
    window must be within twice the jump limit max(``jump_abs``, ``jump_rel`` z) (larger steps are occluding edges,
    found by :func:`depth_edges`), and every pixel of it must have a return."""
    d = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float64)
    limit = 2.0 * jump_limit(depth, jump_abs, jump_rel)
    threshold = np.maximum(3.0 * np.sqrt(6.0) * range_sigma / baseline,
                           min_bend * np.nan_to_num(d, nan=0.0) / camera.fx)
    valley = np.zeros(d.shape, dtype=bool)
    k = int(baseline)
    for a, lim, thr in ((d, limit, threshold), (d.T, limit.T, threshold.T)):
        out = valley if a is d else valley.T
        step = np.abs(np.diff(a, axis=1))  # (H, W - 1); NaN where a return is missing
        with np.errstate(invalid="ignore"):
            smooth = step <= np.minimum(lim[:, 1:], lim[:, :-1])  # False where NaN
        # Every step of the window [u - k, u + k] smooth: a sliding count of smooth steps over 2k steps.
        count = np.cumsum(np.pad(smooth.astype(np.int32), ((0, 0), (1, 0))), axis=1)
        window_ok = (count[:, 2 * k:] - count[:, :-2 * k]) == 2 * k  # (H, W - 2k), for u = k .. W - k - 1
        centre = a[:, k:-k]
        bend = (2.0 * centre - a[:, :-2 * k] - a[:, 2 * k:]) / k
        with np.errstate(invalid="ignore"):
            out[:, k:-k] |= window_ok & (bend > thr[:, k:-k])
    return valley


def segment_depth(depth: np.ndarray, camera: Camera, shelf: Shelf, margin: float = 0.006,
                  jump_abs: float = 0.01, jump_rel: float = 0.02, min_pixels: int | None = None,
                  creases: bool = True, correct_range_offset: bool = True) -> np.ndarray:
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
    if correct_range_offset:  # a range offset moves the back panel past the margin: all of it was foreground
        from slax_drake.perception.range_offset import range_calibration

        offset = range_calibration(depth, camera, shelf, np.ones(depth.shape, bool)).offset
        fg = foreground_mask(np.where(depth > 0, depth - offset, 0.0), camera, shelf, margin)
    else:
        fg = foreground_mask(depth, camera, shelf, margin)
    core = fg & ~depth_edges(depth, jump_abs, jump_rel)
    crease = concave_creases(depth, camera, jump_abs, jump_rel) if creases else np.zeros(depth.shape, bool)
    core &= ~crease
    limit = jump_limit(depth, jump_abs, jump_rel)
    labels = _components(core, min_pixels)
    labels = grow_by_depth(labels, fg, depth, limit)
    # What no instance reached is a surface of its own: a sliver of an object seen between or above nearer
    # ones is all edge pixels, without a core of its own.
    rest = _continuous_components(fg & (labels == 0), depth, 3.0 * limit, min_pixels)
    labels = np.where(rest > 0, rest + labels.max(), labels)
    labels = grow_by_depth(labels, fg, depth, limit)
    labels = merge_fragments(labels, depth, limit, crease, max(min_pixels, int(round(depth.size * FRAGMENT_SHARE))))
    return _left_to_right(labels)


FRAGMENT_SHARE = 0.003  # an instance below this share of the image's pixels may be a fragment (58 px at 160 x 120)


def merge_fragments(labels: np.ndarray, depth: np.ndarray, limit: np.ndarray, crease: np.ndarray,
                    max_pixels: int) -> np.ndarray:
    """Labels (H, W) int32 with each fragment merged into the neighbour it continues: an instance of fewer than
    ``max_pixels`` pixels whose boundary with a larger neighbour is mostly (at least half of its 4-neighbour pairs)
    continuous: a depth step within 1.5 times the jump limit ``limit`` (metres, H x W), or either side's surface
    continued by its own slope meets the other within it; not both pixels on a concave ``crease``.
    Range noise and missing returns break a face into islands of a few pixels, each of which became an instance
    (a hypothesis of a 1 cm box inside a larger object); an object seen beside or behind another keeps its
    instance, as depth jumps or a crease separate them. Smallest fragments first, each merged once."""
    labels = labels.astype(np.int32, copy=True)
    ids, sizes = np.unique(labels[labels > 0], return_counts=True)
    small = ids[sizes < max_pixels]
    if len(small) == 0:
        return labels
    size_of = dict(zip(ids.tolist(), sizes.tolist()))
    d = np.where(np.isfinite(depth), depth, np.nan)
    pairs = []  # (label a, label b, continuous) per 4-neighbour pair with different labels
    for dy, dx in ((0, 1), (1, 0)):
        a, b = labels, _neighbour(labels, dy, dx, 0)
        d_b = _neighbour(d, dy, dx, np.nan)
        differ = (a > 0) & (b > 0) & (a != b)
        # The step between the two, or either surface continued by its own slope onto the other (a receding face
        # meeting its object's other face at a convex edge: a box's top face seen from just above it).
        own_a = np.where(_neighbour(labels, -dy, -dx, 0) == a, _neighbour(d, -dy, -dx, np.nan), np.nan)
        own_b = np.where(_neighbour(labels, 2 * dy, 2 * dx, 0) == b, _neighbour(d, 2 * dy, 2 * dx, np.nan), np.nan)
        with np.errstate(invalid="ignore"):
            step = np.fmin(np.abs(d - d_b), np.fmin(np.abs(2.0 * d - own_a - d_b), np.abs(2.0 * d_b - own_b - d)))
            cont = (step <= 1.5 * np.minimum(limit, _neighbour(limit, dy, dx, 0.0))) \
                & ~(crease & _neighbour(crease, dy, dx, False))
        pairs.append((a[differ], b[differ], cont[differ]))
    a = np.concatenate([p[0] for p in pairs] + [p[1] for p in pairs])
    b = np.concatenate([p[1] for p in pairs] + [p[0] for p in pairs])
    cont = np.concatenate([p[2] for p in pairs] * 2)
    parent = {i: i for i in ids.tolist()}

    def root(i):
        while parent[i] != i:
            i = parent[i]
        return i

    for f in sorted(small.tolist(), key=lambda i: size_of[i]):
        mine = a == f
        if not mine.any():
            continue
        mine_f = root(f)
        roots = np.array([root(n) for n in b[mine].tolist()])
        others = roots != mine_f  # pairs with what an earlier merge joined to f are inside it now
        if not others.any():
            continue
        counts = {}
        for n, c in zip(roots[others].tolist(), cont[mine][others].tolist()):
            counts[n] = counts.get(n, 0) + int(c)
        best = max((n for n in counts if size_of[n] >= size_of[mine_f]), key=lambda n: counts[n], default=None)
        if best is not None and counts[best] > 0 and 2 * counts[best] >= int(others.sum()):
            parent[mine_f] = best
            size_of[best] += size_of[mine_f]
    lut = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    for i in ids.tolist():
        lut[i] = root(i)
    return lut[labels]


def _components(mask: np.ndarray, min_pixels: int) -> np.ndarray:
    """Connected components (4-connectivity) of ``mask`` with at least ``min_pixels`` pixels, labelled 1..K."""
    count, comps, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=4)
    sizes = stats[:, cv2.CC_STAT_AREA].copy()
    sizes[0] = 0  # the background
    return _renumber_big(sizes, min_pixels)[comps]


def _renumber_big(sizes: np.ndarray, min_pixels: int) -> np.ndarray:
    """A lookup from part index to label: 1..K for the parts of at least ``min_pixels`` (in index order), 0 else."""
    lut = np.zeros(len(sizes), dtype=np.int32)
    big = np.nonzero(sizes >= min_pixels)[0]
    lut[big] = np.arange(1, len(big) + 1, dtype=np.int32)
    return lut


def _continuous_components(mask: np.ndarray, depth: np.ndarray, step: np.ndarray, min_pixels: int) -> np.ndarray:
    """Components of ``mask`` whose 4-neighbours join only over a depth step within ``step`` (metres, H x W: the
    smaller of the two pixels'), with at least ``min_pixels`` pixels, labelled 1..K."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    index = -np.ones(mask.shape, dtype=np.int64)
    ys, xs = np.nonzero(mask)
    index[ys, xs] = np.arange(len(ys))
    if len(ys) == 0:
        return np.zeros(mask.shape, dtype=np.int32)
    rows, cols = [], []
    for a, b, da, db, sa, sb in ((index[:, :-1], index[:, 1:], depth[:, :-1], depth[:, 1:], step[:, :-1], step[:, 1:]),
                                 (index[:-1], index[1:], depth[:-1], depth[1:], step[:-1], step[1:])):
        join = (a >= 0) & (b >= 0) & (np.abs(da - db) <= np.minimum(sa, sb))
        rows.append(a[join])
        cols.append(b[join])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(ys), len(ys)))
    _, part = connected_components(graph, directed=False)
    out = np.zeros(mask.shape, dtype=np.int32)
    out[ys, xs] = _renumber_big(np.bincount(part), min_pixels)[part]
    return out


def _left_to_right(labels: np.ndarray) -> np.ndarray:
    """Labels renumbered 1..K by their leftmost pixel (then topmost); 0 stays 0."""
    ys, xs = np.nonzero(labels > 0)
    if len(ys) == 0:
        return labels.astype(np.int32)
    by_position = labels[ys, xs][np.lexsort((ys, xs))]  # by x, then y
    ids, first = np.unique(by_position, return_index=True)
    lut = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    lut[ids[np.argsort(first)]] = np.arange(1, len(ids) + 1, dtype=np.int32)
    return lut[labels]


GROWTH_TIERS = (1.0, 3.0, 6.0)  # the depth steps an instance grows over, in jump limits, tier by tier
_NEIGHBOURS8 = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1))


def _neighbour(a: np.ndarray, dy: int, dx: int, fill) -> np.ndarray:
    """``out[y, x] = a[y + dy, x + dx]``, ``fill`` beyond the image."""
    out = np.full_like(a, fill)
    h, w = a.shape
    out[max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)] = a[max(dy, 0):h + min(dy, 0),
                                                                      max(dx, 0):w + min(dx, 0)]
    return out


def grow_by_depth(labels: np.ndarray, grow: np.ndarray, depth: np.ndarray, limit: np.ndarray,
                  tiers: tuple[float, ...] = GROWTH_TIERS, max_passes: int = 40, slopes: bool = True) -> np.ndarray:
    """Labels (H, W) int32, 0 unassigned -> a copy in which the ``grow`` pixels (bool, H x W) still at 0 take the
    label of the 8-neighbour whose depth (metres; no return: 0 or non-finite) is nearest theirs, or (``slopes``)
    whose surface, continued by its own step from the next pixel of the same label, meets theirs. Tier by tier, a
    pixel joins only over a depth step within ``tier * limit`` (metres, H x W) and the passes repeat until nothing
    joins (at most ``max_passes`` per tier). Pixels with no labelled pixel within reach stay 0."""
    labels = labels.astype(np.int32, copy=True)
    d = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float64)
    ys, xs = np.nonzero(grow | (labels > 0))
    if len(ys) == 0:
        return labels
    # Work on the bounding box of what may grow (and one pixel around it).
    box = (slice(max(ys.min() - 1, 0), ys.max() + 2), slice(max(xs.min() - 1, 0), xs.max() + 2))
    sub, todo_mask, d_sub, lim = labels[box], grow[box], d[box], limit[box]
    # Per neighbour direction, the depth step to that neighbour and (``slopes``) to its surface continued one pixel
    # on (a receding face); no return on either side: never the nearest. The depths do not change between passes.
    with np.errstate(invalid="ignore"):
        steps, ahead = [], []
        for dy, dx in _NEIGHBOURS8:
            d_n = _neighbour(d_sub, dy, dx, np.nan)
            steps.append(np.nan_to_num(np.abs(d_n - d_sub), nan=1e3))
            if slopes:
                ahead.append(np.nan_to_num(np.abs(2.0 * d_n - _neighbour(d_sub, 2 * dy, 2 * dx, np.nan) - d_sub),
                                           nan=1e3))
    for tier in tiers:
        for _ in range(max_passes):
            todo = todo_mask & (sub == 0)
            if not todo.any():
                break
            best = np.zeros(sub.shape, np.int32)
            best_step = np.full(sub.shape, np.inf)
            for k, (dy, dx) in enumerate(_NEIGHBOURS8):
                label = _neighbour(sub, dy, dx, 0)
                step = steps[k]
                if slopes:
                    same = _neighbour(sub, 2 * dy, 2 * dx, 0) == label
                    step = np.where(same & (ahead[k] < step), ahead[k], step)
                better = todo & (label > 0) & (step < best_step)
                best[better] = label[better]
                best_step[better] = step[better]
            join = todo & (best > 0) & (best_step <= tier * lim)
            if not join.any():
                break
            sub[join] = best[join]
    labels[box] = sub
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
