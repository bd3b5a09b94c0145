"""The action model's push_tube_check (issue 17 item 3): the corridor lies where the planner puts the tube, a tall
object in it refuses the push and a low one does not, and (slow) the pushes it removes from seeded Table I scenes
are ones the motion planner rejects."""

import numpy as np
import pytest

from slax_drake.shelf.actions import ActionModel, Push, ToolConfig
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import SceneObject, Shelf, planar_pose

SHELF = Shelf(0.60, 0.60, 0.60, 0.02)
EYE = np.array([0.0, -0.75, 0.20])


def box(name, x, y, sx=0.08, sy=0.08, sz=0.10, yaw=0.0):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, yaw))


def pushes(objects, name, sign, **rules):
    cands = ActionModel(SHELF, EYE, ToolConfig.build(**rules)).enumerate(objects, suctions=False)
    offered = [a for a in cands.feasible if isinstance(a, Push) and a.name == name and np.sign(a.d) == sign]
    why = [r.reason for r in cands.rejected if r.what == f"push {name} {'+x' if sign > 0 else '-x'}"]
    return offered, why


@pytest.mark.parametrize("sign", [+1, -1])
@pytest.mark.parametrize("yaw", [0.0, 0.5])
def test_the_corridor_lies_where_the_planner_puts_the_tube(sign, yaw):
    """The corridor's centre line is the insert waypoint's blade plane, it ends the slack short of the blade's
    tip, and its height is the tube's underside (the blade's upper edge less a tube radius) plus the slack."""
    from slax_drake.planning.waypoints import BLADE_HALF_LENGTH, TUBE_RADIUS, action_waypoints
    from slax_drake.shelf.actions import TUBE_CHECK_SLACK

    tool = ToolConfig.build()
    a = box("a", 0.0, 0.05, yaw=yaw)
    model = ActionModel(SHELF, EYE, tool)
    (push, *_), _ = pushes((a,), "a", sign)
    insert = next(w for w in action_waypoints(push, (a,), SHELF, tool) if w.label == "insert")
    cx, cy, hx, hy, height = model.push_tube_corridor(Footprint.of(a), sign)
    x, y, z = insert.position
    assert cx == pytest.approx(x, abs=1e-9)
    assert cy + hy + TUBE_CHECK_SLACK == pytest.approx(y + BLADE_HALF_LENGTH, abs=1e-9)
    assert cy - hy - TUBE_CHECK_SLACK == pytest.approx(-SHELF.depth / 2, abs=1e-9)
    assert hx == pytest.approx(TUBE_RADIUS - TUBE_CHECK_SLACK)
    assert height == pytest.approx(z + tool.geometry.blade_height / 2 - TUBE_RADIUS + TUBE_CHECK_SLACK, abs=1e-9)


def test_a_tall_object_in_the_tubes_way_refuses_the_push_a_low_one_does_not():
    """``a`` stands deep in the bay; a 4 cm box in front of it, right where the tube passes on its way to the
    blade left of ``a``, refuses the +x push when it stands higher than the tube's underside (7 cm), not when it
    is lower; the paper profile (no tube) offers the push either way."""
    a = box("a", 0.0, 0.15)
    tube_x = 0.0 - 0.04 - 0.015 - 0.004  # a's least x, a tube radius and the standoff
    tall, low = box("c", tube_x, -0.15, 0.04, 0.04, 0.15), box("c", tube_x, -0.15, 0.04, 0.04, 0.05)
    offered, why = pushes((a, tall), "a", +1)
    assert not offered and why == ["the tube's way in left of a is blocked by c"]
    assert pushes((a, tall), "a", +1, push_tube_check=False)[0]
    assert pushes((a, low), "a", +1)[0]
    # beside the corridor (its edge a tube radius from the tube's axis) the tall box refuses nothing
    aside = box("c", tube_x - 0.015 - 0.02 - 0.001, -0.15, 0.04, 0.04, 0.15)
    assert pushes((a, aside), "a", +1)[0]


@pytest.mark.slow
def test_the_pushes_it_removes_from_table1_scenes_are_rejected_by_the_planner():
    """Conservative: on the initial states of seeded Table I scenes, every push the rule removes (offered with
    the rule off, not with it on) is one the Drake planner rejects."""
    import dataclasses

    from slax_drake.config import load_scenario
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.hardware.check_action import make_checker
    from slax_drake.scene.sampling import sample_scene

    scenario = load_scenario("sim_configs/table1.yaml")
    removed = []
    for n, index in [(10, 0), (10, 1)]:
        scene = sample_scene(scenario, n, scene_seed(scenario.protocol.seed, n, index),
                             target_size=tuple(scenario.target.sizes[0]))
        checker = make_checker(scene, "sim_configs/station_sim_shelf.yaml")
        tool = checker.model.tool
        assert tool.rules.push_tube_check
        off = ActionModel(checker.scene.shelf, checker.scene.camera.position[:2],
                          dataclasses.replace(tool, rules=dataclasses.replace(tool.rules, push_tube_check=False)))
        offered = set(checker.candidates().feasible)
        extra = [a for a in off.enumerate(checker.scene.objects).feasible if a not in offered]
        assert all(isinstance(a, Push) for a in extra)
        removed += [(a, checker.planner.plan(a, checker.scene)) for a in extra]
    assert len(removed) >= 3
    assert [a for a, result in removed if result.feasible] == []
