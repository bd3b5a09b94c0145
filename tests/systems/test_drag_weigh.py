"""The weighing of a sideways drag along its pull (slax_drake.systems.drag_weigh) on a stand-in arm whose efforts
are known: the baseline fitted at the approach is taken off, only the samples of the object sliding count, the
friction is their median, and the verdict is the action model's twist check with that force. In Drake:
tests/systems/test_drag_pull_weigh_drake.py."""

import dataclasses

import numpy as np
import pytest

from slax_drake.shelf.actions import GRAVITY, Suction
from slax_drake.systems.drag_weigh import (END_MARGIN, SLIDING_TRAVEL, observe_pull, pull_record, pull_window,
                                           start_pull)
from slax_drake.systems.guard import PutBack


class _Model:
    """An arm whose cup sits at y = -q[0] (world), whose free efforts are zero, whose efforts see a force resisting
    the pull in their first entry and a weight in their second."""

    def effort(self, q, v, a):
        return np.zeros(9)

    def signatures(self, q, push_W, v, a):
        e0, e1 = np.eye(9)[0], np.eye(9)[1]
        return e0, e1, np.zeros(9)

    def cup_position(self, q):
        return np.array([0.0, -float(q[0]), 0.0])


@dataclasses.dataclass
class _Guard:
    model: _Model = dataclasses.field(default_factory=_Model)
    push_W: np.ndarray = dataclasses.field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))


class _Trajectory:
    """The cup pulled 0.10 m out between 2 s and 4 s (q[0]: how far)."""

    times = np.linspace(0.0, 6.0, 601)
    a = np.zeros((601, 9))

    def value(self, t):
        q = np.zeros(9)
        q[0] = 0.10 * float(np.clip((t - 2.0) / 2.0, 0.0, 1.0))
        return q, np.zeros(9)


@dataclasses.dataclass
class _Motion:
    action: object
    waypoint_times: list = dataclasses.field(default_factory=lambda: [("pre-approach", 0.5), ("approach", 1.0),
                                                                     ("seal", 1.5), ("pull", 4.0),
                                                                     ("drag across", 5.0)])
    trajectory: _Trajectory = dataclasses.field(default_factory=_Trajectory)


DRAG = Suction("object_0", (0.0, -0.2, 0.03), 0.15, -0.10, drag=True)


def test_only_a_sideways_drag_is_weighed_between_the_seal_and_the_end_of_its_pull():
    assert pull_window(_Motion(DRAG)) == pytest.approx((1.0, 1.8, 4.0, 4.08))  # seal + 0.3 s; pull + 0.1 - 0.02 s
    assert pull_window(_Motion(dataclasses.replace(DRAG, dx=0.0))) is None  # straight out and in: no twist
    assert pull_window(_Motion(dataclasses.replace(DRAG, drag=False))) is None  # a lift is weighed at the cup


def _weigh(friction, press=3.0, offset=0.7, t_end=4.0):
    """The run after sampling every 10 ms: the arm's efforts read ``offset`` in the free arm's model error, the
    seal's ``press`` (loaded the other way) until the object breaks loose, then ``friction`` while it slides."""
    guard, motion = _Guard(), _Motion(DRAG)
    run = start_pull(guard, motion)
    assert run.length == pytest.approx(0.10)
    for t in np.arange(1.0, t_end + 1e-9, 0.01):
        q, v = motion.trajectory.value(t)
        efforts = np.zeros(9)
        efforts[0] = offset + (-press if t < 1.8 + 0.05 else friction) * (t >= 1.5)
        efforts[1] = 0.2  # a little weight the baseline takes off
        run = observe_pull(guard, run, motion, float(t), q, v, efforts)
    return run


def test_the_friction_is_the_median_force_while_the_object_slides():
    run = _weigh(8.5)
    travel = 0.10 * np.clip((np.arange(1.0, 4.0 + 1e-9, 0.01) - 2.0) / 2.0, 0.0, 1.0)
    counted = np.sum((travel >= SLIDING_TRAVEL) & (travel <= 0.10 - END_MARGIN))
    assert len(run.forces) == pytest.approx(counted, abs=2)
    assert run.friction == pytest.approx(8.5)  # the offset and the press are not counted
    assert _weigh(8.5, t_end=2.1).friction is None  # under 1 cm pulled: nothing weighed


class _Rules:
    max_drag_twist = 0.6362
    drag_safety_factor = 1.5
    drag_friction = 0.44
    drag_twist_flat_factor = 1.2


def test_the_verdict_is_the_action_models_twist_check_with_the_measured_force():
    over = pull_record(_weigh(8.5), 0.08, _Rules())  # 1.5 x 8.5 x 0.08 = 1.02 N m
    assert over["put_back"] and over["why"] == PutBack.TWISTS_OFF.value
    assert over["twist_nm"] == pytest.approx(1.02) and over["friction_n"] == pytest.approx(8.5)
    assert over["mass_kg"] == pytest.approx(8.5 / (0.44 * GRAVITY), abs=1e-4)
    under = pull_record(_weigh(4.0), 0.08, _Rules())  # 0.48 N m
    assert not under["put_back"] and "mass_kg" not in under and under["twist_nm"] == pytest.approx(0.48)
    short = pull_record(_weigh(8.5, t_end=2.1), 0.08, _Rules())
    assert short["friction_n"] is None and not short["put_back"] and "twist_nm" not in short


def test_a_box_s_flat_face_is_held_to_the_flat_factor_s_limit():
    run = _weigh(5.8)  # 1.5 x 5.8 x 0.08 = 0.70 N m: over a curved face's 0.64, under a flat one's 0.76
    assert pull_record(run, 0.08, _Rules(), "cylinder")["put_back"]
    box = pull_record(run, 0.08, _Rules(), "box")
    assert not box["put_back"] and box["limit_nm"] == pytest.approx(1.2 * 0.6362, abs=1e-4)
