"""Exact 2D footprints on the shelf's support surface: oriented rectangles (boxes) and discs (cylinders).

All coordinates are (x, y) in the shelf frame S, metres. Tests are vectorised over many candidate centres
of one moving shape against one fixed footprint, which is what rejection sampling and the occupancy grid need.
Two rectangles are "clear" when some separating axis (an edge normal of either) leaves a gap of at least
``clearance`` between their projections; a disc is clear of a shape when its centre is at least
radius + clearance from the shape.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.caches import memo
from slax_drake.scene.model import SceneObject, Shelf


@dataclasses.dataclass(frozen=True)
class Footprint:
    """A shape's outline on the support surface: ``shape`` "box" (half extents along its yawed axes) or
    "cylinder" (half_x = half_y = radius)."""

    shape: str
    x: float
    y: float
    yaw: float
    half_x: float
    half_y: float

    @staticmethod
    def of(obj: SceneObject) -> "Footprint":
        cx, cy = float(obj.X_SO[0, 3]), float(obj.X_SO[1, 3])
        return Footprint(obj.shape, cx, cy, obj.yaw, obj.size[0] / 2.0, obj.size[1] / 2.0)

    def extents(self) -> tuple[float, float]:
        """Half extents of the axis-aligned bounding box (x, y)."""
        if self.shape == "cylinder":
            return self.half_x, self.half_x
        c, s = abs(math.cos(self.yaw)), abs(math.sin(self.yaw))
        return self.half_x * c + self.half_y * s, self.half_x * s + self.half_y * c

    def corners(self) -> np.ndarray:
        """The rectangle's four corners (4, 2) counter-clockwise; for a disc, its bounding square's."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        local = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) * (self.half_x, self.half_y)
        return local @ np.array([[c, s], [-s, c]]) + (self.x, self.y)

    def polygon(self, segments: int = 48):
        """A shapely polygon of the outline (a disc as a regular polygon circumscribing it)."""
        from shapely.geometry import Point, Polygon

        if self.shape == "cylinder":
            # Circumscribed polygon so that the polygon contains the true disc.
            r = self.half_x / math.cos(math.pi / segments)
            return Point(self.x, self.y).buffer(r, quad_segs=segments // 4)
        return Polygon(self.corners())


def clear_of(
    shape: str,
    centers: np.ndarray,
    yaw: float,
    half: tuple[float, float],
    other: Footprint,
    clearance: float = 0.0,
) -> np.ndarray:
    """Whether a shape placed at each of ``centers`` (K, 2) is clear of ``other``; returns bool (K,)."""
    centers = np.atleast_2d(centers)
    dx = centers[:, 0] - other.x
    dy = centers[:, 1] - other.y
    if shape == "cylinder" and other.shape == "cylinder":
        return np.hypot(dx, dy) >= half[0] + other.half_x + clearance
    if shape == "cylinder" or other.shape == "cylinder":
        # Disc against rectangle: distance from the disc's centre to the rectangle.
        if shape == "cylinder":
            radius, rect_yaw, rect_half, px, py = half[0], other.yaw, (other.half_x, other.half_y), dx, dy
        else:
            radius, rect_yaw, rect_half, px, py = other.half_x, yaw, half, -dx, -dy
        c, s = math.cos(rect_yaw), math.sin(rect_yaw)
        lx, ly = c * px + s * py, -s * px + c * py
        qx = np.maximum(np.abs(lx) - rect_half[0], 0.0)
        qy = np.maximum(np.abs(ly) - rect_half[1], 0.0)
        return np.hypot(qx, qy) >= radius + clearance
    # Rectangle against rectangle: separating axis theorem over the four edge normals.
    separated = np.zeros(len(centers), dtype=bool)
    for ux, uy, reach in _separating_axes(float(yaw), (float(half[0]), float(half[1])),
                                          float(other.yaw), (other.half_x, other.half_y)):
        separated |= np.abs(dx * ux + dy * uy) >= reach + clearance
    return separated


_AXES_CACHE: dict = {}


def _separating_axes(yaw_a: float, half_a: tuple[float, float], yaw_b: float,
                     half_b: tuple[float, float]) -> tuple[tuple[float, float, float], ...]:
    """The four edge normals u = (ux, uy) of two rectangles and, per normal, the sum of their projected half
    extents r_a + r_b (m): what :func:`clear_of` compares the centres' separation with. Pure in its arguments,
    so cached (searches test the same pairs of shapes thousands of times); the values are computed exactly as
    before the cache, so the tests' results do not change."""
    def compute():
        a_axes = _axes(yaw_a)
        b_axes = _axes(yaw_b)
        out = []
        for u in (*a_axes, *b_axes):
            r_a = half_a[0] * abs(a_axes[0] @ u) + half_a[1] * abs(a_axes[1] @ u)
            r_b = half_b[0] * abs(b_axes[0] @ u) + half_b[1] * abs(b_axes[1] @ u)
            out.append((u[0], u[1], r_a + r_b))
        return tuple(out)

    return memo(_AXES_CACHE, (yaw_a, half_a, yaw_b, half_b), compute, 100_000)


def footprints_clear(a: Footprint, b: Footprint, clearance: float = 0.0) -> bool:
    """Whether two footprints are clear of each other by ``clearance``."""
    return bool(clear_of(a.shape, np.array([[a.x, a.y]]), a.yaw, (a.half_x, a.half_y), b, clearance)[0])


MAX_TOUCH_OVERLAP = 0.005  # m: the deepest overlap of two footprints read as touching estimates; deeper is not trusted
# m: how much more than its clearance (or overlap) to a neighbour it touches a carried object's footprint is shrunk, so
# that it may slide out along it (the planner keeps the tool within 1 mm of its straight segments while carrying)
TOUCH_ALLOWANCE = 0.0012


def touch_overlap(a: SceneObject, b: SceneObject) -> float:
    """How far (m) ``a``'s footprint must shrink on every side (mitred) to stop meeting ``b``'s as they stand: 0
    when they do not overlap; estimates of two objects that physics left touching overlap by a few millimetres.
    By bisection to 0.1 mm; ``MAX_TOUCH_OVERLAP`` when they still meet with ``a`` shrunk that far."""
    poly, other = Footprint.of(a).polygon(), Footprint.of(b).polygon()
    if not poly.intersects(other) or poly.distance(other) > 0.0:
        return 0.0
    if poly.buffer(-MAX_TOUCH_OVERLAP, join_style=2).intersects(other):
        return MAX_TOUCH_OVERLAP
    lo, hi = 0.0, MAX_TOUCH_OVERLAP
    while hi - lo > 1e-4:
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if poly.buffer(-mid, join_style=2).intersects(other) else (lo, mid)
    return hi


def inside_shelf(fp: Footprint, shelf: Shelf, clearance: float = 0.0) -> bool:
    """Whether a footprint lies within the bay's walls, keeping ``clearance`` from them."""
    ex, ey = fp.extents()
    return (
        abs(fp.x) + ex <= shelf.width / 2.0 - clearance + 1e-12
        and abs(fp.y) + ey <= shelf.depth / 2.0 - clearance + 1e-12
    )


def _axes(yaw: float) -> tuple[np.ndarray, np.ndarray]:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([c, s]), np.array([-s, c])
