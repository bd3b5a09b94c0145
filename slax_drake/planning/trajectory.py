"""A timed joint trajectory of the planned joints, sampled on a uniform clock (1 ms by default).

Positions in metres (torso) and radians, velocities per second, accelerations per second squared, in the order
of ``names`` (``slax_drake.station.robot.PLANNED_JOINTS``). The samples are exact samples of the Ruckig profiles
(see :mod:`slax_drake.planning.timing`); between samples :meth:`JointTrajectory.value` interpolates linearly.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class JointTrajectory:
    """Joint names, sample times t (N,) s from 0, positions q, velocities v, accelerations a (N, n_joints)."""

    names: tuple[str, ...]
    times: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray

    def __post_init__(self):
        n = len(self.times)
        for name in ("q", "v", "a"):
            arr = getattr(self, name)
            if arr.shape != (n, len(self.names)):
                raise ValueError(f"{name} has shape {arr.shape}, expected {(n, len(self.names))}")

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0]) if len(self.times) else 0.0

    @property
    def dt(self) -> float:
        """The sampling period (s)."""
        return float(self.times[1] - self.times[0]) if len(self.times) > 1 else 0.0

    def jerk(self) -> np.ndarray:
        """Jerk (N-1, n_joints) by finite differences of the sampled accelerations (exact for Ruckig's
        piecewise-constant jerk away from the switching instants)."""
        return np.diff(self.a, axis=0) / np.diff(self.times)[:, None]

    def value(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(q, v) at time t (s), linearly interpolated; held at the ends outside [0, duration]."""
        times = self.times
        if t <= times[0]:
            return self.q[0].copy(), np.zeros(len(self.names))
        if t >= times[-1]:
            return self.q[-1].copy(), np.zeros(len(self.names))
        k = int(np.searchsorted(times, t, side="right")) - 1
        s = (t - times[k]) / (times[k + 1] - times[k])
        return self.q[k] + s * (self.q[k + 1] - self.q[k]), self.v[k] + s * (self.v[k + 1] - self.v[k])

    def then(self, other: "JointTrajectory") -> "JointTrajectory":
        """This trajectory followed by ``other`` (which starts where this one ends, at rest): other's first
        sample is dropped and its clock continues this one's."""
        if self.names != other.names:
            raise ValueError("joint names differ")
        if len(self.times) == 0:
            return other
        times = other.times[1:] - other.times[0] + self.times[-1]
        return JointTrajectory(self.names, np.concatenate([self.times, times]), np.concatenate([self.q, other.q[1:]]),
                               np.concatenate([self.v, other.v[1:]]), np.concatenate([self.a, other.a[1:]]))

    def shifted(self, t0: float) -> "JointTrajectory":
        """The same samples with times starting at t0."""
        return dataclasses.replace(self, times=self.times - self.times[0] + t0)

    def to_dict(self, stride: int = 1, keep_times=()) -> dict:
        """JSON-ready: every ``stride``-th sample, the last one and the samples at ``keep_times`` (s; e.g. where
        motions start), rounded to 1e-6."""
        idx = np.arange(0, len(self.times), stride)
        if len(self.times) and idx[-1] != len(self.times) - 1:
            idx = np.append(idx, len(self.times) - 1)
        if len(self.times) and len(keep_times):
            keep = np.clip(np.searchsorted(self.times, np.asarray(keep_times, float) - 1e-9), 0, len(self.times) - 1)
            idx = np.union1d(idx, keep)
        r = lambda x: np.round(x[idx], 6).tolist()  # noqa: E731
        return {"joint_names": list(self.names), "times": r(self.times), "positions": r(self.q),
                "velocities": r(self.v), "accelerations": r(self.a)}

    @staticmethod
    def from_dict(data: dict) -> "JointTrajectory":
        return JointTrajectory(tuple(data["joint_names"]), np.asarray(data["times"], float),
                               np.asarray(data["positions"], float), np.asarray(data["velocities"], float),
                               np.asarray(data["accelerations"], float))

    @staticmethod
    def hold(names, q, duration: float = 0.0, dt: float = 0.001) -> "JointTrajectory":
        """Standing still at q for ``duration`` seconds."""
        n = max(2, int(round(duration / dt)) + 1)
        q = np.asarray(q, float)
        return JointTrajectory(tuple(names), np.arange(n) * dt, np.tile(q, (n, 1)), np.zeros((n, len(q))),
                               np.zeros((n, len(q))))
