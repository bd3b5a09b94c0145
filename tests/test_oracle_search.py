"""The oracles' exact search: known optima on hand-built scenes, a proven infeasible one, and its pruning
(commutation, the coarse push set) leaving the optimum unchanged."""

import pytest

from slax_drake.config import load_scenario
from slax_drake.policies.actions import ActionModel, Push
from slax_drake.policies.oracle_search import action_regions, commutation_margin, interacts, search_plan
from slax_drake.policies.registry import make_policy, tool_config
from slax_drake.policies.visibility import TargetOcclusion
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target, planar_pose
from slax_drake.scene.sampling import shelf_of


def box(name, x, y, sx=0.10, sy=0.08, sz=0.15):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))


@pytest.fixture(scope="module")
def paper():
    return load_scenario("sim_configs/table1.yaml")


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
    from slax_drake.policies.actions import apply_action
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
