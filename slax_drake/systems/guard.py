"""A guarded push-in: stop a carried object on contact, sensed from the arm's joint efforts alone.

What a real arm has: its joint positions and velocities, the efforts its joint controllers apply
(the station's ``measured_efforts``; a Fetch's ``joint_states``) and its own dynamic model (the robot's URDF).
What it does not have: the poses of objects it cannot see, or contact results. The guard reads only the former.

:class:`EffortModel` (the robot alone, the station's controller plant): the effort the free arm needs at (q, v, a)
(inverse dynamics with gravity), and two joint-space signatures at the cup tip (``cup_tip_frame``): of a unit
force along the push direction u (J^T u) and of a unit upward force (J^T z), in world W.

:class:`ContactMonitor` (pure arithmetic, immutable): the residual r = measured effort - model effort holds what
the model does not know, the carried object's weight and any contact. At the first sample of the push-in (the arm
starts it at rest) the monitor fits the payload as a weight m g at the cup (least squares of r on J^T z) and keeps
what that leaves unexplained; at every later sample it removes the fitted weight at the present configuration and
that remainder, and the fitted payload's inertia (its mass times the cup's acceleration from the planned joint
accelerations: a carried object speeding up with the push-in resists like a contact; on the free push-ins of
``benchmarks/bench_guarded_placement.py`` a 0.6 kg box's peak went 0.7 -> 0.3 N and 1.1 -> 0.8 N with it), and
projects what is left on the push signature: the force resisting the push (N, positive when it
pushes back against u, the push-in's direction: S +y, or -y for a push-in that ends shallower than it starts). It
stops when that force exceeds ``threshold`` (N) plus ``expected`` (N; the friction a dragged object needs to
slide, which the floor adds once it moves).

A drag's push-in starts with the floor's friction still loaded the other way by the pull that brought the object
out (or across): as the object starts sliding in, the friction turns over, up to twice the sliding friction, which
the first sample's baseline cannot tell from a contact (in the Drake trials a 2.3 kg drag stopped 1-2 mm into its
push-in at 19.6 N against 14.6 + 5 N, five times in a row). So a drag's push-in (``expected`` > 0) is watched
against twice the friction bound until the cup has pushed in ``DRAG_REBASE_TRAVEL``; there, with the object
sliding, the baseline is fitted again and the stop force alone counts from then on (the friction is in the
baseline).

At the board's front edge: a lifted object carried out of the bay hangs lower than planned, and its back can meet
the support board's front edge as it comes back in. A stop before the object's believed back is ``EDGE_BAND`` past
the opening is the edge, not an object (:func:`edge_stop_cup_y`, :func:`at_board_edge`): the push-in is made again
higher (``MotionPlanner.edge_retry``), once. An unguarded lift (its placement in space the camera sees) is watched
only there (``GuardRun.edge_only``, :func:`past_edge_band`): a stop in that band retries it, and past it the push-in
runs unwatched, as planned.

Units: efforts in N (the torso) and N m (the rest), forces in N, positions m / rad, times s.
"""

from __future__ import annotations

import dataclasses
import enum

import numpy as np

GRAVITY = 9.81  # m/s^2
# N: the least stop force the guard uses. On the sim station's free push-ins the estimate peaked at 0.3-0.8 N
# (docs/research/guarded-placement.md); a stop force the cup's hold would put lower is raised to this.
MIN_STOP_FORCE = 1.5
# m: how far the cup pushes a dragged object in before the guard takes its baseline again (the object slides)
DRAG_REBASE_TRAVEL = 0.01
UP_W = np.array([0.0, 0.0, 1.0])
WEIGH_EARLY = 0.02  # s: a lifted object is weighed this long before the rest at its lift ends (two 10 ms samples)


