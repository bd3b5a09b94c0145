"""Time a chain of joint waypoints with Ruckig (community edition), one rest-to-rest segment at a time.

Each segment starts and ends at rest (zero velocity and acceleration) and is computed by Ruckig's offline
``calculate`` under the per-joint velocity, acceleration and jerk limits, with phase synchronisation, which
makes a rest-to-rest motion a straight line in joint space (so the geometric path that the planner checked is
the path that is executed). ``intermediate_positions`` is never set: that feature needs Ruckig's web service.
"""

from __future__ import annotations

import numpy as np

from slax_drake.errors import UserError
from slax_drake.planning.trajectory import JointTrajectory

SAMPLE_PERIOD = 0.001  # s


class TimingError(UserError):
    """Ruckig could not time a segment."""


def time_segment(q0, q1, velocity, acceleration, jerk, dt: float = SAMPLE_PERIOD):
    """Samples (t, q, v, a) at period dt of the rest-to-rest Ruckig motion q0 -> q1 (arrays per joint).

    The last sample lies exactly at the segment's end (duration rounded up to a multiple of dt, where the
    profile holds at rest)."""
    from ruckig import InputParameter, Result, Ruckig, Synchronization, Trajectory

    q0 = np.asarray(q0, float)
    q1 = np.asarray(q1, float)
    n = len(q0)
    if np.allclose(q0, q1, atol=1e-12, rtol=0.0):
        return np.zeros(1), q0[None, :].copy(), np.zeros((1, n)), np.zeros((1, n))
    otg = Ruckig(n)
    inp = InputParameter(n)
    inp.current_position = q0.tolist()
    inp.current_velocity = [0.0] * n
    inp.current_acceleration = [0.0] * n
    inp.target_position = q1.tolist()
    inp.target_velocity = [0.0] * n
    inp.target_acceleration = [0.0] * n
    inp.max_velocity = np.asarray(velocity, float).tolist()
    inp.max_acceleration = np.asarray(acceleration, float).tolist()
    inp.max_jerk = np.asarray(jerk, float).tolist()
    inp.synchronization = Synchronization.Phase
    traj = Trajectory(n)
    result = otg.calculate(inp, traj)
    if result not in (Result.Working, Result.Finished):
        raise TimingError(f"Ruckig failed to time a segment: {result}")
    duration = traj.duration
    steps = int(np.ceil(duration / dt - 1e-9))
    t = np.arange(steps + 1) * dt
    q = np.empty((steps + 1, n))
    v = np.empty((steps + 1, n))
    a = np.empty((steps + 1, n))
    for k, tk in enumerate(t):
        p, vel, acc = traj.at_time(min(tk, duration))
        q[k], v[k], a[k] = p, vel, acc
    q[-1], v[-1], a[-1] = q1, 0.0, 0.0
    return t, q, v, a


def time_waypoints(names, waypoints, velocity, acceleration, jerk, dt: float = SAMPLE_PERIOD) -> JointTrajectory:
    """Chains rest-to-rest segments through ``waypoints`` (K, n) into one JointTrajectory sampled at dt.

    Returns the trajectory; the sample index at which each waypoint is reached is ``waypoint_indices``."""
    traj, _ = time_waypoints_indexed(names, waypoints, velocity, acceleration, jerk, dt)
    return traj


def time_waypoints_indexed(names, waypoints, velocity, acceleration, jerk, dt: float = SAMPLE_PERIOD):
    """As :func:`time_waypoints`, also returning the sample index of each waypoint (list of K ints)."""
    waypoints = np.asarray(waypoints, float)
    ts, qs, vs, as_ = [np.zeros(1)], [waypoints[0][None, :]], [np.zeros((1, waypoints.shape[1]))], [
        np.zeros((1, waypoints.shape[1]))]
    indices = [0]
    t_end, count = 0.0, 1
    for q0, q1 in zip(waypoints[:-1], waypoints[1:]):
        t, q, v, a = time_segment(q0, q1, velocity, acceleration, jerk, dt)
        if len(t) > 1:
            ts.append(t[1:] + t_end)
            qs.append(q[1:])
            vs.append(v[1:])
            as_.append(a[1:])
            t_end += t[-1]
            count += len(t) - 1
        indices.append(count - 1)
    times = np.concatenate(ts)
    times = np.round(times / dt) * dt  # a uniform clock
    return JointTrajectory(tuple(names), times, np.concatenate(qs), np.concatenate(vs), np.concatenate(as_)), indices
