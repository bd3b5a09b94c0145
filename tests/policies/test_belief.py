"""Issue 19 item 5: slax-belief, the belief-space beam search (slax_drake/policies/belief.py): it plans the two moves
a stacked occlusion needs, rolls out deterministically, keeps to its per-decision CPU cap, and its per-world
distances agree with a brute-force count."""

import dataclasses
import itertools

import numpy as np
import pytest

from slax_drake.policies.belief import PackedWorlds
from slax_drake.policies.belief_options import BeliefOptions
from slax_drake.policies.hindsight import Worlds
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import execute, observation_for, run_trial
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, Shelf, Target, planar_pose
from slax_drake.scene.sampling import sample_scene, target_visible_fraction

from shelf_scenes import TARGET, box


def stacked_scene(paper):
    """A wide low box in front, a wide tall one behind it, the target behind both: the tall one cannot be pushed
    while the front one hides the space beside it, so the front one must move first, then the tall one."""
    objects = (box("front", 0.0, -0.20, 0.24, 0.06, 0.12), box("middle", 0.0, 0.02, 0.20, 0.06, 0.25))
    target = Target(TARGET, planar_pose(0.0, 0.20, 0.03, 0.0))
    return Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), objects, target, 7)


def test_belief_moves_the_front_object_first_and_plans_the_second_move(paper):
    scene = stacked_scene(paper)
    assert target_visible_fraction(scene) < 0.8
    policy = make_policy("slax-belief", paper, horizon=4)
    policy.reset(scene)
    best = policy.decide(observation_for(policy, scene)).best
    log = policy.decision_log[-1]
    assert best.name == "front"
    assert [a.split()[1] for a in log["plan"][:2]] == ["front", "middle"]
    assert not log["capped"] and log["samples"] == policy.samples
    after, note = execute(scene, best, policy.action_model)
    assert note == "" and target_visible_fraction(after) < 0.8  # the first move alone does not show it
    result = run_trial(scene, make_policy("slax-belief", paper, horizon=4), 4)
    assert result.success and result.steps == 2 and result.actions[0].split()[1] == "front"


def test_belief_rolls_out_the_same_actions_twice(paper):
    scene = sample_scene(paper, 6, 11, target_size=TARGET)
    runs = [run_trial(scene, make_policy("slax-belief", paper, horizon=4), 4) for _ in range(2)]
    assert runs[0].actions == runs[1].actions and len(runs[0].actions) >= 1


def test_belief_stops_deepening_at_its_cpu_cap_and_still_acts(paper):
    scene = stacked_scene(paper)
    capped = make_policy("slax-belief", paper, horizon=4, policy_options={"seconds": 0.0})
    capped.reset(scene)
    decision = capped.decide(observation_for(capped, scene))
    assert decision.best is not None
    log = capped.decision_log[-1]
    assert log["capped"] and log["expanded"] <= capped.beam  # the first level only
    assert len(log["plan"]) == 1


def test_distances_match_a_brute_force_count(paper):
    """The packed per-world distance (fewest objects whose removal shows the target) equals a count over subsets
    of the unpacked masks, for 0, 1 and 2 (and >= 3 where neither)."""
    scene = sample_scene(paper, 10, 100070, target_size=TARGET)
    policy = make_policy("slax-belief", paper, horizon=20)
    policy.reset(scene)
    obs = observation_for(policy, scene)
    centers = policy.draw(policy.placements(obs), 0)
    raw = Worlds(obs.scene_template, centers, TARGET, policy.threshold)
    d = policy.distances(PackedWorlds(raw), tuple(obs.known))
    masks = [raw.hidden_by(o) for o in obs.known]
    need = policy.threshold * raw.n_shown - 1e-9

    def shown_without(removed):
        hidden = np.zeros_like(raw.shown)
        for i, m in enumerate(masks):
            if i not in removed:
                hidden |= m
        return (raw.shown & ~hidden).sum(axis=1) >= need

    brute = np.full(raw.count, 3.0)
    for k in (2, 1, 0):
        for removed in itertools.combinations(range(len(masks)), k):
            brute[shown_without(set(removed))] = k
    exact = brute < 3
    assert exact.any() and (~exact).any()  # the scene has worlds of both kinds
    assert np.array_equal(d[exact & (raw.n_shown > 0)], brute[exact & (raw.n_shown > 0)])
    assert (d[~exact] >= 3).all()