class EffortModel:
    """The free arm's efforts and the cup's force signatures on the robot of ``scenario`` (a StationScenario), in
    ``PLANNED_JOINTS`` order, the head held at ``head_configuration``."""

    def __init__(self, scenario):
        from slax_drake.station import robot as robot_model
        from slax_drake.station.plant import controller_plant

        self.plant = controller_plant(scenario)
        self.context = self.plant.CreateDefaultContext()
        names = robot_model.PLANNED_JOINTS
        self._iq = np.array([self.plant.GetJointByName(n).position_start() for n in names])
        self._iv = np.array([self.plant.GetJointByName(n).velocity_start() for n in names])
        self._q = self.plant.GetPositions(self.context).copy()
        for name, value in scenario.head_configuration.items():
            self._q[self.plant.GetJointByName(name).position_start()] = value
        self._cup = self.plant.GetFrameByName(robot_model.CUP_TIP_FRAME)

    def _set(self, q, v=None):
        full = self._q.copy()
        full[self._iq] = q
        self.plant.SetPositions(self.context, full)
        vf = np.zeros(self.plant.num_velocities())
        if v is not None:
            vf[self._iv] = v
        self.plant.SetVelocities(self.context, vf)

    def effort(self, q, v, a) -> np.ndarray:
        """The efforts (9,) the free arm needs at positions q, velocities v and accelerations a (inverse dynamics
        with gravity and the other force elements)."""
        from pydrake.multibody.tree import MultibodyForces

        self._set(q, v)
        forces = MultibodyForces(self.plant)
        self.plant.CalcForceElementsContribution(self.context, forces)
        af = np.zeros(self.plant.num_velocities())
        af[self._iv] = a
        return self.plant.CalcInverseDynamics(self.context, af, forces)[self._iv]

    def signatures(self, q, push_W, v, a) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At q (one Jacobian): (J^T u, J^T z, J^T a_cup): the efforts (9,) that balance a 1 N force on the cup tip
        pushing back against the unit push direction ``push_W`` (world), a 1 N weight hanging at the cup tip, and
        that give a 1 kg payload at the cup tip the cup's acceleration a_cup = J a + J-dot v (world, m/s^2) when
        the arm moves at velocities v and accelerations a."""
        from pydrake.multibody.tree import JacobianWrtVariable

        self._set(q, v)
        world = self.plant.world_frame()
        J = self.plant.CalcJacobianTranslationalVelocity(self.context, JacobianWrtVariable.kV, self._cup,
                                                         np.zeros(3), world, world)[:, self._iv]
        bias = self.plant.CalcBiasTranslationalAcceleration(self.context, JacobianWrtVariable.kV, self._cup,
                                                            np.zeros(3), world, world)
        accel = J @ np.asarray(a, float) + np.asarray(bias).ravel()
        return J.T @ np.asarray(push_W, float), J.T @ UP_W, J.T @ accel

    def payload(self, q, residual) -> "Payload":
        """The load the cup carries at rest at q, from ``residual`` (9: the measured efforts less :meth:`effort` of
        the free arm at rest): the wrench w = (torque, force) the arm applies at the cup tip, world frame, fitted by
        least squares to residual = J^T w (J the cup tip's spatial Jacobian, 6 x 9: the arm's seven joints and the
        torso over-determine it); a hanging payload's weight is its upward force and the moment its centre hangs
        off the cup is its horizontal torque."""
        from pydrake.multibody.tree import JacobianWrtVariable

        self._set(q)
        world = self.plant.world_frame()
        J = self.plant.CalcJacobianSpatialVelocity(self.context, JacobianWrtVariable.kV, self._cup, np.zeros(3),
                                                   world, world)[:, self._iv]
        w, *_ = np.linalg.lstsq(J.T, np.asarray(residual, float), rcond=None)
        return Payload(weight_n=float(w[5]), moment_nm=float(np.hypot(w[0], w[1])))

    def cup_position(self, q) -> np.ndarray:
        """The cup tip's position (3,) in world at q (m)."""
        self._set(q)
        return self._cup.CalcPoseInWorld(self.context).translation().copy()


