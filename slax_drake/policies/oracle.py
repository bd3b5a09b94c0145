"""Oracle-P and Oracle-P+S (paper Sec. V-D): full-state search for the cheapest action sequence that clears
the overhead visibility triangle from the camera to the target's front face.

The paper clears the triangle from the camera's (x, y) to the target's front face. Our visibility measure
counts the target's top and side faces too (v = 80 % of all points the empty shelf would show), and the rays
to a side face pass beside that triangle, so we clear the convex hull of the camera's (x, y) and the target's
whole footprint (the triangle plus the wedge to the visible side face). It is clear when no object's footprint overlaps it by more than ``overlap_tolerance`` (m^2). The action set is
the policies' own (:class:`~slax_drake.policies.actions.ActionModel`: same blade, cup, discretisation and
hidden-space rule) computed on the full state, with the target as a known obstacle that never moves.

Search: A* over states with cost g = pushes + psi suctions and h = the number of objects overlapping the
triangle. Every action moves one object and costs at least 1, so h never overestimates and the first goal
popped is a cheapest plan on the action lattice (exact); states are deduplicated by their object poses and
plans longer than the remaining horizon H are pruned. ``max_expansions`` bounds the work per plan: a search
that hits it reports ``stop_reason = "search budget"`` (counted as a failure and reported as such).
"""

from __future__ import annotations

import heapq
import itertools

from shapely.geometry import Polygon

from slax_drake.policies.actions import ActionModel, Push, apply_action
from slax_drake.policies.distribution import state_key
from slax_drake.scene.footprint import Footprint


class Oracle:
    def __init__(self, action_model: ActionModel, suctions: bool, psi: float = 1.3, horizon: int | None = None,
                 max_expansions: int = 400, overlap_tolerance: float = 1e-6):
        self.action_model = action_model
        self.suctions = suctions
        self.psi = psi
        self.horizon = horizon
        self.max_expansions = max_expansions
        self.overlap_tolerance = overlap_tolerance
        self.name = "oracle-p+s" if suctions else "oracle-p"
        self.plan: list = []
        self.next_expected = None
        self.steps_taken = 0
        self.stop_reason = None
        self.expansions = 0

    def reset(self, scene) -> None:
        self.plan, self.next_expected, self.steps_taken, self.stop_reason = [], None, 0, None
        self.horizon_total = self.horizon if self.horizon is not None else 2 * len(scene.objects)

    def act(self, scene):
        if not self.plan or state_key(scene.objects) != self.next_expected:
            self.plan = self.search(scene, self.horizon_total - self.steps_taken)
            if self.plan == []:
                self.stop_reason = "triangle clear but target not revealed"
            if not self.plan:
                return None
        action = self.plan.pop(0)
        self.next_expected = state_key(apply_action(tuple(scene.objects), action))
        self.steps_taken += 1
        return action

    # ----------------------------------------------------------------------------------------------------
    def triangle(self, scene) -> Polygon:
        eye = scene.camera.position
        t = scene.target
        hx, hy = t.size[0] / 2, t.size[1] / 2
        tx, ty = float(t.center[0]), float(t.center[1])
        return Polygon([(eye[0], eye[1]), (tx - hx, ty - hy), (tx + hx, ty - hy), (tx + hx, ty + hy),
                        (tx - hx, ty + hy)]).convex_hull

    def search(self, scene, remaining: int):
        """The cheapest action list that clears the triangle within ``remaining`` actions, [] when already clear,
        None when there is none (stop_reason says why)."""
        tri = self.triangle(scene)
        target = (scene.target.as_object(),)
        blocking_cache: dict = {}

        def blocks(obj) -> bool:
            key = (obj.name, round(float(obj.center[0]), 4), round(float(obj.center[1]), 4))
            v = blocking_cache.get(key)
            if v is None:
                v = Footprint.of(obj).polygon(16).intersection(tri).area > self.overlap_tolerance
                blocking_cache[key] = v
            return v

        start = tuple(scene.objects)
        h0 = sum(blocks(o) for o in start)
        if h0 == 0:
            return []
        counter = itertools.count()
        frontier = [(h0, 0, 0.0, next(counter), start, h0, ())]
        seen = {state_key(start): 0.0}
        self.expansions = 0
        while frontier:
            f, neg_depth, g, _, objects, h, plan = heapq.heappop(frontier)
            if h == 0:
                return list(plan)
            if seen.get(state_key(objects), float("inf")) < g - 1e-9:
                continue
            if len(plan) >= remaining:
                continue
            self.expansions += 1
            if self.expansions > self.max_expansions:
                self.stop_reason = "search budget"
                return None
            cands = self.action_model.enumerate(objects, fixed=target, pushes=True, suctions=self.suctions)
            by_name = {o.name: o for o in objects}
            for a in cands.feasible:
                after = apply_action(objects, a)
                old = by_name[a.name]
                new = next(o for o in after if o.name == a.name)
                h2 = h - blocks(old) + blocks(new)
                if h2 > remaining - len(plan) - 1:
                    continue  # cannot be finished within the horizon
                g2 = g + (1.0 if isinstance(a, Push) else self.psi)
                key = state_key(after)
                if seen.get(key, float("inf")) <= g2 + 1e-9:
                    continue
                seen[key] = g2
                heapq.heappush(frontier, (g2 + h2, -(len(plan) + 1), g2, next(counter), after, h2, plan + (a,)))
        self.stop_reason = "no plan within the horizon"
        return None
