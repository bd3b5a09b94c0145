"""The commanded trajectory of a whole trial: a motion replaced before its end (a guarded push-in stopped on
contact) is cut where its replacement starts."""

import types

import numpy as np

from slax_drake.evaluation.trial import executed_trajectory
from slax_drake.planning.trajectory import JointTrajectory

NAMES = ("a", "b")


def _ramp(q0, q1, duration, dt=0.001):
    t = np.arange(int(round(duration / dt)) + 1) * dt
    s = t / duration
    q = np.outer(1 - s, q0) + np.outer(s, q1)
    v = np.tile((np.asarray(q1) - np.asarray(q0)) / duration, (len(t), 1))
    return JointTrajectory(NAMES, t, q, v, np.zeros_like(q))


def test_a_motion_replaced_before_its_end_is_cut_there():
    planner = types.SimpleNamespace(limits=types.SimpleNamespace(names=NAMES), q_observation=np.zeros(2))
    first = types.SimpleNamespace(trajectory=_ramp([0.0, 0.0], [1.0, 1.0], 2.0))
    stop = types.SimpleNamespace(trajectory=_ramp([0.4, 0.4], [0.0, 0.0], 1.0))
    traj = executed_trajectory(planner, [(0.5, first), (1.5, stop)], 3.0)
    assert np.all(np.diff(traj.times) > 0)
    assert abs(traj.times[-1] - 3.0) < 2e-3
    q_at = lambda t: traj.q[int(np.argmin(np.abs(traj.times - t)))]  # noqa: E731
    assert np.allclose(q_at(1.49), [0.495, 0.495], atol=2e-3)  # the first motion, cut at 1.5 s
    assert np.allclose(q_at(2.5), [0.0, 0.0], atol=2e-3)  # the stop motion from 1.5 s, ended at 2.5 s
