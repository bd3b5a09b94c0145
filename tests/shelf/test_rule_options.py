"""The readings of the paper that the paper profile does not take, each a named option (issue 19, item 4): a push
that stops against its neighbour, a push that crosses hidden space, the target placed first, n counting the target;
on hand-built scenes, each option refused when malformed, and today's behaviour kept by default."""

import copy
import dataclasses

import numpy as np
import pytest

from slax_drake.config import ProtocolConfig, Scenario, load_scenario, validate_scenario
from slax_drake.errors import ConfigError, UserError
from slax_drake.evaluation.settings import scenario_digest
from slax_drake.shelf.actions import ActionModel, Push, apply_action
from slax_drake.shelf.floor import free_push_cells, push_end_hidden
from slax_drake.shelf.tool import parse_tool_rules, tool_config, without_defaults
from slax_drake.shelf.rules import ToolConfig, tool_config_problem
from slax_drake.shelf.simulator import execute
from slax_drake.scene.camera import Camera
from slax_drake.scene.footprint import Footprint, footprints_clear
from slax_drake.scene.model import Scene, SceneObject, Shelf, planar_pose
from slax_drake.scene.sampling import sample_scene, target_visible_fraction

SHELF = Shelf(0.60, 0.60, 0.60, 0.02)
EYE = np.array([0.0, -0.75, 0.20])


def box(name, x, y, sx=0.08, sy=0.08, sz=0.10):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))


def longest(model, objects, name, sign):
    cands = model.enumerate(objects, suctions=False, only={name})
    return max((abs(p.d) for p in cands.feasible if isinstance(p, Push) and (p.d > 0) == (sign > 0)), default=None)


# ---- push_stop ------------------------------------------------------------------------------------------------------
GAP = 0.0437  # between a's right side and b's left side (m)
A, B = box("a", -0.10, -0.10), box("b", -0.10 + 0.08 + GAP, -0.10)


def test_lattice_push_stops_short_of_its_neighbour_by_default():
    d = longest(ActionModel(SHELF, EYE, ToolConfig.build("paper")), (A, B), "a", +1)
    assert d == pytest.approx(0.040)  # the last 5 mm step that keeps 2 mm: 3.7 mm short


def test_exact_push_stop_with_no_clearance_ends_against_the_neighbour():
    model = ActionModel(SHELF, EYE, ToolConfig.build("paper", push_stop="exact", clearance=0.0))
    d = longest(model, (A, B), "a", +1)
    assert d == pytest.approx(GAP, abs=2e-6)
    a_after = apply_action((A, B), Push("a", (0.0, 0.0, 0.0), d))[0]
    assert footprints_clear(Footprint.of(a_after), Footprint.of(B), 0.0)  # touching, not overlapping
    assert not footprints_clear(Footprint.of(a_after), Footprint.of(B), 1e-5)
    # the shelf simulator executes that push in full (it stops at the same contact)
    scene = Scene(SHELF, Camera.from_config(load_scenario("sim_configs/table1.yaml").camera), (A, B), None, 0)
    push = next(p for p in model.enumerate((A, B), suctions=False, only={"a"}).feasible if p.d == d)
    moved, note = execute(scene, push, model)
    assert note == "" and float(moved.objects[0].center[0]) == pytest.approx(-0.10 + d)


def test_exact_push_stop_keeps_the_clearance_it_is_given():
    model = ActionModel(SHELF, EYE, ToolConfig.build("paper", push_stop="exact"))  # clearance 2 mm
    assert longest(model, (A, B), "a", +1) == pytest.approx(GAP - 0.002, abs=2e-6)
    # against the wall as well: a alone, pushed left, ends 2 mm from the left wall
    assert longest(model, (A,), "a", -1) == pytest.approx(0.30 - 0.04 - 0.10 - 0.002, abs=2e-6)


# ---- push_hidden_extent ---------------------------------------------------------------------------------------------
# a tall narrow box in front hides a strip of floor behind it; m stands left of that strip and is pushed right
WALL, M = box("w", 0.0, -0.20, sx=0.10, sy=0.04, sz=0.30), box("m", -0.20, 0.10, sx=0.06, sy=0.06)


def test_path_reading_stops_a_push_at_the_edge_of_hidden_space():
    cands = ActionModel(SHELF, EYE, ToolConfig.build("paper")).enumerate((WALL, M), suctions=False, only={"m"})
    assert max(p.d for p in cands.feasible) == pytest.approx(0.09)
    assert "m would hit hidden space after 0.090 m" in [r.reason for r in cands.rejected]


