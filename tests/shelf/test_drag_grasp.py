"""The drag grasp (the ``drag_grasp`` rule): an object the cup may not lift is dragged on the shelf floor when
the pull it needs is within the cup's, it does not tip, and its swept footprint is clear. Hand-built cases of
the lift/drag choice and the shelf simulator's drag (the planner's: tests/planning/test_drag_motion.py)."""

import math

import pytest

from slax_drake.shelf.actions import DRAG_MIN_SEAL_Z, GRAVITY, ActionModel
from slax_drake.shelf.simulator import execute
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

CUP = dict(max_suction_moment=0.4, max_drag_pull=42.412, max_drag_twist=0.6362)  # the station YAML's cup: 0.4 N m
# lift limit, 42.4 N pull, 0.64 N m lip moment


def _box(name, x, y, size, mass=None):
    return SceneObject(name, "box", size, planar_pose(x, y, size[2] / 2, 0.0), mass=mass)


def _model(scenario, profile="station", **rules):
    return ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position,
                       tool_config(scenario, profile, **{**CUP, **rules}))


def _grips(candidates, name):
    return {s.grip for s in candidates.feasible if s.kind == "suction" and s.name == name}


def test_a_light_box_is_lifted_and_a_heavy_one_dragged(sim_scenario):
    model = _model(sim_scenario)
    light = _box("light", 0.0, 0.05, (0.10, 0.10, 0.12), mass=0.2)  # 0.2 x 9.81 x 0.05 = 0.10 N m: lifted
    heavy = _box("heavy", 0.0, 0.05, (0.16, 0.16, 0.16), mass=2.0)  # 2 x 9.81 x 0.08 = 1.6 N m: dragged
    assert _grips(model.enumerate((light,), pushes=False), "light") == {"lift"}
    assert _grips(model.enumerate((heavy,), pushes=False), "heavy") == {"drag"}
    # with drag_grasp off (and in the paper profile) the heavy box is refused, as before
    off = model.__class__(model.shelf, (*model.eye_xy, model.eye_z), tool_config(sim_scenario, "station",
                                                                              drag_grasp=False, **CUP))
    refused = off.enumerate((heavy,), pushes=False)
    assert not refused.feasible and "N m off the cup" in refused.rejected[0].reason
    assert not _model(sim_scenario, "paper").tool.rules.drag_grasp


def test_a_drag_seals_low_enough_not_to_tip(sim_scenario):
    model = _model(sim_scenario)
    heavy = _box("heavy", 0.0, 0.05, (0.16, 0.16, 0.16), mass=2.0)
    limits = model.drag_limits(heavy, 0.16)
    mu = 1.5 * 0.44
    assert limits.refusal is None
    assert limits.tip_z == pytest.approx(0.08 / mu)
    assert limits.pull == pytest.approx(mu * 2.0 * GRAVITY)
    drag = model.enumerate((heavy,), pushes=False).feasible[0]
    assert DRAG_MIN_SEAL_Z <= drag.q[2] <= 0.08 / mu + 1e-9


def test_a_slender_heavy_box_would_tip_and_is_refused(sim_scenario):
    # 3 kg, 3 cm deep: hangs 3 x 9.81 x 0.015 = 0.44 N m off the cup (not lifted); a pull above
    # 1.5 cm / (1.5 x 0.44) = 2.3 cm tips it, and the tube seals no lower than 2.5 cm
    slender = _box("slender", 0.0, 0.05, (0.20, 0.03, 0.25), mass=3.0)
    result = _model(sim_scenario, max_seal_angle_deg=90.0).enumerate((slender,), pushes=False)
    assert not result.feasible
    assert "would tip" in result.rejected[0].reason


def test_a_box_too_heavy_for_the_cups_pull_is_refused(sim_scenario):
    # 8 kg: mu' m g = 0.66 x 8 x 9.81 = 51.8 N > 42.4 N
    brick = _box("brick", 0.0, 0.05, (0.16, 0.16, 0.16), mass=8.0)
    result = _model(sim_scenario).enumerate((brick,), pushes=False)
    assert not result.feasible and "pull to slide" in result.rejected[0].reason
    assert _grips(_model(sim_scenario, max_drag_pull=100.0).enumerate((brick,), pushes=False), "brick") == {"drag"}


