"""slax-hindsight (ours): hindsight optimisation over sampled target placements with a one-move lookahead.

The oracles, which read the full state, nearly always reveal the target while the distribution policies stay far
lower: what they miss is the target's position, not mobility. This policy reads only the PolicyObservation (the seen
objects; never the target) and determinises the unknown, as in hindsight optimisation:

1. Where the target may stand (:func:`possible_placements`): the lattice placements (``grid_step``) of the target
   box clear of the seen objects and wholly hidden at the first observation (the scene generator hides it), seen
   less than the threshold v at each later one (else the trial would have ended), intersected over the trial's
   observations (the target does not move: the 2D form of the history encoding P'_t).
2. ``samples`` of them (stratified along x, drawn by a generator seeded with the scene seed and the step: a
   rollout is a function of the scene) are the worlds (:class:`Worlds`), evaluated together: for an arrangement
   of the seen objects, which worlds' target is seen at v (per-object occlusion masks of the target's surface
   points, cached per object pose), and which worlds' target a moved object would run into.
3. The candidates are Bluction-DAR's (with its corrections), suctions only those whose ways out and in and
   placement stay in space the camera has seen (``safe_suctions``). ``scoring="hindsight"`` (the default): per
   world w, a leaf value L_w(s) of an arrangement s: 0 when the target is seen at v, 1 when taking one object
   away would show it, F = ``failure_cost`` otherwise. Every candidate gets Q(a) = c(a) + mean_w L_w(after a);
   the ``shortlist`` best are looked at one move further, each world taking its own best next move b
   (hindsight): Q(a) = c(a) + mean_w min(L_w(after a), min_b [c(b) + L_w(after a, b)]) over the moves b
   (pushes up to the neighbour, safe suctions). ``scoring="reveal"``: Q(a) = c(a) + (1 - p_a) F, p_a the share
   of worlds a reveals, and one move further c(a) + (1 - p_a) min_b [c(b) + (1 - p_b|a) F], one b for all
   worlds a did not reveal. Pushes cost 1, suctions psi; a world where the moved object runs into the target
   counts the action as wasted. The least Q wins; ties keep Bluction-DAR's order.

No random number is drawn but from the seeded generator, and no limit depends on the clock but ``seconds``, a
safety cap per decision (CPU seconds): when reached, the candidates not yet looked at further are left out
(``decision_log`` records it per decision). Unseen objects are not in the worlds; an action they stop is
excluded by the corrections, and the next decision samples again.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from slax_drake.shelf.actions import Push, Suction, apply_action
from slax_drake.policies.policies import BluctionDAR
from slax_drake.policies.protocol import Decision
from slax_drake.scene.model import state_key


class Hindsight(BluctionDAR):
    """See the module docstring. Options: ``samples`` (worlds per decision), ``shortlist`` (candidates looked at one
    move further), ``failure_cost`` (F), ``safe_suctions``, ``scoring``, ``seconds`` (the per-decision safety cap, CPU s),
    ``grid_step`` (m, the placement lattice), ``threshold`` (v; the registry passes the scenario's)."""

    name = "slax-hindsight"
    uses_visibility_threshold = True

    def __init__(self, *args, samples: int = 64, shortlist: int = 6, seconds: float = 3.0,
                 grid_step: float = 0.01, threshold: float = 0.80, failure_cost: float = 3.0,
                 safe_suctions: bool = True, scoring: str = "hindsight", **kwargs):
        kwargs.setdefault("corrected", True)
        kwargs.setdefault("suction_weighting", "paper")
        super().__init__(*args, **kwargs)
        self.samples = samples
        self.shortlist = shortlist
        if scoring not in ("hindsight", "reveal"):
            raise ValueError("scoring must be 'hindsight' or 'reveal'")
        self.scoring = scoring
        self.seconds = seconds
        self.grid_step = grid_step
        self.threshold = threshold
        self.failure_cost = failure_cost
        self.decision_log: list[dict] = []
        self._consistent: set | None = None
        self._step = 0
        self._moves: dict = {}  # state -> its moves on the seen objects, for the whole trial
        self.safe_model = None  # the suctions it uses: way out, way in and placement in seen space only
        if safe_suctions:
            model = self.action_model
            rules = dataclasses.replace(model.tool.rules, suction_hidden_rule="path")
            self.safe_model = model.with_tool(dataclasses.replace(model.tool, rules=rules))

    def reset(self, scene_or_observation=None) -> None:
        super().reset(scene_or_observation)
        self.decision_log = []
        self._consistent = None
        self._step = 0
        self._moves = {}

    # ---- the target's possible placements ---------------------------------------------------------------------
    def target_size(self) -> tuple:
        return tuple(getattr(self.distribution, "target_size", (0.06, 0.06, 0.06)))

    def placements(self, obs) -> np.ndarray:
        """(K, 2) lattice placements (x, y) where the target may stand: at every observation of this trial so far it
        stood clear of the seen objects and was seen less than the threshold (:func:`possible_placements`)."""
        scene = obs.scene_template.with_objects(obs.known)
        # The first observation: the scene generator hides the target wholly (paper Sec. V-A, our sampler too);
        # later ones: a target seen at the threshold would have ended the trial.
        first = self._consistent is None
        now = possible_placements(scene, self.target_size(), self.grid_step, 1e-9 if first else self.threshold)
        keys = set(self.lattice_keys(now))
        self._consistent = keys if self._consistent is None else (self._consistent & keys)
        if not self._consistent:
            self._consistent = keys  # the seen objects' estimate moved: start the intersection again
        return np.array(sorted(self._consistent), dtype=float).reshape(-1, 2) * self.grid_step

    @property
    def consistent_placements(self) -> frozenset:
        """The lattice keys (i, j) of the target placements still consistent with every observation of the trial
        (placement centre (i, j) * ``grid_step`` in the shelf frame S, metres); empty before the first decision."""
        return frozenset(self._consistent or ())

    def lattice_keys(self, placements) -> list[tuple[int, int]]:
        """The lattice indices (x / grid_step, y / grid_step, rounded) of (x, y) placements (m), in their order."""
        step = self.grid_step
        return [(int(round(x / step)), int(round(y / step))) for x, y in placements]

    def draw(self, placements: np.ndarray, seed: int) -> np.ndarray:
        """``samples`` placements, one per equal-count stratum along x (then y), by a generator seeded with ``seed``
        and the step."""
        rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, self._step])
        order = np.lexsort((placements[:, 1], placements[:, 0]))
        k = min(self.samples, len(placements))
        bounds = np.linspace(0, len(placements), k + 1).astype(int)
        picks = [order[rng.integers(lo, hi)] for lo, hi in zip(bounds[:-1], bounds[1:]) if hi > lo]
        return placements[picks]

    # ---- scoring -----------------------------------------------------------------------------------------------
    def cost(self, action) -> float:
        return 1.0 if isinstance(action, Push) else self.psi

    def rank(self, obs) -> Decision:
        t0 = time.process_time()
        prior = super().rank(obs)
        self._step += 1
        if not prior.candidates:
            return prior
        placements = self.placements(obs)
        log = {"placements": int(len(placements)), "samples": 0, "scored": 0, "capped": False}
        self.decision_log.append(log)
        if not len(placements):
            return prior
        template = obs.scene_template
        seed = template.seed if template.seed is not None else 0
        known = tuple(obs.known)
        worlds = Worlds(template, self.draw(placements, seed), self.target_size(), self.threshold)
        log["samples"] = worlds.count
        cands = list(prior.candidates)
        alive = np.ones(worlds.count, dtype=bool)  # the worlds still possible: all, before any action

        def step(objects, a, after, possible):
            """(probability that ``a`` reveals the target among ``possible`` worlds, the worlds where it does not)."""
            revealed = worlds.revealed(after) & ~worlds.blocks(after, a.name) & possible
            n = possible.sum()
            return (revealed.sum() / n if n else 0.0), possible & ~revealed

        if self.scoring == "hindsight":
            return self.rank_hindsight(prior, known, worlds, log, t0)
        scored = []  # [Q, order in the prior, action, objects after, worlds left]
        for order, a in enumerate(cands):
            after = apply_action(known, a)
            p, left = step(known, a, after, alive)
            scored.append([self.cost(a) + (1.0 - p) * self.failure_cost, order, a, after, left, p])
        scored.sort(key=lambda e: e[:2])
        for entry in scored[: self.shortlist]:  # the most promising first moves, one move further
            if time.process_time() - t0 > self.seconds:
                log["capped"] = True
                break
            a, after, left, p = entry[2], entry[3], entry[4], entry[5]
            if p >= 1.0 or not left.any():
                log["scored"] += 1
                continue
            best_rest = self.failure_cost
            for b, after_b, c in self.moves(after):
                if c >= best_rest:
                    continue
                p_b, _ = step(after, b, after_b, left)
                best_rest = min(best_rest, c + (1.0 - p_b) * self.failure_cost)
            entry[0] = self.cost(a) + (1.0 - p) * best_rest
            log["scored"] += 1
        return self._ranked(scored, log, t0, cands)

    @staticmethod
    def _ranked(scored, log: dict, t0: float, cands) -> Decision:
        """The decision from ``scored`` ([score, tie-break, action] entries, the first ``log["scored"]`` of them
        scored): the best scored action first, then every other candidate in its order; records the decision's CPU
        seconds since ``t0`` in ``log``."""
        top = scored[: max(log["scored"], 1)]
        top.sort(key=lambda e: e[:2])
        log["seconds"] = round(time.process_time() - t0, 3)
        best = top[0][2]
        return Decision((best, *(a for a in cands if a != best)))

    def leaf(self, worlds, objects, a=None, fallback=None) -> np.ndarray:
        """(K,) estimated cost still needed per world after ``objects``: 0 revealed, 1 when removing one object
        would reveal it, ``failure_cost`` otherwise; where ``a``'s moved object runs into the world's target, the
        ``fallback`` values (the action is wasted there)."""
        revealed, one_away = worlds.distance(objects)
        v = np.where(revealed, 0.0, np.where(one_away, 1.0, self.failure_cost))
        if a is not None and fallback is not None:
            v = np.where(worlds.blocks(objects, a.name), fallback, v)
        return v

    def rank_hindsight(self, prior, known, worlds, log, t0) -> Decision:
        """Hindsight scoring: Q(a) = c(a) + mean over worlds of the world's own best continuation (each world
        picks its best next move b, min(leaf after a, c(b) + leaf after b)), for the ``shortlist`` candidates with
        the least one-step value c(a) + mean leaf after a."""
        cands = list(prior.candidates)
        now = self.leaf(worlds, known)
        scored = []
        for order, a in enumerate(cands):
            after = apply_action(known, a)
            v = self.leaf(worlds, after, a, now + self.cost(a))
            scored.append([self.cost(a) + float(v.mean()), order, a, after, v])
        scored.sort(key=lambda e: e[:2])
        for entry in scored[: self.shortlist]:
            if time.process_time() - t0 > self.seconds:
                log["capped"] = True
                break
            a, after, v = entry[2], entry[3], entry[4]
            best = v.copy()
            if (best > 0).any():
                for b, after_b, c in self.moves(after):
                    best = np.minimum(best, c + self.leaf(worlds, after_b, b, v + c))
            entry[0] = self.cost(a) + float(best.mean())
            log["scored"] += 1
        return self._ranked(scored, log, t0, cands)

    def safe_suctions(self, objects) -> set | None:
        """The suctions whose ways out and in and whose placement stay in space the camera has seen (None: every
        suction of the profile is used). In the paper profile a placement may enter hidden space, where an unseen
        object stops it and the object is put back: a wasted action."""
        if self.safe_model is None:
            return None
        return set(self.safe_model.enumerate(objects, pushes=False, suctions=True).feasible)

    def candidates(self, objects, pushes=None, suctions=None):
        """Bluction-DAR's candidates (exclusions and no return applied), suctions only the safe ones; all of them
        when that leaves none."""
        base = super().candidates(objects, pushes, suctions)
        safe = self.safe_suctions(objects)
        if safe is None:
            return base
        kept = [a for a in base if not isinstance(a, Suction) or a in safe]
        return kept or base

    def moves(self, objects) -> list:
        """(action, objects after, cost) of every move from ``objects`` on the seen objects (pushes up to the
        neighbour, as the oracles'; every suction placement), cached for the trial."""
        key = state_key(objects)
        hit = self._moves.get(key)
        if hit is None:
            from slax_drake.policies.oracle_search import maximal_pushes_only

            found = maximal_pushes_only(self.action_model.enumerate(objects, pushes=True, suctions=True).feasible)
            safe = self.safe_suctions(objects)
            if safe is not None:
                found = [a for a in found if not isinstance(a, Suction) or a in safe]
            hit = self._moves[key] = [(a, apply_action(objects, a), self.cost(a)) for a in found]
        return hit


