"""Feasibility rules of the bluction action model on hand-built scenes."""

import numpy as np
import pytest

from slax_drake.shelf.actions import ActionModel, Push, Suction, ToolConfig, apply_action
from slax_drake.scene.footprint import Footprint, footprints_clear, inside_shelf
from slax_drake.scene.model import SceneObject, Shelf, planar_pose

SHELF = Shelf(0.60, 0.60, 0.60, 0.02)
EYE = np.array([0.0, -0.75, 0.20])


def box(name, x, y, sx=0.08, sy=0.08, sz=0.10, yaw=0.0):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, yaw))


def cyl(name, x, y, d=0.10, h=0.10):
    return SceneObject(name, "cylinder", (d, d, h), planar_pose(x, y, h / 2, 0.0))


def model(**kw):
    return ActionModel(SHELF, EYE, ToolConfig.build(**kw))


def reasons(cands, what):
    return [r.reason for r in cands.rejected if r.what.startswith(what)]


def pushes_of(cands, name, sign):
    return [a for a in cands.feasible if isinstance(a, Push) and a.name == name and np.sign(a.d) == sign]


def test_blade_needs_a_gap_as_wide_as_the_blade():
    # a and b stand side by side 3 cm apart: the 6.5 cm blade cannot go between them.
    a, b = box("a", -0.10, -0.10), box("b", -0.10 + 0.08 + 0.03, -0.10)
    c = model().enumerate((a, b), suctions=False)
    assert reasons(c, "push b +x") == ["blade gap left of b blocked by a"]
    assert reasons(c, "push a -x") == ["blade gap right of a blocked by b"]
    # pushed toward each other from the free side, they stop short of the 3 cm gap
    assert max(abs(p.d) for p in pushes_of(c, "b", -1) + pushes_of(c, "a", +1)) <= 0.03 - 0.002 + 1e-9
    # 8 cm apart, it fits.
    b2 = box("b", -0.10 + 0.08 + 0.08, -0.10)
    c2 = model().enumerate((a, b2), suctions=False)
    assert pushes_of(c2, "b", +1)


def test_the_tube_end_past_the_blade_needs_room_behind_the_gap():
    """The cup at the tube's end reaches tube_past_blade (2 cm) beyond the blade's tip: an object standing just
    behind the blade's lane blocks the push; 2.5 cm further back it does not."""
    a = box("a", -0.10, -0.10)  # pushed +x: the blade's lane is left of it, the tip at y = -0.11
    behind = box("c", -0.19, -0.06)  # its front at y = -0.10, 1 cm behind the blade's tip, across the lane
    assert reasons(model().enumerate((a, behind), suctions=False), "push a +x") == ["blade gap left of a blocked by c"]
    assert pushes_of(model(tube_past_blade=0.0).enumerate((a, behind), suctions=False), "a", +1)
    further = box("c", -0.19, -0.035)  # its front at y = -0.075
    assert pushes_of(model().enumerate((a, further), suctions=False), "a", +1)


def test_blade_does_not_fit_against_a_wall():
    a = box("a", -0.30 + 0.04 + 0.03, -0.10)  # 3 cm from the left wall
    c = model().enumerate((a,), suctions=False)
    assert reasons(c, "push a +x") == ["blade does not fit between a and the left wall"]
    assert pushes_of(c, "a", +1) == []
    assert max(abs(p.d) for p in pushes_of(c, "a", -1)) <= 0.03 - 0.002 + 1e-9  # toward the wall: 3 cm at most


def test_shaft_way_in_must_be_clear_in_the_strict_variant_only():
    front, back = box("front", 0.0, -0.20, sx=0.24, sz=0.06), box("back", 0.0, 0.05, sx=0.06)
    strict = model(shaft_lane_check=True, hidden_space="overhead").enumerate((front, back), suctions=False)
    assert reasons(strict, "push back") == ["blade shaft's way in left of back blocked by front",
                                            "blade shaft's way in right of back blocked by front"]
    assert not [a for a in strict.feasible if a.name == "back"]
    # First order (default): the shaft's way in is the planner's business; "back" is pushable, and
    # "front" (0.06 m tall) hides no space where "back" moves, the camera seeing over it.
    first_order = model().enumerate((front, back), suctions=False)
    assert not any("shaft" in r for r in reasons(first_order, "push back"))
    assert pushes_of(first_order, "back", +1) and pushes_of(first_order, "back", -1)


