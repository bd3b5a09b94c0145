"""The trajectory checker, written independently of the planner: real Fetch limits, jerk, continuity, collisions.

Checks on every point of every motion of an :class:`~slax_drake.hardware.trajectory_file.ExportedTrajectory`
(limits from :mod:`slax_drake.hardware.fetch_limits`, never from our model or the planner):

- ``position``: lower + margin <= q <= upper - margin (``margin`` in rad, m for the torso; default 0), with
  ``POSITION_TOL`` for rounding; continuous joints are unlimited;
- ``velocity`` and ``acceleration``: |v| <= v_max, |a| <= a_max (relative tolerance ``LIMIT_REL_TOL`` = 0.01 %,
  covering rounding and the quintic resampling of ``export --rate``);
- ``jerk``: finite differences of the sampled accelerations, (a[k+1] - a[k]) / (t[k+1] - t[k]), against j_max.
  For jerk-limited (Ruckig) profiles the difference quotient is the mean jerk over the interval, so it never
  exceeds j_max; the tolerance is ``JERK_REL_TOL`` of j_max plus 2e-6 / dt for accelerations rounded to 1e-6
  (trial.json) -- 2e-4 rad/s^3 at 100 Hz;
- ``discontinuity``: within a motion |q[k+1] - q[k]| <= v_max (t[k+1] - t[k]) (1 + LIMIT_REL_TOL) + POSITION_TOL;
  between motions the next motion starts where the previous one ended (``CONTINUITY_TOL``) and each motion
  starts and ends at rest (|v|, |a| <= ``REST_TOL``), since the robot holds still between motions; the first
  motion starts at the trajectory's initial positions when the metadata gives them;
- ``collision``: :class:`~slax_drake.hardware.collision.CollisionWorld` at every point and at quintic Hermite
  interpolated configurations every ``collision_step`` seconds in between.

Time monotonicity is enforced when the file is read (a non-monotonic file is rejected as malformed).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.hardware.fetch_limits import FetchLimits
from slax_drake.hardware.interpolation import quintic_hermite
from slax_drake.hardware.trajectory_file import ExportedTrajectory

POSITION_TOL = 1e-6  # rad or m
LIMIT_REL_TOL = 1e-4  # relative: rounding, and quintic interpolation between records (export --rate)
JERK_REL_TOL = 0.01
JERK_ROUNDING = 2e-6  # rad/s^2: two accelerations rounded to 1e-6
CONTINUITY_TOL = 1e-6  # rad or m
REST_TOL = 1e-6  # rad/s and rad/s^2
COLLISION_STEP = 0.005  # s

KINDS = ("position", "velocity", "acceleration", "jerk", "discontinuity", "collision")


@dataclasses.dataclass(frozen=True)
class Violation:
    """One violated check: kind, motion index, time from the motion's start (s), what (joint or bodies), the
    offending value and the limit (SI units), and a sentence."""

    kind: str
    motion: int
    time: float
    what: str
    value: float
    limit: float
    message: str


@dataclasses.dataclass
class CheckReport:
    violations: list
    checked: dict  # what was checked: counts, options, structural pairs left out
    margins: dict  # per joint: the smallest distance to the position limits (rad or m)

    @property
    def ok(self) -> bool:
        return not self.violations

    def by_kind(self) -> dict:
        out = {k: [] for k in KINDS}
        for v in self.violations:
            out[v.kind].append(v)
        return out

    def summary(self, max_lines: int = 5) -> str:
        lines = [f"checked {self.checked['motions']} motions, {self.checked['points']} points "
                 f"({', '.join(self.checked['checks'])})"]
        if self.checked.get("structural_pairs"):
            lines.append("self-collision pairs overlapping at the reference pose (not checked): "
                         + ", ".join(f"{a}/{b}" for a, b in self.checked["structural_pairs"]))
        if self.ok:
            lines.append("OK: no violation")
            return "\n".join(lines)
        lines.append(f"FAILED: {len(self.violations)} violations")
        for kind, found in self.by_kind().items():
            if not found:
                continue
            groups = {}
            for v in found:
                groups.setdefault((v.motion, v.what), []).append(v)
            lines.append(f"{kind}: {len(found)} in {len(groups)} (motion, joint/bodies) groups")
            for (motion, what), vs in list(groups.items())[:max_lines]:
                worst = max(vs, key=lambda v: abs(v.value) - abs(v.limit))
                lines.append(f"  motion {motion} {what}: {len(vs)} points from t = {vs[0].time:.3f} s, worst: "
                             f"{worst.message}")
            if len(groups) > max_lines:
                lines.append(f"  ... and {len(groups) - max_lines} more groups")
        return "\n".join(lines)


def check_trajectory(traj: ExportedTrajectory, world=None, limits: FetchLimits | None = None, margin: float = 0.0,
                     collision_step: float = COLLISION_STEP) -> CheckReport:
    """Runs every check (module docstring); ``world``: a CollisionWorld, or None to skip collisions."""
    lim = limits or FetchLimits.real_fetch()
    names = lim.names
    out: list[Violation] = []
    lower = lim.position_lower + margin
    upper = lim.position_upper - margin
    low_margin = np.full(len(names), np.inf)
    points = 0
    previous_end = None
    initial = traj.metadata.get("initial_positions")
    if initial is not None:
        previous_end = np.asarray(initial, float)
    for m_index, m in enumerate(traj.motions):
        t, q, v, a = m.times, m.q, m.v, m.a
        points += len(t)
        low_margin = np.minimum(low_margin, np.minimum(q - lim.position_lower, lim.position_upper - q).min(axis=0))
        _bounds(out, "position", m_index, t, q, lower - POSITION_TOL, upper + POSITION_TOL, names, "m or rad")
        vmax = lim.velocity * (1 + LIMIT_REL_TOL)
        _bounds(out, "velocity", m_index, t, v, -vmax, vmax, names, "/s")
        amax = lim.acceleration * (1 + LIMIT_REL_TOL)
        _bounds(out, "acceleration", m_index, t, a, -amax, amax, names, "/s^2")
        if len(t) > 1:
            dt = np.diff(t)[:, None]
            jerk = np.diff(a, axis=0) / dt
            jmax = lim.jerk * (1 + JERK_REL_TOL) + JERK_ROUNDING / dt
            _bounds(out, "jerk", m_index, t[:-1], jerk, -jmax, jmax, names, "/s^3")
            step = np.abs(np.diff(q, axis=0))
            allowed = lim.velocity * dt * (1 + LIMIT_REL_TOL) + POSITION_TOL
            for k, j in zip(*np.nonzero(step > allowed)):
                out.append(Violation("discontinuity", m_index, float(t[k]), names[j], float(step[k, j]), float(allowed[k, j]),
                                     f"{names[j]} jumps by {step[k, j]:.6g} between t = {t[k]:.4f} and {t[k + 1]:.4f} s "
                                     f"(at most {allowed[k, j]:.6g} at the velocity limit)"))
        for label, idx in (("start", 0), ("end", -1)):
            moving = np.maximum(np.abs(v[idx]), np.abs(a[idx]))
            for j in np.flatnonzero(moving > REST_TOL):
                out.append(Violation("discontinuity", m_index, float(t[idx]), names[j], float(moving[j]), REST_TOL,
                                     f"the motion's {label} is not at rest: {names[j]} v = {v[idx, j]:.6g}, "
                                     f"a = {a[idx, j]:.6g} (the robot holds still between motions)"))
        if previous_end is not None:
            gap = np.abs(q[0] - previous_end)
            for j in np.flatnonzero(gap > CONTINUITY_TOL):
                where = "the initial positions" if m_index == 0 else f"motion {m_index - 1}'s end"
                out.append(Violation("discontinuity", m_index, 0.0, names[j], float(gap[j]), CONTINUITY_TOL,
                                     f"{names[j]} starts {gap[j]:.6g} away from {where}"))
        previous_end = q[-1]
    checks = ["position", "velocity", "acceleration", "jerk", "continuity"]
    checked = {"motions": len(traj.motions), "points": points, "margin": margin, "checks": checks}
    if world is not None:
        checks.append("collision" + (" (robot, shelf, objects)" if world.objects else " (robot only)"))
        checked["structural_pairs"] = world.structural_pairs
        checked["collision_configurations"] = _collisions(out, traj, world, collision_step)
    return CheckReport(out, checked, dict(zip(names, low_margin.tolist())))


def _bounds(out, kind, motion, t, x, lo, hi, names, unit) -> None:
    lo = np.broadcast_to(lo, x.shape)
    hi = np.broadcast_to(hi, x.shape)
    for k, j in zip(*np.nonzero((x < lo) | (x > hi))):
        limit = lo[k, j] if x[k, j] < lo[k, j] else hi[k, j]
        out.append(Violation(kind, motion, float(t[k]), names[j], float(x[k, j]), float(limit),
                             f"{names[j]} {kind} {x[k, j]:.6g} {unit} beyond the limit {limit:.6g} at t = {t[k]:.4f} s"))


def _collisions(out, traj, world, step) -> int:
    count = 0
    for m_index, m in enumerate(traj.motions):
        world.place_objects(m.objects_before, m.lost)
        allowed = (m.action or {}).get("object")
        extra = np.arange(0.0, m.duration, step) if step and step > 0 else np.zeros(0)
        times = np.union1d(m.times, extra)
        qs, _, _ = quintic_hermite(m.times, m.q, m.v, m.a, times)
        for t, q in zip(times, qs):
            count += 1
            for a, b, depth in world.collisions(q, touching_allowed=allowed):
                out.append(Violation("collision", m_index, float(t), f"{a}/{b}", depth, world.tolerance,
                                     f"{a} penetrates {b} by {depth * 1000:.1f} mm at t = {t:.4f} s"))
    return count
