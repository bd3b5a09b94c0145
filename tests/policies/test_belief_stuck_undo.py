"""slax-belief's ``stuck_undo`` option: when no plan from the moves the corrections allow reveals anything, the moves
they screened out only as a return or a shuttle may start a plan, taken when that plan reveals part of the belief."""

import pytest

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.belief_options import BeliefOptions
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import CameraObserver, run_trial
from slax_drake.shelf.tool import parse_tool_rules

# the physics benchmark's rules: the Drake station's cup, reach map and guarded placement
STATION_RULES = ["max_drag_pull=42.412", "max_drag_twist=0.6362", "max_seal_angle_deg=10",
                 "max_suction_moment=0.4", "reach_map=models/reach/station_sim_shelf.json",
                 "suction_hidden_rule=guarded"]


def test_stuck_undo_is_off_by_default_and_on_in_its_variant():
    assert BeliefOptions().stuck_undo is False
    scenario = load_scenario("sim_configs/table1.yaml")
    assert make_policy("slax-belief", scenario, horizon=8).stuck_undo is False
    assert make_policy("slax-belief-stuck-undo", scenario, horizon=8).stuck_undo is True
    both = make_policy("slax-belief-stuck-undo-dead-end", scenario, horizon=8)
    assert both.stuck_undo is True and both.dead_end == "corrections" and both.blocked_rule == "box"
    dead_end_risk = make_policy("slax-belief-dead-end-risk", scenario, horizon=8)
    assert dead_end_risk.stuck_undo is False and dead_end_risk.dead_end == "corrections"
    assert dead_end_risk.blocked_rule == "risk"
    risk = make_policy("slax-belief-stuck-undo-dead-end-risk", scenario, horizon=8)
    assert risk.stuck_undo is True and risk.dead_end == "corrections" and risk.blocked_rule == "risk"


def _trial(options: dict):
    scenario = load_scenario("sim_configs/table1_household.yaml")
    seed = scene_seed(0, 6, 10)
    scene = protocol_scene(scenario, 6, seed)
    # the earlier default, the base stuck_undo was measured on (today's default prices dead ends and ends 6:10 else)
    policy = make_policy("slax-belief-box", scenario, horizon=12, profile="station", policy_options=options,
                         tool_overrides=parse_tool_rules(STATION_RULES, "station"))
    observer = CameraObserver(scene.shelf, scene.camera, tuple(scenario.target.sizes[0]),
                              width=policy.observation_width)
    result = run_trial(scene, policy, 12, threshold=scenario.target.visibility_threshold, density=6,
                       observer=observer)
    return policy, result


@pytest.mark.slow  # two camera trials of a few seconds each; CI's slow step
def test_a_move_back_that_starts_a_revealing_plan_is_taken_when_the_search_is_stuck():
    """Table I household scene 6:10 under the Drake station's rules, camera mode: after four actions no plan from the
    moves the corrections allow reveals anything; the earlier default wanders with cheap moves until only moves back are
    left and stops. With ``stuck_undo`` the search looks at those moves back too and takes one whose plan reveals
    the rest of the belief (the target is found)."""
    plain_policy, plain = _trial({})
    assert not plain.success and plain.reason == "no feasible action"
    assert plain.screened.get("shuttle", 0) > 0  # the moves left were screened out as moves back
    assert not any("undo" in log for log in plain_policy.decision_log)
    policy, result = _trial({"stuck_undo": True})
    assert result.success
    taken = [i for i, log in enumerate(policy.decision_log) if "undo" in log and log["revealed"] > 0]
    assert taken  # a decision took a plan starting with a move the corrections had screened out
    # the first such decision comes where the earlier default's search revealed nothing
    i = taken[0]
    assert plain_policy.decision_log[i]["revealed"] == 0.0 and plain_policy.decision_log[i].get("widened")