class Worlds:
    """The sampled target placements as worlds, evaluated together: which of them an arrangement of the seen
    objects reveals (the target there seen at the threshold), and which of them a moved object runs into."""

    def __init__(self, template, centers: np.ndarray, size, threshold: float, spacing: float = 0.02):
        from slax_drake.scene.raycast import SceneRaycaster
        from slax_drake.scene.surface import box_surface_points

        self.template, self.size, self.threshold = template, tuple(size), threshold
        self.centers = np.asarray(centers, dtype=float).reshape(-1, 2)
        self.count = len(self.centers)
        points, normals = box_surface_points(self.size, spacing)
        offsets = np.column_stack([self.centers, np.full(self.count, self.size[2] / 2.0)])
        self.points = points[None, :, :] + offsets[:, None, :]  # (K, P, 3) in the shelf frame (m)
        self.eye = np.asarray(template.camera.position, dtype=float)
        facing = np.einsum("pj,kpj->kp", normals, self.eye - self.points) > 0.0
        self.shown = facing & SceneRaycaster(template, objects=()).visible(self.eye, self.points)
        self.n_shown = self.shown.sum(axis=1)
        # (K, P): the bearing (rad) of each point seen from above, from the eye: atan2(dx, dy), dy > 0 (the points
        # stand in the shelf, the eye in front of it)
        self.bearing = np.arctan2(self.points[..., 0] - self.eye[0], self.points[..., 1] - self.eye[1])
        self._revealed: dict = {}
        self._hidden: dict = {}

    def hidden_by(self, obj) -> np.ndarray:
        """(K, P) bool: the target points of each world that ``obj`` alone hides (cached per object pose); a point is
        hidden past several objects exactly when one of them hides it, so a state's masks are OR-ed."""
        key = state_key((obj,))[0]
        hit = self._hidden.get(key)
        if hit is None:
            from slax_drake.scene.raycast import SceneRaycaster

            # rays only to the points the empty shelf shows: the others are not hidden by anything (each ray is
            # cast on its own, so its result does not depend on which other rays are cast); and against the object
            # alone: the shelf hides none of those points (its first hit along such a ray lies no nearer than the
            # point less VISIBILITY_EPS), so the ray's first hit before that, if any, is the object's
            worlds, points = np.nonzero(self.shown & self.in_bearing_of(obj))
            hit = np.zeros_like(self.shown)
            if len(worlds):
                hit[worlds, points] = ~SceneRaycaster(self.template, objects=(obj,), shelf=False).visible(
                    self.eye, self.points[worlds, points])
            self._hidden[key] = hit
        return hit

    def in_bearing_of(self, obj, margin: float = 0.002) -> np.ndarray:
        """(K, P) bool: the points whose ray from the eye could meet ``obj``. Seen from above, a ray is a segment
        from the eye along its point's bearing, and the object's mesh (the triangles the rays are cast against) lies
        in the axis-aligned box of its vertices; that box, grown by ``margin`` (m, far more than Embree's float32
        error), lies beyond the eye and spans the bearings between its corners' least and greatest. A ray outside
        them passes beside the object and is not cast. All True when the grown box reaches back to the eye's y."""
        from slax_drake.scene.raycast import object_triangles

        xy = object_triangles(obj).reshape(-1, 3)[:, :2] - self.eye[:2]
        (x0, y0), (x1, y1) = xy.min(axis=0) - margin, xy.max(axis=0) + margin
        if y0 <= 0.0:
            return np.ones(self.shown.shape, dtype=bool)
        corners = np.arctan2([x0, x0, x1, x1], [y0, y1, y0, y1])
        return (self.bearing >= corners.min()) & (self.bearing <= corners.max())

    def distance(self, objects) -> tuple[np.ndarray, np.ndarray]:
        """(K,) bool twice: the target of each world seen at the threshold past ``objects``; and seen so once one
        of the objects is taken away (a point hidden by that object alone is then seen)."""
        key = ("distance", state_key(objects))
        hit = self._revealed.get(key)
        if hit is None:
            masks = np.stack([self.hidden_by(o) for o in objects]) if objects else np.zeros((0,) + self.shown.shape, bool)
            count = masks.sum(axis=0)
            need = self.threshold * self.n_shown - 1e-9
            revealed = (self.n_shown > 0) & ((self.shown & (count == 0)).sum(axis=1) >= need)
            alone = (self.shown[None] & (count[None] - masks == 0)).sum(axis=2)  # (n, K) seen without object i
            one_away = (self.n_shown > 0) & (alone >= need[None]).any(axis=0) if len(objects) else revealed
            hit = self._revealed[key] = (revealed, one_away | revealed)
        return hit

    def revealed(self, objects) -> np.ndarray:
        """(K,) bool: the target of each world seen at the threshold past ``objects``."""
        key = state_key(objects)
        hit = self._revealed.get(key)
        if hit is None:
            hidden = np.zeros_like(self.shown)
            for o in objects:
                hidden |= self.hidden_by(o)
            seen = (self.shown & ~hidden).sum(axis=1)
            hit = self._revealed[key] = (self.n_shown > 0) & (seen >= self.threshold * self.n_shown - 1e-9)
        return hit

    def blocks(self, objects, name: str) -> np.ndarray:
        """(K,) bool: the object ``name`` of ``objects`` overlaps the target of each world."""
        from slax_drake.scene.footprint import Footprint, clear_of

        obj = next(o for o in objects if o.name == name)
        return ~clear_of("box", self.centers, 0.0, (self.size[0] / 2, self.size[1] / 2), Footprint.of(obj), 0.0)


