"""The object carried by the suction cup is collision-checked with the tool (pull out, translate, push in, and
the lift and lowering less the object's bottom); lift height over lower objects; rest-contact allowance."""

import numpy as np
import pytest

from slax_drake.planning.planner import MotionPlanner
from slax_drake.planning.waypoints import LIFT, LIFT_CLEARANCE, action_waypoints, carry_lift, pull_out_options
from slax_drake.planning.world import PlanningWorld, rest_gap
from slax_drake.shelf.actions import ActionModel, Suction
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.model import SceneObject, planar_pose
from slax_drake.scene.sampling import sample_scene, shelf_of
from slax_drake.station.scenario import load_station_scenario


def _box(name, x, y, size):
    return SceneObject(name, "box", tuple(size), planar_pose(x, y, size[2] / 2.0, 0.0))


@pytest.fixture(scope="module")
def two_boxes(sim_scenario):
    """A in the front row on the left, a low B in the front row right of it (same depth), nothing else."""
    scene = sample_scene(sim_scenario, 2, seed=0)
    a = _box("object_0", -0.20, -0.15, (0.08, 0.08, 0.12))
    b = _box("object_1", 0.0, -0.15, (0.10, 0.10, 0.04))
    scene = scene.with_objects((a, b))
    station = load_station_scenario()
    planner = MotionPlanner(station, tool_config(sim_scenario))
    return scene, planner, a, b


def _contact(scene, sim_scenario, name):
    model = ActionModel(shelf_of(sim_scenario), scene.camera.position, tool_config(sim_scenario))
    obj = next(o for o in scene.objects if o.name == name)
    return model.suction_contact(obj)


@pytest.mark.slow  # several seconds; runs in CI's slow step
def test_carried_object_that_would_hit_a_neighbour_is_rejected_with_a_reason(two_boxes, sim_scenario):
    scene, planner, a, b = two_boxes
    q = _contact(scene, sim_scenario, a.name)
    # placed where B stands: lifted over B (B is crossed on the way in) and lowered onto it
    onto_b = Suction(a.name, q, round(float(b.center[0] - a.center[0]), 6), float(b.center[1]))
    result = planner.plan(onto_b, scene)
    assert not result.feasible
    assert f"the carried {a.name} collides with" in result.reason and b.name in result.reason
    # the same object placed in free space plans, so the check is not what rejects every suction
    free = Suction(a.name, q, 0.0, 0.0)
    motion = planner.plan(free, scene)
    assert motion.feasible, motion.reason
    assert any(seg[3] == "clear" for seg in motion.segments) and any(seg[3] == "resting" for seg in motion.segments)


@pytest.mark.slow  # several seconds; runs in CI's slow step
def test_without_the_carried_check_the_colliding_action_would_pass(two_boxes, sim_scenario, monkeypatch):
    """The rejection above comes from the carried object alone: with the attachment disabled, the tool itself
    passes (the cup and tube stay above B)."""
    scene, _, a, b = two_boxes
    planner = MotionPlanner(load_station_scenario(), tool_config(sim_scenario))
    q = _contact(scene, sim_scenario, a.name)
    onto_b = Suction(a.name, q, round(float(b.center[0] - a.center[0]), 6), float(b.center[1]))
    monkeypatch.setattr(PlanningWorld, "carry", lambda self, obj, q, trim_bottom=0.0: None)
    assert planner.plan(onto_b, scene).feasible