def test_thin_blade_gap_is_the_tube_width_and_the_strict_gap_the_blade_width():
    # 5 cm between a and b: enough for the 3.5 cm first-order gap, not for the 6.5 cm strict one.
    a, b = box("a", -0.10, -0.10), box("b", -0.10 + 0.08 + 0.05, -0.10)
    assert pushes_of(model().enumerate((a, b), suctions=False), "b", +1)
    strict = model(blade_gap=0.065).enumerate((a, b), suctions=False)
    assert reasons(strict, "push b +x") == ["blade gap left of b blocked by a"]
    # q keeps its meaning (the 6.5 cm lane's centre beside the object) whatever the gap
    q = pushes_of(model().enumerate((a, b), suctions=False), "b", +1)[0].q
    assert q[0] == pytest.approx(b.center[0] - 0.04 - 0.065 / 2)


def test_push_moves_exactly_one_object_and_stops_before_its_neighbour():
    a, b = box("a", -0.15, -0.10), box("b", 0.10, -0.10)
    m = model()
    c = m.enumerate((a, b), suctions=False)
    right = pushes_of(c, "a", +1)
    d_max = max(a_.d for a_ in right)
    gap = (0.10 - 0.04) - (-0.15 + 0.04)
    assert d_max == pytest.approx(gap - m.tool.physics.clearance, abs=m.tool.grid.cell)
    assert d_max <= gap - m.tool.physics.clearance + 1e-9
    after = apply_action((a, b), max(right, key=lambda p: p.d))
    assert np.allclose(after[1].X_SO, b.X_SO)  # b did not move
    assert after[0].center[1] == pytest.approx(a.center[1]) and after[0].center[0] > a.center[0]
    assert footprints_clear(Footprint.of(after[0]), Footprint.of(after[1]), m.tool.physics.clearance - 1e-9)
    # every candidate distance is a multiple of the resolution, or the maximal push
    for p in right:
        assert p.d == pytest.approx(d_max) or abs(p.d / m.tool.grid.push_resolution - round(p.d / m.tool.grid.push_resolution)) < 1e-6


def test_nothing_is_pushed_into_space_hidden_behind_another_object():
    # "front" hides the space behind it; "back" stands to its right, deeper, in the open.
    front = box("front", -0.05, -0.20, sx=0.16, sy=0.06, sz=0.20)
    back = box("back", 0.15, 0.10, sx=0.07, sy=0.07)
    m = model()
    c = m.enumerate((front, back), suctions=False)
    left = pushes_of(c, "back", -1)
    assert left, "back can be pushed left a little"
    d_min = min(p.d for p in left)  # the longest push to the left
    moved = apply_action((front, back), Push("back", (0, 0, 0), d_min))[1]
    # The shadow of "front": rays from the camera through its right edge; the moved object stays right of it.
    fp = Footprint.of(moved)
    ex, ey = fp.extents()
    corner = np.array([fp.x - ex, fp.y - ey])  # the moved object's front-left corner
    edge = np.array([-0.05 + 0.08, -0.20 - 0.03])  # front's front-right corner: its shadow's right boundary
    ray = edge - EYE[:2]
    to_corner = corner - EYE[:2]
    assert ray[0] * to_corner[1] - ray[1] * to_corner[0] <= 0.01 * np.hypot(*to_corner)  # corner not left of ray
    assert any("hidden space" in r for r in reasons(c, "push back -x"))


@pytest.mark.parametrize("hidden_space", ["overhead", "3d"])
def test_low_objects_hide_space_only_overhead(hidden_space):
    # A 6 cm tall box in front: the camera (z = 0.20) sees over it, so only the overhead rule forbids
    # pushing "back" into the space behind it.
    front = box("front", -0.05, -0.20, sx=0.16, sy=0.06, sz=0.06)
    back = box("back", 0.15, 0.10, sx=0.07, sy=0.07)
    c = model(hidden_space=hidden_space).enumerate((front, back), suctions=False)
    longest = -min(p.d for p in pushes_of(c, "back", -1))
    if hidden_space == "overhead":
        assert longest < 0.10 and any("hidden space" in r for r in reasons(c, "push back -x"))
    else:
        assert longest == pytest.approx(0.15 - 0.035 + 0.30 - 0.002, abs=0.006)  # to the left wall


