"""Points sampled on a box target's surface, used for every visibility test of the target.

The target rests on the support surface, so its bottom face is never seen and is left out. Points lie on a
regular grid on each other face with spacing at most ``spacing`` (edges and corners included).
"""

from __future__ import annotations

import functools
import math

import numpy as np


@functools.lru_cache(maxsize=64)
def box_surface_points(size: tuple[float, float, float], spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Points (P, 3) and outward unit normals (P, 3) on a box centred at the origin, bottom face excluded."""
    half = np.asarray(size, dtype=float) / 2.0
    points, normals = [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            if axis == 2 and sign < 0:
                continue  # bottom face rests on the shelf
            u, v = [a for a in range(3) if a != axis]
            nu = max(2, math.ceil(size[u] / spacing) + 1)
            nv = max(2, math.ceil(size[v] / spacing) + 1)
            gu, gv = np.meshgrid(np.linspace(-half[u], half[u], nu), np.linspace(-half[v], half[v], nv))
            face = np.zeros((gu.size, 3))
            face[:, u], face[:, v], face[:, axis] = gu.ravel(), gv.ravel(), sign * half[axis]
            normal = np.zeros(3)
            normal[axis] = sign
            points.append(face)
            normals.append(np.broadcast_to(normal, face.shape))
    points = np.concatenate(points)
    normals = np.concatenate(normals)
    points.setflags(write=False)
    normals.setflags(write=False)
    return points, normals


def facing_points(points: np.ndarray, normals: np.ndarray, offset: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """The points whose face looks toward ``eye`` once the box is translated by ``offset`` (3,).

    A point on a face turned away from the eye is never the first surface point along its ray, so a box
    is completely hidden exactly when all of its eye-facing points are hidden."""
    keep = np.einsum("ij,ij->i", normals, eye - (points + offset)) > 0.0
    return points[keep] + offset