def test_carried_segments_are_collision_free_with_the_object_attached(two_boxes, sim_scenario):
    """Re-check every carried segment of a planned suction with the object attached at the seal."""
    scene, planner, a, _ = two_boxes
    q = _contact(scene, sim_scenario, a.name)
    motion = planner.plan(Suction(a.name, q, 0.0, 0.0), scene)
    assert motion.feasible
    world = PlanningWorld(planner.scenario, scene)
    q_seal = motion.segments[[i for i, s in enumerate(motion.segments) if s[3]][0]][0]  # lift starts at the seal
    carried = [s for s in motion.segments if s[3]]
    assert len(carried) >= 5
    for qa, qb, contact, how in carried:
        world.allow_tool_contact(a.name, contact)
        world.carry(a, q_seal, trim_bottom=LIFT if how == "resting" else 0.0)
        assert world.edge_free(qa, qb)
        world.drop()
    # the object rises by the lift while carried, and comes out of the shelf when pulled all the way
    world.carry(a, q_seal)
    X_lifted = world.carried_pose_S(carried[0][1])
    assert X_lifted[2, 3] == pytest.approx(a.center[2] + LIFT, abs=1e-3)
    world.drop()


def test_lift_clears_the_lower_objects_crossed(two_boxes):
    scene, _, a, b = two_boxes
    # straight out of the shelf: nothing in the way
    assert carry_lift(a, scene.objects, [(0.0, 0.0), (0.0, -0.3)]) == LIFT
    # across B at its depth: over B
    assert carry_lift(a, scene.objects, [(0.0, 0.0), (0.2, 0.0)]) == pytest.approx(b.size[2] + LIFT_CLEARANCE)
    waypoints = action_waypoints(Suction(a.name, (-0.2, -0.19, 0.1), 0.2, -0.15), scene.objects, scene.shelf)
    lifted = {w.label: w.position[2] for w in waypoints}
    assert lifted["push in"] - lifted["seal"] == pytest.approx(b.size[2] + LIFT_CLEARANCE)


def test_shallower_carry_depths_avoid_the_target(two_boxes):
    scene, _, a, _ = two_boxes
    action = Suction(a.name, (-0.2, -0.19, 0.1), 0.2, -0.15)
    options = pull_out_options(action, a, scene.shelf, None)
    assert options[0] < options[-1] and all(y <= action.q[1] - 0.04 + 1e-9 for y in options)
    assert np.all(np.diff(options) > 0)
    # a target standing across A's way at every depth but the full pull-out leaves only that one
    from slax_drake.scene.model import Target

    target = Target((0.06, 0.06, 0.1), planar_pose(-0.1, -0.25, 0.05, 0.0))
    blocked = pull_out_options(action, a, scene.shelf, target)
    assert blocked == options[:1] and len(options) > 1


def test_rest_gap_sees_walls_and_neighbours(two_boxes):
    scene, _, a, b = two_boxes
    assert rest_gap(a, scene) == pytest.approx(0.06, abs=1e-6)  # to the left wall (0.06) and to B (0.11)
    touching = _box("object_0", -0.3 + 0.04, -0.15, (0.08, 0.08, 0.12))  # against the left wall
    assert abs(rest_gap(touching, scene.with_objects((touching, b)))) < 1e-9


def test_rest_gap_of_overlapping_estimates_is_the_overlap_depth(two_boxes):
    """Two estimates of boxes that physics left touching overlap by a few mm: the gap is minus the overlap's depth
    (how far the footprint must shrink to clear it), not a fixed -1 mm; a gross overlap counts as the cap."""
    from slax_drake.planning.world import MAX_REST_OVERLAP

    scene, _, a, _ = two_boxes
    right_of_a = _box("object_1", a.center[0] + 0.08 - 0.003, a.center[1], (0.08, 0.08, 0.12))  # 3 mm into A
    assert rest_gap(a, scene.with_objects((a, right_of_a))) == pytest.approx(-0.003, abs=2e-4)
    deep = _box("object_1", a.center[0] + 0.05, a.center[1], (0.08, 0.08, 0.12))  # 3 cm into A
    assert rest_gap(a, scene.with_objects((a, deep))) == pytest.approx(-MAX_REST_OVERLAP)


