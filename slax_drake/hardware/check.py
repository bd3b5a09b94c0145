"""The trajectory checker, written independently of the planner: real Fetch limits, jerk, continuity, collisions.

The checker trusts nothing it checks: the file's positions and times are the motion; its velocity and
acceleration fields are checked against them, and its claims about the world (``objects_before``, ``lost``, the
action's names) never make it check less (:mod:`slax_drake.hardware.collision`). Checks on every point of every
motion of an :class:`~slax_drake.hardware.trajectory_file.ExportedTrajectory` (limits from
:mod:`slax_drake.hardware.fetch_limits`, never from our model or the planner):

- ``position``: lower + margin <= q <= upper - margin (``margin`` in rad, m for the torso; default 0, at most a
  quarter of the torso's range), with ``POSITION_TOL`` for rounding; continuous joints are unlimited;
- ``velocity``, ``acceleration``, ``jerk`` from positions: divided differences of the positions on the file's own
  time grid (v = q[t0, t1], a = 2 q[t0, t1, t2], j = 6 q[t0, .., t3]: weighted means of the true derivative, so a
  motion within the limits never exceeds them) against the limits, with the limit's relative tolerance plus the
  effect of positions rounded to ``POSITION_RESOLUTION`` (at 10 ms: 1e-4 /s, 0.02 /s^2, 4 /s^3);
- ``fields``: the velocity and acceleration fields (what a controller feeds forward) must integrate to the
  positions and velocities on every interval, within rounding, a jerk switch inside the interval and the
  resampling error of ``export --rate`` (:func:`_fields_agree`);
- the fields themselves, once they agree with the positions: |v| <= v_max, |a| <= a_max (relative tolerance
  ``LIMIT_REL_TOL`` = 0.01 %), and jerk as (a[k+1] - a[k]) / (t[k+1] - t[k]) against j_max (the mean jerk over
  the interval; tolerance ``JERK_REL_TOL`` of j_max plus 2e-6 / dt for accelerations rounded to 1e-6);
- ``discontinuity``: within a motion |q[k+1] - q[k]| <= v_max (t[k+1] - t[k]) (1 + LIMIT_REL_TOL) + POSITION_TOL;
  between motions the next motion starts where the previous one ended (``CONTINUITY_TOL``) and each motion
  starts and ends at rest (|v|, |a| <= ``REST_TOL``), since the robot holds still between motions; the first
  motion starts at the trajectory's initial positions when the metadata gives them;
- ``collision``: :meth:`~slax_drake.hardware.collision.CollisionWorld.check_motions` at every point and at
  quintic Hermite interpolated configurations every ``collision_step`` seconds in between, in the world of the
  scene given (the objects moved only by the checker's own model of each push and suction). A guarded push-in
  (a motion's ``action.guarded_push_in``: a plan-step file's, or a trial's guarded suction) is run by the
  controller as a guarded move: the first collision with an object inside its window is where it stops, and the
  motion's collisions from then on are not the robot's (:func:`_guarded_stop`); everything before it is checked
  as any motion. A motion cut where a
  trial's guard stopped it (``guarded_push_in.stopped_at_s`` at its end, inside the window) may end moving, and
  the next motion may start up to ``GUARD_STOP_TOL`` from its end (the measured pose, not the commanded one).

A file with no motion, or a margin that leaves no room, is refused (TrajectoryFileError, exit code 2). Time
monotonicity is enforced when the file is read (a non-monotonic file is rejected as malformed).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.errors import TrajectoryFileError
from slax_drake.hardware.fetch_limits import FetchLimits
from slax_drake.hardware.trajectory_file import ExportedTrajectory
from slax_drake.io import plural

POSITION_TOL = 1e-6  # rad or m
LIMIT_REL_TOL = 1e-4  # relative: rounding, and quintic interpolation between records (export --rate)
JERK_REL_TOL = 0.01
JERK_ROUNDING = 2e-6  # rad/s^2: two accelerations rounded to 1e-6
CONTINUITY_TOL = 1e-6  # rad or m
GUARD_STOP_TOL = 0.01  # rad or m: where the motion after a guard's stop may start from the stopped motion's end
REST_TOL = 1e-6  # rad/s and rad/s^2
COLLISION_STEP = 0.005  # s
POSITION_RESOLUTION = 1e-6  # rad or m: trial.json rounds positions to 1e-6; resampling (--rate) stays within it
FIELD_TOL_Q = 2 * POSITION_RESOLUTION + 1e-7  # rad or m: two rounded positions, plus the fields' rounding
FIELD_TOL_V = 4e-6  # rad/s: two velocities and two accelerations (times h) rounded to 1e-6
FIELD_ACCEL_REL = 0.05  # of a_max: how far the acceleration fields may lie from the positions' profile
FIELD_VELOCITY_S = 0.0025  # s, times a_max: how far the velocity fields may lie from it

OBJECTS_BEFORE_NOTE = 0.002  # m: the summary notes objects_before further than this from the checked world

KINDS = ("position", "velocity", "acceleration", "jerk", "discontinuity", "fields", "world", "collision")


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
        lines = [f"checked {plural(self.checked['motions'], 'motion')}, {plural(self.checked['points'], 'point')} "
                 f"({', '.join(self.checked['checks'])})"]
        reasons = self.checked.get("structural_reasons") or {}
        for a, b in self.checked.get("structural_pairs") or ():
            lines.append(f"self-collision pair not checked: {a}/{b}: {reasons.get(f'{a}/{b}', '')}")
        for k, entry in enumerate((self.checked.get("objects") or {}).get("motions", [])):
            touched = entry.get("touched")
            what = (f"may touch {touched}" + (f" (pushed {entry['pushed_m'] * 1000:.0f} mm)" if "pushed_m" in entry
                                              else " (carried)" if entry.get("carried") else "")) if touched \
                else f"touches nothing ({entry.get('association')})"
            for name, m in (entry.get("guarded_met") or {}).items():  # pushed ahead of a guarded placement
                what += f"; it pushed {name} {m['pushed_m'] * 1000:.0f} mm ahead from t = {m['time_s']:.3f} s"
            for name, depth in (entry.get("seal_pressed") or {}).items():  # the seal's press against a neighbour
                what += f"; the seal pressed it {depth * 1000:.1f} mm against {name}"
            offset = entry.get("objects_before_offset_m")
            if offset is not None and math.isfinite(offset) and offset > OBJECTS_BEFORE_NOTE:
                what += f"; the file's objects_before lie up to {offset * 1000:.0f} mm from the checked world"
            elif offset is not None and not math.isfinite(offset):
                what += "; the file's objects_before do not name the scene's objects"
            lines.append(f"motion {k}: the tool {what}")
        for stop in self.checked.get("guarded_stops") or ():
            t0, t1 = stop["window_s"]
            force = f" (stops over {stop['stop_force_n']} N)" if stop.get("stop_force_n") is not None else ""
            line = f"motion {stop['motion']}: a guarded push-in from {t0:.3f} to {t1:.3f} s{force}"
            if stop["time_s"] is not None:
                line += (f": it meets {stop['bodies']} at t = {stop['time_s']:.3f} s, where the guard stops it; the "
                         "motion's collisions after that are not the robot's and are not checked")
            elif stop.get("stopped_at_s") is not None:
                line += f": the trial's guard stopped it at t = {stop['stopped_at_s']:.3f} s (the motion ends there)"
            else:
                line += ": nothing in its way"
            lines.append(line)
        if self.checked.get("claimed_lost"):
            lines.append("the file calls lost: " + ", ".join(self.checked["claimed_lost"])
                         + " (checked anyway, at their last pose in the checked world)")
        if self.ok:
            lines.append("OK: no violation")
            return "\n".join(lines)
        lines.append(f"FAILED: {plural(len(self.violations), 'violation')}")
        for kind, found in self.by_kind().items():
            if not found:
                continue
            groups = {}
            for v in found:
                groups.setdefault((v.motion, v.what), []).append(v)
            lines.append(f"{kind}: {len(found)} in {plural(len(groups), '(motion, joint/bodies) group')}")
            for (motion, what), vs in list(groups.items())[:max_lines]:
                worst = max(vs, key=lambda v: abs(v.value) - abs(v.limit))
                lines.append(f"  motion {motion} {what}: {plural(len(vs), 'point')} from t = {vs[0].time:.3f} s, worst: "
                             f"{worst.message}")
            if len(groups) > max_lines:
                lines.append(f"  ... and {len(groups) - max_lines} more groups")
        return "\n".join(lines)


def check_trajectory(traj: ExportedTrajectory, world=None, limits: FetchLimits | None = None, margin: float = 0.0,
                     collision_step: float = COLLISION_STEP) -> CheckReport:
    """Runs every check (module docstring); ``world``: a CollisionWorld, or None to skip collisions. Raises
    TrajectoryFileError when there is nothing to check (no motion) or ``margin`` leaves no room."""
    lim = limits or FetchLimits.real_fetch()
    names = lim.names
    if not traj.motions:
        raise TrajectoryFileError("the trajectory has no motion: nothing to check (and nothing to send to a robot)")
    check_margin(margin, lim)
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
            _from_positions(out, m_index, t, q, lim)
            _fields_agree(out, m_index, t, q, v, a, lim)
        for label, idx in (("start", 0), ("end", -1)):
            if label == "end" and _stopped_by_guard(m):  # a guard stops the push-in on contact, moving
                continue
            moving = np.maximum(np.abs(v[idx]), np.abs(a[idx]))
            for j in np.flatnonzero(moving > REST_TOL):
                out.append(Violation("discontinuity", m_index, float(t[idx]), names[j], float(moving[j]), REST_TOL,
                                     f"the motion's {label} is not at rest: {names[j]} v = {v[idx, j]:.6g}, "
                                     f"a = {a[idx, j]:.6g} (the robot holds still between motions)"))
        if previous_end is not None:
            gap = np.abs(q[0] - previous_end)
            # after a guard's stop the next motion starts where the arm stopped: the measured pose, off the
            # commanded one by the tracking error
            tol = GUARD_STOP_TOL if m_index > 0 and _stopped_by_guard(traj.motions[m_index - 1]) else CONTINUITY_TOL
            for j in np.flatnonzero(gap > tol):
                where = "the initial positions" if m_index == 0 else f"motion {m_index - 1}'s end"
                out.append(Violation("discontinuity", m_index, 0.0, names[j], float(gap[j]), tol,
                                     f"{names[j]} starts {gap[j]:.6g} away from {where}"))
        previous_end = q[-1]
    checks = ["position", "velocity", "acceleration", "jerk", "continuity",
              "derivatives from positions", "fields against positions"]
    checked = {"motions": len(traj.motions), "points": points, "margin": margin, "checks": checks}
    claimed_lost = sorted({n for m in traj.motions for n in m.lost})
    if claimed_lost:
        checked["claimed_lost"] = claimed_lost
    if world is not None:
        checks.append("collision" + (" (robot, shelf, objects)" if world.objects else " (robot only)"))
        checked["structural_pairs"] = world.structural_pairs
        checked["structural_reasons"] = world.structural_reasons
        checked["collision_configurations"] = world.check_motions(traj, out, collision_step, Violation)
        checked["objects"] = world.report
        for m_index, m in enumerate(traj.motions):
            guarded = (m.action or {}).get("guarded_push_in")
            if guarded:
                carried = world.report["motions"][m_index].get("touched")
                out[:] = _guarded_stop(out, guarded, m_index, m, set(world.objects) - {carried}, checked)
    return CheckReport(out, checked, dict(zip(names, low_margin.tolist())))


def _stopped_by_guard(motion) -> bool:
    """Whether ``motion`` ends where a guard stopped its push-in: its action's ``guarded_push_in`` (or, an unguarded
    lift's watch at the board's edge, ``edge_watch``) says it stopped at the motion's end (``stopped_at_s``), inside
    its push-in window."""
    action = motion.action or {}
    g = action.get("guarded_push_in") or action.get("edge_watch") or {}
    stop = g.get("stopped_at_s")
    return stop is not None and abs(float(stop) - motion.duration) <= 1e-6 and \
        float(g["t_start_s"]) <= float(stop) <= float(g["t_end_s"]) + 1e-6


def _guarded_stop(out: list, guarded: dict, m_index: int, motion, objects: set, checked: dict) -> list:
    """The violations once motion ``m_index`` holds a guarded push-in (``guarded``: its action's
    ``guarded_push_in``, the window ``t_start_s``..``t_end_s``, s from the motion's start): the controller runs
    that window as a guarded move, so a collision with one of ``objects`` (the scene's objects but the carried one:
    not the shelf, not the robot itself, not the carried object on the shelf) that first appears inside it is where
    the guard stops the push, and the motion's collisions from that time on are left out (a plan-step file's motion
    goes on as planned after it, which is not what runs; the stop motion is the controller's). The stop goes into
    ``checked["guarded_stops"]``. A collision before the window, or one of the shelf or the robot with itself,
    stays a violation; a window outside the motion is one ("world")."""
    t0, t1 = float(guarded["t_start_s"]), float(guarded["t_end_s"])
    stops = checked.setdefault("guarded_stops", [])
    if not 0.0 <= t0 < t1 or t0 > motion.duration + 1e-6:
        return out + [Violation("world", m_index, t0, "guarded_push_in", t1, motion.duration,
                                f"the guarded push-in's window {t0:.3f}-{t1:.3f} s lies outside the motion "
                                f"(0-{motion.duration:.3f} s)")]
    met = [v for v in out if v.kind == "collision" and v.motion == m_index and t0 <= v.time <= t1
           and set(v.what.split("/")) & objects]
    first = min(met, key=lambda v: v.time, default=None)
    stops.append({"motion": m_index, "window_s": [t0, t1], "stop_force_n": guarded.get("stop_force_n"),
                  "stopped_at_s": guarded.get("stopped_at_s"),
                  "time_s": None if first is None else first.time, "bodies": None if first is None else first.what})
    if first is None:
        return out
    return [v for v in out if not (v.kind == "collision" and v.motion == m_index and v.time >= first.time)]


def check_margin(margin: float, limits: FetchLimits | None = None) -> None:
    """Refuses a position margin (rad, m for the torso) that is not a finite number >= 0 or that leaves less than
    half of any limited joint's range (the narrowest: the torso, 0.386 m) to move in."""
    lim = limits or FetchLimits.real_fetch()
    span = lim.position_upper - lim.position_lower
    finite = np.isfinite(span)
    largest = float(np.min(span[finite]) / 4.0)
    if not (np.isfinite(margin) and 0.0 <= margin <= largest):
        narrow = lim.names[int(np.flatnonzero(finite)[np.argmin(span[finite])])]
        raise TrajectoryFileError(f"--margin {margin:g} is not between 0 and {largest:.4g} (a quarter of the narrowest "
                                  f"range, {narrow}'s {4 * largest:.4g}; rad, m for the torso)")


def _from_positions(out, motion, t, q, lim) -> None:
    """Velocity, acceleration and jerk as divided differences of the positions on the file's own time grid.

    v = q[t0, t1], a = 2 q[t0, t1, t2], j = 6 q[t0, .., t3]: each is a positively weighted mean of the true
    derivative over its points' span, so a motion within the limits never exceeds them. The tolerance is the
    limit's LIMIT_REL_TOL plus the worst effect of positions rounded to ``POSITION_RESOLUTION`` carried through
    the differences (at 10 ms: 1e-4 /s, 0.02 /s^2, 4 /s^3)."""
    names = lim.names
    h = np.diff(t)[:, None]
    vel = np.diff(q, axis=0) / h
    e_v = np.broadcast_to(POSITION_RESOLUTION / h, vel.shape)
    _bounds(out, "velocity", motion, t[:-1], vel, -(lim.velocity * (1 + LIMIT_REL_TOL) + e_v),
            lim.velocity * (1 + LIMIT_REL_TOL) + e_v, names, "/s (from positions)")
    if len(t) < 3:
        return
    span2 = (t[2:] - t[:-2])[:, None]
    acc = 2.0 * np.diff(vel, axis=0) / span2
    e_a = 2.0 * (e_v[1:] + e_v[:-1]) / span2
    amax = lim.acceleration * (1 + LIMIT_REL_TOL) + e_a
    _bounds(out, "acceleration", motion, t[1:-1], acc, -amax, amax, names, "/s^2 (from positions)")
    if len(t) < 4:
        return
    span3 = (t[3:] - t[:-3])[:, None]
    jerk = 3.0 * np.diff(acc, axis=0) / span3
    e_j = 3.0 * (e_a[1:] + e_a[:-1]) / span3
    jmax = lim.jerk * (1 + JERK_REL_TOL) + e_j
    _bounds(out, "jerk", motion, t[1:-2], jerk, -jmax, jmax, names, "/s^3 (from positions)")


def _fields_agree(out, motion, t, q, v, a, lim) -> None:
    """The file's velocity and acceleration fields must agree with its positions (they are what a controller
    feeds forward): on each interval of length h,

    - q1 - q0 = h (v0 + v1) / 2 + h^2 (a0 - a1) / 12 within ``FIELD_TOL_Q`` + j_max h^4 / 24 + h dv + h^2 da / 6
      (exact for a cubic, i.e. a jerk-limited profile without a switch inside the interval; a jerk switch costs at
      most j_max h^4 / 62);
    - v1 - v0 = h (a0 + a1) / 2 within ``FIELD_TOL_V`` + j_max h^2 / 4 + h da (exact for a linear acceleration; a
      jerk switch inside the interval costs at most j_max h^2 / 4);

    where da = ``FIELD_ACCEL_REL`` a_max and dv = ``FIELD_VELOCITY_S`` a_max are how far the fields may lie from
    the profile through the positions: ``export --rate`` interpolates accelerations linearly between 10 ms
    records, off by up to j_max * 5 ms = 5 % of a_max at a jerk switch (the Fetch's j_max is 10 a_max per s).
    A chattering joint (+-0.01 rad every 10 ms: 0.02 rad against about 1e-5) or zero fields on a moving joint
    (v h against h dv: caught above 0.4 % of a_max per s, about 4 mrad/s) stand far outside.

    One violation (kind ``fields``) per joint and motion: the interval where they contradict most."""
    names = lim.names
    h = np.diff(t)[:, None]
    jmax = lim.jerk * (1 + JERK_REL_TOL)
    da = FIELD_ACCEL_REL * lim.acceleration  # what the fields may be off by: export --rate's resampling error
    dv = FIELD_VELOCITY_S * lim.acceleration
    rq = np.diff(q, axis=0) - (h / 2 * (v[1:] + v[:-1]) + h ** 2 / 12 * (a[:-1] - a[1:]))
    tol_q = FIELD_TOL_Q + jmax * h ** 4 / 24 + h * dv + h ** 2 * da / 6
    rv = np.diff(v, axis=0) - h / 2 * (a[1:] + a[:-1])
    tol_v = FIELD_TOL_V + jmax * h ** 2 / 4 + h * da
    for label, r, tol, unit in (("position change", rq, tol_q, ""), ("velocity change", rv, tol_v, "/s")):
        bad = np.abs(r) > tol
        for j in np.flatnonzero(bad.any(axis=0)):
            k = int(np.argmax(np.abs(r[:, j]) - tol[:, j]))  # the worst interval
            field = "velocities" if label == "position change" else "accelerations"
            out.append(Violation("fields", motion, float(t[k]), names[j], float(r[k, j]), float(tol[k, j]),
                                 f"{names[j]}'s {field} contradict its {'positions' if field == 'velocities' else 'velocities'}: "
                                 f"the {label} from t = {t[k]:.4f} to {t[k + 1]:.4f} s differs by {r[k, j]:.6g}{unit} "
                                 f"from the fields' integral (tolerance {tol[k, j]:.3g}; {int(bad[:, j].sum())} intervals)"))


def _bounds(out, kind, motion, t, x, lo, hi, names, unit) -> None:
    lo = np.broadcast_to(lo, x.shape)
    hi = np.broadcast_to(hi, x.shape)
    for k, j in zip(*np.nonzero((x < lo) | (x > hi))):
        limit = lo[k, j] if x[k, j] < lo[k, j] else hi[k, j]
        out.append(Violation(kind, motion, float(t[k]), names[j], float(x[k, j]), float(limit),
                             f"{names[j]} {kind} {x[k, j]:.6g} {unit} beyond the limit {limit:.6g} at t = {t[k]:.4f} s"))
