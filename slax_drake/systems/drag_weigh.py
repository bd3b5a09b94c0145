"""A sideways drag weighed along its pull: the floor's friction, sensed from the arm's joint efforts, before the
object is slid across (the ``weigh_drag_pull`` rule).

A drag seals on an object's camera-facing side, pulls it toward the opening sliding on the floor ("pull"), slides it
across by d_x ("drag across") and pushes it in. Sliding across, the floor's friction acts at the object's centre, a
lever away from the contact, and twists the object about the cup; over what the cup's lip holds the seal slips round
and the object is left turned short of its placement (in the Drake trials, cylinders of 1.35-1.96 kg moved 3.5-6 cm
of 10-40 cm and turned 25-30 deg; ``research/drag_twist.py``). The action model checks that twist
(``max_drag_twist``: ``drag_safety_factor`` x ``drag_friction`` x m g x lever) with the mass it believes, for an
object not weighed yet its class's ``mass_quantile``. The pull measures it: while the object slides out, the force
resisting the cup is the floor's sliding friction, the force that will resist the slide across (Coulomb friction is
the same along every direction of the floor). So the check is made again at the pull's end with the measured force
in place of ``drag_friction`` x m g; over the limit, the drag is undone from there (the pull played backward: the
object pushed back to where it was sealed and released; :meth:`MotionPlanner.put_back`) and the object is reckoned
from then on with the mass that friction implies, so the action model drags it straight out and in only.

The estimate (:class:`PullRun`): a :class:`~slax_drake.systems.guard.ContactMonitor` along the pull direction
(S -y, in world) whose baseline is fitted at the "approach" waypoint, the arm at rest and free. Not at the seal: the
cup presses into the face there and the floor's static friction holds the press, which turns over as the pull starts
(with the baseline at the seal a 2 kg box's 8.9 N of friction read 13.6 N; at the approach 8.7 N, and a 1 kg box's
4.5 N read 4.1 N; ``sim_configs/station_sim_shelf.yaml``'s station). The friction is the median of the samples
taken once the cup has pulled ``SLIDING_TRAVEL`` (the object slides) and until ``END_MARGIN`` before the pull's
planned end (the arm slows to rest there). A pull shorter than that (an object already near the opening) weighs
nothing and the drag goes on as planned.

Units: forces N, moments N m, lengths m, times s from the motion's start.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.systems.guard import ContactMonitor, planned_acceleration

ALONG_PULL = "pull"  # the ``along`` of a drag's ``weighed`` record (a lift's has none)
SLIDING_TRAVEL = 0.01  # m the cup pulls before its samples count (the object has broken loose and slides)
END_MARGIN = 0.005  # m before the pull's planned end after which samples no longer count (the arm slows to rest)
MIN_SAMPLES = 3  # samples the friction needs; fewer: the pull weighs nothing


@dataclasses.dataclass(frozen=True)
class PullRun:
    """A drag's pull being weighed: the monitor (its baseline fitted at ``t_base``, the "approach"), the pull's
    window [t0, t1] (s from the motion's start: the seal's dwell ends, the "pull" waypoint is reached), when the
    verdict is made (``t_decide``: the arm at rest at the pull's end, ``PULL_DWELL``), its planned length (m), the cup's position (world, m) at the pull's first sample and the forces (N) sampled so far."""

    monitor: ContactMonitor
    t_base: float
    t0: float
    t1: float
    t_decide: float  # s from the motion's start: the verdict, late in the rest at the pull's end
    length: float
    p_start: tuple | None = None
    forces: tuple = ()

    @property
    def friction(self) -> float | None:
        """N: the median of the sampled forces, None under ``MIN_SAMPLES``."""
        return float(np.median(self.forces)) if len(self.forces) >= MIN_SAMPLES else None


def is_pull_record(weighed) -> bool:
    """Whether a trial record's ``weighed`` (a dict, or None) is a drag's weighing along its pull, not a lift's."""
    return isinstance(weighed, dict) and weighed.get("along") == ALONG_PULL


def believed_pull(obj, contact_xy) -> tuple[float, str]:
    """(lever m, face shape) of a drag whose cup seals at ``contact_xy`` (S) on the believed object ``obj``: the
    contact's distance to its centre and its shape; for an object the believed scene does not hold (None), no lever
    and a curved face (the stricter limit: :func:`~slax_drake.shelf.rules.drag_twist_limit`)."""
    from slax_drake.shelf.actions import contact_lever

    return (0.0, "cylinder") if obj is None else (contact_lever(obj, contact_xy), obj.shape)


def pull_window(motion) -> tuple[float, float, float, float] | None:
    """(baseline, pull start, pull end, verdict), s from the motion's start, of a drag that slides its object across
    (d_x != 0), planned under the ``weigh_drag_pull`` rule: the "approach" waypoint, the end of the dwell at the
    "seal", the "pull" waypoint, and ``WEIGH_EARLY`` before the end of the rest there (``PULL_DWELL``: the arm and
    the object have stopped; the records before the verdict hold the arm at rest, where a put-back starts); None for
    any other motion."""
    from slax_drake.planning.waypoints import DWELL, PULL_DWELL
    from slax_drake.systems.guard import WEIGH_EARLY

    action = motion.action
    if not getattr(action, "drag", False) or abs(float(action.dx)) < 1e-9:
        return None
    at = {str(label): float(t) for label, t in motion.waypoint_times}
    if not {"approach", "seal", "pull"} <= at.keys():
        return None
    return at["approach"], at["seal"] + DWELL, at["pull"], at["pull"] + PULL_DWELL - WEIGH_EARLY


def start_pull(guard, motion) -> PullRun | None:
    """The PullRun of ``motion`` (None unless it is a sideways drag: :func:`pull_window`); ``guard``: the station's
    :class:`~slax_drake.systems.guard.Guard` (its effort model)."""
    window = pull_window(motion)
    if window is None:
        return None
    t_base, t0, t1, t_decide = window
    q0, _ = motion.trajectory.value(t0)
    q1, _ = motion.trajectory.value(t1)
    length = float(np.linalg.norm(guard.model.cup_position(q1) - guard.model.cup_position(q0)))
    return PullRun(ContactMonitor(math.inf), t_base, t0, t1, t_decide, length)


def observe_pull(guard, run: PullRun, motion, t: float, q, v, efforts) -> PullRun:
    """``run`` after one joint-state sample at ``t`` (s from the motion's start, at or after ``run.t_base``): the
    first sample fits the baseline; samples in the pull count once the cup has pulled ``SLIDING_TRAVEL``, until
    ``END_MARGIN`` before its planned end."""
    a = planned_acceleration(motion.trajectory, t)
    residual = np.asarray(efforts, float) - guard.model.effort(q, v, a)
    pull_W = -guard.push_W
    push, weight, payload = guard.model.signatures(q, pull_W, v, a)
    if run.monitor.weight is None:  # the baseline: the free arm at rest at the approach
        return dataclasses.replace(run, monitor=run.monitor.update(residual, push, weight, payload))
    if t < run.t0 or t > run.t1:
        return run
    p = guard.model.cup_position(q)
    if run.p_start is None:
        return dataclasses.replace(run, p_start=tuple(float(x) for x in p))
    monitor = run.monitor.update(residual, push, weight, payload)
    travel = float((p - np.asarray(run.p_start)) @ pull_W)
    if SLIDING_TRAVEL <= travel <= run.length - END_MARGIN:
        return dataclasses.replace(run, monitor=monitor, forces=run.forces + (monitor.force,))
    return dataclasses.replace(run, monitor=monitor)


def pull_twist(friction: float, lever: float, safety_factor: float) -> float:
    """N m: the twist the slide across asks of the seal with the measured ``friction`` (N) at ``lever`` (m, the
    floor-plane distance from the contact to the object's centre), reckoned as the action model reckons it
    (``max_drag_twist``) with the measured force in place of mu m g."""
    return float(safety_factor) * float(friction) * float(lever)


def pull_record(run: PullRun, lever: float, rules, shape: str = "cylinder") -> dict:
    """The trial record (the action's ``weighed``, ``along`` "pull") of a drag weighed along its pull: the friction
    (N; None when the pull was too short to weigh), the samples, the lever (m), the twist and the limit (N m; for the
    believed ``shape``'s face: :func:`~slax_drake.shelf.rules.drag_twist_limit`) and whether it is put back (``why``
    "twists off the cup") with the mass (kg) that friction implies at the action model's ``drag_friction``."""
    from slax_drake.shelf.actions import GRAVITY
    from slax_drake.shelf.rules import drag_twist_limit
    from slax_drake.systems.guard import PutBack

    friction = run.friction
    limit = drag_twist_limit(rules, shape)
    out = {"along": ALONG_PULL, "friction_n": None if friction is None else round(friction, 3),
           "samples": len(run.forces), "pull_m": round(run.length, 4), "lever_m": round(float(lever), 4),
           "limit_nm": round(limit, 4), "put_back": False}
    if friction is None:
        return out
    twist = pull_twist(friction, lever, rules.drag_safety_factor)
    out["twist_nm"] = round(twist, 4)
    if twist > limit:
        out.update(put_back=True, why=PutBack.TWISTS_OFF.value,
                   mass_kg=round(friction / (rules.drag_friction * GRAVITY), 4))
    return out