def test_end_reading_lets_a_push_cross_hidden_space_but_not_stop_in_it():
    model = ActionModel(SHELF, EYE, ToolConfig.build("paper", push_hidden_extent="end"))
    ds = sorted(p.d for p in model.enumerate((WALL, M), suctions=False, only={"m"}).feasible if p.d > 0)
    assert ds[-1] == pytest.approx(0.465)  # across the strip to the wall (2 mm short)
    assert 0.05 in ds and not any(0.06 < d < 0.34 for d in ds)  # no push comes to rest in the hidden strip


def test_push_end_hidden_agrees_with_the_path_reading_before_the_first_hidden_cell():
    hidden = np.zeros((10, 20), dtype=bool)
    hidden[2:6, 9:11] = True
    fp = np.zeros_like(hidden)
    fp[3:5, 2:5] = True
    end = push_end_hidden(fp, hidden, +1, 15)
    first = free_push_cells(fp, hidden, +1)
    assert first == 4 and not end[:first].any() and end[first]  # the 5th step covers column 9
    assert not end[8:].any()  # from step 9 on the object is past the strip
    assert push_end_hidden(fp, hidden, -1, 2).tolist() == [False, False]


@pytest.mark.parametrize("rule,value", [("push_stop", "contact"), ("push_hidden_extent", "middle")])
def test_malformed_reading_options_are_refused(rule, value):
    assert rule in tool_config_problem(ToolConfig.build("paper", **{rule: value}))
    with pytest.raises(ValueError):
        ActionModel(SHELF, EYE, ToolConfig.build("paper", **{rule: value}))
    with pytest.raises(UserError):
        parse_tool_rules([f"{rule}={value}"], "paper")


def test_a_clearance_override_reaches_the_action_model_and_is_recorded():
    scenario = load_scenario("sim_configs/table1.yaml")
    assert tool_config(scenario, "paper", clearance=0.0).physics.clearance == 0.0
    assert tool_config(scenario, "paper").physics.clearance == scenario.objects.clearance
    assert without_defaults({"clearance": 0.0, "push_stop": "exact", "push_hidden_extent": "path"}, "paper") == \
        {"clearance": 0.0, "push_stop": "exact"}


# ---- scenario readings ----------------------------------------------------------------------------------------------
def test_n_may_count_the_target():
    assert ProtocolConfig().occluders(8) == 8
    assert ProtocolConfig(count_includes_target=True).occluders(8) == 7
    scenario = Scenario()
    scenario.protocol.count_includes_target = True
    scenario.protocol.densities = [1, 4]
    with pytest.raises(ConfigError, match="count_includes_target"):
        validate_scenario(scenario)


def test_target_placed_first_is_fully_hidden_clear_of_the_occluders_and_seeded():
    scenario = load_scenario("sim_configs/table1.yaml")
    first = copy.deepcopy(scenario)
    first.target.placement = "first"
    a = sample_scene(first, 6, 123, target_size=(0.06, 0.06, 0.06))
    b = sample_scene(first, 6, 123, target_size=(0.06, 0.06, 0.06))
    assert np.array_equal(a.target.center, b.target.center)
    assert target_visible_fraction(a) == 0.0
    target = Footprint.of(a.target.as_object())
    assert all(footprints_clear(Footprint.of(o), target, scenario.objects.clearance - 1e-9) for o in a.objects)
    default = sample_scene(scenario, 6, 123, target_size=(0.06, 0.06, 0.06))
    assert not np.array_equal(default.target.center, a.target.center)


def test_malformed_target_placement_is_refused():
    scenario = Scenario()
    scenario.target.placement = "behind-front-row"
    with pytest.raises(ConfigError, match="target.placement"):
        validate_scenario(scenario)


def test_the_readings_change_the_recorded_scenario_digest_only_when_taken():
    scenario = load_scenario("sim_configs/table1.yaml")
    before = dataclasses.asdict(scenario)  # what the digest hashed before the options existed
    before["target"].pop("placement")
    before["protocol"].pop("count_includes_target")
    import hashlib
    import json

    for key in ("seed", "densities", "scenes_per_density"):
        before["protocol"].pop(key)
    assert scenario_digest(scenario) == hashlib.sha256(json.dumps(before, sort_keys=True).encode()).hexdigest()
    for section, key, value in (("target", "placement", "first"), ("protocol", "count_includes_target", True)):
        changed = copy.deepcopy(scenario)
        setattr(getattr(changed, section), key, value)
        assert scenario_digest(changed) != scenario_digest(scenario)
