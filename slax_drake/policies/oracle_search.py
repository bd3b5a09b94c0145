"""The oracles' exact search over action sequences (paper Sec. V-D: "generates all action trees up to H"), in the
first-order model: a cheapest plan (cost: pushes + psi suctions) that reaches the goal within H actions, with a
proof of what was found.

Phases within one time limit per decision (``seconds``, CPU seconds, all phases together; a share
``fallback_share``, default :data:`FALLBACK_SHARE`, is kept back for phase 3):

1. weighted A* (f = g + w h, ``weight`` w >= 1), until ``(1 - fallback_share)`` of the limit: finds a plan fast;
   its cost U is an upper bound (and, since h is admissible, at most w times the optimum);
2. once phase 1 has a plan, A* (f = g + h) pruned by U, until the whole limit: proves U optimal, or finds the
   cheaper plan, or, when neither phase finds a plan and the frontier empties, proves that no plan exists
   within H (on the action lattice). With w = 1 phase 2 runs alone, until ``(1 - fallback_share)`` of the limit;
3. only when phases 1-2 are cut by time without a plan, in the rest of the limit: the greedy dive, best-first on
   h alone with the deepest node first among equal h (the same children, duplicate, horizon and commutation
   pruning), which finds some plan within H where the weighted search wanders on a plateau of h (Table I's
   paper-profile scenes cut at the first decision: 8 of 16 have a dive plan within 10 CPU s, and its plans are
   long, up to H); then A* pruned by the dive plan's cost with the time left, which proves it optimal or finds
   the cheaper plan. An exhausted dive proves infeasibility, as phase 1 does. A search whose phase 1 (or, with
   w = 1, phase 2) ends before ``(1 - fallback_share)`` of the limit is the same as without phase 3.

The result's ``status``: "optimal" (an A* phase finished with a plan, or phase 3's A* exhausted its frontier
below the dive plan's cost), "infeasible" (proven: no plan within the horizon), "cut by time" (the limit came
first; the plan, if any, is phase 1's or the dive's, with ``lower_bound`` the least g + h left on the A*
frontier; ``greedy`` says that phase 3 ran, recorded as ``greedy_fallback`` in the trial file).

Pruning that keeps the search exact:

- duplicate states: a node is kept only when no node of the same key has both a cost g and a depth no larger
  (the depth matters because of the horizon: a cheaper arrival may have spent more actions);
- the horizon: a child whose heuristic exceeds the actions left is dropped (h never overestimates: every
  action moves one object and costs at least 1);
- commutation: two actions on different objects whose regions do not interact (:func:`action_regions`) lead to
  the same state in either order at the same cost, so after an action on object A the search expands an
  independent action on object B only when B's name sorts after A's (one canonical order). The node key holds
  the last action's region, so two arrivals at one state with different pruning are not merged.
"""

from __future__ import annotations

import dataclasses
import heapq
import itertools
import math
import time

from slax_drake.caches import IdentityMemo
from slax_drake.shelf.actions import FRONT_MARGIN, ActionModel, Push, apply_action
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import state_key

Box = tuple[float, float, float, float]  # x_lo, x_hi, y_lo, y_hi in the shelf frame (m)
# The search reads the CPU clock every this many nodes taken from the frontier, not at each: inside a search on our
# loaded 2-core machine a read took 0.5 ms of wall time, and a 10 CPU-second search that read it at every node
# expanded 5,799 nodes against 6,451 reading it every 8th (Table I's first 10-object scene, Oracle-P). A search runs
# at most this many nodes past its limit; only where the limit cuts a search does it matter.
DEADLINE_CHECK_EVERY = 8
# The share of a search's time limit kept for the greedy dive (phase 3), which runs only when the exact phases found
# no plan by the rest of the limit. 0.3: of the 16 paper-profile Table I searches cut at 20 s with no plan, the
# dive alone found a plan within 6 CPU s in 6 (10 s: 8); uncut searches whose phase 1 took under 14 s stay as they were.
# See search_plan.
FALLBACK_SHARE = 0.3