def test_suction_placements_are_collision_free_and_inside_the_shelf():
    objs = (box("a", -0.15, -0.15), box("b", 0.10, -0.05, sx=0.12), cyl("c", 0.0, 0.18, d=0.10))
    m = model()
    c = m.enumerate(objs, pushes=False)
    sucs = [a for a in c.feasible if isinstance(a, Suction)]
    assert sucs
    for s in sucs:
        after = apply_action(objs, s)
        fps = [Footprint.of(o) for o in after]
        for i in range(len(fps)):
            assert inside_shelf(fps[i], SHELF, m.tool.physics.clearance - 1e-9)
            for j in range(i + 1, len(fps)):
                assert footprints_clear(fps[i], fps[j], m.tool.physics.clearance - 1e-9), s


def test_suction_rejections_say_why():
    heavy = box("heavy", -0.15, -0.15, 0.20, 0.20, 0.20)  # 3.2 kg at 400 kg/m^3
    thin = cyl("thin", 0.15, -0.15, d=0.06)  # radius 3 cm < 4 cm seal radius
    blocked = box("blocked", 0.15, 0.10, sz=0.12)  # thin stands in its way out
    strict = dict(max_suction_mass=2.0, min_seal_radius=0.04, tube_approach_check=True, suction_lift="slight")
    c = model(**strict).enumerate((heavy, thin, blocked), pushes=False)
    assert reasons(c, "suction heavy") == ["heavy weighs 3.20 kg > 2.00 kg"]
    assert reasons(c, "suction thin") == ["thin's camera-facing side is too small or curved for the cup"]
    assert reasons(c, "suction blocked") == ["tube approach to blocked blocked by thin"] or reasons(
        c, "suction blocked") == ["path out of the shelf blocked by thin"]


def test_first_order_suction_defaults():
    # No weight limit, a 3 cm radius cylinder seals (the cup is 1.5 cm), a 2 cm wide face is too small.
    heavy = box("heavy", -0.15, -0.15, 0.20, 0.20, 0.20)
    thin = cyl("thin", 0.15, -0.15, d=0.06)
    sliver = box("sliver", 0.0, 0.15, sx=0.02, sy=0.10, sz=0.10)  # its camera-facing face is 2 cm wide
    c = model().enumerate((heavy, thin, sliver), pushes=False)
    names = {a.name for a in c.feasible}
    assert {"heavy", "thin"} <= names and "sliver" not in names
    assert reasons(c, "suction sliver") == ["sliver's camera-facing side is too small or curved for the cup"]


@pytest.mark.parametrize("lift", ["slight", "over-lower"])
def test_lifted_object_passes_over_lower_objects_only_when_allowed(lift):
    low = box("low", 0.0, -0.20, sx=0.20, sy=0.08, sz=0.06)  # right in front of "tall"
    tall = box("tall", 0.0, 0.0, sx=0.10, sy=0.08, sz=0.15)
    c = model(suction_lift=lift).enumerate((low, tall), pushes=False)
    tall_moves = [a for a in c.feasible if a.name == "tall"]
    if lift == "slight":
        assert tall_moves == [] and reasons(c, "suction tall") == ["path out of the shelf blocked by low"]
    else:
        assert tall_moves  # 0.06 + 0.02 + 0.15 < 0.60: lifted over "low"
        for s in tall_moves:  # and never put down on it
            after = apply_action((low, tall), s)
            assert footprints_clear(Footprint.of(after[0]), Footprint.of(after[1]), 0.002 - 1e-9)


