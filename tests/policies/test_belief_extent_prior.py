"""slax-belief's ``extent_prior``: a target placement inside a seen object's extent range weighs the chance that the
object's unseen part does not reach it."""

import math

import numpy as np
import pytest

from slax_drake.perception.estimator import ExtentRange
from slax_drake.policies.belief import extent_free_weights, extent_share_tail

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
