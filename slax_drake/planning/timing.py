"""Time a chain of joint waypoints with Ruckig (community edition), one rest-to-rest segment at a time.

Each segment starts and ends at rest (zero velocity and acceleration) and is computed by Ruckig's offline
``calculate`` as a one-dimensional profile of the path parameter along the straight line in joint space, under
the per-joint velocity, acceleration and jerk limits (so the geometric path that the planner checked is the
path that is executed, and no joint overshoots its ends). ``intermediate_positions`` is never set: that feature needs Ruckig's web service.
"""

from __future__ import annotations

import numpy as np

from slax_drake.errors import TimingError
from slax_drake.planning.trajectory import JointTrajectory

SAMPLE_PERIOD = 0.001  # s


def time_segment(q0, q1, velocity, acceleration, jerk, dt: float = SAMPLE_PERIOD):
    """Samples (t, q, v, a) at period dt of the rest-to-rest motion q0 -> q1 (arrays per joint) on the straight
    line between them.

    Ruckig times the path parameter s in [0, 1] (q = q0 + s (q1 - q0)) under the tightest of the joints' limits
    divided by their travel, so every joint stays within its own velocity, acceleration and jerk limits and the
    motion never leaves the line (Ruckig's multi-joint phase synchronisation, which would give the same
    profile, silently falls back to time synchronisation, off the line, when it cannot synchronise). The last
    sample lies exactly at the segment's end (duration rounded up to a multiple of dt, where the profile holds at
    rest)."""
    from ruckig import InputParameter, Ruckig, Trajectory

    q0 = np.asarray(q0, float)
    q1 = np.asarray(q1, float)
    n = len(q0)
    if np.allclose(q0, q1, atol=1e-12, rtol=0.0):
        return np.zeros(1), q0[None, :].copy(), np.zeros((1, n)), np.zeros((1, n))
    d = q1 - q0
    moving = np.abs(d) > 0.0
    travel = np.abs(d[moving])
    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [1.0], [0.0], [0.0]
    inp.max_velocity = [float(np.min(np.asarray(velocity, float)[moving] / travel))]
    inp.max_acceleration = [float(np.min(np.asarray(acceleration, float)[moving] / travel))]
    inp.max_jerk = [float(np.min(np.asarray(jerk, float)[moving] / travel))]
    traj = _calculate(otg, inp, Trajectory(1))
    duration = traj.duration
    steps = int(np.ceil(duration / dt - 1e-9))
    t = np.arange(steps + 1) * dt
    sv = _sample_profile(traj, np.minimum(t, duration))
    q = q0 + sv[:, :1] * d
    v = sv[:, 1:2] * d
    a = sv[:, 2:3] * d
    q[-1], v[-1], a[-1] = q1, 0.0, 0.0
    return t, q, v, a


LIMIT_BACKOFF = 0.999  # the limits' share Ruckig is asked again with when it fails on the exact ones


def _calculate(otg, inp, traj):
    """Ruckig's offline ``calculate`` of ``inp`` into ``traj``. Where the limits put the profile exactly on the
    boundary between two of its shapes (the acceleration reached at the very moment the velocity is: seen with a
    joint travel that made the path's limits 72.7, 50 and 500), rounding can make Ruckig 0.19 fail or raise
    ("error in step 1"); it is asked once more with every limit at ``LIMIT_BACKOFF`` of its value, off the
    boundary and within the joints' limits (the segment takes 0.1 % longer). TimingError when that fails too."""
    from ruckig import Result, RuckigError

    for _ in range(2):
        try:
            result = otg.calculate(inp, traj)
        except RuckigError as e:
            result = e
        if result in (Result.Working, Result.Finished):
            return traj
        inp.max_velocity = [v * LIMIT_BACKOFF for v in inp.max_velocity]
        inp.max_acceleration = [a * LIMIT_BACKOFF for a in inp.max_acceleration]
        inp.max_jerk = [j * LIMIT_BACKOFF for j in inp.max_jerk]
    raise TimingError(f"Ruckig failed to time a segment: {' '.join(str(result).split())[:200]}")


def _sample_profile(traj, times) -> np.ndarray:
    """(len(times), 3): the path parameter's position, velocity and acceleration at ``times`` (s, within the
    duration) of Ruckig's one-dimensional trajectory ``traj``, evaluated from its seven constant-jerk phases at once
    (what ``Trajectory.at_time`` does one time at a time, a thousand calls per second of motion). A profile with a
    braking or accelerating pre-phase (none for a segment from rest) is sampled with ``at_time``."""
    profile = traj.profiles[0][0]
    if profile.brake.duration > 0.0 or profile.accel.duration > 0.0:
        return np.array([[v[0] for v in traj.at_time(float(tk))] for tk in times])
    starts = np.concatenate([[0.0], np.cumsum(profile.t)[:-1]])  # s, when each phase begins
    phase = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(starts) - 1)
    tau = times - starts[phase]
    j, a0, v0, p0 = (np.asarray(x, float)[phase] for x in (profile.j, profile.a[:-1], profile.v[:-1], profile.p[:-1]))
    return np.stack([p0 + tau * (v0 + tau * (a0 / 2.0 + tau * j / 6.0)),
                     v0 + tau * (a0 + tau * j / 2.0),
                     a0 + tau * j], axis=1)


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
