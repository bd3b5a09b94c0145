"""Oracle-P and Oracle-P+S (paper Sec. V-D): full-state A* search for the cheapest action sequence (cost
pushes + psi suctions) that reveals the target, over the policies' own action set
(:class:`~slax_drake.shelf.actions.ActionModel`, computed on the full state with the target as a known
obstacle that never moves).

Goal (``goal``):

- ``"visibility"`` (default): the target's visible fraction reaches the threshold v, computed exactly as the
  simulator's success test (:mod:`slax_drake.shelf.visibility`: a union of per-object 3D occlusions, cached
  per object pose). Objects below the line of sight do not count. The heuristic is the fewest objects whose
  removal would reveal the target (admissible: a plan of k actions moves at most k objects).
- ``"triangle"``: the paper's overhead rule, widened to our visibility measure: no object footprint overlaps
  the convex hull of the camera's (x, y) and the target's whole footprint (by more than ``overlap_tolerance``
  m^2), whatever its height; the heuristic is the number of overlapping objects. The paper clears the
  triangle to the front face only, "equivalent to the 3D problem" for objects taller than the line of sight;
  with the camera 0.20 m high looking down 12 degrees, low objects do not occlude, so this goal is stricter.

Search (:func:`slax_drake.policies.oracle_search.search_plan`): weighted A* for a first plan, then A* pruned
by its cost to prove it optimal, with duplicate-state detection, commutation pruning and the horizon, within
``seconds`` CPU seconds per decision; when those find no plan within ``1 - fallback_share`` of it, a greedy dive
on h in the rest finds a fallback plan (then A* pruned by its cost). Each search's outcome ("optimal",
"infeasible": proven, no plan within the horizon, "cut by time") is kept in ``search_log``; a search cut by time
with a plan (phase 1's or the dive's) still executes that plan.
"""

from __future__ import annotations

from shapely.geometry import Polygon

from slax_drake.shelf.actions import ActionModel, apply_action
from slax_drake.policies.oracle_search import FALLBACK_SHARE, search_plan
from slax_drake.policies.protocol import Decision, Exclusions
from slax_drake.scene.model import state_key
from slax_drake.shelf.visibility import TargetOcclusion
from slax_drake.scene.footprint import Footprint


class Oracle:
    """Oracle-P (pushes) or Oracle-P+S (pushes and suctions); implements
    :class:`~slax_drake.policies.protocol.Policy` on the true scene (``needs_true_scene``). ``decide`` returns the
    next action of the current plan as a one-candidate Decision, searching again when the scene is not the one the
    plan expected or when the last candidate was excluded."""

    needs_true_scene = True
    distribution = None  # reads the true scene, not a distribution
    history = None  # keeps no distribution history

    def __init__(self, action_model: ActionModel, suctions: bool, psi: float = 1.3, horizon: int | None = None,
                 seconds: float = 20.0, weight: float = 5.0, maximal_pushes: bool = True, overlap_tolerance: float = 1e-6,
                 goal: str = "visibility", threshold: float = 0.80, fallback_share: float = FALLBACK_SHARE):
        if goal not in ("visibility", "triangle"):
            raise ValueError("goal must be 'visibility' or 'triangle'")
        self.goal = goal
        self.threshold = threshold
        self._action_model = action_model
        self.suctions = suctions
        self.psi = psi
        self.horizon = horizon
        self.seconds = seconds  # the time limit per decision (s)
        self.weight = weight  # the first phase's heuristic weight
        self.fallback_share = fallback_share  # the share of ``seconds`` kept for the greedy dive (search_plan)
        self.maximal_pushes = maximal_pushes  # the paper's coarse push set (oracle_search.maximal_pushes_only)
        self.search_log: list[dict] = []  # one record per search (SearchResult.record())
        self.overlap_tolerance = overlap_tolerance
        self.name = "oracle-p+s" if suctions else "oracle-p"
        self.plan: list = []
        self.next_expected = None
        self.steps_taken = 0
        self.stop_reason = None
        self.expansions = 0
        self._exclusions = Exclusions()
        self._asked_again = False
        self._objects = ()

    @property
    def action_model(self) -> ActionModel:
        return self._action_model

    @property
    def exclusions(self) -> tuple:
        return self._exclusions.records

    def reset(self, scene) -> None:
        self.plan, self.next_expected, self.steps_taken, self.stop_reason = [], None, 0, None
        self.search_log = []
        self.horizon_total = self.horizon if self.horizon is not None else 2 * len(scene.objects)
        self._exclusions, self._asked_again, self._objects = Exclusions(), False, ()

    def exclude(self, action, reason: str, whole_group: bool = False) -> None:
        self._exclusions.add(action, reason, whole_group, self._objects)
        self._asked_again = True

    def decide(self, scene) -> Decision:
        if self._asked_again:  # the same step again, without the excluded candidate: search anew
            self._asked_again, self.plan = False, []
            self.steps_taken -= 1
        self._objects = tuple(scene.objects)
        if not self.plan or state_key(scene.objects) != self.next_expected:
            self.plan = self.search(scene, self.horizon_total - self.steps_taken)
            if self.plan == []:
                self.stop_reason = "triangle clear but target not revealed"
            if not self.plan:
                return Decision.stop(self.stop_reason or "no plan")
        action = self.plan.pop(0)
        self.next_expected = state_key(apply_action(tuple(scene.objects), action))
        self.steps_taken += 1
        return Decision((action,))

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
        target = (scene.target.as_object(),)
        if self.goal == "visibility":
            occlusion = TargetOcclusion(scene, threshold=self.threshold)

            def h_of(objects, h_parent=None, old=None, new=None) -> int:
                return occlusion.min_objects_to_move(objects)
        else:
            tri = self.triangle(scene)
            blocking_cache: dict = {}

            def blocks(obj) -> bool:
                key = (obj.name, round(float(obj.center[0]), 4), round(float(obj.center[1]), 4))
                v = blocking_cache.get(key)
                if v is None:
                    v = Footprint.of(obj).polygon(16).intersection(tri).area > self.overlap_tolerance
                    blocking_cache[key] = v
                return v

            def h_of(objects, h_parent=None, old=None, new=None) -> int:
                if h_parent is None:
                    return sum(blocks(o) for o in objects)
                return h_parent - blocks(old) + blocks(new)

        result = search_plan(self.action_model, scene.objects, target, h_of, remaining, self.suctions, self.psi,
                             self.seconds, self.weight, maximal_pushes=self.maximal_pushes,
                             allowed=self._exclusions.allowed, fallback_share=self.fallback_share)
        self.expansions = result.expansions
        self.search_log.append(result.record())
        if result.plan is None:
            self.stop_reason = ("no plan within the horizon" if result.status == "infeasible"
                                else "search cut by time")
        return result.plan
