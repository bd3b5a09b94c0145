"""The oracles' exact search: known optima on hand-built scenes, a proven infeasible one, and its pruning
(commutation, the coarse push set) leaving the optimum unchanged."""

import pytest

from slax_drake.shelf.actions import ActionModel, Push
from slax_drake.policies.oracle_search import action_regions, commutation_margin, interacts, search_plan
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.tool import tool_config
from slax_drake.shelf.visibility import TargetOcclusion
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target, planar_pose
from slax_drake.scene.sampling import shelf_of


def box(name, x, y, sx=0.10, sy=0.08, sz=0.15):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))


def scene_with(objects, target_xy, scenario):
    target = Target((0.06, 0.06, 0.06), planar_pose(target_xy[0], target_xy[1], 0.03, 0.0))
    return Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(scenario.camera), tuple(objects), target, 0)


def search(scene, scenario, horizon, suctions=False, **options):
    model = ActionModel(shelf_of(scenario), scene.camera.position, tool_config(scenario))
    occlusion = TargetOcclusion(scene, threshold=scenario.target.visibility_threshold)
    return search_plan(model, scene.objects, (scene.target.as_object(),), occlusion.min_objects_to_move, horizon,
                       suctions, scenario.protocol.suction_cost, seconds=60.0, **options)


def two_blockers(scenario):
    # two boxes one behind the other on the camera's line to the target, a bystander at the left wall
    return scene_with([box("a", 0.0, -0.15, sx=0.12), box("b", 0.0, 0.05, sx=0.12), box("c", -0.24, 0.20)],
                      (0.0, 0.22), scenario)


def test_two_blockers_need_exactly_two_pushes_and_are_proven_infeasible_in_one(paper):
    s = two_blockers(paper)
    one = search(s, paper, 1)
    assert one.status == "infeasible" and one.plan is None
    two = search(s, paper, 2)
    assert two.status == "optimal" and two.cost == 2.0 and len(two.plan) == 2
    assert {a.name for a in two.plan} == {"a", "b"} and all(isinstance(a, Push) for a in two.plan)
    # the policy records the proof per search
    oracle = make_policy("oracle-p", paper, horizon=1)
    oracle.reset(s)
    assert oracle.search(s, 1) is None and oracle.search_log[-1]["status"] == "infeasible"
    assert oracle.stop_reason == "no plan within the horizon"


def test_pruning_keeps_the_optimum(paper):
    s = two_blockers(paper)
    for suctions in (False, True):
        reference = search(s, paper, 3, suctions=suctions, commute=False, weight=1.0)
        for options in ({}, {"weight": 1.0}, {"maximal_pushes": False}):
            r = search(s, paper, 3, suctions=suctions, **options)
            assert r.status == reference.status == "optimal", options
            assert r.cost == pytest.approx(reference.cost), options


def test_commutation_regions_separate_far_apart_pushes_only(paper):
    model = ActionModel(shelf_of(paper), (0.0, -0.75, 0.20), tool_config(paper))
    objects = (box("l", -0.22, -0.20, sx=0.06, sz=0.05), box("r", 0.22, -0.20, sx=0.06, sz=0.05),
               box("m", 0.02, -0.20, sx=0.06, sz=0.05))
    margin = commutation_margin(model)
    left_out = action_regions(model, objects, Push("l", (0, 0, 0), -0.02))
    right_out = action_regions(model, objects, Push("r", (0, 0, 0), +0.02))
    m_right = action_regions(model, objects, Push("m", (0, 0, 0), +0.05))
    assert not interacts(left_out, right_out, margin)  # pushed apart toward the walls: independent
    assert interacts(m_right, right_out, margin)  # m's push runs toward r: r's move may change m's stopper


def test_cached_pushes_equal_the_whole_states_pushes(paper):
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.shelf.actions import apply_action
    from slax_drake.policies.oracle_search import PushCache
    from slax_drake.scene.sampling import sample_scene

    model = ActionModel(shelf_of(paper), paper.camera.position, tool_config(paper))
    for n in (6, 10):
        s = sample_scene(paper, n, scene_seed(0, n, 0), target_size=(0.06, 0.06, 0.06))
        fixed = (s.target.as_object(),)
        cache = PushCache(model, fixed)
        states = [s.objects]
        whole = model.enumerate(s.objects, fixed=fixed, suctions=False).feasible
        states += [apply_action(s.objects, a) for a in whole]
        for objects in states:
            expected = model.enumerate(objects, fixed=fixed, suctions=False).feasible
            assert sorted(map(repr, cache.pushes(objects))) == sorted(map(repr, expected))
    # a push of an object behind another's push band leaves that one's pushes as they were: no recomputation
    front, back = box("f", -0.15, -0.20, sx=0.08, sz=0.10), box("b", 0.15, 0.20, sx=0.08, sz=0.10)
    cache = PushCache(model, ())
    first = cache.pushes((front, back))
    moved = apply_action((front, back), next(a for a in first if a.name == "b"))
    assert cache.pushes(moved) == model.enumerate(moved, suctions=False).feasible and cache.hits == 1