def test_belief_rejects_an_unknown_selection(paper):
    with pytest.raises(ValueError, match="select"):
        BeliefOptions(select="greedy")


@pytest.mark.parametrize("option", [{"evidence": "all"}, {"block_weight": 0.0}, {"block_weight": -1.0},
                                    {"widen_beam": -1}, {"widen_beam": 2.5}])
def test_belief_rejects_v3_options_out_of_range(paper, option):
    with pytest.raises(ValueError, match=next(iter(option))):
        BeliefOptions(**option)
    with pytest.raises(ValueError, match=next(iter(option))):
        make_policy("slax-belief", paper, policy_options=option)


def test_registry_passes_the_protocol_horizon_to_slax_belief_only(paper):
    assert make_policy("slax-belief", paper, horizon=7).horizon == 7
    assert make_policy("slax-belief", paper).horizon is None  # no horizon given: planned as unknown
    assert make_policy("slax-belief", paper, horizon=7, policy_options={"horizon": 3}).horizon == 3
    assert not hasattr(make_policy("slax-hindsight", paper, horizon=7), "horizon")


def _push_outcome_setup(paper, options=None):
    """A lone box at the shelf's centre, pushed +0.15 m along x; the belief holds four target placements: in its
    path at x = 0.08 and 0.10 and 0.12 m (a target there stops it, the nearer the earlier) and one far away."""
    from slax_drake.shelf.actions import Push

    block = box("block", 0.0, 0.0, 0.06, 0.06, 0.10)
    template = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), (block,), None, 3)
    policy = make_policy("slax-belief", paper, horizon=4, policy_options=options)
    policy.reset(template)
    keys = {(8, 0), (10, 0), (12, 0), (-20, 20)}
    policy._consistent = set(keys)
    policy._template = template
    policy._executed = (Push("block", (-0.04, -0.03, 0.05), 0.15), (block,))
    return policy, template, block, keys


def test_belief_drops_the_placements_a_completed_push_swept(paper):
    """The push went as far as the seen objects predict: no target stood in its way, so the three placements in
    its path leave the belief (certain), the far one stays, and no weight changes."""
    policy, template, block, _ = _push_outcome_setup(paper)
    after, note = execute(template, policy._executed[0], policy.action_model)
    assert note == ""
    policy.condition_on_outcome(after.objects)
    assert policy._consistent == {(-20, 20)}
    assert policy._weights == {}
    assert policy.evidence_log[-1]["stopped"] is False and policy.evidence_log[-1]["removed"] == 3


def test_belief_weighs_up_the_placements_that_explain_a_stopped_push(paper):
    """The true target at x = 0.10 m stopped the push short (what the robot sees: the box moved less than
    commanded). A target at 0.10 explains it (weight x block_weight); one at 0.08 would have stopped it earlier
    (dropped); one at 0.12 or far away is left as it was (an unseen object may have stopped it)."""
    policy, template, block, _ = _push_outcome_setup(paper)
    truth = Scene(template.shelf, template.camera, (block,), Target(TARGET, planar_pose(0.10, 0.0, 0.03, 0.0)), 3)
    after, note = execute(truth, policy._executed[0], policy.action_model)
    assert "stopped" in note
    policy.condition_on_outcome(after.objects)
    assert policy._consistent == {(10, 0), (12, 0), (-20, 20)}
    assert policy._weights == {(10, 0): policy.block_weight}
    assert {k: policy.evidence_log[-1][k] for k in ("stopped", "removed", "explained")} == \
        {"stopped": True, "removed": 1, "explained": 1}


