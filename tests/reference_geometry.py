"""Independent geometry for the tests: exact ray tests against boxes and cylinders (no triangulation, no
Embree) and shapely footprints, used to check what the package computes its own way."""

import math

import numpy as np
from shapely.geometry import Point, Polygon

from slax_drake.scene.model import Scene, SceneObject


def segment_hits_object(eye: np.ndarray, points: np.ndarray, obj: SceneObject, eps: float = 1e-7) -> np.ndarray:
    """Whether each segment eye -> point (P, 3) passes through the interior of ``obj`` before the point."""
    R, c = obj.X_SO[:3, :3], obj.X_SO[:3, 3]
    o = (eye - c) @ R
    d = (points - eye) @ R
    half = np.asarray(obj.size) / 2.0
    if obj.shape == "box":
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (-half - o) / d
            t2 = (half - o) / d
        t_lo = np.nanmax(np.where(np.abs(d) < 1e-15, np.where(np.abs(o) < half, -np.inf, np.inf), np.minimum(t1, t2)), axis=1)
        t_hi = np.nanmin(np.where(np.abs(d) < 1e-15, np.where(np.abs(o) < half, np.inf, -np.inf), np.maximum(t1, t2)), axis=1)
        return (t_lo < t_hi - eps) & (t_lo < 1.0 - eps) & (t_hi > eps)
    r = half[0]
    a = d[:, 0] ** 2 + d[:, 1] ** 2
    b = 2 * (o[0] * d[:, 0] + o[1] * d[:, 1])
    cc = o[0] ** 2 + o[1] ** 2 - r * r
    disc = b * b - 4 * a * cc
    ok = (disc > 0) & (a > 1e-15)
    sq = np.sqrt(np.where(ok, disc, 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (-b - sq) / (2 * a), (-b + sq) / (2 * a)
        tz1 = (-half[2] - o[2]) / d[:, 2]
        tz2 = (half[2] - o[2]) / d[:, 2]
    tz_lo, tz_hi = np.minimum(tz1, tz2), np.maximum(tz1, tz2)
    t_lo = np.maximum(ta, tz_lo)
    t_hi = np.minimum(tb, tz_hi)
    return ok & (t_lo < t_hi - eps) & (t_lo < 1.0 - eps) & (t_hi > eps)


def segment_blocked_by_shelf(scene: Scene, eye: np.ndarray, points: np.ndarray) -> np.ndarray:
    """A segment from a camera in front of the shelf to a point inside it passes the open front face
    y = -depth/2; it is blocked unless it crosses that plane inside the opening."""
    shelf = scene.shelf
    y0 = -shelf.depth / 2
    t = (y0 - eye[1]) / (points[:, 1] - eye[1])
    cross = eye + t[:, None] * (points - eye)
    inside = (np.abs(cross[:, 0]) <= shelf.width / 2) & (cross[:, 2] >= 0) & (cross[:, 2] <= shelf.height)
    return ~inside


def visible_points(scene: Scene, points: np.ndarray) -> np.ndarray:
    eye = scene.camera.position
    blocked = segment_blocked_by_shelf(scene, eye, points)
    for obj in scene.objects:
        blocked |= segment_hits_object(eye, points, obj)
    return ~blocked


def footprint_polygon(obj: SceneObject):
    if obj.shape == "cylinder":
        return Point(obj.X_SO[0, 3], obj.X_SO[1, 3]).buffer(obj.size[0] / 2, quad_segs=64)
    half = np.asarray(obj.size[:2]) / 2
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half
    return Polygon(corners @ obj.X_SO[:2, :2].T + obj.X_SO[:2, 3])


def dense_box_points(size, center, spacing=0.0025) -> np.ndarray:
    """Points on every face of an axis-aligned box but the bottom."""
    half = np.asarray(size) / 2
    pts = []
    for axis in range(3):
        for sign in (-1, 1):
            if axis == 2 and sign < 0:
                continue
            u, v = [a for a in range(3) if a != axis]
            gu, gv = np.meshgrid(
                np.linspace(-half[u], half[u], max(2, math.ceil(size[u] / spacing) + 1)),
                np.linspace(-half[v], half[v], max(2, math.ceil(size[v] / spacing) + 1)),
            )
            face = np.zeros((gu.size, 3))
            face[:, u], face[:, v], face[:, axis] = gu.ravel(), gv.ravel(), sign * half[axis]
            pts.append(face)
    return np.concatenate(pts) + center
