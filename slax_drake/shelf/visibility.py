"""The target's visibility as a union of per-object occlusions, for the oracles' goal test and heuristic.

:func:`slax_drake.scene.sampling.target_visible_fraction` counts the target's surface points (``spacing``
apart, shelf frame S, metres) that the camera sees, among those it would see with the shelf holding the target
alone (the set U). A point of U is hidden exactly when the segment from the eye to it meets some object, so the
hidden set of a state is the union over objects of the points each object hides on its own. Each object's
hidden set depends only on its own pose; :class:`TargetOcclusion` caches it as a bitset (a Python int over U)
keyed by the object's name and pose, so the visible fraction of any state the oracle reaches costs a few ORs.

An object whose overhead footprint does not meet the convex hull of the eye's (x, y) and the target's
footprint hides nothing (every eye-to-target segment projects inside that hull), so it is not ray cast.
Objects lower than the line of sight are ray cast and hide nothing: the test is 3D, not overhead.
"""

from __future__ import annotations

import itertools

import numpy as np
from shapely.geometry import MultiPoint

from slax_drake.caches import IdentityMemo
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.surface import box_surface_points


class TargetOcclusion:
    """Per-object hidden-point bitsets of one scene's target (the shelf, camera and target never move)."""

    def __init__(self, scene, spacing: float = 0.005, threshold: float = 0.80):
        if scene.target is None:
            raise ValueError("the scene has no target")
        self.scene = scene
        self.threshold = threshold
        points, _ = box_surface_points(tuple(scene.target.size), spacing)
        points = points + scene.target.center
        self.eye = scene.camera.position
        unoccluded = SceneRaycaster(scene, include_target=True, objects=()).visible(self.eye, points)
        self.points = points[unoccluded]
        self.n = int(len(self.points))
        t = Footprint.of(scene.target.as_object())
        hull_pts = [tuple(self.eye[:2])] + [tuple(c) for c in t.corners()]
        self.hull = MultiPoint(hull_pts).convex_hull
        self._weights = 1 << np.arange(self.n, dtype=object) if self.n else np.zeros(0, dtype=object)
        self._cache: dict = {}
        self._bits_of = IdentityMemo(self._bits_by_pose, limit=200_000)  # a search passes the same objects again
        self.raycasts = 0

    def hidden_bits(self, obj) -> int:
        """The points of U that ``obj`` hides on its own, as a bitset."""
        return self._bits_of(obj)

    def _bits_by_pose(self, obj) -> int:
        key = (obj.name, round(float(obj.center[0]), 5), round(float(obj.center[1]), 5), round(obj.yaw, 5))
        bits = self._cache.get(key)
        if bits is not None:
            return bits
        bits = 0
        if self.n and Footprint.of(obj).polygon(16).intersects(self.hull):
            seen = SceneRaycaster(self.scene, include_target=True, objects=(obj,)).visible(self.eye, self.points)
            self.raycasts += 1
            hidden = np.flatnonzero(~seen)
            bits = sum(1 << int(i) for i in hidden)
        self._cache[key] = bits
        return bits

    def visible_fraction(self, objects) -> float:
        """Equals ``target_visible_fraction`` of the scene holding ``objects`` (0 when U is empty)."""
        if not self.n:
            return 0.0
        union = 0
        for o in objects:
            union |= self.hidden_bits(o)
        return 1.0 - union.bit_count() / self.n

    def revealed(self, objects) -> bool:
        return self.n > 0 and self.visible_fraction(objects) >= self.threshold - 1e-12

    def min_objects_to_move(self, objects, cap: int = 3) -> int:
        """The fewest objects whose removal reveals the target (at most ``cap``; ``cap`` means "cap or more").

        A plan of k actions moves at most k objects and every object it leaves in place keeps hiding its
        points, so this never exceeds the number of actions still needed: an admissible A* heuristic."""
        if not self.n:
            return cap
        allowed = self.n - int(np.ceil(self.threshold * self.n - 1e-9))  # hidden points we may keep
        bits = [self.hidden_bits(o) for o in objects]
        occluders = [b for b in bits if b]
        total = 0
        for b in occluders:
            total |= b
        if total.bit_count() <= allowed:
            return 0
        m = len(occluders)
        for k in range(1, min(cap, m + 1)):
            for removed in itertools.combinations(range(m), k):
                union = 0
                for i in range(m):
                    if i not in removed:
                        union |= occluders[i]
                if union.bit_count() <= allowed:
                    return k
        return min(cap, m)