def test_belief_without_evidence_leaves_the_belief_alone(paper):
    """``evidence="none"`` (slax-belief v2's behaviour) ignores the outcome."""
    policy, template, block, keys = _push_outcome_setup(paper, {"evidence": "none"})
    after, _ = execute(template, policy._executed[0], policy.action_model)
    policy.condition_on_outcome(after.objects)
    assert policy._consistent == keys and policy.evidence_log == []


def test_weighted_draw_is_seeded_and_follows_the_weights(paper):
    """With a weight, the draw samples the weighted belief systematically: a placement of weight 8 among 8 of
    weight 1 gets half of the 9 samples (as many as placements), 4 or 5; the same seed and step give the same
    draw; without weights the draw is slax-hindsight's uniform one."""
    policy = make_policy("slax-belief", paper, policy_options={"samples": 16})
    placements = np.array([[0.01 * i, 0.1] for i in range(9)])
    uniform = policy.draw(placements, 5)
    policy._weights = {(4, 10): 8.0}
    first, again = policy.draw(placements, 5), policy.draw(placements, 5)
    assert np.array_equal(first, again)
    heavy = int(np.sum(np.all(np.isclose(first, [0.04, 0.1]), axis=1)))
    assert len(first) == 9 and heavy in (4, 5)
    policy._weights = {}
    assert np.array_equal(policy.draw(placements, 5), uniform)


def test_belief_remembers_an_untouched_object_that_became_hidden(paper):
    """An object seen at one decision and hidden at the next stays in the policy's seen objects where it stood,
    unless it is the object the last action moved (where that one stopped is not known); with remember_objects off it forgets."""
    from slax_drake.shelf.actions import Push

    scene = stacked_scene(paper)
    policy = make_policy("slax-belief", paper, horizon=4)
    policy.reset(scene)
    obs = observation_for(policy, scene)
    assert [o.name for o in obs.known] == ["front", "middle"]
    assert policy.with_remembered(obs).known == obs.known
    front_only = dataclasses.replace(obs, known=obs.known[:1])  # "middle" hidden now
    policy._executed = (Push("front", (0.0, -0.2, 0.05), 0.05), obs.known)
    remembered = policy.with_remembered(front_only)
    assert [o.name for o in remembered.known] == ["front", "middle"]
    assert remembered.known[1] is obs.known[1] and [o.name for o in remembered.scene_template.objects] == \
        ["front", "middle"]
    policy._executed = (Push("middle", (0.0, 0.02, 0.05), 0.05), remembered.known)
    assert [o.name for o in policy.with_remembered(front_only).known] == ["front"]  # it moved: not remembered
    forgetful = make_policy("slax-belief", paper, horizon=4, policy_options={"remember_objects": False})
    forgetful.reset(scene)
    forgetful.with_remembered(obs)
    assert forgetful.with_remembered(front_only).known == front_only.known


def test_belief_widens_its_beam_only_when_nothing_is_revealed(paper):
    """Behind a low front box stands a wall box almost as wide as the bay, 2 cm behind (no room for the target
    between): one action (only the front box can move) reveals nothing, so the search runs again with the wider
    beam, looking at more plans; without ``widen_beam`` it does not. Where the first search reveals something, it
    is not widened."""
    objects = (box("front", 0.0, -0.20, 0.24, 0.06, 0.12), box("middle", 0.0, -0.11, 0.54, 0.06, 0.25))
    scene = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), objects,
                  Target(TARGET, planar_pose(0.0, 0.20, 0.03, 0.0)), 7)
    logs = {}
    for widen in (0, 4):
        policy = make_policy("slax-belief", paper, horizon=4, policy_options={
            "depth": 1, "max_depth": 1, "beam": 1, "widen_beam": widen})
        policy.reset(scene)
        policy.decide(observation_for(policy, scene))
        logs[widen] = policy.decision_log[-1]
    assert logs[0]["revealed"] == 0 and "widened" not in logs[0] and logs[0]["expanded"] == 1
    assert logs[4]["widened"] and logs[4]["expanded"] > 1
    deep = make_policy("slax-belief", paper, horizon=4, policy_options={"beam": 1, "widen_beam": 4})
    deep.reset(stacked_scene(paper))
    deep.decide(observation_for(deep, stacked_scene(paper)))
    assert deep.decision_log[-1]["revealed"] > 0 and "widened" not in deep.decision_log[-1]