@dataclasses.dataclass(frozen=True)
class Payload:
    """What the cup holds, weighed at rest (:meth:`EffortModel.payload`): its weight (N) and the moment (N m) its
    weight hangs off the cup, the load that peels the seal's lip."""

    weight_n: float
    moment_nm: float

    def mass_at(self, lever: float) -> float:
        """The mass (kg) to reckon the weighed object with at the believed ``lever`` (m;
        :func:`slax_drake.shelf.actions.weighed_mass`)."""
        from slax_drake.shelf.actions import weighed_mass

        return weighed_mass(self.weight_n, self.moment_nm, lever)


# N: a lifted suction whose cup weighs less than this holds nothing (its seal let go at the lift); the lightest
# household goods of the mass model weigh more than 0.5 N
MIN_HELD_WEIGHT = 0.3
# A weighed object hangs free when its weight's lever (moment / weight) is at least this share of the least lever
# the camera allows it (its centre no nearer the cup than the observed part of it puts it); a shorter lever means
# the floor carries part of it, its seal peeling (a cylinder of 0.69 N m held 0.37 N m at 0.71 of its radius in the
# Drake trial 6:13 and fell off the cup during the carry; freely hanging objects read 0.99-1.56 of their lever)
FREE_HANG_SHARE = 0.8


class PutBack(str, enum.Enum):
    """Why a weighed lift (:func:`weigh_verdict`) or drag (:func:`slax_drake.systems.drag_weigh.pull_record`) is put
    back; the value is the trial record's ``why``."""

    NOTHING_HELD = "nothing held"  # under MIN_HELD_WEIGHT: the seal let go
    TOO_HEAVY = "too heavy"  # its moment over the limit the lift was planned under
    NOT_HANGING_FREE = "not hanging free"  # its lever under FREE_HANG_SHARE of the least lever: the floor carries part
    TWISTS_OFF = "twists off the cup"  # a drag weighed along its pull: the slide across would twist it off the cup
    # (slax_drake.systems.drag_weigh)


def weigh_verdict(payload: Payload, limit: float, least_lever: float) -> PutBack | None:
    """Why a lifted object weighed ``payload`` must be put back rather than carried (:class:`PutBack`), or None:
    nothing held (under ``MIN_HELD_WEIGHT``), too heavy (its moment over ``limit``, N m: what the lift was planned
    under), not hanging free (its lever under ``FREE_HANG_SHARE`` of ``least_lever``, m; 0: not judged)."""
    if payload.weight_n < MIN_HELD_WEIGHT:
        return PutBack.NOTHING_HELD
    if payload.moment_nm > limit:
        return PutBack.TOO_HEAVY
    if least_lever > 0.0 and payload.moment_nm / payload.weight_n < FREE_HANG_SHARE * least_lever:
        return PutBack.NOT_HANGING_FREE
    return None


def least_lever(hypothesis, contact_xy) -> float:
    """m: the shortest horizontal distance from the cup's contact (S) to the centre of the object a hypothesis may
    be, as far as the camera tells: a cylinder's fitted centre; a box's centre with its depth cut to the part the
    camera measured (:class:`~slax_drake.perception.estimator.Uncertainty` ``depth``), its front face kept; 0 when
    unknown."""
    from slax_drake.shelf.actions import contact_lever

    obj = getattr(hypothesis, "object", hypothesis)
    lever = contact_lever(obj, contact_xy)
    uncertainty = getattr(hypothesis, "uncertainty", None)
    if obj.shape == "cylinder":
        return lever
    extent = abs(obj.size[1] * np.cos(obj.yaw)) + abs(obj.size[0] * np.sin(obj.yaw))  # along S y, the view's axis
    if uncertainty is None or extent <= 0.0:
        return 0.0
    return lever * min(1.0, max(0.0, float(uncertainty.depth[0])) / float(extent))


def dragged_after_weighing(action: dict) -> bool:
    """Whether a trial record's action is a lift weighed, put back and then dragged to the same placement in the
    same action (the ``drag_after_weighing`` rule; its ``weighed.drag_after_weighing.started_at``)."""
    weighed = action.get("weighed") if isinstance(action.get("weighed"), dict) else {}
    return bool(weighed.get("put_back")) and "started_at" in (weighed.get("drag_after_weighing") or {})


