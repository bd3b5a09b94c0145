"""slax-belief's ``extent_prior`` (a target placement inside a seen object's extent range weighs the chance that the
object's unseen part does not reach it) and ``extent_risk`` (a first move scored by the share of joint draws of the
seen objects' extents in which it fails)."""

import math

import numpy as np
import pytest

from slax_drake.perception.estimator import ExtentRange
from slax_drake.policies.extents import EXTENT_DRAWS, extent_free_weights, extent_share_tail
from slax_drake.policies.registry import make_policy
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, Shelf, Target, planar_pose
from slax_drake.shelf.actions import Suction
from slax_drake.shelf.simulator import CameraObserver

from shelf_scenes import TARGET, box

HALF = (0.03, 0.03)  # the Table I target's half sizes (m)


def _range(yaw: float = 0.0) -> ExtentRange:
    """A box seen 0.10 m wide and 0.06 m deep (its front face at y = 0), which may reach 0.10 m deeper."""
    return ExtentRange("box", yaw, (-0.05, 0.0), (0.05, 0.06), (-0.05, 0.0), (0.05, 0.16))


def test_tail_falls_from_one_to_zero_past_the_range():
    tail = extent_share_tail(np.array([0.0, 0.1, 0.5, 1.0, 1.01]))
    assert tail[0] == 1.0 and tail[-1] == 0.0
    assert np.all(np.diff(tail[:-1]) < 0)


def test_weight_grows_with_the_share_of_the_range_the_object_must_reach():
    # behind the object: its target footprint begins 0.01, 0.04 and 0.11 m past the observed part (range 0.10 m)
    placements = np.array([[0.0, 0.10], [0.0, 0.13], [0.0, 0.20]])
    w = extent_free_weights(placements, HALF, [_range()])
    assert w[0] == pytest.approx(1.0 - extent_share_tail(np.array([0.1]))[0])
    assert w[1] == pytest.approx(1.0 - extent_share_tail(np.array([0.4]))[0])
    assert w[2] == 1.0  # beyond the farthest the frame allows
    assert w[0] < w[1] < w[2]


def test_beside_the_object_where_its_width_is_measured_weighs_one():
    w = extent_free_weights(np.array([[0.12, 0.10], [-0.12, 0.03]]), HALF, [_range()])
    assert np.all(w == 1.0)


def test_ranges_multiply_and_turn_with_the_object():
    p = np.array([[0.0, 0.10]])
    one = extent_free_weights(p, HALF, [_range()])[0]
    assert extent_free_weights(p, HALF, [_range(), _range()])[0] == pytest.approx(one * one)
    # the same object turned a quarter turn: its unseen depth now runs along -x, away from the placement
    assert extent_free_weights(p, HALF, [_range(math.pi / 2)])[0] == 1.0


def _deep_box_frame(paper):
    """A 0.16 m deep box seen face on (its hypothesis only as deep as the frame shows) and, to its left, a box 0.11 m
    behind the shelf's front, too tall to pass over: carried there, the deep box meets that box's front face before
    it is inside the bay, where its hypothesis fits in front of it."""
    objects = [box("deep", 0.05, 0.0, 0.12, 0.16, 0.25), box("front", -0.18, -0.15, 0.10, 0.08, 0.45)]
    scene = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), tuple(objects),
                  Target(TARGET, planar_pose(0.2, 0.22, 0.03, 0.0)), 7)
    obs, names = CameraObserver(scene.shelf, scene.camera, TARGET, width=160).observe(scene)
    return obs, {names[o.name]: o for o in obs.known}


def _risk(paper, obs, action) -> float:
    """``action``'s extent risk as the first move of a fresh slax-belief (``extent_risk`` 1) at its first decision."""
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"extent_risk": 1.0})
    policy.reset()
    policy._template, policy._extent_belief, policy._step = obs.scene_template, obs.belief, 1
    return policy.first_move_extent_risk(tuple(obs.known), action)


def test_extent_risk_is_the_share_of_draws_in_which_the_first_move_fails(paper):
    obs, seen = _deep_box_frame(paper)
    deep = seen["deep"]
    model = make_policy("slax-belief", paper, horizon=4).action_model
    suctions = {(round(a.dx, 3), round(a.dz, 3)): a for a in model.enumerate(tuple(obs.known)).feasible
                if isinstance(a, Suction) and a.name == deep.name}
    # carried to the front of the bay beside the tall box: the deep box, as deep as it is, meets it
    risky = _risk(paper, obs, suctions[(-0.25, -0.25)])
    assert 0 < risky < 1 and risky * EXTENT_DRAWS == pytest.approx(round(risky * EXTENT_DRAWS))
    assert _risk(paper, obs, suctions[(-0.25, -0.25)]) == risky  # the draws are seeded (scene seed, step)
    assert _risk(paper, obs, suctions[(-0.1, 0.1)]) == 0.0  # deeper in the bay, clear of it however deep
