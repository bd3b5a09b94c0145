"""A push's waypoints move the object by d: the tool travels d plus the gap between the object and the surface
that meets it first, the blade's face for an object lower than the tube, the tube's side for one that reaches it
(measured in Drake: a push planned for the blade moved boxes taller than the tube 8.5-11.9 mm too far,
research/push_contact.py --heights)."""

import dataclasses

import numpy as np
import pytest

from slax_drake.planning.waypoints import (BLADE_HALF_THICKNESS, PUSH_BACK_SLACK, TUBE_PUSH_ANGLE, TUBE_RADIUS,
                                           action_waypoints, push_back_slack, push_lead)
from slax_drake.shelf.actions import TUBE_STANDOFF
from slax_drake.shelf.actions import BLADE_LIFT, ActionModel, Push, ToolConfig
from slax_drake.scene.model import SceneObject, Shelf, planar_pose

SHELF = Shelf(0.60, 0.60, 0.60, 0.02)
EYE = np.array([0.0, -0.75, 0.20])
TOOL = ToolConfig.build()
TUBE_AXIS_Z = TOOL.geometry.blade_height + BLADE_LIFT  # the tube's axis runs along the blade's upper edge


def box(height, x=0.0, y=0.05, sx=0.08, sy=0.08):
    return SceneObject("a", "box", (sx, sy, height), planar_pose(x, y, height / 2, 0.0))


def leading_surface_travel(height: float, sign: int, d: float, others=()) -> tuple[float, float, float]:
    """Where the surface that meets the object stands at the insert, at the push's end and after backing off, as
    x in S along the push (sign times x), for the push of ``d`` the action model offers the box alone, planned with
    ``others`` beside it."""
    a = box(height)
    push = next(p for p in ActionModel(SHELF, EYE, TOOL).enumerate((a,), suctions=False).feasible
                if isinstance(p, Push) and abs(p.d - sign * d) < 1e-9)
    wps = {w.label: w for w in action_waypoints(push, (a, *others), SHELF, TOOL)}
    lead = push_lead(height, TOOL)
    start = sign * wps["insert"].position[0] + lead
    end = sign * wps["push"].position[0] + lead
    back = sign * wps["back off"].position[0] + lead
    assert wps["retract"].position[0] == wps["back off"].position[0]
    return start, end, back


@pytest.mark.parametrize("sign", [+1, -1])
@pytest.mark.parametrize("height", [0.05, 0.12, 0.25])
def test_the_surface_that_meets_the_object_ends_d_past_the_objects_extreme(sign, height):
    """The leading surface starts clear of the object and ends exactly d past the object's extreme on its side,
    so the object moves by d, whether the blade (a 5 cm box) or the tube (12 and 25 cm) pushes it; backing off,
    it leaves the object ``PUSH_BACK_SLACK`` farther behind than it stood before the push (a 0.10 m push)."""
    extreme = sign * (0.0 - sign * 0.04)  # the box's extreme x on the blade's side, along the push
    start, end, back = leading_surface_travel(height, sign, 0.10)
    assert start < extreme - 1e-3
    assert end == pytest.approx(extreme + 0.10, abs=1e-9)
    assert end - back == pytest.approx(extreme - start + PUSH_BACK_SLACK, abs=1e-9)


@pytest.mark.parametrize("sign", [+1, -1])
def test_a_short_push_backs_off_to_the_lane_it_came_in_by(sign):
    """A push no longer than ``PUSH_BACK_SLACK`` backs off and retracts along the lane of its insert (an object that
    moved less than d, or leaned onto the tool, is left clear); a longer one backs off that much farther than its
    gap."""
    a = box(0.12)
    model = ActionModel(SHELF, EYE, TOOL)
    push = next(p for p in model.enumerate((a,), suctions=False).feasible if isinstance(p, Push) and p.d * sign > 0)
    short = dataclasses.replace(push, d=sign * 0.015)  # as a neighbour would stop it
    wps = {w.label: w for w in action_waypoints(short, (a,), SHELF, TOOL)}
    assert wps["back off"].position[0] == pytest.approx(wps["insert"].position[0], abs=1e-9)
    assert wps["retract"].position[0] == pytest.approx(wps["pre-approach"].position[0], abs=1e-9)
    assert push_back_slack(short.d) == pytest.approx(abs(short.d))
    assert push_back_slack(sign * 0.30) == PUSH_BACK_SLACK


def test_which_surface_leads():
    """Below the tube (or meeting it steeper than TUBE_PUSH_ANGLE below its axis) the blade's face leads; at and
    above the tube's axis the tube's full radius; in between, the tube's side at the object's top."""
    steep = TUBE_RADIUS * np.sin(TUBE_PUSH_ANGLE)
    assert push_lead(0.05, TOOL) == BLADE_HALF_THICKNESS
    assert push_lead(TUBE_AXIS_Z - steep - 1e-4, TOOL) == BLADE_HALF_THICKNESS
    assert push_lead(TUBE_AXIS_Z, TOOL) == pytest.approx(TUBE_RADIUS)
    assert push_lead(0.30, TOOL) == pytest.approx(TUBE_RADIUS)
    below = steep / 2
    assert push_lead(TUBE_AXIS_Z - below, TOOL) == pytest.approx(np.sqrt(TUBE_RADIUS ** 2 - below ** 2))


def tube_plane(sign: int, others=()) -> float:
    """The blade's plane (S x) at the insert of box "a"'s push of 0.10 m toward ``sign`` x (the push the action
    model offers the box alone), planned with ``others`` beside it."""
    a = box(0.12)
    push = next(p for p in ActionModel(SHELF, EYE, TOOL).enumerate((a,), suctions=False).feasible
                if isinstance(p, Push) and abs(p.d - sign * 0.10) < 1e-9)
    return float({w.label: w for w in action_waypoints(push, (a, *others), SHELF, TOOL)}["insert"].position[0])


