"""Objects remembered across camera frames: the estimator's per-frame hypotheses associated with tracked objects.

A segmentation numbers its segments anew in every frame, so ``segment_<id>`` says nothing about which object a
hypothesis is from one frame to the next. :class:`ObjectTracker` keeps one track per object seen in this trial and
gives each a stable name (``track_<k>``, numbered by first sighting; distinct from the true objects'
``object_<k>``), so that logs, step figures, trial records and the policies' memory of arrangements name the same
object the same way across frames.

Per frame (:meth:`ObjectTracker.update`), with the action executed since the last frame (if any):

1. Prediction. Every track stands where it was last estimated, except the one the action moved: it is expected
   anywhere on the commanded path between where it stood and where the action model predicts it (a push or a
   placement may stop early on something unseen; a refused placement puts it back).
2. Association. A hypothesis and a track of the same shape are compared by their visible front: the footprint's
   x centre and its front face's y (the depth the camera measures; the unseen depth behind it is a prior and
   may differ between frames). The cost is the distance (m) between the two fronts, for the moved track the
   distance to its commanded path; pairs further apart than ``gate`` (m) do not match. The pairs are chosen by
   least total cost (one-to-one). Then a hypothesis left unmatched whose footprint overlaps an unmatched,
   unmoved track's (same shape) by more than ``overlap_share`` of the smaller one is that object (its estimate changed between
   frames: another yaw fitted, a face seen anew). Last, when nothing matched the moved track, a hypothesis left
   unmatched (same shape) that overlaps its footprint swept along the commanded path by more than ``overlap_share``
   is that object: physics turned it or moved it deeper than the gate allows (a push that slid; Table I 10:15 in
   Drake, where the pushed box came out 5.5 cm from its path, turned 9 deg, and was named anew).
3. Update. A matched track takes the hypothesis's estimate and name; its uncertainty (m) is the frame's. An
   unmatched hypothesis starts a new track. An unmatched track is hidden: it keeps its last estimate, flagged
   ``remembered``, and its uncertainty grows to cover the commanded path when the action moved it. A hidden
   track that the frame contradicts -- the frame sees past its surface (deeper by ``see_through`` m) on more
   than half of the pixels where it would show were it alone on the shelf -- is dropped: it is not there.
4. With ``fuse_extents``: a box track matched and not moved since its last estimate keeps what earlier frames
   showed of it. Its new estimate is the least rectangle, in the new estimate's axes, holding both footprints,
   when the two yaws agree within ``FUSE_YAW`` (modulo a quarter turn) and they overlap by at least half of the
   new one: what the camera saw of an object stays part of it when another object is placed in front of it and
   the frame shows less (in the camera-mode Table I trials at 10 objects, 6 % of such estimates lost more than
   1 cm^2 of footprint from one frame to the next, a median of 12 cm^2).

Positions in the shelf frame S (x right, y into the shelf; metres). Deterministic; the state is plain data
(:meth:`ObjectTracker.to_dict`, :meth:`ObjectTracker.from_dict`) so that a caller that sees one frame per process
(``plan-step``) can carry it between calls.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import SceneObject

FUSE_YAW = np.radians(3.0)  # fuse_extents: the most two estimates' yaws may differ (modulo a quarter turn)
PREFIX = "track_"  # the stable names: track_1, track_2, ... in order of first sighting (true objects are object_<k>)


@dataclasses.dataclass
class Track:
    """One tracked object: its stable ``name``, the last estimate ``object`` (a SceneObject named ``name``),
    ``uncertainty`` (m, the radius within which its position is known), ``hidden`` (not seen in the last frame),
    ``frames`` seen so far, ``mass`` (kg) once the arm weighed it (:meth:`ObjectTracker.weighed`; None before)."""

    name: str
    object: SceneObject
    uncertainty: float = 0.0
    hidden: bool = False
    frames: int = 1
    mass: float | None = None


def _front(o: SceneObject) -> np.ndarray:
    """The visible front of ``o``: (x centre, y of the face nearest the camera) in S, metres."""
    fp = Footprint.of(o)
    _, ey = fp.extents()
    return np.array([fp.x, fp.y - ey])


def _to_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    n = float(ab @ ab)
    t = 0.0 if n <= 1e-18 else min(1.0, max(0.0, float((p - a) @ ab) / n))
    return float(np.linalg.norm(p - (a + t * ab)))


def _swept(o: SceneObject, displacement: np.ndarray):
    """The footprint of ``o`` swept along ``displacement`` (dx, dy) m: a shapely polygon in S."""
    from shapely import affinity

    poly = Footprint.of(o).polygon()
    return poly.union(affinity.translate(poly, float(displacement[0]), float(displacement[1]))).convex_hull


def commanded_displacement(action, obj: SceneObject) -> tuple[float, float]:
    """(dx, dy) m: where ``action`` sends ``obj`` (a push, with ``d``: along x by ``d``; a suction, with ``dx`` and
    ``dz``: by ``dx`` along x, to depth y = ``dz``); (0, 0) for anything else."""
    if hasattr(action, "d"):
        return float(action.d), 0.0
    if hasattr(action, "dx") and hasattr(action, "dz"):
        return float(action.dx), float(action.dz) - float(obj.center[1])
    return 0.0, 0.0


class ObjectTracker:
    """See the module docstring. ``gate`` (m): the farthest a hypothesis's front may stand from a track's
    predicted front and still be that object; ``overlap_share``: the footprint overlap (a share of the smaller
    footprint) that makes an otherwise unmatched hypothesis the object of an unmatched, unmoved track;
    ``see_through`` (m): how far past a hidden track's surface the frame must see to contradict it."""

    def __init__(self, gate: float = 0.04, see_through: float = 0.01, overlap_share: float = 0.2,
                 fuse_extents: bool = False):
        self.gate = float(gate)
        self.fuse_extents = bool(fuse_extents)
        self.overlap_share = float(overlap_share)
        self.see_through = float(see_through)
        self.reset()

    def reset(self) -> None:
        self.tracks: dict[str, Track] = {}
        self.next_id = 1
        self.frames = 0

    # ---- per frame -------------------------------------------------------------------------------------------
    def update(self, hypotheses, action=None, frame=None, template=None) -> list:
        """The hypotheses of this frame renamed to their tracks' names (new tracks for new objects), in the
        order given. ``action``: the action executed since the last frame, named by a track (None: nothing moved
        or unknown). ``frame`` (an Observation) and ``template`` (a Scene with the shelf): when given, hidden
        tracks the frame contradicts are dropped (module docstring). Each element of ``hypotheses`` is an
        estimator Hypothesis (its ``object`` is renamed) or a SceneObject."""
        items = list(hypotheses)
        objs = [h.object if hasattr(h, "object") else h for h in items]
        names = sorted(self.tracks)
        moved = self.tracks.get(action.name) if action is not None else None
        path = {}
        if moved is not None:
            a = _front(moved.object)
            dx, dy = commanded_displacement(action, moved.object)
            path[moved.name] = (a, a + np.array([dx, dy]))
        cost = np.full((len(objs), len(names)), np.inf)
        for i, o in enumerate(objs):
            f = _front(o)
            for j, n in enumerate(names):
                t = self.tracks[n]
                if t.object.shape != o.shape:
                    continue
                if n in path:
                    d = _to_segment(f, *path[n])
                else:
                    d = float(np.linalg.norm(f - _front(t.object)))
                if d <= self.gate + t.uncertainty:
                    cost[i, j] = d
        pairs = _assign(cost)
        out_names = [None] * len(objs)
        for i, j in pairs:
            out_names[i] = names[j]
        # a second pass: an estimate that changed much between frames (another yaw, a face seen anew) still stands
        # where an unmatched track stood; the footprints overlapping by more than ``overlap_share`` of the
        # smaller one make them the same object (the unmoved tracks only: the moved one was judged on its path)
        free = [j for j in range(len(names)) if names[j] not in out_names and names[j] not in path]
        for i, o in enumerate(objs):
            if out_names[i] is not None or not free:
                continue
            poly = Footprint.of(o).polygon()
            best, share = None, self.overlap_share
            for j in free:
                if self.tracks[names[j]].object.shape != o.shape:
                    continue
                q = Footprint.of(self.tracks[names[j]].object).polygon()
                common = poly.intersection(q).area / max(1e-12, min(poly.area, q.area))
                if common > share:
                    best, share = j, common
            if best is not None:
                out_names[i] = names[best]
                free.remove(best)
        # a third pass, for the moved track when nothing matched it on its path: physics may have turned it or
        # carried it deeper or shallower than the gate allows (a push that slid); an unmatched hypothesis of its
        # shape whose footprint overlaps the footprint swept along the commanded path (by more than
        # ``overlap_share`` of the smaller) is that object
        for n in path:
            if n in out_names:
                continue
            swept = _swept(self.tracks[n].object, path[n][1] - path[n][0])
            best, share = None, self.overlap_share
            for i, o in enumerate(objs):
                if out_names[i] is not None or o.shape != self.tracks[n].object.shape:
                    continue
                poly = Footprint.of(o).polygon()
                common = poly.intersection(swept).area / max(1e-12, min(poly.area, swept.area))
                if common > share:
                    best, share = i, common
            if best is not None:
                out_names[best] = n
        seen = set()
        for i, o in enumerate(objs):
            name = out_names[i]
            if self.fuse_extents and name is not None and name not in path:
                fused = fused_box(self.tracks[name].object, o)
                if fused is not None:
                    objs[i] = o = fused
            if name is None:
                name = f"{PREFIX}{self.next_id}"
                self.next_id += 1
                self.tracks[name] = Track(name, o, 0.0, False, 0)
                out_names[i] = name
            t = self.tracks[name]
            t.object = dataclasses.replace(o, name=name, remembered=False, mass=o.mass if t.mass is None else t.mass)
            t.uncertainty = _uncertainty_of(items[i])
            t.hidden = False
            t.frames += 1
            seen.add(name)
        for n in names:
            if n in seen:
                continue
            t = self.tracks[n]
            t.hidden = True
            t.object = dataclasses.replace(t.object, remembered=True)
            if n in path:  # moved and not seen since: it stands somewhere along the commanded path
                a, b = path[n]
                t.uncertainty = max(t.uncertainty, float(np.linalg.norm(b - a)))
        if frame is not None and template is not None:
            self._drop_contradicted(frame, template)
        self.frames += 1
        out = []
        for h, o, name in zip(items, objs, out_names):
            mass = self.tracks[name].mass
            if hasattr(h, "object"):
                out.append(dataclasses.replace(h, object=dataclasses.replace(o, name=name, mass=o.mass if mass is None
                                                                             else mass)))
            else:
                out.append(dataclasses.replace(o, name=name, mass=o.mass if mass is None else mass))
        return out

    def weighed(self, name: str, mass: float) -> None:
        """The arm weighed track ``name``: from the next frame on its hypotheses carry ``mass`` (kg), which the
        action model reckons its held moment and drag with instead of its class's median."""
        t = self.tracks[name]
        t.mass = float(mass)
        t.object = dataclasses.replace(t.object, mass=t.mass)

    def _drop_contradicted(self, frame, template) -> None:
        from slax_drake.scene.raycast import SceneRaycaster

        for n in sorted(self.tracks):
            t = self.tracks[n]
            if not t.hidden:
                continue
            depth, labels = SceneRaycaster(template.with_objects((t.object,))).render(frame.camera)
            pixels = labels == 1
            if pixels.any() and (frame.depth[pixels] > depth[pixels] + self.see_through).mean() > 0.5:
                del self.tracks[n]

    # ---- queries ---------------------------------------------------------------------------------------------
    def hidden(self) -> tuple:
        """The hidden tracks' last estimates (SceneObjects flagged ``remembered``), by name."""
        return tuple(self.tracks[n].object for n in sorted(self.tracks) if self.tracks[n].hidden)

    def uncertainty(self, name: str) -> float:
        return self.tracks[name].uncertainty

    # ---- state -----------------------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The tracker's state as JSON-ready data (:meth:`from_dict` restores it)."""
        tracks = []
        for n in sorted(self.tracks):
            t = self.tracks[n]
            o = t.object
            tracks.append({"name": n, "shape": o.shape, "size": [float(v) for v in o.size],
                           "x": float(o.center[0]), "y": float(o.center[1]), "z": float(o.center[2]),
                           "yaw": float(o.yaw),
                           "uncertainty": t.uncertainty, "hidden": t.hidden, "frames": t.frames,
                           **({"mass": t.mass} if t.mass is not None else {})})
        return {"next_id": self.next_id, "frames": self.frames, "tracks": tracks,
                "gate": self.gate, "see_through": self.see_through, "overlap_share": self.overlap_share,
                "fuse_extents": self.fuse_extents}

    @classmethod
    def from_dict(cls, doc: dict) -> "ObjectTracker":
        from slax_drake.scene.model import planar_pose

        tracker = cls(gate=float(doc.get("gate", 0.04)), see_through=float(doc.get("see_through", 0.01)),
                      overlap_share=float(doc.get("overlap_share", 0.2)),
                      fuse_extents=bool(doc.get("fuse_extents", False)))
        tracker.next_id = int(doc.get("next_id", 1))
        tracker.frames = int(doc.get("frames", 0))
        for t in doc.get("tracks", []):
            size = tuple(float(v) for v in t["size"])
            X = planar_pose(float(t["x"]), float(t["y"]), float(t.get("z", size[2] / 2)), float(t["yaw"]))
            mass = None if t.get("mass") is None else float(t["mass"])
            o = SceneObject(t["name"], t["shape"], size, X, remembered=bool(t["hidden"]), mass=mass)
            tracker.tracks[t["name"]] = Track(t["name"], o, float(t["uncertainty"]), bool(t["hidden"]),
                                              int(t["frames"]), mass)
        return tracker


