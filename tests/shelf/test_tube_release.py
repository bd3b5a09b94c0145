"""A turned suction's tube where it puts its object down: its way out along its axis keeps ``TUBE_CLEARANCE`` from
every object it cannot pass over (a Drake trial ended on a placement whose tube met a low neighbour beside its way
out, physics benchmark 8:0 at 81c07f5); a tube along y stays in the object's own lane and is not tested."""

import math

import pytest
from shapely.geometry import LineString, box as rectangle

from slax_drake.shelf.actions import TUBE_CLEARANCE, ActionModel, Suction
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

CUP_LIMITS = dict(max_seal_angle_deg=10.0, max_suction_moment=0.4)  # the station YAML's cup


def _model(scenario, **rules):
    return ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position[:2],
                       tool_config(scenario, "station", **{**CUP_LIMITS, **rules}))


def _placements(model, objects):
    return {(round(a.dx, 6), round(a.dz, 6)): a for a in model.enumerate(objects, pushes=False).feasible
            if isinstance(a, Suction) and a.name == "object_0" and not a.drag}


def _tube_gap(model, obj, action, other) -> float:
    """The distance (m) from the tube's surface, on its axis from the cup at the placement out to in front of the
    opening, to ``other``'s footprint (shapely, independent of the model's test)."""
    cx, cy, _ = action.q
    cup = (cx + action.dx, cy + action.dz - float(obj.center[1]))
    length = (cup[1] - model.y_front) / math.cos(action.yaw)
    out = (cup[0] + math.sin(action.yaw) * length, cup[1] - math.cos(action.yaw) * length)
    x, y = float(other.center[0]), float(other.center[1])
    footprint = rectangle(x - other.size[0] / 2, y - other.size[1] / 2, x + other.size[0] / 2, y + other.size[1] / 2)
    return LineString([cup, out]).distance(footprint) - 0.015


def test_a_placement_whose_turned_tube_meets_a_neighbour_is_not_offered(sim_scenario):
    """A box turned 20 deg (the tool turns with it) and a 9 cm neighbour, lower than the box but taller than the
    tube's underside, left of its way out: the placements moved left at the box's depth put the tube over the
    neighbour and are refused; every placement offered keeps the clearance, and every one refused lacks it."""
    obj = SceneObject("object_0", "box", (0.08, 0.10, 0.12), planar_pose(0.0, -0.15, 0.06, math.radians(20.0)))
    neighbour = SceneObject("object_1", "box", (0.04, 0.04, 0.09), planar_pose(-0.12, -0.25, 0.045, 0.0))
    model = _model(sim_scenario)
    offered = _placements(model, (obj, neighbour))
    unchecked = _placements(_model(sim_scenario, tube_approach_check=False), (obj, neighbour))
    assert offered and math.degrees(next(iter(offered.values())).yaw) == pytest.approx(20.0, abs=1e-3)
    refused = set(unchecked) - set(offered)
    assert refused and set(offered) <= set(unchecked)
    for key in refused:
        assert _tube_gap(model, obj, unchecked[key], neighbour) < TUBE_CLEARANCE
    for action in offered.values():
        assert _tube_gap(model, obj, action, neighbour) >= TUBE_CLEARANCE - 1e-9
    # alone, the box is offered every placement the unchecked model offers beside the neighbour, and more
    assert set(unchecked) <= set(_placements(model, (obj,)))


def test_a_tube_along_y_is_not_tested_where_it_puts_its_object_down(sim_scenario):
    """Unturned, the same box and neighbour: the tube stays in the box's own lane; the check removes nothing."""
    obj = SceneObject("object_0", "box", (0.08, 0.10, 0.12), planar_pose(0.0, -0.15, 0.06, 0.0))
    neighbour = SceneObject("object_1", "box", (0.04, 0.04, 0.09), planar_pose(-0.12, -0.25, 0.045, 0.0))
    assert (set(_placements(_model(sim_scenario), (obj, neighbour)))
            == set(_placements(_model(sim_scenario, tube_approach_check=False), (obj, neighbour))))
