"""The oracles find the known optimum on hand-built scenes."""

import numpy as np

from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import run_trial
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target, planar_pose
from slax_drake.scene.sampling import target_visible_fraction


def box(name, x, y, sx=0.10, sy=0.08, sz=0.15):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))


def scene_with(objects, target_xy, scenario):
    target = Target((0.06, 0.06, 0.06), planar_pose(target_xy[0], target_xy[1], 0.03, 0.0))
    shelf = Shelf(0.6, 0.6, 0.6, 0.02)
    return Scene(shelf, Camera.from_config(scenario.camera), tuple(objects), target, 0)


def test_one_push_reveals_a_target_behind_one_box(sim_scenario):
    s = scene_with([box("a", 0.0, 0.0)], (0.0, 0.15), sim_scenario)
    assert target_visible_fraction(s) < 0.8
    for name in ("oracle-p", "oracle-p+s"):
        r = run_trial(s, make_policy(name, sim_scenario, horizon=2), 2)
        assert r.success and r.steps == 1 and r.pushes == 1, (name, r)


def test_two_blockers_need_two_actions(sim_scenario):
    s = scene_with([box("a", -0.02, -0.15, sx=0.12), box("b", 0.04, 0.05, sx=0.10)], (0.02, 0.20), sim_scenario)
    assert target_visible_fraction(s) < 0.8
    oracle = make_policy("oracle-p", sim_scenario, horizon=4)
    oracle.reset(s)
    plan = oracle.search(s, 4)
    assert plan is not None and len(plan) == 2
    r = run_trial(s, make_policy("oracle-p", sim_scenario, horizon=4), 4)
    assert r.success and r.steps == 2


def test_suction_when_no_push_fits(sim_scenario):
    # A row of three boxes 2 cm apart and 2 cm from the walls: no blade fits anywhere, so only suction
    # (cost psi) can clear the middle one, which hides the target.
    row = [box("l", -0.20, -0.10, sx=0.16, sz=0.12), box("m", 0.0, -0.10, sx=0.20, sz=0.12),
           box("r", 0.20, -0.10, sx=0.16, sz=0.12)]
    s = scene_with(row, (0.0, 0.15), sim_scenario)
    assert target_visible_fraction(s) < 0.8
    r_p = run_trial(s, make_policy("oracle-p", sim_scenario, horizon=2), 2)
    assert not r_p.success and r_p.steps == 0
    r_ps = run_trial(s, make_policy("oracle-p+s", sim_scenario, horizon=2), 2)
    assert r_ps.success and r_ps.suctions == 1 and r_ps.steps == 1
    assert np.isclose(r_ps.cost, 1.3)


def test_occlusion_union_equals_the_simulators_visible_fraction(sim_scenario):
    from slax_drake.shelf.visibility import TargetOcclusion
    from slax_drake.scene import sample_scene

    for seed in range(3):
        s = sample_scene(sim_scenario, 6, seed, target_size=(0.06, 0.06, 0.06))
        occ = TargetOcclusion(s)
        for k in range(len(s.objects)):
            sub = s.objects[:k] + s.objects[k + 1:]
            assert occ.visible_fraction(sub) == target_visible_fraction(s.with_objects(sub))


def test_low_object_is_no_obstacle_for_the_visibility_goal(sim_scenario):
    # A 4 cm tall box between the camera and the target: the camera (z = 0.20, 12 deg down) sees over it,
    # the target is visible, but it overlaps the overhead triangle, so the triangle goal would move it.
    s = scene_with([box("low", 0.0, 0.0, sx=0.12, sz=0.04)], (0.0, 0.15), sim_scenario)
    assert target_visible_fraction(s) >= 0.8
    vis = make_policy("oracle-p", sim_scenario, horizon=2)
    vis.reset(s)
    assert vis.search(s, 2) == []
    tri = make_policy("oracle-p", sim_scenario, horizon=2, oracle_options={"goal": "triangle"})
    tri.reset(s)
    assert len(tri.search(s, 2)) == 1


def test_the_heuristic_never_overestimates(sim_scenario):
    # Removing objects until revealed takes at least min_objects_to_move removals (checked by brute force).
    import itertools

    from slax_drake.shelf.visibility import TargetOcclusion
    from slax_drake.scene import sample_scene

    for seed in range(3):
        s = sample_scene(sim_scenario, 8, 50 + seed, target_size=(0.06, 0.06, 0.06))
        occ = TargetOcclusion(s)
        h = occ.min_objects_to_move(s.objects, cap=8)
        best = next(k for k in range(len(s.objects) + 1) for rm in itertools.combinations(range(len(s.objects)), k)
                    if occ.revealed([o for i, o in enumerate(s.objects) if i not in rm]))
        assert h == best