def test_a_box_that_would_twist_off_the_cup_is_dragged_only_straight_out_and_back(sim_scenario):
    """Sliding sideways, the floor's friction at the centre twists the box about the cup: mu' x the held moment.
    1 kg 8 cm behind the contact: 0.66 x 0.78 = 0.52 N m, under the lip's 0.64; 2 kg: 1.04 N m, over."""
    model = _model(sim_scenario)
    one = _box("one", 0.0, 0.10, (0.16, 0.16, 0.16), mass=1.0)
    two = _box("two", 0.0, 0.10, (0.16, 0.16, 0.16), mass=2.0)
    assert {round(s.dx, 3) for s in model.enumerate((one,), pushes=False).feasible} - {0.0}
    assert {round(s.dx, 3) for s in model.enumerate((two,), pushes=False).feasible} == {0.0}
    blocked = _box("blocked", 0.0, -0.10, (0.16, 0.16, 0.16), mass=2.0)
    result = model.enumerate((blocked,), pushes=False)  # at the front already: dz >= its y, none deeper free
    assert all(s.dx == 0.0 for s in result.feasible)


def test_a_drag_never_passes_over_a_low_object(sim_scenario):
    """A lifted object passes over a low one in front of it; a dragged one cannot: it is refused."""
    heavy = _box("heavy", 0.0, 0.10, (0.16, 0.16, 0.16), mass=2.0)
    low = _box("low", 0.0, -0.17, (0.12, 0.08, 0.06), mass=0.1)
    result = _model(sim_scenario).enumerate((heavy, low), pushes=False, only=("heavy",))
    assert not result.feasible
    assert "path out of the shelf blocked by low" in result.rejected[0].reason
    lifted = _model(sim_scenario, max_suction_moment=math.inf).enumerate((heavy, low), pushes=False, only=("heavy",))
    assert _grips(lifted, "heavy") == {"lift"}


def test_a_drags_way_across_must_be_clear(sim_scenario):
    """An object standing on the front row to the right blocks every drag to the right across it."""
    heavy = _box("heavy", -0.15, 0.10, (0.16, 0.16, 0.16), mass=1.0)
    front = _box("front", 0.10, -0.22, (0.08, 0.08, 0.12), mass=0.1)
    result = _model(sim_scenario).enumerate((heavy, front), pushes=False, only=("heavy",))
    dxs = {round(s.dx, 3) for s in result.feasible}
    assert dxs and all(heavy.center[0] + dx < 0.10 - 0.04 - 0.08 for dx in dxs)


def test_the_simulator_stops_a_drag_at_an_unseen_object(sim_scenario):
    model = _model(sim_scenario)
    heavy = _box("heavy", 0.0, 0.10, (0.16, 0.16, 0.16), mass=1.0)
    shelf = shelf_of(sim_scenario)
    drag = next(s for s in model.enumerate((heavy,), pushes=False).feasible if s.dx == 0.15 and s.dz > 0.05)
    unseen = _box("unseen", 0.15, 0.20, (0.10, 0.06, 0.10), mass=0.2)
    after, note = execute(Scene(shelf, Camera.from_config(sim_scenario.camera), (heavy, unseen), None), drag, model)
    assert "stopped early" in note
    moved = after.objects[0]
    assert moved.center[0] == pytest.approx(0.15) and moved.center[1] < drag.dz


# ---- guarded placement (suction_hidden_rule "guarded", a named variant of no profile) ------------------------
def _hidden_scene():
    """A wide box at the front hides the back left of the bay; a light box to the right may be suctioned."""
    wall = _box("wall", -0.12, -0.15, (0.30, 0.06, 0.30), mass=0.3)
    light = _box("light", 0.20, -0.10, (0.08, 0.08, 0.10), mass=0.2)
    return wall, light


def test_a_guarded_placement_reaches_into_hidden_space(sim_scenario):
    wall, light = _hidden_scene()
    station = _model(sim_scenario).enumerate((wall, light), pushes=False, only=("light",)).feasible
    guarded = _model(sim_scenario, suction_hidden_rule="guarded").enumerate(
        (wall, light), pushes=False, only=("light",)).feasible
    assert station and not any(s.guarded for s in station)
    into_hidden = [s for s in guarded if s.guarded]
    assert into_hidden and {(s.dx, s.dz) for s in into_hidden}.isdisjoint({(s.dx, s.dz) for s in station})
    assert {(s.dx, s.dz) for s in guarded if not s.guarded} == {(s.dx, s.dz) for s in station}
    assert into_hidden[0].describe().endswith(" guarded")