def fused_box(old: SceneObject, new: SceneObject) -> SceneObject | None:
    """``new`` grown to the least rectangle, in its own axes, that holds both its footprint and ``old``'s (the same
    unmoved box estimated in an earlier frame), at ``new``'s height; None when either is not a box, their yaws
    differ by more than :data:`FUSE_YAW` modulo a quarter turn, they overlap by less than half of ``new``'s
    footprint, or ``old`` adds nothing (under 0.5 mm on every side)."""
    if old.shape != "box" or new.shape != "box":
        return None
    turn = (new.yaw - old.yaw) % (np.pi / 2)
    if min(turn, np.pi / 2 - turn) > FUSE_YAW:
        return None
    p_old, p_new = Footprint.of(old).polygon(), Footprint.of(new).polygon()
    if p_old.intersection(p_new).area < 0.5 * p_new.area:
        return None
    c, s = np.cos(new.yaw), np.sin(new.yaw)
    axes = np.array([[c, s], [-s, c]])
    along_new = np.asarray(p_new.exterior.coords) @ axes.T
    along_both = np.vstack([along_new, np.asarray(p_old.exterior.coords) @ axes.T])
    lo, hi = along_both.min(axis=0), along_both.max(axis=0)
    if np.all(lo >= along_new.min(axis=0) - 5e-4) and np.all(hi <= along_new.max(axis=0) + 5e-4):
        return None
    from slax_drake.scene.model import planar_pose

    mid = axes.T @ ((lo + hi) / 2)
    size = (float(hi[0] - lo[0]), float(hi[1] - lo[1]), float(new.size[2]))
    return dataclasses.replace(new, size=size, X_SO=planar_pose(float(mid[0]), float(mid[1]), float(new.center[2]),
                                                                new.yaw))


def _uncertainty_of(h) -> float:
    """The position uncertainty (m) of a hypothesis: the estimator's front-face interval's half width when known."""
    u = getattr(h, "uncertainty", None)
    front = getattr(u, "front_y", None)
    if front is not None:
        try:
            lo, hi = front
            return float(abs(hi - lo) / 2)
        except (TypeError, ValueError):
            return 0.0
    return 0.0


def _assign(cost: np.ndarray) -> list[tuple[int, int]]:
    """Pairs (row, column) of least total cost among the finite entries, one-to-one."""
    if cost.size == 0 or not np.isfinite(cost).any():
        return []
    from scipy.optimize import linear_sum_assignment

    big = 1e6
    c = np.where(np.isfinite(cost), cost, big)
    rows, cols = linear_sum_assignment(c)
    return [(int(i), int(j)) for i, j in zip(rows, cols) if np.isfinite(cost[i, j])]
