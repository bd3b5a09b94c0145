"""How deep the camera sees into the shelf in each image column, from the objects' footprints: what the no-shuttle
correction asks when it lets a move back pass only if it "reveals space no earlier arrangement revealed".

Top view at the target's mid height: each object is a prism standing on the shelf floor, so at that height it is
its footprint. Its outline is sampled every ``spacing`` (m) at height ``height`` (m, shelf frame S) and projected
into a coarse camera; per image column the nearest sample's depth along the optical axis (m, camera frame C) is
where the camera's view of the shelf stops in that column. A column no object meets is seen to the back panel
(``inf``).

Across a trial the deepest view each column has had (:class:`DeepestView`) says which space some arrangement has
shown; a move that would let a column see deeper than that, by more than ``tolerance``, shows space never shown.
Unlike the footprint's own x extent (what :meth:`~slax_drake.policies.trial_memory.TrialMemory.vacates_unseen`
reads), this knows that the space behind an object moved far away was shown when it stood elsewhere, and that the
space behind another object it leaves in front of was never shown: it counts what every seen object hides.
"""

from __future__ import annotations

import numpy as np

from slax_drake.scene.footprint import Footprint


class SightDepths:
    """Per column of ``camera`` at ``width`` px, the depth (m) at which the view stops at height ``height`` (m)."""

    def __init__(self, camera, width: int = 160, height: float = 0.03, spacing: float = 0.002):
        rows = max(1, int(round(camera.height * width / camera.width)))
        self.camera = camera.with_resolution(width, rows)
        self.width = width
        self.height = height
        self.spacing = spacing
        self._cache: dict = {}  # (shape, x, y, yaw, size) -> (columns, depths) of one object's outline

    def _outline(self, obj) -> tuple[np.ndarray, np.ndarray]:
        """(columns, depths) of ``obj``'s outline samples that fall inside the image."""
        key = (obj.shape, round(float(obj.center[0]), 4), round(float(obj.center[1]), 4),
               round(float(obj.yaw), 4), tuple(round(float(v), 4) for v in obj.size))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        fp = Footprint.of(obj)
        if fp.shape == "cylinder":
            n = max(16, int(np.ceil(2 * np.pi * fp.half_x / self.spacing)))
            t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
            xy = np.column_stack([fp.x + fp.half_x * np.cos(t), fp.y + fp.half_x * np.sin(t)])
        else:
            corners = np.asarray(fp.corners(), float)
            parts = []
            for a, b in zip(corners, np.roll(corners, -1, axis=0)):
                n = max(2, int(np.ceil(np.linalg.norm(b - a) / self.spacing)))
                s = np.linspace(0.0, 1.0, n, endpoint=False)[:, None]
                parts.append(a + s * (b - a))
            xy = np.concatenate(parts)
        points = np.column_stack([xy, np.full(len(xy), self.height)])
        p_C = self.camera.to_camera(points)
        z = p_C[:, 2]
        u = np.floor(self.camera.fx * p_C[:, 0] / np.maximum(z, 1e-9) + self.camera.cx).astype(int)
        keep = (z > 0) & (u >= 0) & (u < self.width)
        out = (u[keep], z[keep])
        if len(self._cache) > 4096:
            self._cache.clear()
        self._cache[key] = out
        return out

    def of(self, objects) -> np.ndarray:
        """(width,) float64: per column, the depth (m) of the nearest object outline; ``inf`` where none."""
        depth = np.full(self.width, np.inf)
        for obj in objects:
            u, z = self._outline(obj)
            np.minimum.at(depth, u, z)
        return depth

    def column_width(self, depth: np.ndarray) -> np.ndarray:
        """The width (m) one column spans at ``depth`` (m)."""
        return np.asarray(depth, float) / self.camera.fx


class DeepestView:
    """The deepest view (m) each column has had over the arrangements observed in a trial (:meth:`observe`), and
    the width of the space a new arrangement would show for the first time (:meth:`newly_shown`).

    An object seen in an earlier arrangement and not among the objects of a new one (hidden behind another now,
    and not remembered by the policy) is taken to stand where it was last seen: the robot moves only what it sees.
    Without that, moving its occluder away again would "show" the space it stands in as if empty, every time."""

    def __init__(self, sight: SightDepths, tolerance: float = 0.01):
        self.sight = sight
        self.tolerance = tolerance
        self.deepest: np.ndarray | None = None
        self.last_seen: dict = {}  # object name -> the object where it was last observed

    def observe(self, objects) -> None:
        objects = tuple(objects)
        view = self.sight.of(objects)
        self.deepest = view if self.deepest is None else np.maximum(self.deepest, view)
        self.last_seen.update((o.name, o) for o in objects)

    def newly_shown(self, objects) -> float:
        """The width (m, at the depth where each column's deepest view so far stopped) of the columns in which the
        arrangement ``objects`` (with the objects seen before and absent from it where they were last seen) would
        let the camera see more than ``tolerance`` deeper than any observed one."""
        if self.deepest is None:
            return float("inf")
        objects = tuple(objects)
        names = {o.name for o in objects}
        view = self.sight.of(objects + tuple(o for name, o in self.last_seen.items() if name not in names))
        new = np.isfinite(self.deepest) & (view > self.deepest + self.tolerance)
        return float(self.sight.column_width(self.deepest[new]).sum())