def test_a_neighbour_whose_estimate_overlaps_is_not_lifted_over_on_a_way_away_from_it(two_boxes):
    """Estimates of two objects that physics left touching overlap by a few mm (a Drake trial's 4:17 and 8:11
    ended when every carry of such an object was lifted over its neighbour and the lift near the robot had no IK
    solution): pulled straight out, away from the neighbour, the object is lifted the plain LIFT; carried into the
    neighbour, or overlapping it deeper than the trusted 5 mm, it is lifted over it."""
    scene, _, a, _ = two_boxes
    tall = _box("object_1", a.center[0] + 0.08 - 0.003, a.center[1] + 0.02, (0.08, 0.08, 0.10))  # 3 mm into A
    objects = (a, tall)
    over = tall.size[2] + LIFT_CLEARANCE
    assert carry_lift(a, objects, [(0.0, 0.0), (0.0, -0.3)]) == LIFT
    assert carry_lift(a, objects, [(0.0, 0.0), (0.0, -0.3), (-0.1, -0.3)]) == LIFT  # out, then away from it
    assert carry_lift(a, objects, [(0.0, 0.0), (0.05, 0.0)]) == pytest.approx(over)  # into it
    deep = _box("object_1", a.center[0] + 0.06, a.center[1] + 0.02, (0.08, 0.08, 0.10))  # 2 cm into A
    assert carry_lift(a, (a, deep), [(0.0, 0.0), (0.0, -0.3)]) == pytest.approx(over)


def test_the_way_out_is_lifted_only_as_high_as_it_needs(two_boxes):
    """A is carried out (nothing in its way), across in front of the shelf and pushed in over B's spot: it leaves
    at the plain lift, and the translation rises to B's height plus the clearance before it is pushed in."""
    scene, _, a, b = two_boxes
    waypoints = action_waypoints(Suction(a.name, (-0.2, -0.19, 0.1), 0.2, -0.15), scene.objects, scene.shelf)
    z = {w.label: w.position[2] for w in waypoints}
    assert z["lift"] - z["seal"] == pytest.approx(LIFT)
    assert z["pull out"] - z["seal"] == pytest.approx(LIFT)
    assert z["translate"] - z["seal"] == pytest.approx(b.size[2] + LIFT_CLEARANCE)
    assert z["push in"] == pytest.approx(z["translate"])
    # C behind B, pulled out over B and pushed in at the free lane between A and B: high out, low in
    c = _box("object_2", 0.0, 0.05, (0.08, 0.08, 0.12))
    behind = scene.with_objects((a, b, c))
    z = {w.label: w.position[2] for w in action_waypoints(Suction(c.name, (0.0, 0.01, 0.1), -0.1, 0.05),
                                                             behind.objects, behind.shelf)}
    assert z["pull out"] - z["seal"] == pytest.approx(b.size[2] + LIFT_CLEARANCE)
    assert z["push in"] - z["seal"] == pytest.approx(LIFT)


def test_a_lift_over_a_tall_object_rests_one_lift_up_to_be_weighed_before_it_rises(sim_scenario):
    """The arm weighs what the cup holds 1 cm up (the "weigh" waypoint's rest), before a high lift: an object the
    cup cannot hold falls from there, not from over its neighbour."""
    from slax_drake.planning.waypoints import WEIGH_DWELL

    a = _box("object_0", -0.20, 0.05, (0.08, 0.08, 0.12))  # behind a low box: its way out crosses it
    b = _box("object_1", -0.20, -0.15, (0.10, 0.10, 0.04))
    shelf = shelf_of(sim_scenario)
    wps = action_waypoints(Suction(a.name, (-0.2, 0.01, 0.1), 0.2, 0.05), (a, b), shelf)
    labels = [w.label for w in wps]
    assert labels[2:5] == ["seal", "weigh", "lift"]
    z = {w.label: w.position[2] for w in wps}
    assert z["weigh"] - z["seal"] == pytest.approx(LIFT) and z["lift"] - z["seal"] == pytest.approx(0.04 + LIFT_CLEARANCE)
    dwell = {w.label: w.dwell for w in wps}
    assert dwell["weigh"] == WEIGH_DWELL and dwell["lift"] == 0.0
