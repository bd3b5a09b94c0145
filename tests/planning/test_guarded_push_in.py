"""A guarded placement's push-in runs at the lowest carry, where the guard senses what hides in its way: one carried
over a known object (and so pushed in high) is rejected with its typed failure."""

import dataclasses

import pytest

from slax_drake.planning.failures import FailureKind
from slax_drake.planning.planner import _Reject, _reject_a_lifted_guarded_push_in
from slax_drake.planning.waypoints import LIFT, action_waypoints
from slax_drake.scene.model import SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.shelf.actions import Suction


def _box(name, x, y, size):
    return SceneObject(name, "box", size, planar_pose(x, y, size[2] / 2, 0.0))


def test_a_guarded_push_in_carried_over_a_known_object_is_rejected(sim_scenario):
    shelf = shelf_of(sim_scenario)
    carried = _box("carried", 0.15, -0.20, (0.08, 0.08, 0.10))
    low = _box("low", 0.0, 0.05, (0.10, 0.10, 0.05))  # in the carried box's way in at x = 0
    q = (0.15, -0.24, 0.05)
    straight = Suction("carried", q, 0.0, 0.15, guarded=True)  # its way in crosses nothing
    over = Suction("carried", q, -0.15, 0.15, guarded=True)  # pushed in over the low box
    wps = action_waypoints(straight, (carried, low), shelf)
    _reject_a_lifted_guarded_push_in(straight, wps)  # pushed in at LIFT: accepted
    wps = action_waypoints(over, (carried, low), shelf)
    with pytest.raises(_Reject) as e:
        _reject_a_lifted_guarded_push_in(over, wps)
    (failure,) = e.value.failures
    assert failure.kind is FailureKind.GUARDED_LIFTED and failure.waypoint == "push in"
    assert failure.deviation > LIFT
    _reject_a_lifted_guarded_push_in(dataclasses.replace(over, guarded=False), wps)  # not guarded: not this rule