@dataclasses.dataclass
class SearchResult:
    """A search's outcome: ``plan`` (a list of actions; [] when the goal holds already; None when none was found),
    ``status`` ("optimal", "infeasible" or "cut by time"), its ``cost``, ``lower_bound`` on the optimum, nodes
    ``expansions`` and CPU ``seconds`` spent (all phases), ``greedy``: whether the greedy dive (phase 3) ran."""

    plan: list | None
    status: str
    cost: float | None
    lower_bound: float
    expansions: int
    seconds: float
    greedy: bool = False

    def record(self) -> dict:
        out = {"status": self.status, "cost": self.cost, "lower_bound": round(self.lower_bound, 6),
               "actions": None if self.plan is None else len(self.plan), "expansions": self.expansions,
               "seconds": round(self.seconds, 3)}
        if self.greedy:  # the exact phases were cut without a plan and the greedy dive ran (only then: old records)
            out["greedy_fallback"] = True
        return out


# ---- commutation -------------------------------------------------------------------------------------------------
def shadow_box(model: ActionModel, fp: Footprint) -> Box:
    """A box holding the space ``fp`` hides from the camera (its overhead shadow to the back wall, which holds
    the 3D one): the footprint's box and the corners' rays from the eye to the back wall."""
    ex, ey = fp.extents()
    back = model.shelf.depth / 2
    ex_, ey_ = model.eye_xy
    xs = [fp.x - ex, fp.x + ex]
    for cx in (fp.x - ex, fp.x + ex):
        for cy in (fp.y - ey, fp.y + ey):
            if cy > ey_ + 1e-9:
                xs.append(ex_ + (cx - ex_) * (back - ey_) / (cy - ey_))
    return min(xs), max(xs), fp.y - ey, back


def action_regions(model: ActionModel, objects, action) -> tuple[list[Box], list[Box]]:
    """(act boxes, shadow boxes) of ``action`` taken on ``objects``: the act boxes hold everything whose contents
    decide the action's feasibility and its candidate set (the object's sweep, the tool's lanes, the band to
    the wall in a push's direction, where its stopper may stand; a suction's ways out and in), the shadow boxes
    the space the object hides before and after. They depend only on the moved object's pose and the action."""
    obj = next(o for o in objects if o.name == action.name)
    fp = Footprint.of(obj)
    ex, ey = fp.extents()
    half_w = model.shelf.width / 2
    y_front = -model.shelf.depth / 2 - FRONT_MARGIN
    if isinstance(action, Push):
        sign = 1 if action.d > 0 else -1
        rects = model.push_swept_rects(fp, sign)  # the parts of the tool a push checks (and drags along)
        y_lo = min([fp.y - ey] + [r[1] - r[3] for r in rects])
        y_hi = max([fp.y + ey] + [r[1] + r[3] for r in rects])
        x_tail = min([fp.x - ex] + [r[0] - r[2] for r in rects]) if sign > 0 else \
            max([fp.x + ex] + [r[0] + r[2] for r in rects])
        act = [(x_tail, half_w, y_lo, y_hi) if sign > 0 else (-half_w, x_tail, y_lo, y_hi)]
        after = dataclasses.replace(fp, x=fp.x + action.d)
    else:
        x_new = fp.x + action.dx
        act = [(fp.x - ex, fp.x + ex, y_front, fp.y + ey), (x_new - ex, x_new + ex, y_front, action.dz + ey)]
        after = dataclasses.replace(fp, x=x_new, y=action.dz)
    return act, [shadow_box(model, fp), shadow_box(model, after)]


def _overlap(a: Box, b: Box, margin: float) -> bool:
    return a[0] - margin <= b[1] and b[0] - margin <= a[1] and a[2] - margin <= b[3] and b[2] - margin <= a[3]


def interacts(regions_a, regions_b, margin: float) -> bool:
    """Whether two actions' regions interact: an act box of one meets an act or shadow box of the other."""
    act_a, shadow_a = regions_a
    act_b, shadow_b = regions_b
    return any(_overlap(p, q, margin) for p in act_a for q in act_b + shadow_b) or \
        any(_overlap(p, q, margin) for p in act_b for q in shadow_a)


