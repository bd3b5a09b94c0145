"""slax-belief's ``dead_end`` option: a plan that ends where the search could not go on (no move the action model
allows, or none the corrections would leave) loses the worlds it has not revealed; and the trial memory a plan
would leave (:meth:`TrialMemory.after_plan`), which the search judges those corrections by."""

import pytest

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.belief_options import BeliefOptions
from slax_drake.policies.registry import make_policy
from slax_drake.policies.trial_memory import TrialMemory
from slax_drake.shelf.actions import Push, apply_action
from slax_drake.shelf.simulator import CameraObserver
from slax_drake.shelf.tool import parse_tool_rules

from shelf_scenes import box


def test_dead_end_takes_only_its_three_rules():
    assert BeliefOptions(dead_end="model").dead_end == "model"
    with pytest.raises(ValueError, match="dead_end"):
        BeliefOptions(dead_end="yes")


def test_after_plan_records_the_plans_moves_and_arrangements_and_leaves_the_memory_unchanged():
    objects = (box("a", -0.1, 0.0, 0.08, 0.08, 0.1), box("b", 0.15, 0.0, 0.08, 0.08, 0.1))
    memory = TrialMemory()
    memory.observe(objects)
    plan = (Push("a", (0.0, 0.0, 0.0), -0.10), Push("b", (0.0, 0.0, 0.0), 0.05))
    after = memory.after_plan(objects, plan)
    assert memory.moves == {} and len(memory.observed) == 1
    assert after.moves["a"] == pytest.approx((-0.10, 0.0)) and after.moves["b"] == pytest.approx((0.05, 0.0))
    assert len(after.observed) == 3
    end = apply_action(apply_action(objects, plan[0]), plan[1])
    # pushing a back to where it stood is a move back against its last move, and leads back to an arrangement
    back = Push("a", (0.0, 0.0, 0.0), 0.10)
    assert after.undoes(end, back) and not memory.undoes(end, back)
    assert after.leads_back(apply_action(objects, plan[0]), [plan[1]]) == [True]


def _station_policy(options):
    scenario = load_scenario("sim_configs/table1_household.yaml")
    rules = parse_tool_rules(["max_seal_angle_deg=10", "reach_map=models/reach/station_sim_shelf.json",
                              "max_suction_moment=0.4"], "station")
    scene = protocol_scene(scenario, 4, scene_seed(0, 4, 14))
    # the earlier default (no dead-end price, a failed placement's box refused): today's default prices dead ends
    policy = make_policy("slax-belief-box", scenario, horizon=8, profile="station", policy_options=options,
                         tool_overrides=rules)
    policy.reset(scene)
    observer = CameraObserver(scene.shelf, scene.camera, tuple(scenario.target.sizes[0]),
                              width=policy.observation_width)
    observer.start()
    obs, _ = observer.observe(scene)
    return policy, obs


@pytest.mark.slow  # several seconds; runs in CI's slow step
def test_a_push_that_locks_the_shelf_is_chosen_without_the_option_and_not_with_it():
    """Table I scene 4:14 under the Drake station's rules (household masses, camera): the earlier default's first
    move pushes one object 0.24 m right, behind a neighbour that then blocks every tool path: after it the action model
    allows no move at all. With ``dead_end`` that plan loses the worlds it leaves, and another move is taken."""
    plain, obs = _station_policy({})
    first = plain.decide(obs).best
    after = apply_action(obs.known, first)
    assert plain.action_model.enumerate(after).feasible == []
    policy, obs = _station_policy({"dead_end": "corrections"})
    chosen = policy.decide(obs).best
    assert chosen != first
    assert policy.action_model.enumerate(apply_action(obs.known, chosen)).feasible
    assert policy.decision_log[-1].get("dead_ends", 0) >= 1