def test_suction_placements_avoid_hidden_space():
    objs = (box("a", -0.15, -0.15, sz=0.18), box("b", 0.10, -0.05, sx=0.12), cyl("c", 0.0, 0.18, d=0.10))
    m = model()
    from slax_drake.shelf.actions import _StateContext

    ctx = _StateContext(m, objs, ())
    sucs = [a for a in m.enumerate(objs, pushes=False).feasible]
    assert sucs
    for s in sucs:
        i = [o.name for o in objs].index(s.name)
        placed = apply_action(objs, s)[i]
        mask = m.grid.footprint_mask(Footprint.of(placed))
        assert not (mask & ctx.hidden_all & ~ctx.masks[i]).any(), s


def test_suction_beyond_the_tube_is_not_reachable():
    deep = box("deep", 0.0, 0.22)  # front face 0.48 m behind the opening
    assert reasons(model().enumerate((deep,), pushes=False), "suction deep") == ["deep's face is beyond the tube's reach"]


def test_enumeration_is_deterministic():
    objs = (box("a", -0.15, -0.15), box("b", 0.10, -0.05, sx=0.12, yaw=0.4), cyl("c", 0.0, 0.18))
    assert model().enumerate(objs).feasible == model().enumerate(objs).feasible


def test_hidden_slivers_narrower_than_the_smallest_object_do_not_count():
    from slax_drake.shelf.floor import open_with_disc

    mask = np.zeros((40, 40), dtype=bool)
    mask[5:30, 5:9] = True  # 4 cells (2 cm) wide: no 6 cm disc (radius 6 cells) fits
    mask[5:25, 20:35] = True  # 15 x 20 cells: it does
    opened = open_with_disc(mask, 6)
    assert not opened[:, :10].any()
    assert opened[11:19, 20:35].all() and opened[5:25, 26:29].all()  # all but the rounded corners
    assert not (opened & ~mask).any()
    assert (open_with_disc(mask, 0) == mask).all()