# ---- the greedy dive (phase 3) -------------------------------------------------------------------------------------
class PhaseClock:
    """An injected CPU clock for search_plan with a limit of ``seconds``: 0 at the start, then 0.75 of the limit (past
    the exact phases' share, inside the dive's) until the search's heuristic has met a goal state; after that, past
    the limit for every reader but the greedy dive (read from the caller's ``greedy`` local), so the dive keeps
    its plan and the A* after it is cut at its first look. ``cut_after_goal=False``: never past the limit."""

    def __init__(self, seconds: float, cut_after_goal: bool = True):
        self.seconds, self.cut_after_goal = seconds, cut_after_goal
        self.started = self.goal_seen = False

    def h_of(self, h):
        def wrapped(objects):
            value = h(objects)
            self.goal_seen |= value == 0
            return value
        return wrapped

    def __call__(self) -> float:
        import sys

        if not self.started:
            self.started = True
            return 0.0
        in_dive = sys._getframe(1).f_locals.get("greedy") is True
        if self.goal_seen and self.cut_after_goal and not in_dive:
            return 2.0 * self.seconds
        return 0.75 * self.seconds


def search_with_clock(scene, scenario, horizon, clock, suctions=True):
    model = ActionModel(shelf_of(scenario), scene.camera.position, tool_config(scenario))
    occlusion = TargetOcclusion(scene, threshold=scenario.target.visibility_threshold)
    result = search_plan(model, scene.objects, (scene.target.as_object(),), clock.h_of(occlusion.min_objects_to_move),
                         horizon, suctions, scenario.protocol.suction_cost, seconds=20.0, clock=clock)
    return result, model, occlusion


def test_dive_plan_is_the_fallback_when_the_exact_phases_are_cut(paper):
    from slax_drake.shelf.actions import apply_action

    s, horizon = two_blockers(paper), 4
    result, model, occlusion = search_with_clock(s, paper, horizon, PhaseClock(20.0))
    assert result.status == "cut by time" and result.greedy and result.record()["greedy_fallback"] is True
    assert result.plan and len(result.plan) <= horizon
    objects, fixed, cost = s.objects, (s.target.as_object(),), 0.0
    for action in result.plan:  # each step feasible in the state it is taken in
        assert action in model.enumerate(objects, fixed=fixed).feasible
        objects = apply_action(objects, action)
        cost += 1.0 if isinstance(action, Push) else paper.protocol.suction_cost
    assert occlusion.min_objects_to_move(objects) == 0  # the goal: the target revealed
    assert result.cost == pytest.approx(cost)
    assert 2.0 - 1e-9 <= result.lower_bound <= result.cost  # two objects must move; the bound stays a bound


def test_dive_then_astar_proves_the_optimum_and_an_exhausted_dive_proves_infeasibility(paper):
    s = two_blockers(paper)
    result, _, _ = search_with_clock(s, paper, 3, PhaseClock(20.0, cut_after_goal=False))
    exact = search(s, paper, 3, suctions=True)
    assert result.greedy and result.status == exact.status == "optimal"
    assert result.cost == pytest.approx(exact.cost)
    result, _, _ = search_with_clock(s, paper, 1, PhaseClock(20.0, cut_after_goal=False))
    assert result.greedy and result.status == "infeasible" and result.plan is None


def test_an_uncut_search_is_the_same_with_and_without_the_dive(paper):
    s = two_blockers(paper)
    for suctions in (False, True):
        for horizon in (1, 2, 3):
            with_dive = search(s, paper, horizon, suctions=suctions)
            without = search(s, paper, horizon, suctions=suctions, fallback_share=0.0)
            assert not with_dive.greedy and "greedy_fallback" not in with_dive.record()
            assert (with_dive.plan, with_dive.status, with_dive.cost, with_dive.lower_bound, with_dive.expansions) == \
                (without.plan, without.status, without.cost, without.lower_bound, without.expansions)
