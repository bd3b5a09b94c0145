"""slax-belief in camera mode with a partly seen target (``seen_target``): the belief collapses onto the placements
that hold the seen part, and the search clears what still hides the rest first, even where the no-return and
no-shuttle corrections would refuse the move (``uncover_seen``)."""

import numpy as np
import pytest

from slax_drake.policies.registry import make_policy
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, Shelf, Target, planar_pose
from slax_drake.scene.sampling import target_visible_fraction
from slax_drake.shelf.actions import apply_action
from slax_drake.shelf.simulator import CameraObserver, run_trial

from shelf_scenes import TARGET, box


def partly_seen_scene(paper):
    """A small box hides the left part of the target (about 30 % of what the empty shelf shows); a wide box to the
    right hides much more of the shelf, where most of the unseen placements lie."""
    objects = (box("front", -0.19, 0.0, 0.08, 0.08, 0.16), box("wide", 0.12, -0.05, 0.26, 0.08, 0.2))
    return Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), objects,
                 Target(TARGET, planar_pose(-0.17, 0.2, 0.03, 0.0)), 7)


def camera_trial(scene, policy, horizon):
    return run_trial(scene, policy, horizon, observer=CameraObserver(scene.shelf, scene.camera, TARGET, width=160))


def test_the_first_action_uncovers_a_partly_seen_target_and_reveals_it(paper):
    """The target is partly seen at the first frame: slax-belief moves the box in front of it first and the trial
    ends revealed after that one action; slax-belief-no-seen-target (the frame's target mask not read), whose
    belief spreads over the hidden space behind the wide box, moves the wide box first."""
    scene = partly_seen_scene(paper)
    assert 0.5 < target_visible_fraction(scene) < 0.8
    policy = make_policy("slax-belief", paper, horizon=6)
    result = camera_trial(scene, policy, 6)
    assert result.actions[0].split()[1] == "front"
    assert result.success and result.steps == 1
    assert policy.decision_log[0]["target_seen"]
    blind = make_policy("slax-belief-no-seen-target", paper, horizon=6)
    plain = camera_trial(scene, blind, 6)
    assert plain.actions[0].split()[1] == "wide"
    assert "target_seen" not in blind.decision_log[0]


def refused_uncovering_move(paper, uncover, wide_earlier):
    """A policy whose trial memory says the box in front of the target got there from where the uncovering move
    would put it (an earlier arrangement observed, then the opposite move), so that the no-return and no-shuttle
    corrections refuse moving it back; in the earlier arrangement the wide box stood at ``wide_earlier`` (x, y; m)
    or, for None, where it stands now. Returns (policy, its observation, the uncovering move)."""
    scene = partly_seen_scene(paper)
    first = make_policy("slax-belief", paper, horizon=6)
    first.reset(scene)
    observer = CameraObserver(scene.shelf, scene.camera, TARGET, width=160)
    obs, names = observer.observe(scene)
    front = next(o.name for o in obs.known if names[o.name] == "front")
    move = first.decide(obs).best
    assert move.name == front

    policy = make_policy("slax-belief", paper, horizon=6, policy_options={"uncover_seen": uncover})
    policy.reset(scene)
    earlier = apply_action(obs.known, move)  # where the box stood before a move brought it here
    if wide_earlier is not None:
        earlier = tuple(o if names[o.name] != "wide" else o.moved_to(*wide_earlier) for o in earlier)
    before = next(o for o in obs.known if o.name == front)
    dx = float(next(o for o in earlier if o.name == front).center[0] - before.center[0])
    assert abs(dx) > 0.02
    policy.memory.observe(earlier)
    policy.memory.observe(obs.known)
    policy.memory.moves[front] = (-dx, 0.0)
    assert move not in policy.candidates(obs.known, True, True)  # refused as a shuttle
    return policy, obs, move


@pytest.mark.parametrize("uncover", [True, False])
def test_a_move_the_no_shuttle_correction_refuses_is_taken_when_it_uncovers_the_seen_target(paper, uncover):
    """In the earlier arrangement the wide box stood in front of the target too (it has been carried away since):
    moving the front box back shows more of the target than any arrangement observed. With ``uncover_seen`` the
    policy takes that move first (its decision log counts the moves let through); without it, another one."""
    policy, obs, move = refused_uncovering_move(paper, uncover, wide_earlier=(-0.1, -0.2))
    decision = policy.decide(obs)
    if uncover:
        assert decision.best == move and policy.decision_log[0]["uncovering"] >= 1
    else:
        assert decision.best != move and "uncovering" not in policy.decision_log[0]


def test_a_move_back_to_an_arrangement_that_showed_no_more_of_the_target_stays_refused(paper):
    """The earlier arrangement is the one the move would lead back to, the wide box where it stands now: that
    arrangement showed as much of the target as the move would, so ``uncover_seen`` does not let the move through
    (the cycle of a Drake trial: pushed right, carried left, pushed right, ... until the horizon)."""
    policy, obs, move = refused_uncovering_move(paper, True, wide_earlier=None)
    decision = policy.decide(obs)
    assert decision.best != move and "uncovering" not in policy.decision_log[0]


def test_unseen_risk_keeps_the_hidden_space_of_the_placement_risk_after_the_collapse(paper):
    """With ``unseen_risk``, once the belief holds only the partly seen target, the space behind the wide box still
    counts as hidden for the suctions' risk (an unseen object may stand there): the hidden space the risk reads
    keeps the placements behind it, far from the target, while the belief keeps none of them. Without it (the
    default) the risk reads the belief."""
    scene = partly_seen_scene(paper)
    default = make_policy("slax-belief", paper, horizon=6)
    default.reset(scene)
    default.decide(CameraObserver(scene.shelf, scene.camera, TARGET, width=160).observe(scene)[0])
    assert len(default._hidden_centers) == len(default.consistent_placements)
    policy = make_policy("slax-belief", paper, horizon=6, policy_options={"unseen_risk": True})
    policy.reset(scene)
    obs, _ = CameraObserver(scene.shelf, scene.camera, TARGET, width=160).observe(scene)
    policy.decide(obs)
    assert policy.decision_log[0]["target_seen"]
    step = policy.grid_step
    belief = np.array(sorted(policy.consistent_placements), dtype=float) * step
    hidden = policy._hidden_centers
    assert np.max(np.hypot(belief[:, 0] + 0.17, belief[:, 1] - 0.2)) <= 0.1
    behind_wide = (hidden[:, 0] > 0.05) & (hidden[:, 1] > 0.0)
    assert behind_wide.sum() >= 10
    assert policy.box_risk((0.1, 0.2, 0.1, 0.2), hidden) > 0 == policy.box_risk((0.1, 0.2, 0.1, 0.2), belief)