def commutation_margin(model: ActionModel) -> float:
    """How far apart two regions must stay to be independent (m): hidden space is opened with a disc
    ``min_hidden_width`` wide (a point is in the opening when some such disc inside the hidden space covers it,
    so what is hidden at a point depends on the shadows and footprints within that width of it), plus the
    clearance, two raster cells (the erosion and rounding to cells) and 1 mm."""
    t = model.tool
    return t.rules.min_hidden_width + t.physics.clearance + 2 * t.grid.cell + 1e-3


def maximal_pushes_only(actions: list) -> list:
    """``actions`` with each object's pushes reduced to the longest one per direction (the paper's "push next to
    the nearest neighbour"); suctions unchanged; order kept."""
    longest: dict = {}
    for a in actions:
        if isinstance(a, Push):
            key = (a.name, a.d > 0)
            if key not in longest or abs(a.d) > abs(longest[key].d):
                longest[key] = a
    keep = set(id(a) for a in longest.values())
    return [a for a in actions if not isinstance(a, Push) or id(a) in keep]


class StateKeys:
    """:func:`slax_drake.scene.model.state_key` of objects and states, each object's key computed once: a search
    passes the same (unmoved) object instances in thousands of states, so the keys are cached by identity (the
    cache holds the objects, so their ids are not reused while it lives). Equal to ``state_key`` always."""

    def __init__(self):
        self.of_object = IdentityMemo(lambda obj: state_key((obj,))[0])

    def of_state(self, objects) -> tuple:
        return tuple(self.of_object(o) for o in objects)


class PushCache:
    """Each object's feasible pushes, cached by everything they depend on: the object's pose and the poses of the
    objects that reach its push band (the strip of y its pushes and their tool lanes span, across the shelf,
    widened by :func:`commutation_margin`) with their footprints or their shadows. The others cannot change
    its blockers, stoppers or the hidden space in the band, so the pushes are computed on the smaller state
    (exact: the same candidates as on the whole state)."""

    def __init__(self, model: ActionModel, fixed, keys: StateKeys | None = None):
        self.model, self.fixed = model, tuple(fixed)
        self.margin = commutation_margin(model)
        self.keys = keys or StateKeys()
        self.cache: dict = {}
        self._boxes_and_band = IdentityMemo(self._geometry)  # by identity: they depend on the object's pose only
        self.hits = self.misses = 0

    def band(self, fp: Footprint) -> Box:
        rects = [r for sign in (1, -1) for r in self.model.push_swept_rects(fp, sign)]  # what a push checks
        ex, ey = fp.extents()
        y_lo = min([fp.y - ey] + [r[1] - r[3] for r in rects])
        y_hi = max([fp.y + ey] + [r[1] + r[3] for r in rects])
        half_w = self.model.shelf.width / 2
        return -half_w, half_w, y_lo, y_hi

    def _geometry(self, obj):
        """((footprint box, shadow box), push band) of ``obj``."""
        fp = Footprint.of(obj)
        ex, ey = fp.extents()
        return ((fp.x - ex, fp.x + ex, fp.y - ey, fp.y + ey), shadow_box(self.model, fp)), self.band(fp)

    def pushes(self, objects) -> list:
        geometry = [self._boxes_and_band(o) for o in objects]
        boxes = [g[0] for g in geometry]
        out = []
        for i, obj in enumerate(objects):
            band = geometry[i][1]
            near = [j for j in range(len(objects)) if j == i or any(_overlap(b, band, self.margin) for b in boxes[j])]
            key = tuple(self.keys.of_object(objects[j]) for j in near) + (i,)
            hit = self.cache.get(key)
            if hit is None:
                self.misses += 1
                sub = tuple(objects[j] for j in near)
                hit = self.cache[key] = self.model.enumerate(sub, fixed=self.fixed, suctions=False,
                                                             only={obj.name}).feasible
            else:
                self.hits += 1
            out.extend(hit)
        return out