def weigh_time(motion) -> float | None:
    """s from the motion's start at which a lifted suction's object is weighed: at the end of the rest at the lift
    (``WEIGH_DWELL`` after the "weigh" waypoint, or the "lift" waypoint of a lift no higher than ``LIFT``, is
    reached, less one ``WEIGH_EARLY``: the arm and its load have settled, the carry has not begun); None for a drag,
    a push or a motion without a lift."""
    from slax_drake.planning.waypoints import WEIGH_DWELL

    if getattr(motion.action, "drag", True):
        return None
    at = dict(motion.waypoint_times)
    t_rest = at.get("weigh", at.get("lift"))
    return None if t_rest is None else t_rest + WEIGH_DWELL - WEIGH_EARLY


@dataclasses.dataclass(frozen=True)
class ContactMonitor:
    """The guard's state along one push-in (see the module docstring): ``threshold`` and ``expected`` in N."""

    threshold: float
    expected: float = 0.0
    weight: float | None = None  # N, the payload's weight fitted at the first sample (None before it)
    offset: tuple | None = None  # the residual the fit leaves unexplained at the first sample (9 efforts)
    force: float = 0.0  # N, the last estimate of the force resisting the push
    peak: float = 0.0  # N, its largest value so far

    @property
    def stopped(self) -> bool:
        return self.weight is not None and self.force > self.threshold + self.expected

    def update(self, residual, push_signature, weight_signature, payload_signature=None) -> "ContactMonitor":
        """The monitor after one sample: ``residual`` (measured minus model efforts), the signatures of a 1 N
        force resisting the push and of a 1 N weight at the cup, at the sample's configuration; and
        ``payload_signature`` (None: not known), the efforts that accelerate a 1 kg payload with the cup
        (the third of :meth:`EffortModel.signatures`): the fitted payload's inertia, m a along the push as the push-in
        speeds up, is not taken for a contact."""
        r = np.asarray(residual, float)
        s = np.asarray(push_signature, float)
        w = np.asarray(weight_signature, float)
        p = np.zeros_like(r) if payload_signature is None else np.asarray(payload_signature, float)
        if self.weight is None:
            ww = float(w @ w)
            weight = float(w @ r) / ww if ww > 0 else 0.0
            offset = r - weight * w - max(weight, 0.0) / GRAVITY * p
            return dataclasses.replace(self, weight=weight, offset=tuple(offset), force=0.0, peak=0.0)
        left = r - self.weight * w - max(self.weight, 0.0) / GRAVITY * p - np.asarray(self.offset)
        ss = float(s @ s)
        force = float(s @ left) / ss if ss > 0 else 0.0
        return dataclasses.replace(self, force=force, peak=max(self.peak, force))


@dataclasses.dataclass(frozen=True)
class GuardRun:
    """A guarded push-in being watched: the monitor, the motion's push-in window [t0, t1] (s from the motion's
    start), the cup's planned y (S, m) at the push-in's start and end, and the record once it ended."""

    monitor: ContactMonitor
    t0: float
    t1: float
    y_start: float
    y_end: float
    rebase_at: float = 0.0  # m of cup travel along the push before the baseline is taken again (a drag); 0: none
    p_start: tuple | None = None  # the cup's position (world, m) at the first sample, while a rebase is due
    friction: float = 0.0  # N, a drag's friction bound, the stop's margin until the rebase
    edge_cup_y: float | None = None  # S y (m) of the cup up to which a stop is the board's front edge (edge_stop_cup_y)
    edge_stop: dict | None = None  # the record of the stop at the board's edge this run retries (None: the first)
    edge_only: bool = False  # an unguarded lift's push-in, watched only while a stop would be the board's edge

    @property
    def direction(self) -> float:
        """+1 when the push-in runs into the shelf (S +y), -1 when it runs out (a placement shallower than the
        carry's depth)."""
        return 1.0 if self.y_end >= self.y_start else -1.0