def shift_mask(mask: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """The mask translated by (rows, cols) cells; cells shifted in from outside are False."""
    out = np.zeros_like(mask)
    ny, nx = mask.shape
    if abs(rows) >= ny or abs(cols) >= nx:
        return out
    src = mask[max(0, -rows): ny - max(0, rows), max(0, -cols): nx - max(0, cols)]
    out[max(0, rows): ny - max(0, -rows), max(0, cols): nx - max(0, -cols)] = src
    return out


def test_disc_opening_equals_the_union_of_fitting_discs():
    """OpenCV's opening against the definition: a cell is kept when some disc lying entirely inside the mask
    (cells beyond the raster's edge are outside) covers it."""
    from slax_drake.shelf.floor import disc_offsets, open_with_disc

    rng = np.random.default_rng(3)
    for radius in (1, 3, 6):
        kept = 0
        for _ in range(5):
            # blocks of free cells with holes, so discs of every radius fit in some places and not in others
            mask = np.kron(rng.random((8, 9)) < 0.6, np.ones((5, 5), dtype=bool))[:37, :45]
            mask &= rng.random(mask.shape) < 0.98
            offsets = disc_offsets(radius)
            centres = mask.copy()
            for dr, dc in offsets:
                centres &= shift_mask(mask, -dr, -dc)
            expected = np.zeros_like(mask)
            for dr, dc in offsets:
                expected |= shift_mask(centres, dr, dc)
            assert (open_with_disc(mask, radius) == expected).all()
            kept += int(expected.sum())
        assert kept > 0



@pytest.mark.parametrize("obj", [box("b", 0.0, 0.0, sx=0.16, sy=0.06, yaw=y) for y in (0.0, 0.4, 1.2, 2.55, 3.0)]
                         + [cyl("c", 0.0, 0.0, d=0.16)])
@pytest.mark.parametrize("sign", [+1, -1])
def test_the_blade_meets_the_object_where_the_push_starts(obj, sign):
    """The blade (a plate at the object's extreme x on its side, blade_width along y, its tip at q's y) touches
    the object within 1 mm of travel: for turned boxes its extreme corner, for discs the point level with the
    centre, lies within the blade's span."""
    from shapely.geometry import LineString, Point

    m = model()
    fp = Footprint.of(obj)
    ex, _ = fp.extents()
    tip = m.blade_depth(fp, sign)
    x_plate = fp.x - sign * ex + sign * 0.001  # the blade's face after 1 mm of travel
    plate = LineString([(x_plate, tip - m.tool.geometry.blade_width), (x_plate, tip)])
    # a disc's true outline (the polygon circumscribes it), a rectangle's exact one
    outline = fp.polygon(16) if fp.shape == "box" else Point(fp.x, fp.y).buffer(fp.half_x, 256)
    assert plate.intersects(outline)
    assert tip >= fp.y - fp.extents()[1] + m.tool.geometry.push_contact_depth - 1e-12


def test_the_tube_must_reach_the_cup_contact_past_the_objects_in_front():
    # "back" is seen above "front" from the camera, but its sealable face is lower than front's top: the
    # horizontal tube would pass through front. Over-lower lifting would carry back over front on the way out.
    back = box("back", 0.0, 0.12, sx=0.10, sy=0.08, sz=0.20)
    front = box("front", 0.0, -0.10, sx=0.12, sy=0.08, sz=0.19)
    contact = model().suction_contact(back)
    assert contact[2] - 0.015 < 0.19  # the tube's underside is below front's top
    strict = model().enumerate((back, front), pushes=False)
    assert not [a for a in strict.feasible if a.name == "back"]
    assert reasons(strict, "suction back") == ["tube approach to back blocked by front"]
    loose = model(tube_approach_check=False).enumerate((back, front), pushes=False)
    assert [a for a in loose.feasible if a.name == "back"]


def test_an_object_hanging_too_much_weight_off_the_cup_is_not_suctioned():
    # 0.08 x 0.20 x 0.10 m at 400 kg/m^3 = 0.64 kg, its centre 0.10 m behind its face: 0.63 N m off the cup.
    long = box("long", 0.0, 0.0, sx=0.08, sy=0.20, sz=0.10)
    short = box("short", 0.0, 0.0, sx=0.08, sy=0.08, sz=0.10)  # 0.256 kg, 0.04 m: 0.10 N m
    held = model(max_suction_moment=0.4, drag_grasp=False)
    assert reasons(held.enumerate((long,), pushes=False), "suction long") == [
        "long's weight hangs 0.63 N m off the cup > 0.40 N m"]
    # the station profile drags it instead (tests/shelf/test_drag_grasp.py)
    assert {a.grip for a in model(max_suction_moment=0.4).enumerate((long,), pushes=False).feasible} == {"drag"}
    assert [a for a in held.enumerate((short,), pushes=False).feasible if a.name == "short"]
    assert [a for a in model().enumerate((long,), pushes=False).feasible if a.name == "long"]


@pytest.mark.parametrize("yaw_deg, angle_deg", [(0.0, 0.0), (8.0, 8.0), (25.0, 25.0), (70.0, 20.0), (135.0, 45.0)])
def test_a_box_face_turned_too_far_from_the_tube_is_not_sealed(yaw_deg, angle_deg):
    """With the tube along the shelf's y (``max_tool_yaw_deg=0``), the seal angle is the front face's turn from
    it; the cup refuses more than max_seal_angle_deg, and the first-order default (90) refuses nothing. With the
    station's turning tool (30 deg) only the turn beyond 30 deg counts."""
    import math

    turned = box("turned", 0.0, 0.0, sx=0.10, sy=0.10, sz=0.10, yaw=math.radians(yaw_deg))
    assert ActionModel.seal_angle_deg(turned) == pytest.approx(angle_deg, abs=1e-6)
    assert ActionModel.seal_angle_deg(cyl("round", 0.0, 0.0)) == 0.0
    turning = model(max_seal_angle_deg=10.0).enumerate((turned,), pushes=False)
    assert bool(turning.feasible) == (angle_deg <= 40.0)
    sealed = model(max_seal_angle_deg=10.0, max_tool_yaw_deg=0.0).enumerate((turned,), pushes=False)
    if angle_deg > 10.0:
        assert not sealed.feasible
        assert reasons(sealed, "suction turned") == [
            f"turned's camera-facing side is turned {angle_deg:.0f} deg from the tube > 10 deg"]
    else:
        assert sealed.feasible
    assert model().enumerate((turned,), pushes=False).feasible
