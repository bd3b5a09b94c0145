"""slax-belief's ``shuttle_rule`` "belief": a first move back against its object's last move passes the no-shuttle
correction when it uncovers new width (the default rule) or when the arrangement after it shows the target in a
world the belief still holds (a place no frame of the trial has shown)."""

import pytest

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.belief_options import BeliefOptions
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import CameraObserver, run_trial
from slax_drake.shelf.tool import parse_tool_rules

STATION_RULES = ["max_drag_pull=42.412", "max_drag_twist=0.6362", "max_seal_angle_deg=10",
                 "max_suction_moment=0.4", "reach_map=models/reach/station_sim_shelf.json",
                 "suction_hidden_rule=guarded"]


def test_only_a_policy_with_a_belief_takes_the_belief_rule():
    scenario = load_scenario("sim_configs/table1.yaml")
    assert make_policy("slax-belief", scenario, horizon=8).shuttle_rule == "width"
    assert make_policy("slax-belief-belief-shuttle", scenario, horizon=8).shuttle_rule == "belief"
    with pytest.raises(ValueError, match="shuttle_rule"):
        BeliefOptions(shuttle_rule="beliefs")
    bdar = make_policy("bluction-dar", scenario, horizon=8)  # no belief to judge by
    with pytest.raises(ValueError, match="shuttle_rule must be one of 'width', 'sight'"):
        type(bdar)(bdar.action_model, bdar.distribution, corrected=True, shuttle_rule="belief")


@pytest.mark.slow  # a 6-object camera trial of a few seconds; CI's slow step
def test_a_move_back_that_shows_a_world_still_held_passes_and_is_recorded():
    """Table I household scene 6:10 under the Drake station's rules, camera at full resolution: the belief rule lets
    a move back through that uncovers no new width of its own footprint, because the arrangement after it shows the
    target in some of the belief's worlds; the trial record says it passed ("uncovers new width"), and a move back
    later in a plan is judged by width alone."""
    scenario = load_scenario("sim_configs/table1_household.yaml")
    scene = protocol_scene(scenario, 6, scene_seed(0, 6, 10))
    policy = make_policy("slax-belief-belief-shuttle", scenario, horizon=12, profile="station",
                         tool_overrides=parse_tool_rules(STATION_RULES, "station"))
    observer = CameraObserver(scene.shelf, scene.camera, tuple(scenario.target.sizes[0]),
                              width=policy.observation_width, full_resolution=True)
    passed_by_belief = []
    decide = policy.decide

    def watched(obs):
        decision = decide(obs)
        best, objects = decision.best, policy._objects
        if best is not None and policy.memory.undoes(objects, best):
            width = policy.memory.vacates_unseen(objects, best) >= policy.shuttle_reveal
            if not width:
                assert policy.reveals_new(objects, best)  # it was taken: the belief rule passed it
                assert str(policy.reversal_rule(best)) == "uncovers new width"
                # judged as a later move of a plan (another memory), width alone refuses it
                assert not policy.reveals_new(objects, best, policy.memory.after_plan(objects, ()))
                passed_by_belief.append(best.describe())
        return decision

    policy.decide = watched
    run_trial(scene, policy, 12, threshold=scenario.target.visibility_threshold, density=6, observer=observer)
    assert passed_by_belief  # the rule made a difference in this trial
