"""The action model's two rule profiles on hand-built scenes, and the profile as scenario data."""

import json

import numpy as np
import pytest

from slax_drake.config import load_scenario
from slax_drake.errors import ConfigError
from slax_drake.shelf.actions import ActionModel, Push, Suction
from slax_drake.shelf.rules import PROFILES, RULES, RuleSet, ToolConfig, overrides_of, profile_values, rule_set
from slax_drake.scene.model import SceneObject, Shelf, planar_pose

SHELF = Shelf(0.60, 0.60, 0.60, 0.02)
EYE = np.array([0.0, -0.75, 0.20])


def box(name, x, y, sx=0.08, sy=0.08, sz=0.10):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))


def model(profile, **overrides):
    return ActionModel(SHELF, EYE, ToolConfig.build(profile, **overrides))


def reasons(cands, what):
    return [r.reason for r in cands.rejected if r.what.startswith(what)]


def test_station_blade_lane_refuses_a_push_that_the_paper_thin_blade_makes():
    # 2 cm between a and b: the station's 3.5 cm lane does not fit beside b, the paper's 1 mm blade does.
    a, b = box("a", -0.10, -0.10), box("b", -0.10 + 0.08 + 0.02, -0.10)
    station = model("station").enumerate((a, b), suctions=False)
    assert reasons(station, "push b +x") == ["blade gap left of b blocked by a"]
    paper = model("paper").enumerate((a, b), suctions=False)
    assert any(isinstance(p, Push) and p.name == "b" and p.d > 0 for p in paper.feasible)
    # the same paper push with the station's lane put back as a single override is refused again
    back = model("paper", blade_gap=0.035).enumerate((a, b), suctions=False)
    assert reasons(back, "push b +x") == ["blade gap left of b blocked by a"]


def test_tube_way_in_is_a_station_rule_only():
    # a tall box stands right in front of a's camera-facing face: the horizontal tube cannot reach a's face.
    a, front = box("a", 0.0, 0.10), box("f", 0.0, -0.10, sx=0.10, sz=0.15)
    station = model("station").enumerate((a, front), pushes=False)
    assert reasons(station, "suction a") == ["tube approach to a blocked by f"]
    paper = model("paper").enumerate((a, front), pushes=False)
    assert any(isinstance(s, Suction) and s.name == "a" for s in paper.feasible)


def test_suction_placements_into_hidden_space_only_in_the_paper_profile():
    # a wide tall box in front hides the space behind it; m stands to the right in the open.
    wall, m = box("w", 0.0, -0.15, sx=0.24, sy=0.06, sz=0.30), box("m", 0.20, 0.0)
    hidden_spot = lambda c: [s for s in c.feasible if isinstance(s, Suction) and s.name == "m"  # noqa: E731
                             and abs(s.dx + 0.20) < 1e-6 and abs(s.dz - 0.15) < 1e-6]
    assert hidden_spot(model("paper").enumerate((wall, m), pushes=False))
    assert not hidden_spot(model("station").enumerate((wall, m), pushes=False))


def test_the_tubes_reach_limits_station_suctions():
    deep = box("d", 0.0, 0.20)  # its face 0.46 m behind the opening, past the 0.40 m tube
    assert reasons(model("station").enumerate((deep,), pushes=False), "suction d") == ["d's face is beyond the tube's reach"]
    assert any(isinstance(s, Suction) for s in model("paper").enumerate((deep,), pushes=False).feasible)


def test_profiles_are_data_with_a_docstring_per_rule():
    assert PROFILES == ("paper", "station")
    assert [f.name for f in __import__("dataclasses").fields(RuleSet)] == list(RULES)
    for name, rule in RULES.items():
        assert len(rule.doc) > 40, name
        assert rule.problem(rule.paper) is None and rule.problem(rule.station) is None, name
        if rule.paper != rule.station:  # a rule that differs says why, naming both profiles
            assert "``paper``" in type(rule).__doc__ and "``station``" in type(rule).__doc__, name
    paper = profile_values("paper")
    assert paper["blade_gap"] == 0.001 and paper["tube_past_blade"] == 0.0 and not paper["tube_approach_check"]
    assert paper["suction_hidden_rule"] == "none"
    assert overrides_of(rule_set("paper", blade_gap=0.035), "paper") == {"blade_gap": 0.035}
    assert overrides_of(rule_set("station"), "station") == {}
    with pytest.raises(ValueError, match="unknown rule"):
        rule_set("paper", no_such_rule=1.0)


def test_the_scenario_selects_the_profile(tmp_path):
    assert load_scenario("sim_configs/table1.yaml").profile == "paper"
    assert load_scenario("sim_configs/sim_shelf.yaml").profile == "station"
    bad = tmp_path / "bad.yaml"
    bad.write_text("profile: lab\n")
    with pytest.raises(ConfigError, match="profile"):
        load_scenario(bad)


def test_the_default_drake_trial_plans_with_the_station_rules():
    from slax_drake.shelf.tool import tool_config
    from slax_drake.systems.trial import TrialOptions

    opts = TrialOptions()
    assert opts.profile == "station"
    tool = tool_config(load_scenario(opts.config), opts.profile)
    assert tool.rules == rule_set("station") and tool.profile == "station"


def test_benchmark_records_the_profile_and_refuses_another(tmp_path, capsys):
    from slax_drake.cli import main
    from slax_drake.errors import SettingsMismatchError
    from slax_drake.evaluation.table1 import run_benchmark

    scenario = load_scenario("sim_configs/table1.yaml")
    table = run_benchmark(scenario, ["oracle-p"], 1, 0, tmp_path, densities=[4], progress=False, oracle_seconds=5)
    assert table["meta"]["profile"] == "paper"
    trial = json.loads((tmp_path / "trials" / "oracle-p" / "04_0000.json").read_text())
    assert trial["profile"] == "paper" and trial["oracle_status"] in ("optimal", "infeasible", "cut by time", "none")
    assert "the 'paper' profile" in (tmp_path / "table1.md").read_text()
    with pytest.raises(SettingsMismatchError, match='another --profile .*: "paper" there, "station" now'):
        run_benchmark(scenario, ["oracle-p"], 1, 0, tmp_path, densities=[4], progress=False, profile="station",
                      oracle_seconds=5)
    assert main(["benchmark", "--policies", "oracle-p", "--profile", "station", "--scenes-per-density", "1",
                 "--observation", "privileged", "--oracle-seconds", "5",
                 "--out", str(tmp_path), "--no-progress"]) == 2
    assert '"paper" there, "station" now' in capsys.readouterr().err