def test_belief_when_nothing_reveals_takes_the_plan_nearest_to_a_reveal(paper):
    """The wall scene of the test above: no plan reveals anything, even widened. stuck_select="progress" takes the
    plan whose end is nearest to revealing (least V - G), "value" (the default) the least V, over the same plans:
    each choice is at least as good as the other's by its own rule. Where a plan reveals something, both choose
    alike."""
    objects = (box("front", 0.0, -0.20, 0.24, 0.06, 0.12), box("middle", 0.0, -0.11, 0.54, 0.06, 0.25))
    scene = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), objects,
                  Target(TARGET, planar_pose(0.0, 0.20, 0.03, 0.0)), 7)
    logs = {}
    for rule in ("progress", "value"):
        policy = make_policy("slax-belief", paper, horizon=6, policy_options={
            "depth": 2, "max_depth": 2, "beam": 2, "widen_beam": 4, "stuck_select": rule})
        policy.reset(scene)
        policy.decide(observation_for(policy, scene))
        logs[rule] = policy.decision_log[-1]
    assert all(log["widened"] and log["revealed"] == 0 for log in logs.values())
    progress, value = logs["progress"], logs["value"]
    assert progress["value"] - progress["expected_cost"] <= value["value"] - value["expected_cost"] + 1e-3
    assert value["value"] <= progress["value"] + 1e-3
    assert make_policy("slax-belief", paper, horizon=4).stuck_select == "value"
    plans = []
    for rule in ("progress", "value"):
        policy = make_policy("slax-belief", paper, horizon=4, policy_options={"stuck_select": rule})
        policy.reset(stacked_scene(paper))
        policy.decide(observation_for(policy, stacked_scene(paper)))
        plans.append(policy.decision_log[-1]["plan"])
    assert plans[0] == plans[1] and plans[0]


def test_belief_with_stuck_select_stop_stops_where_no_plan_reveals_anything(paper):
    """The wall scene above: no plan reveals anything, even widened. With stuck_select "stop" the policy stops there
    with NO_REVEALING_PLAN (its decision log says it stalled) instead of taking the plan nearest to a reveal; where a
    plan reveals something it decides as the default does."""
    from slax_drake.policies.protocol import NO_REVEALING_PLAN

    objects = (box("front", 0.0, -0.20, 0.24, 0.06, 0.12), box("middle", 0.0, -0.11, 0.54, 0.06, 0.25))
    scene = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), objects,
                  Target(TARGET, planar_pose(0.0, 0.20, 0.03, 0.0)), 7)
    small = {"depth": 2, "max_depth": 2, "beam": 2, "widen_beam": 4}
    stopping = make_policy("slax-belief", paper, horizon=6, policy_options={**small, "stuck_select": "stop"})
    stopping.reset(scene)
    decision = stopping.decide(observation_for(stopping, scene))
    assert decision.best is None and decision.stop_reason == NO_REVEALING_PLAN
    assert stopping.decision_log[-1]["stalled"] and stopping.decision_log[-1]["widened"]
    result = run_trial(scene, make_policy("slax-belief", paper, horizon=6, policy_options={
        **small, "stuck_select": "stop"}), 6)
    assert result.reason == NO_REVEALING_PLAN and result.steps == 0
    plans = []
    for rule in ("stop", "value"):
        policy = make_policy("slax-belief", paper, horizon=4, policy_options={"stuck_select": rule})
        policy.reset(stacked_scene(paper))
        plans.append(policy.decide(observation_for(policy, stacked_scene(paper))).best)
    assert plans[0] == plans[1] is not None
    assert make_policy("slax-belief-stall-stop", paper, horizon=4).stuck_select == "stop"


def test_belief_rejects_an_unknown_stuck_rule(paper):
    with pytest.raises(ValueError, match="stuck_select"):
        make_policy("slax-belief", paper, horizon=4, policy_options={"stuck_select": "random"})
