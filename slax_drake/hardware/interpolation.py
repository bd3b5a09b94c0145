"""Quintic Hermite interpolation of sampled joint trajectories.

Between two samples (t0: q0, v0, a0) and (t1: q1, v1, a1) the position is the unique quintic polynomial that
matches position, velocity and acceleration at both ends; velocity and acceleration are its derivatives. The
planner's Ruckig profiles are piecewise cubic in position (piecewise-constant jerk), so between samples where
the jerk does not switch the interpolant reproduces the profile exactly, and across a switch the error is of the
order of jerk * dt^3 (about 1e-6 rad at 10 ms samples and 25 rad/s^3).
"""

from __future__ import annotations

import numpy as np


def quintic_hermite(times, q, v, a, t_query):
    """(q, v, a) at ``t_query`` (M,) from samples ``times`` (N,) strictly increasing, q, v, a (N, J).

    Queries outside [times[0], times[-1]] are clamped to the end samples (held there with zero v and a)."""
    times = np.asarray(times, float)
    q, v, a = (np.asarray(x, float) for x in (q, v, a))
    t = np.asarray(t_query, float)
    n = len(times)
    if n == 1:
        m = len(t)
        return np.tile(q[0], (m, 1)), np.zeros((m, q.shape[1])), np.zeros((m, q.shape[1]))
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, n - 2)
    h = (times[k + 1] - times[k])[:, None]
    s = np.clip((t - times[k])[:, None] / h, 0.0, 1.0)
    p0, p1, v0, v1, a0, a1 = q[k], q[k + 1], v[k], v[k + 1], a[k], a[k + 1]
    dp = p1 - p0
    c1 = h * v0
    c2 = 0.5 * h * h * a0
    c3 = 10 * dp - 6 * h * v0 - 4 * h * v1 - 1.5 * h * h * a0 + 0.5 * h * h * a1
    c4 = -15 * dp + 8 * h * v0 + 7 * h * v1 + 1.5 * h * h * a0 - h * h * a1
    c5 = 6 * dp - 3 * h * v0 - 3 * h * v1 - 0.5 * h * h * a0 + 0.5 * h * h * a1
    qs = p0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    vs = (c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))) / h
    as_ = (2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))) / (h * h)
    before = t < times[0]
    after = t > times[-1]
    if before.any() or after.any():
        qs[before], vs[before], as_[before] = q[0], 0.0, 0.0
        qs[after], vs[after], as_[after] = q[-1], 0.0, 0.0
    return qs, vs, as_


def resample(times, q, v, a, t_query):
    """Resampling used by ``export --rate``: positions by :func:`quintic_hermite`; accelerations linearly between
    samples (a jerk-limited profile's acceleration is piecewise linear, so this never exceeds the samples'
    accelerations nor the largest jerk between them); velocities by integrating that acceleration from the left
    sample, plus the linear correction that makes them meet the right sample (the trapezoid rule's error, at most
    j_max dt^2 / 8 at a jerk switch), so they do not overshoot a saturated velocity."""
    times = np.asarray(times, float)
    q, v, a = (np.asarray(x, float) for x in (q, v, a))
    t = np.asarray(t_query, float)
    qs, _, _ = quintic_hermite(times, q, v, a, t)
    if len(times) == 1:
        return qs, np.zeros_like(qs), np.zeros_like(qs)
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    h = (times[k + 1] - times[k])[:, None]
    tau = np.clip((t - times[k])[:, None], 0.0, h)
    a0, a1, v0, v1 = a[k], a[k + 1], v[k], v[k + 1]
    as_ = a0 + (a1 - a0) * tau / h
    v_end = v0 + 0.5 * (a0 + a1) * h
    vs = v0 + a0 * tau + 0.5 * (a1 - a0) * tau * tau / h + (v1 - v_end) * tau / h
    outside = (t < times[0]) | (t > times[-1])
    vs[outside], as_[outside] = 0.0, 0.0
    return qs, vs, as_