def test_the_simulator_stops_a_guarded_placement_on_an_unseen_object_and_completes_it_otherwise(sim_scenario):
    model = _model(sim_scenario, suction_hidden_rule="guarded")
    wall, light = _hidden_scene()
    shelf = shelf_of(sim_scenario)
    camera = Camera.from_config(sim_scenario.camera)
    action = next(s for s in model.enumerate((wall, light), pushes=False, only=("light",)).feasible
                  if s.guarded and s.dz >= 0.15)
    done, note = execute(Scene(shelf, camera, (wall, light), None), action, model)
    assert note == "" and done.objects[1].center[1] == pytest.approx(action.dz)
    x = light.center[0] + action.dx
    unseen = _box("unseen", x, action.dz + 0.02, (0.08, 0.08, 0.40), mass=0.2)  # too tall to pass over
    stopped, note = execute(Scene(shelf, camera, (wall, light, unseen), None), action, model)
    assert note == "guarded placement stopped on contact"
    assert stopped.objects[1].center[1] < action.dz and stopped.objects[2] == unseen


def test_a_guarded_placement_whose_way_in_passes_over_a_known_object_is_not_offered(sim_scenario):
    """The planner refuses a lifted guarded push-in carried higher than the lowest carry (over a known object on the
    way in: it could pass over a lower unseen one and be lowered onto it); the action model offers none such, so the
    shelf simulator and the Drake trial execute the same placements. Non-guarded placements may still pass over."""
    wall, light = _hidden_scene()
    low = _box("low", 0.20, -0.24, (0.06, 0.06, 0.03), mass=0.1)  # in front of the light box, low enough to pass
    model = _model(sim_scenario, suction_hidden_rule="guarded")
    without = model.enumerate((wall, light), pushes=False, only=("light",)).feasible
    with_low = model.enumerate((wall, light, low), pushes=False, only=("light",)).feasible
    half = light.size[0] / 2 + low.size[0] / 2

    def crosses_low(s):  # the light box's way in at its placement's column overlaps the low box's x extent
        return abs(light.center[0] + s.dx - low.center[0]) < half and s.dz > low.center[1]

    assert any(s.guarded and crosses_low(s) for s in without)
    assert with_low
    assert not any(s.guarded and crosses_low(s) for s in with_low)
    assert any(not s.guarded and crosses_low(s) for s in with_low)  # carried over it, placed in seen space


def test_the_mass_quantile_plans_an_unweighed_hypothesis_heavier(sim_scenario):
    """Under the household mass model a hypothesis without a mass weighs its class's ``mass_quantile``: at the
    median (the default) a 1.9 L box 0.16 m deep is lifted (0.28 kg, 0.22 N m off the cup), at 0.9 it is planned
    at 0.65 kg (0.51 N m > 0.4) and dragged; a box with a recorded mass is planned with that mass at any quantile."""
    import dataclasses

    household = dataclasses.replace(sim_scenario, physics=dataclasses.replace(sim_scenario.physics,
                                                                              mass_model="household"))
    hyp = _box("hyp", 0.0, 0.05, (0.10, 0.16, 0.12))
    median, cautious = _model(household), _model(household, mass_quantile=0.9)
    assert median.planning_mass(hyp) == pytest.approx(math.sqrt(0.10 * 0.80))
    assert cautious.planning_mass(hyp) == pytest.approx(0.10 * 8.0 ** 0.9)
    assert _grips(median.enumerate((hyp,), pushes=False), "hyp") == {"lift"}
    assert _grips(cautious.enumerate((hyp,), pushes=False), "hyp") == {"drag"}
    weighed = dataclasses.replace(hyp, mass=0.2)
    assert _grips(cautious.enumerate((weighed,), pushes=False), "hyp") == {"lift"}


@pytest.mark.parametrize("value", ["1.5", "-0.1"])
def test_a_mass_quantile_outside_0_1_is_refused(value):
    from slax_drake.shelf.rules import RULES

    assert RULES["mass_quantile"].problem(float(value)) == "must be between 0 and 1"
    assert RULES["mass_quantile"].problem(0.75) is None