def push_in_window(motion) -> tuple[float, float] | None:
    """(start, end) in s from the motion's start of a guarded suction's push-in (the segment arriving at "push in"),
    or None when the motion's action is not a guarded suction."""
    if not getattr(motion.action, "guarded", False):
        return None
    return push_in_of(motion.waypoint_times)


def push_in_of(waypoint_times) -> tuple[float, float] | None:
    """(start, end) in s of the segment arriving at "push in" in ``waypoint_times`` ([(label, time s)], as a
    PlannedMotion or a trial's action record holds them); None when there is none."""
    labels = [str(label) for label, _ in waypoint_times]
    if "push in" not in labels or labels.index("push in") == 0:
        return None
    k = labels.index("push in")
    return float(waypoint_times[k - 1][1]), float(waypoint_times[k][1])


def lift_stop_force(threshold: float, lip_moment: float, held_moment: float, lever: float) -> float:
    """The stop force (N) for a lifted object hanging ``held_moment`` (N m) off the cup: a force resisting the push
    at the object's bottom, ``lever`` (m) below the cup, adds its moment to the weight's, and the seal peels when
    they exceed the cup's ``lip_moment`` (N m); so ``threshold`` (N, the station's), or less, what the lip has left
    over the lever, but not under ``MIN_STOP_FORCE`` (the effort estimate's noise)."""
    if lever <= 0.0:
        return float(threshold)
    return min(float(threshold), max(MIN_STOP_FORCE, (lip_moment - held_moment) / lever))


def push_in_forces(action, obj, action_model, threshold: float, lip_moment: float) -> tuple[float, float]:
    """(stop force, expected resistance), N, of a guarded suction's push-in on ``obj`` (the believed object; None
    when unknown): a drag meets its floor friction as the action model bounds it (its pull) and stops at
    ``threshold`` over that; a lift meets nothing and stops at :func:`lift_stop_force` of the moment the object's
    weight (the action model's mass) hangs off the cup, with the cup's height above the floor as the lever."""
    if obj is None:
        return float(threshold), 0.0
    if action.drag:
        return float(threshold), float(action_model.drag_limits(obj, action.q[2]).pull)
    return lift_stop_force(threshold, lip_moment, held_moment(action_model, obj, action), float(action.q[2])), 0.0


def held_moment(model, obj, action) -> float:
    """N m: the moment ``obj``'s weight (the action model ``model``'s mass) hangs off the cup at ``action``'s
    contact (its horizontal distance from the object's centre)."""
    return model.held_moment(obj, action.q[:2])


def planned_acceleration(trajectory, t: float) -> np.ndarray:
    """The planned joint accelerations at ``t`` (s from the trajectory's start; the nearest sample)."""
    k = int(np.clip(np.searchsorted(trajectory.times, t), 0, len(trajectory.times) - 1))
    return trajectory.a[k]