def possible_placements(scene, size, step: float, threshold: float, spacing: float = 0.02) -> np.ndarray:
    """(K, 2) centres (x, y) on the ``step`` lattice of the shelf frame (m) where a target box of ``size`` (yaw 0,
    on the support surface) stands inside the bay, clear of ``scene.objects``, and is seen less than ``threshold``
    from the camera: of its surface points (``spacing`` apart, bottom excluded) that the empty shelf would show
    (facing the eye, not behind a wall), less than that share is seen past the objects. Such a target is what the
    trial still searches for; the paper's occupancy keeps the wholly hidden ones only, which loses a target that a
    step left partly visible."""
    from slax_drake.scene.footprint import Footprint, clear_of
    from slax_drake.scene.raycast import SceneRaycaster
    from slax_drake.scene.surface import box_surface_points

    shelf = scene.shelf
    hx, hy = size[0] / 2.0, size[1] / 2.0
    xs = np.arange(math.ceil((-shelf.width / 2 + hx) / step - 1e-9), math.floor((shelf.width / 2 - hx) / step + 1e-9) + 1)
    ys = np.arange(math.ceil((-shelf.depth / 2 + hy) / step - 1e-9), math.floor((shelf.depth / 2 - hy) / step + 1e-9) + 1)
    gx, gy = np.meshgrid(xs * step, ys * step, indexing="ij")
    centers = np.column_stack([gx.ravel(), gy.ravel()])
    ok = np.ones(len(centers), dtype=bool)
    for o in scene.objects:
        ok &= clear_of("box", centers, 0.0, (hx, hy), Footprint.of(o), 0.0)
    centers = centers[ok]
    if not len(centers):
        return centers
    points, normals = box_surface_points(tuple(size), spacing)
    offsets = np.column_stack([centers, np.full(len(centers), size[2] / 2.0)])
    world = points[None, :, :] + offsets[:, None, :]  # (K, P, 3)
    eye = np.asarray(scene.camera.position, dtype=float)
    facing = np.einsum("pj,kpj->kp", normals, eye - world) > 0.0
    shown = facing & SceneRaycaster(scene, objects=()).visible(eye, world)
    seen = shown & SceneRaycaster(scene).visible(eye, world)
    n_shown = shown.sum(axis=1)
    keep = (n_shown > 0) & (seen.sum(axis=1) < threshold * n_shown - 1e-9)
    return centers[keep]