# ---- search ------------------------------------------------------------------------------------------------------
def search_plan(model: ActionModel, start, fixed, h_of, remaining: int, suctions: bool, psi: float,
                seconds: float, weight: float = 5.0, commute: bool = True, maximal_pushes: bool = True,
                allowed=None, fallback_share: float = FALLBACK_SHARE, clock=time.process_time) -> SearchResult:
    """The cheapest plan from ``start`` (objects) to a state where ``h_of(objects) == 0`` within ``remaining``
    actions; ``fixed``: known obstacles that never move (the target); ``h_of(objects)``: an admissible
    heuristic (0 exactly at the goal) counting actions; ``seconds``: the time limit (CPU seconds of this process,
    so that other work on the machine does not change the result); ``weight``: phase 1's
    w (1 skips phase 1); ``commute``: commutation pruning (off only to check it); ``maximal_pushes``: the paper's
    coarse push set, each object pushed each way only up to its neighbour (the maximal push), not also on the
    ``push_resolution`` lattice (see :func:`maximal_pushes_only`); ``allowed(candidates, objects)``: the candidates
    the search may use (the policy's exclusions, :class:`slax_drake.policies.protocol.Exclusions`), all when None;
    ``fallback_share``: the share of ``seconds`` kept for the greedy dive (0: no dive, the search as before it);
    ``clock``: the CPU clock (seconds), injectable for tests."""
    t0 = clock()  # CPU seconds of this process: the limit does not shrink when the machine is shared
    deadline = t0 + seconds
    exact_deadline = deadline - fallback_share * seconds  # phase 1's, and phase 2's while no plan is known
    start = tuple(start)
    h0 = h_of(start)
    if h0 == 0:
        return SearchResult([], "optimal", 0.0, 0.0, 0, 0.0)
    margin = commutation_margin(model)
    keys = StateKeys()
    push_cache = PushCache(model, fixed, keys)
    expansions = 0
    children_cache: dict = {}
    start_key = keys.of_state(start)

    def children(objects, key):
        """Feasible (action, after, h, step cost, key of after, key of the moved object before) of a state with
        state key ``key``, cached across phases. The key of after is ``key`` with the moved object's entry
        replaced (apply_action changes that object alone and keeps the order)."""
        hit = children_cache.get(key)
        if hit is None:
            cands = push_cache.pushes(objects)
            if suctions:
                cands = cands + model.enumerate(objects, fixed=fixed, pushes=False, suctions=True).feasible
            if maximal_pushes:
                cands = maximal_pushes_only(cands)
            if allowed is not None:
                cands = list(allowed(cands, objects))
            index: dict = {}
            for k, o in enumerate(objects):
                index.setdefault(o.name, k)  # the first of a name, as apply_action moves
            hit = []
            for a in cands:
                after, k = apply_action(objects, a), index[a.name]
                after_key = key[:k] + (keys.of_object(after[k]),) + key[k + 1:]
                hit.append((a, after, h_of(after), 1.0 if isinstance(a, Push) else psi, after_key, key[k]))
            children_cache[key] = hit
        return hit

    regions_cache: dict = {}

    def regions(objects, moved_key, a):
        """:func:`action_regions` of ``a`` on ``objects``, cached by the moved object's key and the action (the
        regions depend on nothing else)."""
        r = regions_cache.get((moved_key, a))
        if r is None:
            r = regions_cache[(moved_key, a)] = action_regions(model, objects, a)
        return r

    def run(w: float, bound: float, until: float):
        """One best-first search stopped at CPU time ``until``; ``w``: the weight of h in f = g + w h, or math.inf
        for the greedy dive (f = h: the fewest objects left to move first, then the deepest, then the cheapest);
        ties always go to the deeper node, then the cheaper; returns (plan, cost, exhausted, least g + h left).
        ``bound``: nodes with g + h at or above it are pruned."""
        nonlocal expansions
        greedy = math.isinf(w)
        counter = itertools.count()
        # node: (f, -depth, g, tie, objects, h, plan, last (parent objects, moved object's key, action) or None,
        # node key, state key)
        frontier = [(h0 if greedy else w * h0, 0, 0.0, next(counter), start, h0, (), None, None, start_key)]
        best: dict = {}
        pops = 0
        while frontier:
            if pops % DEADLINE_CHECK_EVERY == 0 and clock() > until:
                return None, None, False, min(n[2] + n[5] for n in frontier)
            pops += 1
            f, neg_depth, g, _, objects, h, plan, last, node_key, key = heapq.heappop(frontier)
            if node_key is not None and (g, len(plan)) not in best.get(node_key, ()):
                continue  # a better arrival at the same node came later
            if h == 0:
                return list(plan), g, False, g
            if g + h >= bound - 1e-9:
                continue
            depth = len(plan)
            if depth >= remaining:
                continue
            expansions += 1
            last_regions = regions(*last) if (commute and last is not None) else None
            last_name = last[2].name if last is not None else None
            for a, after, h2, c, after_key, moved_key in children(objects, key):
                if h2 > remaining - depth - 1:
                    continue  # cannot be finished within the horizon
                g2 = g + c
                if g2 + h2 >= bound - 1e-9:
                    continue
                if last_regions is not None and a.name != last_name and a.name < last_name and \
                        not interacts(last_regions, regions(objects, moved_key, a), margin):
                    continue  # the same state is reached with a first, in the canonical order
                node_key = (after_key, (moved_key,))
                kept = best.setdefault(node_key, [])
                if any(g_old <= g2 + 1e-9 and d_old <= depth + 1 for g_old, d_old in kept):
                    continue
                kept[:] = [(g_old, d_old) for g_old, d_old in kept if not (g2 <= g_old + 1e-9 and depth + 1 <= d_old)]
                kept.append((g2, depth + 1))
                f2 = h2 if greedy else g2 + w * h2
                heapq.heappush(frontier, (f2, -(depth + 1), g2, next(counter), after, h2, plan + (a,),
                                          (objects, moved_key, a), node_key, after_key))
        return None, None, True, math.inf

    def used() -> float:
        return clock() - t0

    upper, plan = math.inf, None
    if weight > 1.0:
        plan1, cost1, exhausted, least = run(weight, math.inf, exact_deadline)
        if plan1 is not None:
            upper, plan = cost1, plan1
        elif exhausted:
            return SearchResult(None, "infeasible", None, math.inf, expansions, used())
    if plan is not None or weight <= 1.0:
        plan2, cost2, exhausted, least = run(1.0, upper + 1e-6 if plan is not None else math.inf,
                                             deadline if plan is not None else exact_deadline)
        if plan2 is not None:
            return SearchResult(plan2, "optimal", cost2, cost2, expansions, used())
        if exhausted:
            if plan is not None:
                return SearchResult(plan, "optimal", upper, upper, expansions, used())
            return SearchResult(None, "infeasible", None, math.inf, expansions, used())
        if plan is not None:
            return SearchResult(plan, "cut by time", upper, least, expansions, used())
    # The exact phases were cut by time without a plan: the greedy dive, then A* pruned by its plan's cost.
    lower = float(h0) if weight > 1.0 else least  # phase 1 is weighted: its frontier's least g + h is not kept
    if fallback_share <= 0.0:
        return SearchResult(None, "cut by time", None, lower, expansions, used())
    plan3, cost3, exhausted, _ = run(math.inf, math.inf, deadline)
    if plan3 is None:
        if exhausted:
            return SearchResult(None, "infeasible", None, math.inf, expansions, used(), greedy=True)
        return SearchResult(None, "cut by time", None, lower, expansions, used(), greedy=True)
    plan4, cost4, exhausted, least4 = run(1.0, cost3 + 1e-6, deadline)
    if plan4 is not None:
        return SearchResult(plan4, "optimal", cost4, cost4, expansions, used(), greedy=True)
    if exhausted:
        return SearchResult(plan3, "optimal", cost3, cost3, expansions, used(), greedy=True)
    return SearchResult(plan3, "cut by time", cost3, min(cost3, max(lower, least4)), expansions, used(), greedy=True)