class Guard:
    """What a guarded push-in needs at run time: the effort model of the station's robot, the push direction
    (S +y, in world) and the stop threshold ``threshold`` (N; the station's ``guarded_stop_force``). ``period``:
    seconds between the checks (the joint-state rate)."""

    def __init__(self, scenario, R_WS, threshold: float, period: float = 0.01):
        self.model = EffortModel(scenario)
        self.push_W = np.asarray(R_WS, float)[:, 1].copy()
        self.threshold = float(threshold)
        self.period = float(period)
        self.lip_moment = float(scenario.suction.lip_moment)

    def stop_force(self, held_moment: float, lever: float) -> float:
        """The stop force (N) for a lifted object hanging ``held_moment`` (N m) off the cup (:func:`lift_stop_force`
        with the station's threshold and lip moment)."""
        return lift_stop_force(self.threshold, self.lip_moment, held_moment, lever)

    def weigh(self, t: float, motion, q, v, efforts) -> Payload:
        """The payload the cup holds at ``t`` (s from the motion's start; the arm at rest at the lift), from one
        joint-state sample: the measured efforts less the free arm's at (q, v, the planned accelerations)."""
        a = planned_acceleration(motion.trajectory, t)
        return self.model.payload(q, np.asarray(efforts, float) - self.model.effort(q, v, a))

    def start(self, motion, cup_y_S, expected: float = 0.0, threshold: float | None = None,
              edge_only: bool = False) -> GuardRun | None:
        """A GuardRun for ``motion`` when it is a guarded suction, else None; with ``edge_only``, for an unguarded
        lifted suction's push-in instead (watched only while a stop would be the board's edge: :func:`past_edge_band`;
        the caller sets its ``edge_cup_y``). ``cup_y_S(q)``: the cup's y (S, m) at planned joint positions q;
        ``expected``: N of resistance the free push-in meets (a drag's friction); ``threshold``: the stop force (N;
        default the station's)."""
        action = motion.action
        if edge_only:
            lifted = not getattr(action, "drag", True) and not getattr(action, "guarded", True)
            window = push_in_of(motion.waypoint_times) if lifted else None
        else:
            window = push_in_window(motion)
        if window is None:
            return None
        traj = motion.trajectory
        q0, _ = traj.value(window[0])
        q1, _ = traj.value(window[1])
        stop = self.threshold if threshold is None else threshold
        drag = expected > 0.0  # the friction turns over at the start: twice the bound until the rebase
        return GuardRun(ContactMonitor(stop, 2.0 * expected if drag else expected), window[0], window[1],
                        float(cup_y_S(q0)), float(cup_y_S(q1)), rebase_at=DRAG_REBASE_TRAVEL if drag else 0.0,
                        friction=float(expected), edge_only=edge_only)

    def stopped(self, run: GuardRun, motion, q, planner, believed, cup_y_S, now: float):
        """(the motion to play from ``now`` (s, simulated), the GuardRun watching it or None, the record) once
        ``run`` stopped ``motion`` with the arm at the measured joint positions ``q``: at the board's front edge
        (:func:`at_board_edge`) the push-in again higher (``planner.edge_retry``), watched with the same forces;
        otherwise, or when that has no IK solution, ``planner.guarded_stop`` (hold, lower, release, back off, the
        way back). An edge-only watch (``run.edge_only``) retries unwatched, and without a retry gives (None, None,
        None): the motion goes on as planned. ``believed``: the Scene the motion was planned in; ``cup_y_S(q)``: the
        cup's y (S, m)."""
        y = cup_y_S(q)
        record = guard_record(run, stopped=True, cup_y=y)
        retry = planner.edge_retry(motion, q, believed) if at_board_edge(run, y) else None
        if run.edge_only and retry is None:  # an unguarded lift goes on as planned, unwatched
            return None, None, None
        after = retry if retry is not None else planner.guarded_stop(motion, q, believed)
        record["stop_time"] = round(now, 4)
        record["stop_motion"] = {"duration_s": round(after.trajectory.duration, 3),
                                 "waypoint_times": after.waypoint_times, "suction_intervals": after.suction_intervals}
        if retry is None:
            return after, None, record
        record["edge"] = True
        if run.edge_only:  # the push-in again is not watched, as the first was not past the edge band
            return after, None, {"guarded": False, "edge_only": True, "stopped": False, "edge_stop": record}
        again = self.start(retry, cup_y_S, run.friction, run.monitor.threshold)
        return after, (None if again is None else dataclasses.replace(again, edge_stop=record)), record

    def observe(self, run: GuardRun, motion, t: float, q, v, efforts) -> GuardRun:
        """``run`` after one joint-state sample at ``t`` (s from the motion's start) inside its window; a drag's
        baseline is fitted again once the cup has pushed in ``run.rebase_at`` (module docstring)."""
        a = planned_acceleration(motion.trajectory, t)
        residual = np.asarray(efforts, float) - self.model.effort(q, v, a)
        push_W = run.direction * self.push_W
        push, weight, payload = self.model.signatures(q, push_W, v, a)
        if run.rebase_at > 0.0:
            p = self.model.cup_position(q)
            if run.p_start is None:
                run = dataclasses.replace(run, p_start=tuple(float(x) for x in p))
            elif float((p - np.asarray(run.p_start)) @ push_W) >= run.rebase_at:  # sliding: a new baseline
                monitor = dataclasses.replace(run.monitor, expected=0.0, weight=None, offset=None)
                return dataclasses.replace(run, rebase_at=0.0, p_start=None,
                                           monitor=monitor.update(residual, push, weight, payload))
        return dataclasses.replace(run, monitor=run.monitor.update(residual, push, weight, payload))