@pytest.mark.parametrize("sign", [+1, -1])
def test_the_tube_stands_midway_in_a_narrow_gap(sign):
    """A tall neighbour closer to the tube's far side than TUBE_STANDOFF moves the tube toward the pushed object
    until both stand equally far from it (measured on the plane's x from the outlines, not from the code's
    formula); the push still ends d past the object's extreme."""
    plane = tube_plane(sign)
    far_side = plane - sign * TUBE_RADIUS  # the tube's surface away from the pushed box
    near_side = plane + sign * TUBE_RADIUS
    own = sign * ((0.0 - sign * 0.04) - near_side)  # the box's extreme on the blade's side
    assert own == pytest.approx(TUBE_STANDOFF)
    gap = 0.001  # a tall box 1 mm beyond the tube, standing from the front of the bay to past the tube's end
    wall = SceneObject("b", "box", (0.04, 0.55, 0.20), planar_pose(far_side - sign * (gap + 0.02), 0.0, 0.10, 0.0))
    shifted = tube_plane(sign, (wall,))
    assert sign * (shifted - plane) == pytest.approx((TUBE_STANDOFF - gap) / 2, abs=1e-9)
    # both sides now equally clear
    own_now = sign * ((0.0 - sign * 0.04) - (shifted + sign * TUBE_RADIUS))
    far_now = sign * ((shifted - sign * TUBE_RADIUS) - (far_side - sign * gap))
    assert own_now == pytest.approx(far_now, abs=1e-9)
    start, end, back = leading_surface_travel(0.12, sign, 0.10, (wall,))
    assert end == pytest.approx(-0.04 + 0.10, abs=1e-9)  # the extreme along the push is -0.04 either way
    assert end - back == pytest.approx(-0.04 - start + PUSH_BACK_SLACK, abs=1e-9)


@pytest.mark.parametrize("sign", [+1, -1])
def test_the_tube_keeps_its_standoff_beside_low_or_distant_neighbours(sign):
    """A neighbour under the tube's underside, one farther than TUBE_STANDOFF, and one on the pushed object's side
    leave the tube where it was."""
    plane = tube_plane(sign)
    far_side = plane - sign * TUBE_RADIUS
    low = SceneObject("b", "box", (0.04, 0.20, 0.04), planar_pose(far_side - sign * 0.021, -0.15, 0.02, 0.0))
    distant = SceneObject("b", "box", (0.04, 0.20, 0.20), planar_pose(far_side - sign * 0.030, -0.15, 0.10, 0.0))
    behind = SceneObject("b", "box", (0.04, 0.08, 0.20), planar_pose(sign * 0.20, 0.05, 0.10, 0.0))
    for other in (low, distant, behind):
        assert tube_plane(sign, (other,)) == pytest.approx(plane, abs=1e-12)


@pytest.mark.parametrize("sign", [+1, -1])
@pytest.mark.parametrize("mass", [0.3, 2.0])
def test_a_push_travels_farther_by_the_arms_give_under_the_objects_friction(sign, mass):
    """With the station's compliance c (m/N), the push's end and back-off move by c x drag_friction x m g along the
    push (the arm gives way by that much against the sliding object: research/push_contact.py), the insert does not
    move, and the tool backs off to where it would have without the give; with no compliance nothing changes."""
    from slax_drake.planning.waypoints import push_give

    a = SceneObject("a", "box", (0.08, 0.08, 0.05), planar_pose(0.0, 0.05, 0.025, 0.0), mass=mass)
    push = next(p for p in ActionModel(SHELF, EYE, TOOL).enumerate((a,), suctions=False).feasible
                if isinstance(p, Push) and abs(p.d - sign * 0.10) < 1e-9)
    stiff = {w.label: w.position for w in action_waypoints(push, (a,), SHELF, TOOL)}
    zero = {w.label: w.position for w in action_waypoints(push, (a,), SHELF, TOOL, push_compliance=0.0)}
    assert all(np.array_equal(zero[k], stiff[k]) for k in stiff)
    c = 0.0011
    give = c * TOOL.rules.drag_friction * mass * 9.81
    assert push_give(a, c, TOOL) == pytest.approx(give)
    soft = {w.label: w.position for w in action_waypoints(push, (a,), SHELF, TOOL, push_compliance=c)}
    assert soft["insert"] == pytest.approx(stiff["insert"], abs=1e-12)
    assert sign * (soft["push"][0] - stiff["push"][0]) == pytest.approx(give, abs=1e-12)
    assert soft["back off"] == pytest.approx(stiff["back off"], abs=1e-12)
    assert soft["retract"] == pytest.approx(stiff["retract"], abs=1e-12)


def test_an_unweighed_object_gives_as_its_class_median_weighs():
    """A hypothesis without a mass gives as much as the action model reckons it weighs (household: its class's
    median), and a density-model object as its density times its volume."""
    from slax_drake.planning.waypoints import push_give
    from slax_drake.scene.mass import object_mass

    a = SceneObject("a", "box", (0.08, 0.08, 0.05), planar_pose(0.0, 0.05, 0.025, 0.0))
    expected = object_mass(a, TOOL.physics.object_density, TOOL.physics, TOOL.rules.mass_quantile)
    assert expected > 0
    assert push_give(a, 0.001, TOOL) == pytest.approx(0.001 * TOOL.rules.drag_friction * expected * 9.81)
    assert push_give(a, 0.0, TOOL) == 0.0