# m: a lifted object's guarded push-in that stops before the object's leading face (as believed) is this far past the
# opening met the support board's front edge, not an object: the camera sees the board's front strip, and the carry
# was checked against what it sees there (slax_drake.scene_world's FRONT_EDGE_LENGTH is as deep)
EDGE_BAND = 0.02


def edge_stop_cup_y(action, obj, shelf, y_start: float) -> float | None:
    """The cup's y (S, m) up to which a contact on the guarded push-in of the lifted suction ``action`` of ``obj``
    (the believed object) is the support board's front edge: until the object's leading face (its side along S +y,
    as believed) is ``EDGE_BAND`` past the opening (y = -depth / 2 of ``shelf``). None for a drag (it slides on the
    board), an unknown object, or a push-in that starts (the cup at ``y_start``) with that face inside the opening (a
    carry across inside the shelf)."""
    from slax_drake.scene.footprint import Footprint
    from slax_drake.shelf.actions import SEAL_PRESS

    if obj is None or getattr(action, "drag", True):
        return None
    _, ey = Footprint.of(obj).extents()
    lead = float(obj.center[1]) + ey - (float(action.q[1]) + SEAL_PRESS * float(action.axis[1]))
    y_open = -shelf.depth / 2.0
    if y_start + lead >= y_open:
        return None
    return y_open + EDGE_BAND - lead


def at_board_edge(run: GuardRun, cup_y: float) -> bool:
    """Whether ``run``, stopped with the cup at ``cup_y`` (S, m), stopped at the board's front edge, to be retried
    higher (:meth:`slax_drake.planning.planner.MotionPlanner.edge_retry`): once, on a push-in into the shelf."""
    return (run.edge_stop is None and run.edge_cup_y is not None and run.direction > 0
            and cup_y <= run.edge_cup_y)


def past_edge_band(run: GuardRun, cup_y: float) -> bool:
    """Whether an edge-only watch (``run.edge_only``: an unguarded lift's push-in) is over, the cup at ``cup_y`` (S,
    m) past the cup y up to which a stop would be the board's front edge: from there the push-in runs unwatched, as
    a placement the camera sees."""
    return run.edge_only and (run.edge_cup_y is None or cup_y > run.edge_cup_y)


def guard_record(run: GuardRun, stopped: bool, cup_y: float | None = None) -> dict:
    """The trial record of a guarded push-in: whether it stopped on contact, how far the cup had pushed in then
    and how far short of the planned placement (m, along the push-in), the largest resisting force seen and the
    threshold (N; a drag's: ``friction_n``, its friction bound, and ``rebased``, whether the baseline was taken again
    once it slid, after which the peak counts); for the push-in retried higher after a stop at the board's front
    edge, ``edge_stop``: that stop's record (with its ``stop_time`` and the retry's ``stop_motion``)."""
    out = {"guarded": True, "stopped": bool(stopped), "threshold_n": round(run.monitor.threshold + run.monitor.expected, 3),
           "peak_force_n": round(run.monitor.peak, 3)}
    if run.friction > 0.0:
        out["friction_n"] = round(run.friction, 3)
        out["rebased"] = run.rebase_at == 0.0
    if stopped and cup_y is not None:
        out["pushed_in_m"] = round(abs(cup_y - run.y_start), 4)
        out["short_m"] = round(run.direction * (run.y_end - cup_y), 4)
    if run.edge_stop is not None:
        out["edge_stop"] = run.edge_stop
    return out
