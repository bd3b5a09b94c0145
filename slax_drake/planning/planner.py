"""Turn a policy's action into a checked, timed joint trajectory of the planned joints, or reject it.

:meth:`MotionPlanner.plan` (action, scene as it stands, start configuration):

1. tool waypoints of the action (:func:`slax_drake.planning.waypoints.action_waypoints`);
2. IK per waypoint (:func:`slax_drake.planning.ik.solve_tool_pose`, ``LIMIT_MARGIN`` inside the position
   limits; while the cup holds the object, ``HOLD_*_TOLERANCE``), warm-started from the previous one; the
   first from the start configuration and a fixed seed library (the first solution joined to the start by a
   collision-free straight line is taken, else up to ``MAX_FIRST_SOLUTIONS``). A solution that collides is
   solved again with a minimum-distance constraint, unless the tool itself (the bodies rigid with the tool
   frame) meets the environment, which no other solution of that pose avoids: then the action is rejected at
   once. A waypoint the warm start cannot reach is solved from the seed library and the waypoints before it
   are solved again backward from there (at most ``MAX_REANCHORS`` times); where IK from the warm start finds no
   solution, the pose halfway along the segment is solved first and the waypoint from there (continuation);
3. each straight tool segment is refined: where the joint-space straight line between two solutions moves the
   tool more than ``deviation_tolerance`` (``CARRIED_DEVIATION_TOLERANCE`` while carrying an object) from the
   Cartesian segment, the midpoint is solved (warm-started from the joint-space midpoint, else from either end)
   and inserted;
4. the free segments from the start to the first waypoint and from the last one back to the observation pose
   are straight when that is collision-free; the way back then tries the way it came (last waypoint, first
   waypoint, the way from the start reversed); else :func:`slax_drake.planning.free_path.free_path`
   (RRT-Connect around the robot itself); the way back is searched and checked with the moved object where the
   action leaves it (:func:`placed_pose`, :meth:`~slax_drake.planning.world.PlanningWorld.place`); every joint
   segment is checked
   densely with SceneGraphCollisionChecker against the world as it stands and against the robot itself
   (:mod:`slax_drake.planning.world`: padding 2 mm to the environment, 3 mm between non-adjacent links; the
   tool may touch the manipulated object only on the action's contact segments; a suctioned object is
   attached to the tool on the segments that carry it and checked with 1 mm margin, see
   :meth:`slax_drake.planning.world.PlanningWorld.carry`);
5. Ruckig times the chain rest to rest (:mod:`slax_drake.planning.timing`), with dwells at rest where the
   waypoints ask for them; the suction command is on during the segments that carry the object.

A guarded lift (``Suction.guarded``) whose push-in would carry the object higher than ``LIFT`` is rejected
(:attr:`~slax_drake.planning.failures.FailureKind.GUARDED_LIFTED`; a shallower carry may avoid it): it would pass
over a lower object hidden in its way and lower onto it, where the guard, which senses the push, is blind.

When the waypoints in front of the opening fail (out of reach, no free way) or a straight segment cannot be kept
(:attr:`~slax_drake.planning.failures.PlanningFailure.straight_segment`), the action is planned again with the tool's tip 1 cm in front of the opening
(``APPROACH_MARGINS``); when a carried segment fails, a suctioned object is carried across at shallower depths
inside the shelf and then, pulled all the way out, with the tool turned ``CARRY_YAWS`` each way about the cup's
vertical axis (:func:`slax_drake.planning.waypoints.carry_options`: straight ahead of the shoulder the arm cannot
hold the tube along S y that close to the robot; turned it can). IK solves and free paths are memoised per planning
world (one decision's candidates share their approach waypoints); the IK solves without a distance constraint, which
read the robot's kinematics alone, are also kept across worlds (``keep_kinematic_ik``: the next decision's
candidates on objects that did not move ask for the same tool poses from the same seeds). Any failure returns a :class:`Rejection`: the
typed failure of the last variant tried (:class:`slax_drake.planning.failures.PlanningFailure`: its kind, the
waypoint, the colliding body or what the carried object meets) and the reason in words, made from the failures:
the last variant's leads, the others follow in brackets. Timings of each stage are kept (seconds of wall clock) for the
benchmark.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from slax_drake.planning.failures import RETURN, FailureKind, PlanningFailure, distinct, joined_message, lead_last
from slax_drake.planning.free_path import free_path
from slax_drake.planning.ik import CONTINUOUS_JOINTS, LIMIT_MARGIN, solve_tool_pose
from slax_drake.planning.timing import SAMPLE_PERIOD, time_segment
from slax_drake.planning.trajectory import JointTrajectory
from slax_drake.planning.waypoints import DWELL, LIFT, APPROACH_MARGINS, ToolWaypoint, action_waypoints, carry_options
from slax_drake.planning.world import TOOL_RIGID_BODIES, PlanningWorld, pairs_text
from slax_drake.shelf.actions import ActionModel, Push, Suction, apply_action
from slax_drake.shelf.rules import ToolConfig
from slax_drake.scene.model import Scene, state_key
from slax_drake.station import robot as robot_model
from slax_drake.station.plant import station_joint_limits
from slax_drake.station.scenario import StationScenario, observation_positions

DEVIATION_TOLERANCE = 0.004  # m; the requirement is < 5 mm, 1 mm is left for the 1 ms sampling and IK tolerance
CARRIED_DEVIATION_TOLERANCE = 0.001  # m, on segments carrying an object, which may slide along a wall it touches
MAX_REFINE_DEPTH = 6
NUM_RANDOM_SEEDS = 12
SEED_LIBRARY_SEED = 0
MAX_FIRST_SOLUTIONS = 3
MIN_DISTANCE = 0.004  # m, IK's robot-environment and self distance when the unconstrained solution collides
MAX_DISTANCE_RETRIES = 2  # colliding IK solutions re-solved with the distance constraint, per waypoint
CARRIED_PROBES = 21  # poses along a colliding carried segment examined to name what the object meets
# Rejections that a smaller approach margin may avoid: at the waypoints in front of the opening (or the joint
# segments arriving at them), and no free way back
MARGIN_DEPENDENT = frozenset({"pre-approach", "retract"})
MARGIN_DEPENDENT_KINDS = frozenset({FailureKind.NO_WAY_BACK})
# Rejections that carrying a suctioned object across at another depth (hence, perhaps, lifted less) may avoid: at
# the carrying waypoints or the joint segments arriving at them
PULL_DEPENDENT = frozenset({"lift", "pull out", "translate", "push in", "lower"})
# ... and a pose after the placement with no IK solution: IK solves it from the configuration the carry left the arm
# in (one branch of the arm's solutions), so after another carry it may have one (Table I household scene 4:7: a
# carry 0.30 m across whose retract had none after the straight carries, planned carried across turned 30 deg)
PULL_DEPENDENT_AFTER = frozenset({"release", "back off", "retract"})
# Rejections of a straight tool segment (the joint-space line between two IK solutions leaves it and the midpoints
# cannot bring it back: the solutions lie on different branches; PlanningFailure.straight_segment) depend on the
# solutions the chain took, which another carrying depth or approach margin changes: they let the next variant be
# tried, as the ones above do.
MAX_REANCHORS = 2  # waypoints re-solved from the seed library (and the path before them backward) per plan
FREE_PATH_SEED = 0
KINEMATIC_IK_CACHE_SIZE = 50_000  # kinematic IK solutions kept across planning worlds (cleared when full)
# IK tolerances while the cup holds the object (seal to release): the object turns and shifts with the tool, and
# IK's default tolerances (0.5 mm, 0.01 rad) would let it wander ~2 mm between waypoints.
HOLD_POSITION_TOLERANCE = 1e-4  # m
HOLD_ANGLE_TOLERANCE = 1e-3  # rad
GUARD_HOLD = 0.2  # s, a guarded push-in stopped on contact holds the pose reached this long before it lowers
# m: a lifted object whose guarded push-in stopped at the board's front edge is raised this much and pushed in again
# (edge_retry). In the Drake trials a 0.58 kg cylinder carried 1 cm up hung 0.6-1.0 mm above the board's level
# (the cup's give and the arm's droop) and met the edge (docs/research/table-ii.md).
EDGE_RETRY_RISE = 0.01
# Indices in PLANNED_JOINTS of the continuous joints (upperarm, forearm and wrist roll): a whole turn of one leaves the
# arm's pose unchanged, and IK may return any of those equivalent values
_TURNING = np.array([robot_model.PLANNED_JOINTS.index(n) for n in CONTINUOUS_JOINTS])


def nearest_turn(q, q_ref) -> np.ndarray:
    """``q`` (planned joints, rad) with each continuous joint moved by whole turns to the value nearest to
    ``q_ref``'s: the same pose of every link. An IK solution seeded far from the start (the seed library spans
    half a turn either way, and each solve may turn a roll joint half a turn from its warm start) may otherwise put a
    roll joint turns away from where the arm stands, and the free path to it must sweep those turns."""
    q = np.array(q, float)
    ref = np.asarray(q_ref, float)
    q[_TURNING] -= 2.0 * np.pi * np.round((q[_TURNING] - ref[_TURNING]) / (2.0 * np.pi))
    return q


@dataclasses.dataclass
class Rejection:
    """An action whose motion is infeasible, and why: ``failure``, the leading failure of the last variant tried
    (decisions rest on it), and ``reason``, every variant's failures in words (for logs and trial files)."""

    action: object
    reason: str
    timings: dict
    failure: PlanningFailure | None = None

    feasible = False


@dataclasses.dataclass
class PlannedMotion:
    """A checked, timed motion of an action: the trajectory (from t = 0), the suction command's on-intervals
    [(t_on, t_off)] in seconds, the times at which each tool waypoint is reached, the largest tool deviation
    from the Cartesian segments found by the refinement (m), and stage timings (s)."""

    action: object
    trajectory: JointTrajectory
    suction_intervals: list
    waypoint_times: list
    max_deviation: float
    timings: dict
    segments: list  # (q_a, q_b, contact, carried) of every checked joint segment, for tests and re-checks
    waypoints: list = dataclasses.field(default_factory=list)  # the ToolWaypoints planned (after any fallback)

    feasible = True

    def suction_at(self, t: float) -> bool:
        return any(t0 <= t < t1 for t0, t1 in self.suction_intervals)


class _Reject(Exception):
    """A planning variant failed: ``failures`` (one per first IK solution tried, distinct messages)."""

    def __init__(self, *failures: PlanningFailure):
        self.failures = failures
        super().__init__(joined_message(failures))


class _PoseReject(_Reject):
    """A waypoint's tool pose itself is infeasible (the tool meets the environment there): no other IK solution,
    first solution or re-anchoring can help."""


class MotionPlanner:
    """Plans actions for one station (robot, shelf placement, observation pose)."""

    def __init__(self, scenario: StationScenario, tool: ToolConfig = ToolConfig(),
                 deviation_tolerance: float = DEVIATION_TOLERANCE, keep_kinematic_ik: bool = True):
        import pydrake.planning  # noqa: F401  (loaded once here, ~0.7 s, not in the first decision's planning)

        self.scenario = scenario
        self.tool = tool
        self.deviation_tolerance = deviation_tolerance
        self.q_observation = observation_positions(scenario)
        self.limits = station_joint_limits(scenario)
        self._world_key = None
        self._world = None
        # Results of IK solves and free paths in the current world (both deterministic), keyed by their inputs:
        # the candidates of one decision share waypoints (every suction of an object has the same approach).
        self._memo = {}
        # IK solves without a distance constraint (the robot's kinematics alone: the same answer in every world of
        # this station), kept across worlds when ``keep_kinematic_ik``
        self.keep_kinematic_ik = keep_kinematic_ik
        self._kinematic_ik = {}
        self._tight = False  # the near-miss variant: every waypoint and midpoint solved with the hold tolerances
        self._hidden_model = None  # ((shelf, eye), ActionModel) that reckons hidden space (hidden_space)

    def hidden_space(self, scene: Scene, name: str):
        """(floor grid, bool (ny, nx) cells) of the space the objects of ``scene`` other than ``name`` hide from
        its camera, as the action model reckons it (:meth:`ActionModel.hidden_by_others`), or None when the
        ``carry_hidden_check`` rule is off: a suctioned object is not carried across it. Kept with the planning
        world of ``scene`` (:meth:`world`, called first): every candidate of one object in one decision shares it."""
        if not self.tool.rules.carry_hidden_check:
            return None
        eye = tuple(float(v) for v in scene.camera.position)
        hit = self._memo.get(("hidden space", name, eye))
        if hit is None:
            key = (scene.shelf, eye)
            if self._hidden_model is None or self._hidden_model[0] != key:
                self._hidden_model = (key, ActionModel(scene.shelf, eye, self.tool))
            model = self._hidden_model[1]
            hit = self._memo[("hidden space", name, eye)] = (model.grid, model.hidden_by_others(scene.objects, name))
        return hit

    def world(self, scene: Scene) -> PlanningWorld:
        """The planning world of the scene's objects as they stand (built once per object state)."""
        key = (state_key(scene.objects), scene.shelf)
        if key != self._world_key:
            self._world = PlanningWorld(self.scenario, scene)
            self._world_key = key
            self._memo = {}
        return self._world

    def plan(self, action, scene: Scene, q_start=None):
        """A :class:`PlannedMotion` from q_start (default: the observation pose) through the action and back
        to the observation pose, or a :class:`Rejection`."""
        timings = {"world_s": 0.0, "ik_s": 0.0, "check_s": 0.0, "timing_s": 0.0, "ik_solves": 0}
        t_all = time.perf_counter()
        t0 = time.perf_counter()
        world = self.world(scene)
        timings["world_s"] = time.perf_counter() - t0
        q_start = self.q_observation.copy() if q_start is None else np.asarray(q_start, float)
        reasons = []
        motion = None
        hidden = self.hidden_space(scene, action.name) if isinstance(action, Suction) else None
        for margin in APPROACH_MARGINS:
            pulls = [(None, 0.0)]
            if isinstance(action, Suction):
                obj = next(o for o in scene.objects if o.name == action.name)
                x_robot = world.X_WS.inverse().translation()[0]  # the robot's base (W origin) in S
                pulls = carry_options(action, obj, scene.shelf, scene.target, margin,
                                      wrist_side=action.q[0] - x_robot, hidden=hidden)
            for pull, carry_yaw in pulls:
                self._anchor_failed = set()
                try:
                    waypoints = action_waypoints(action, scene.objects, scene.shelf, self.tool, approach_margin=margin,
                                                 pull_to=pull, carry_yaw=carry_yaw,
                                                 push_compliance=self.scenario.push_compliance)
                    _reject_a_lifted_guarded_push_in(action, waypoints)
                    motion = self._plan(world, action, waypoints, q_start, timings)
                    break
                except _Reject as e:
                    world.allow_tool_contact(action.name, False)
                    where = f"approach margin {margin * 100:.0f} cm" + (f", carried across at y = {pull:+.3f}"
                                                                        if len(pulls) > 1 else "") + (
                        f" turned {np.degrees(carry_yaw):+.0f} deg" if carry_yaw else "")
                    reasons.append((where, e.failures))
                    if not _another_carry_may_differ(e.failures):
                        break
            if motion is not None or not _may_differ(reasons[-1][1], MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS):
                break
        if motion is None and isinstance(action, Push) and _near_miss(reasons[-1][1]):
            motion = self._plan_tight(world, action, scene, q_start, timings, reasons)
        if motion is None:
            timings["total_s"] = time.perf_counter() - t_all
            # The leading variant's failures come first (their first is the Rejection's failure, which the
            # PlannerSystem reads); the other variants follow in brackets (failures.lead_last).
            ordered = lead_last(reasons)
            said = [(w, joined_message(f)) for w, f in ordered]
            reason = said[-1][1] if len(said) == 1 else (
                f"{said[-1][1]} [{said[-1][0]}; before: " + " | ".join(f"{w}: {r}" for w, r in said[:-1]) + "]")
            return Rejection(action, reason, _rounded(timings), ordered[-1][1][0])
        timings["total_s"] = time.perf_counter() - t_all
        motion.timings = _rounded(timings)
        return motion

    def _plan_tight(self, world, action, scene, q_start, timings, reasons):
        """The near-miss variant of a push whose tool met an object on a straight segment: every
        waypoint and midpoint solved with the hold tolerances and the straight segments kept within
        ``CARRIED_DEVIATION_TOLERANCE`` (1 mm) of their lines, at the nominal approach margin. IK's default
        tolerances let the tube's far end stray up to 3 mm and the segments 4 mm, so a tube whose lane passes 2-5 mm
        from a taller neighbour met it in one solution and clears it in this one. The motion, or None with the
        variant's failures put first in ``reasons`` (so that the report's leading variant stays the one it was)."""
        self._tight, self._anchor_failed = True, set()
        try:
            waypoints = action_waypoints(action, scene.objects, scene.shelf, self.tool,
                                         approach_margin=APPROACH_MARGINS[0],
                                         push_compliance=self.scenario.push_compliance)
            return self._plan(world, action, waypoints, q_start, timings)
        except _Reject as e:
            world.allow_tool_contact(action.name, False)
            reasons.insert(0, ("tool solved within the hold tolerances", e.failures))
            return None
        finally:
            self._tight = False

    def reaches(self, scene: Scene, waypoint: ToolWaypoint) -> bool:
        """Whether the planner finds a collision-free IK solution for ``waypoint`` in ``scene`` from the
        observation pose (its first-waypoint search: every seed of its library)."""
        timings = {"ik_s": 0.0, "check_s": 0.0, "ik_solves": 0}
        try:
            self._first_waypoints(self.world(scene), waypoint, self.q_observation, "", timings)
        except _Reject:
            return False
        return True

    @staticmethod
    def put_back(motion: PlannedMotion, t_from: float) -> PlannedMotion:
        """A lifted suction undone from ``t_from`` (s from the motion's start, the cup holding its object lifted,
        at rest): the motion played backward to its start (its own checked path), the object lowered to where it
        was sealed, released there (suction off on arriving at the seal, which the forward motion dwells at), and
        the cup backed off, retracted and returned the way it came. A new motion from t = 0."""
        traj = motion.trajectory
        k = int(np.clip(np.searchsorted(traj.times, t_from - 1e-9), 0, len(traj.times) - 1))
        t_end = float(traj.times[k])
        back = JointTrajectory(traj.names, t_end - traj.times[k::-1], traj.q[k::-1].copy(), -traj.v[k::-1],
                               traj.a[k::-1].copy())
        at = dict(motion.waypoint_times)
        t_release = t_end - (at["seal"] + DWELL)
        labels = [("lower", t_release), ("release", t_release), ("back off", t_end - at["approach"]),
                  ("retract", t_end - at["pre-approach"]), ("return", t_end)]
        return PlannedMotion(motion.action, back, [(0.0, round(t_release, 6))],
                             [(label, round(float(t), 6)) for label, t in labels], motion.max_deviation,
                             {"total_s": 0.0}, [], list(motion.waypoints))

    def guarded_stop(self, motion: PlannedMotion, q_stop, scene: Scene, hold: float = GUARD_HOLD) -> PlannedMotion:
        """The rest of a guarded suction stopped on contact during its push-in at the measured joint positions
        ``q_stop`` (9,), as a new motion from there (t = 0): hold still ``hold`` s with the cup on, lower the
        object as the plan lowers it (a lift's "lower"; a drag's object is on the floor already), release and
        dwell, back off along the cup's axis as planned, move to the planned "retract" configuration and return
        by the plan's own way back to the observation pose. The tool keeps the plan's orientation; the new poses
        are the stop's tool position shifted as the plan shifts the completed placement's. ``scene``: the
        believed scene the motion was planned in. The segments are refined to straight tool segments where IK
        allows and timed rest to rest with Ruckig; they are not collision-checked (the tool backs out the way the
        object came in)."""
        from pydrake.math import RigidTransform

        timings = {"world_s": 0.0, "ik_s": 0.0, "check_s": 0.0, "timing_s": 0.0, "ik_solves": 0}
        t_all = time.perf_counter()
        world = self.world(scene)
        q_stop = np.asarray(q_stop, float)
        wps = {w.label: w for w in motion.waypoints}
        push, release, back = wps["push in"], wps["release"], wps["back off"]
        rest = wps.get("lower", release)
        traj = motion.trajectory
        t_retract = dict(motion.waypoint_times)["retract"]
        k_retract = int(np.argmin(np.abs(traj.times - t_retract)))
        q_retract = traj.q[k_retract]
        X_stop = world.tool_pose_S(q_stop, push.frame).GetAsMatrix4()

        def at(wp, shift):  # wp's orientation at the stop's position shifted by the plan's shift
            X = wp.X_SF.copy()
            X[:3, 3] = X_stop[:3, 3] + shift
            return dataclasses.replace(wp, X_SF=X)

        low = at(rest, rest.X_SF[:3, 3] - push.X_SF[:3, 3])
        off = at(back, low.X_SF[:3, 3] - X_stop[:3, 3] + back.X_SF[:3, 3] - release.X_SF[:3, 3])
        chain = [(q_stop, True, None)]  # (q, suction on while arriving, waypoint label)
        max_dev = 0.0
        prev_q, prev_X = q_stop, X_stop
        for wp, label, suction in ((low, "lower", True), (off, "back off", False)):
            q = self._ik(world, wp, prev_q, timings)
            if q is None:
                q = self._ik(world, dataclasses.replace(wp, suction=False), prev_q, timings)
            if q is None:  # out of reach: stay where it stopped (the back off and retract follow from here)
                continue
            inner, dev = self._refine_or_straight(world, prev_q, prev_X, q, wp.X_SF, wp, timings)
            max_dev = max(max_dev, dev)
            chain.extend((p, suction, None) for p in inner)
            chain.append((q, suction, label))
            prev_q, prev_X = q, wp.X_SF
        retract = wps["retract"]
        inner, dev = self._refine_or_straight(world, prev_q, prev_X, q_retract, retract.X_SF, retract, timings)
        max_dev = max(max_dev, dev)
        chain.extend((p, False, None) for p in inner)
        chain.append((q_retract, False, "retract"))
        t0 = time.perf_counter()
        out, waypoint_times, suction_off, t_join = self._timed_after_stop(q_stop, hold, chain, traj, k_retract)
        waypoint_times += [(label, round(t - t_retract + t_join, 6)) for label, t in motion.waypoint_times
                           if t > t_retract]
        timings["timing_s"] += time.perf_counter() - t0
        timings["total_s"] = time.perf_counter() - t_all
        return PlannedMotion(motion.action, out, [(0.0, round(float(suction_off), 6))], waypoint_times, float(max_dev),
                             _rounded(timings), [], list(motion.waypoints))

    def edge_retry(self, motion: PlannedMotion, q_stop, scene: Scene, rise: float = EDGE_RETRY_RISE,
                   hold: float = GUARD_HOLD) -> PlannedMotion | None:
        """The rest of a lifted suction whose guarded push-in stopped at the support board's front edge (the carried
        object hangs lower than planned: the cup's give and the arm's droop under its weight) at the measured joint
        positions ``q_stop`` (9,), as a new motion from there (t = 0): hold still ``hold`` s with the cup on, raise
        the object ``rise`` (m), push it in as planned but ``rise`` higher (a "push in" of its own, which the guard
        watches as it watched the first), lower it to the plan's "lower" pose and go on with the plan from there
        (release, back off, retract, the way back). Its waypoints are the plan's with the push-in raised, so that
        :meth:`guarded_stop` applies to it. None for a motion without a lowering (a drag) or when IK finds no pose
        for the raise or the raised push-in (the caller stops as at any contact). ``scene``: the believed scene the
        motion was planned in. Not collision-checked: the object passes where it was carried, ``rise`` higher."""
        timings = {"world_s": 0.0, "ik_s": 0.0, "check_s": 0.0, "timing_s": 0.0, "ik_solves": 0}
        t_all = time.perf_counter()
        wps = {w.label: w for w in motion.waypoints}
        at = dict(motion.waypoint_times)
        if "lower" not in wps or "lower" not in at or "push in" not in wps:
            return None
        world = self.world(scene)
        q_stop = np.asarray(q_stop, float)
        push, lower = wps["push in"], wps["lower"]
        X_stop = world.tool_pose_S(q_stop, push.frame).GetAsMatrix4()
        up, push_up = X_stop.copy(), push.X_SF.copy()
        up[2, 3] += rise
        push_up[2, 3] += rise
        raised = dataclasses.replace(push, X_SF=push_up)
        traj = motion.trajectory
        t_lower = float(at["lower"])
        k_lower = int(np.argmin(np.abs(traj.times - t_lower)))
        chain = [(q_stop, True, None)]  # (q, suction on while arriving, waypoint label)
        max_dev = 0.0
        prev_q, prev_X = q_stop, X_stop
        for wp, label in ((dataclasses.replace(push, label="raise", X_SF=up), "raise"), (raised, "push in"),
                          (lower, "lower")):
            q = traj.q[k_lower] if label == "lower" else self._ik(world, wp, prev_q, timings)
            if q is None:
                return None
            inner, dev = self._refine_or_straight(world, prev_q, prev_X, q, wp.X_SF, wp, timings)
            max_dev = max(max_dev, dev)
            chain.extend((p, True, None) for p in inner)
            chain.append((q, True, label))
            prev_q, prev_X = q, wp.X_SF
        t0 = time.perf_counter()
        out, waypoint_times, _, t_join = self._timed_after_stop(q_stop, hold, chain, traj, k_lower)
        k_label = [label for label, _ in motion.waypoint_times].index("lower")
        waypoint_times += [(label, round(t - t_lower + t_join, 6)) for label, t in motion.waypoint_times[k_label + 1:]]
        # the cup holds on from the stop to the plan's own release, shifted as the tail is
        off = next((t1 for t0_, t1 in motion.suction_intervals if t0_ <= t_lower <= t1 + 1e-9), None)
        suction = [(0.0, round(float(off - t_lower + t_join), 6))] if off is not None else []
        timings["timing_s"] += time.perf_counter() - t0
        timings["total_s"] = time.perf_counter() - t_all
        waypoints = [raised if w.label == "push in" else w for w in motion.waypoints]
        return PlannedMotion(motion.action, out, suction, waypoint_times, float(max_dev), _rounded(timings), [],
                             waypoints)

    def _timed_after_stop(self, q_stop, hold: float, chain, traj, k_tail):
        """The motion from a stop at ``q_stop``: held still ``hold`` s, then ``chain`` [(q, suction on while arriving,
        waypoint label or None)], which starts at ``q_stop``, timed segment by segment rest to rest with Ruckig (where
        the suction first goes off the arm dwells ``DWELL`` at rest, released, "release"), then the planned
        trajectory ``traj`` from its sample ``k_tail`` on. Returns (the trajectory, its waypoint times up to the tail,
        the time the suction went off (s; None: it stays on), the time the tail starts (s))."""
        lim = self.limits
        out = JointTrajectory.hold(lim.names, q_stop, hold)
        waypoint_times = [("stop", 0.0), ("hold", round(float(out.times[-1]), 6))]
        suction_off = None
        for (qa, _, _), (qb, on, label) in zip(chain[:-1], chain[1:]):
            if not on and suction_off is None:
                suction_off = float(out.times[-1])
                out = out.then(JointTrajectory.hold(lim.names, qa, DWELL))  # released, at rest
                waypoint_times.append(("release", round(suction_off, 6)))
            t, q, v, a = time_segment(qa, qb, lim.velocity, lim.acceleration, lim.jerk, SAMPLE_PERIOD)
            if len(t) > 1:
                out = out.then(JointTrajectory(lim.names, t, q, v, a))
            if label is not None:
                waypoint_times.append((label, round(float(out.times[-1]), 6)))
        t_join = float(out.times[-1])
        tail = JointTrajectory(lim.names, traj.times[k_tail:] - traj.times[k_tail], traj.q[k_tail:], traj.v[k_tail:],
                               traj.a[k_tail:])
        if len(tail.times) > 1:
            out = out.then(tail)
        return out, waypoint_times, suction_off, t_join

    def _refine_or_straight(self, world, qa, Xa, qb, Xb, wp, timings):
        """:meth:`_refine`'s inserted configurations, or none (the joint-space line) when it cannot keep the tool
        on the straight segment; and the deviation it found (m; nan when it gave up)."""
        try:
            return self._refine(world, qa, np.asarray(Xa), qb, np.asarray(Xb), wp, timings, 0)
        except _Reject:
            return [], float("nan")

    # -----------------------------------------------------------------------------------------------------
    def _ik(self, world, wp: ToolWaypoint, guess, timings, min_distance=None, tight: bool = False):
        """IK of the waypoint's tool pose from ``guess`` (memoised): IK's default tolerances, or the hold
        tolerances (``HOLD_POSITION_TOLERANCE``, ``HOLD_ANGLE_TOLERANCE``) while the cup holds an object or when
        ``tight``; with ``min_distance``, the robot-environment distance constraint."""
        from pydrake.math import RigidTransform

        kinematic = min_distance is None and self.keep_kinematic_ik
        memo = self._kinematic_ik if kinematic else self._memo
        tight = tight or wp.suction or self._tight
        key = ("ik", wp.frame, wp.X_SF.tobytes(), np.asarray(guess, float).tobytes(), wp.shaft, tight,
               min_distance, False if kinematic else world._ik_filter is not None)
        if key in memo:
            q = memo[key]
            return None if q is None else q.copy()
        t0 = time.perf_counter()
        tol = dict(position_tolerance=HOLD_POSITION_TOLERANCE, angle_tolerance=HOLD_ANGLE_TOLERANCE) if tight else {}
        q = solve_tool_pose(world, wp.frame, RigidTransform(wp.X_SF), guess, wp.shaft, min_distance=min_distance, **tol)
        timings["ik_s"] += time.perf_counter() - t0
        timings["ik_solves"] += 1
        if kinematic and len(memo) >= KINEMATIC_IK_CACHE_SIZE:
            memo.clear()
        memo[key] = None if q is None else q.copy()
        return q

    def _free_path(self, world, qa, qb):
        """:func:`free_path` (no tool contact), memoised in the current world."""
        key = ("free", np.asarray(qa, float).tobytes(), np.asarray(qb, float).tobytes(), world.placed_key)
        if key not in self._memo:
            self._memo[key] = free_path(world, qa, qb, self.limits, LIMIT_MARGIN, seed=FREE_PATH_SEED)
        path = self._memo[key]
        return None if path is None else [np.array(q) for q in path]

    def _free(self, world, q, timings) -> bool:
        t0 = time.perf_counter()
        ok = world.config_free(q)
        timings["check_s"] += time.perf_counter() - t0
        return ok

    def _tight_or_reject(self, world, wp: ToolWaypoint, q, timings):
        """For a waypoint whose every solution collided, ``q`` the first: the pose solved again from ``q`` with
        the hold tolerances (not for a waypoint solved with them already) when that solution is collision-free;
        else raises _PoseReject when the tool meets the environment at it (or at ``q``, when IK finds none there),
        :func:`_reject_if_the_tool_hits`; else None (the arm collides: the caller's distance-constrained
        retries)."""
        q_tight = None if wp.suction else self._ik(world, wp, q, timings, tight=True)
        if q_tight is not None and self._free(world, q_tight, timings):
            return q_tight
        _reject_if_the_tool_hits(world, wp, q, q_tight)
        return None

    def _solve_waypoint(self, world, wp, guesses, name, timings):
        """IK for a waypoint from the guesses in turn; when every solution collides, solved again with a
        minimum-distance constraint from the colliding solutions (at most ``MAX_DISTANCE_RETRIES``) and the
        first guess."""
        world.allow_tool_contact(name, wp.contact)
        colliding = []
        for guess in guesses:
            q = self._ik(world, wp, guess, timings)
            if q is None:
                continue
            if self._free(world, q, timings):
                return q
            colliding.append(q)
        if colliding:
            q_tight = self._tight_or_reject(world, wp, colliding[0], timings)
            if q_tight is not None:
                return q_tight
            world.ik_tool_contact(name, wp.contact)
            try:
                for guess in colliding[:MAX_DISTANCE_RETRIES] + list(guesses[:1]):
                    q = self._ik(world, wp, guess, timings, min_distance=MIN_DISTANCE)
                    if q is not None and self._free(world, q, timings):
                        return q
            finally:
                world.ik_tool_contact(name, False)
            hits = (pairs_text(world.collision_pairs(colliding[0])) or ", ".join(world.colliding_bodies(colliding[0]))
                    or "the environment")
            raise _Reject(PlanningFailure(FailureKind.EVERY_SOLUTION_COLLIDES, wp.label, hits=hits))
        raise _Reject(PlanningFailure(FailureKind.NO_IK_SOLUTION, wp.label))

    def _solve_next(self, world, wp_from: ToolWaypoint, q_from, wp: ToolWaypoint, name, timings):
        """The next waypoint of a chain, warm-started from ``q_from`` (the solution at ``wp_from``). IK from a good
        warm start can fail to converge where the pose is reachable (a replayed push's 2.5 cm segment failed from the
        insert's solution, and planned with its inputs 10 um apart): when no guess gives a solution, the pose
        halfway along the segment is solved first and the waypoint from there (continuation); the first failure is
        raised when that fails too."""
        try:
            return self._solve_waypoint(world, wp, [q_from], name, timings)
        except _PoseReject:
            raise
        except _Reject as e:
            if e.failures[0].kind is not FailureKind.NO_IK_SOLUTION:
                raise
            first = e
        X = np.eye(4)
        X[:3, :3] = _midway_rotation(wp_from.X_SF[:3, :3], wp.X_SF[:3, :3])
        X[:3, 3] = (wp_from.X_SF[:3, 3] + wp.X_SF[:3, 3]) / 2.0
        q_mid = self._ik(world, dataclasses.replace(wp, X_SF=X), q_from, timings)
        if q_mid is None:
            raise first
        try:
            return self._solve_waypoint(world, wp, [q_mid], name, timings)
        except _PoseReject:
            raise
        except _Reject:
            raise first from None

    def _seeds(self, q_start):
        """Initial guesses for the first waypoint: the start, the observation pose with the torso low, mid and
        high, then a fixed set of pseudo-random configurations (seeded: the planner is deterministic)."""
        seeds = [np.asarray(q_start, float), self.q_observation]
        for torso in (0.2, 0.38):
            s = self.q_observation.copy()
            s[0] = torso
            seeds.append(s)
        lim = self.limits
        lo = np.where(np.isfinite(lim.position_lower), lim.position_lower, -np.pi)
        hi = np.where(np.isfinite(lim.position_upper), lim.position_upper, np.pi)
        rng = np.random.default_rng(SEED_LIBRARY_SEED)
        for _ in range(NUM_RANDOM_SEEDS):
            s = rng.uniform(lo, hi)
            s[-1] = self.q_observation[-1]
            seeds.append(s)
        return seeds

    def _first_waypoints(self, world, wp, q_start, name, timings):
        """Up to ``MAX_FIRST_SOLUTIONS`` distinct collision-free IK solutions of the first waypoint, in seed order,
        or the first one joined to the start by a collision-free straight line alone (the free path's random
        search is by far the slowest step); when every seed's solution collides, one solved with the distance
        constraint."""
        world.allow_tool_contact(name, False)
        found, colliding = [], []
        seeds = self._seeds(q_start)
        for guess in seeds:
            q = self._ik(world, wp, guess, timings)
            if q is None:
                continue
            q = nearest_turn(q, q_start)
            if not self._free(world, q, timings):
                colliding.append(q)
                continue
            if all(np.linalg.norm(q - f) > 0.1 for f in found):
                found.append(q)
                t0 = time.perf_counter()
                straight = world.edge_free(q_start, q)
                timings["check_s"] += time.perf_counter() - t0
                if straight:  # reachable from the start in a straight line: no better first solution needed
                    found = [q] + [f for f in found if f is not q]
                    break
            if len(found) >= MAX_FIRST_SOLUTIONS:
                break
        if not found and colliding:
            q_tight = self._tight_or_reject(world, wp, colliding[0], timings)
            if q_tight is not None:
                return [q_tight]
            try:
                found.append(self._solve_waypoint(world, wp, colliding[:1] + seeds[:1], name, timings))
            except _Reject:
                pass
        if not found:
            raise _Reject(PlanningFailure(FailureKind.FIRST_OUT_OF_REACH, wp.label, seeds=len(seeds),
                                          collides=bool(colliding)))
        return found

    def _plan(self, world, action, waypoints, q_start, timings) -> PlannedMotion:
        failures = []
        for q_first in self._first_waypoints(world, waypoints[0], q_start, action.name, timings):
            try:
                return self._plan_from(world, action, waypoints, q_start, q_first, timings)
            except _PoseReject:
                raise
            except _Reject as e:
                failures.extend(e.failures)
        raise _Reject(*distinct(failures))

    def _plan_from(self, world, action, waypoints, q_start, q_first, timings) -> PlannedMotion:
        name = action.name
        # 2. IK along the path, warm-started from the previous waypoint. A waypoint the warm start cannot reach
        # is solved from the seed library and the waypoints before it again, backward, warm-started from it.
        qs = [q_first]
        anchors = 0
        for k in range(1, len(waypoints)):
            try:
                qs.append(self._solve_next(world, waypoints[k - 1], qs[-1], waypoints[k], name, timings))
                continue
            except _PoseReject:
                raise
            except _Reject as e:
                if anchors >= MAX_REANCHORS or k in self._anchor_failed:
                    raise
                first_error = e
            anchors += 1
            self._anchor_failed.add(k)  # tried once per plan: later first solutions do not repeat it
            try:
                q_k = self._solve_waypoint(world, waypoints[k], self._seeds(qs[-1]), name, timings)
                back = [q_k]
                for j in range(k - 1, -1, -1):
                    back.append(self._solve_next(world, waypoints[j + 1], back[-1], waypoints[j], name, timings))
            except _Reject:
                raise first_error
            qs = back[::-1]
            turns = nearest_turn(qs[0], q_start) - qs[0]  # whole turns of the roll joints: the same poses
            qs = [q + turns for q in qs]
            self._anchor_failed.discard(k)
        # 3. Cartesian refinement of each straight tool segment.
        # (q, contact and suction of the segment arriving here, the waypoint or None for inserted points)
        chain = [(q_start, False, False, None), (qs[0], False, waypoints[0].suction, waypoints[0])]
        carried = {0: "", 1: waypoints[0].carried}  # chain index -> how the segment arriving there carries
        max_dev = 0.0
        for k in range(1, len(waypoints)):
            a, b = waypoints[k - 1], waypoints[k]
            world.allow_tool_contact(name, b.contact)
            inner, dev = self._refine(world, qs[k - 1], a.X_SF, qs[k], b.X_SF, b, timings, 0)
            max_dev = max(max_dev, dev)
            for q in inner:
                carried[len(chain)] = b.carried
                chain.append((q, b.contact, b.suction, None))
            carried[len(chain)] = b.carried
            chain.append((qs[k], b.contact, b.suction, b))
        # Free segments from the start and back to the observation pose: straight, or around the robot itself.
        t0 = time.perf_counter()
        world.allow_tool_contact(name, False)
        to_first = self._free_path(world, q_start, qs[0])
        # the way back clears the moved object where the action leaves it, not where it stood
        placed = placed_pose(action, world.scene)
        back = None
        try:
            if placed is not None:
                world.place(*placed)
            if to_first is not None and not world.edge_free(qs[-1], self.q_observation):
                # back the way it came: to the first waypoint's configuration, then the way from the start reversed
                via = [qs[-1], qs[0]] + to_first[::-1][1:] + [self.q_observation]
                via = [q for i, q in enumerate(via) if i == 0 or not np.array_equal(q, via[i - 1])]
                if all(world.edge_free(a, b) for a, b in zip(via[:-1], via[1:])):
                    back = via
            if back is None:
                back = self._free_path(world, qs[-1], self.q_observation)
        finally:
            world.unplace()
        timings["check_s"] += time.perf_counter() - t0
        if to_first is None:
            raise _Reject(PlanningFailure(FailureKind.NO_WAY_FROM_START, waypoints[0].label))
        if back is None:
            raise _Reject(PlanningFailure(FailureKind.NO_WAY_BACK))
        carried = [carried[i] for i in range(len(chain))]
        chain[1:1] = [(q, False, False, None) for q in to_first[1:-1]]
        carried[1:1] = [""] * len(to_first[1:-1])
        carried.extend("" for _ in back[1:])
        chain.extend((q, False, False, None) for q in back[1:])
        i_back = len(chain) - len(back)  # the segments from here on are the way back
        obj = next((o for o in world.scene.objects if o.name == name), None)
        i_seal = next((i for i, wp in enumerate(waypoints) if wp.suction), None)
        # 4. Dense collision checks of every joint segment.
        segments = []
        attached = ""
        t0 = time.perf_counter()
        try:
            for i, ((qa, _, _, wa), (qb, contact, _, wb), carry) in enumerate(zip(chain[:-1], chain[1:], carried[1:])):
                if i == i_back and placed is not None:
                    world.place(*placed)
                world.allow_tool_contact(name, contact)
                if carry != attached:
                    world.drop()
                    if carry:
                        world.carry(obj, qs[i_seal], trim_bottom=LIFT if carry == "resting" else 0.0)
                    attached = carry
                if not world.edge_free(qa, qb):
                    timings["check_s"] += time.perf_counter() - t0
                    ahead = next((w for _, _, _, w in chain[i + 1:] if w is not None), None)
                    where = ahead.label if ahead is not None else RETURN
                    if carry:
                        hits = _carried_hits(world, qa, qb)
                        if hits is not None:
                            raise _Reject(PlanningFailure(FailureKind.CARRIED_COLLIDES, where, hits=hits, carried=name))
                    pairs = world.first_collision_on(qa, qb)
                    raise _Reject(PlanningFailure(FailureKind.SEGMENT_COLLIDES, where,
                                                  hits=pairs_text(pairs) if pairs else "",
                                                  tool=any(a in TOOL_RIGID_BODIES for a, _ in pairs)))
                segments.append((np.asarray(qa).copy(), np.asarray(qb).copy(), contact, carry))
        finally:
            world.drop()
            world.unplace()
            world.allow_tool_contact(name, False)
        timings["check_s"] += time.perf_counter() - t0
        # 5. Ruckig timing, segment by segment, with dwells and the suction schedule.
        t0 = time.perf_counter()
        lim = self.limits
        traj = JointTrajectory.hold(lim.names, chain[0][0], 0.0)
        suction, waypoint_times = [], []
        on_since = None
        for (qa, _, _, _), (qb, _, want, wb) in zip(chain[:-1], chain[1:]):
            if want and on_since is None:
                on_since = float(traj.times[-1])
            if not want and on_since is not None:
                suction.append((on_since, float(traj.times[-1])))
                on_since = None
            t, q, v, a = time_segment(qa, qb, lim.velocity, lim.acceleration, lim.jerk, SAMPLE_PERIOD)
            if len(t) > 1:
                traj = traj.then(JointTrajectory(lim.names, t, q, v, a))
            if wb is not None:
                waypoint_times.append((wb.label, round(float(traj.times[-1]), 6)))
                if wb.dwell > 0:
                    traj = traj.then(JointTrajectory.hold(lim.names, qb, wb.dwell))
        if on_since is not None:
            suction.append((on_since, float(traj.times[-1])))
        timings["timing_s"] += time.perf_counter() - t0
        # The joint-limit margin of IK holds along the timed trajectory (straight rest-to-rest segments); the
        # start configuration, which the planner does not choose, may only be as close to a limit as it is.
        lower = np.minimum(lim.position_lower + LIMIT_MARGIN, q_start)
        upper = np.maximum(lim.position_upper - LIMIT_MARGIN, q_start)
        outside = np.flatnonzero(np.any((traj.q < lower - 1e-9) | (traj.q > upper + 1e-9), axis=0))
        if len(outside):
            raise _Reject(PlanningFailure(FailureKind.JOINT_LIMIT, hits=lim.names[outside[0]], margin=LIMIT_MARGIN))
        return PlannedMotion(action, traj, [(round(float(a), 6), round(float(b), 6)) for a, b in suction],
                             waypoint_times, float(max_dev), {}, segments, list(waypoints))

    def _refine(self, world, qa, Xa, qb, Xb, wp, timings, depth):
        """Configurations to insert between qa and qb (excluding both) so that the joint-space straight line
        keeps ``wp.frame`` within the tolerance of the Cartesian segment; and the largest deviation left."""
        pa, pb = Xa[:3, 3], Xb[:3, 3]
        n = max(6, int(np.ceil(np.linalg.norm(pb - pa) / 0.01)) + 1)
        dev = 0.0
        for s in np.linspace(0.0, 1.0, n)[1:-1]:
            p = world.tool_pose_S(qa + s * (qb - qa), wp.frame).translation()
            dev = max(dev, _distance_to_segment(p, pa, pb))
        if dev <= (min(self.deviation_tolerance, CARRIED_DEVIATION_TOLERANCE) if wp.carried or self._tight
                   else self.deviation_tolerance):
            return [], dev
        if depth >= MAX_REFINE_DEPTH:
            raise _Reject(PlanningFailure(FailureKind.LEAVES_STRAIGHT_SEGMENT, wp.label, deviation=dev))
        X_mid = Xa.copy()
        X_mid[:3, :3] = _midway_rotation(Xa[:3, :3], Xb[:3, :3])
        X_mid[:3, 3] = (pa + pb) / 2.0
        mid = dataclasses.replace(wp, X_SF=X_mid, label=wp.label)
        q_mid = None
        for guess in ((qa + qb) / 2.0, qa, qb):  # the joint-space midpoint, else either end's branch
            q_mid = self._ik(world, mid, guess, timings)
            if q_mid is not None:
                break
        if q_mid is None:
            raise _Reject(PlanningFailure(FailureKind.STRAIGHT_SEGMENT_OUT_OF_REACH, wp.label))
        left, d1 = self._refine(world, qa, Xa, q_mid, X_mid, wp, timings, depth + 1)
        right, d2 = self._refine(world, q_mid, X_mid, qb, Xb, wp, timings, depth + 1)
        return left + [q_mid] + right, max(d1, d2)


def _near_miss(failures) -> bool:
    """Whether a variant failed because a body rigid with the tool met the environment on a segment (the failure
    :meth:`MotionPlanner._plan_tight` may avoid; a pose the tool meets is decided within the hold tolerances
    already, :meth:`MotionPlanner._tight_or_reject`)."""
    return failures[0].kind is FailureKind.SEGMENT_COLLIDES and failures[0].tool


def _another_carry_may_differ(failures) -> bool:
    """Whether a suction carried across at another depth or turned may avoid a variant's ``failures``: those at the
    carrying waypoints (``PULL_DEPENDENT``), straight-segment failures, and a pose after the placement with no IK
    solution (``PULL_DEPENDENT_AFTER``)."""
    return _may_differ(failures, PULL_DEPENDENT) or (failures[0].kind is FailureKind.NO_IK_SOLUTION
                                                     and failures[0].names_any(PULL_DEPENDENT_AFTER))


def _may_differ(failures, dependent: frozenset, kinds: frozenset = frozenset()) -> bool:
    """Whether another planning variant may avoid a variant's ``failures`` (one per first IK solution tried): the
    first names a waypoint of ``dependent`` (or a joint segment arriving at one) or is of one of ``kinds``, or any
    is a straight-segment failure."""
    return (failures[0].names_any(dependent) or failures[0].kind in kinds
            or any(f.straight_segment for f in failures))


def placed_pose(action, scene: Scene):
    """(the object ``action`` moves, its pose X_SO (4x4, shelf frame) where the action leaves it as the action model
    predicts the translation (:func:`~slax_drake.shelf.actions.apply_action`: a suction's placement at x + d_x,
    y = d_z; a push's x + d, its turn left out), or None when ``scene`` does not hold the object."""
    obj = next((o for o in scene.objects if o.name == action.name), None)
    if obj is None:
        return None
    translated = dataclasses.replace(action, turns=False) if isinstance(action, Push) else action
    (moved,) = apply_action((obj,), translated)
    return obj, np.array(moved.X_SO, float)


def _reject_a_lifted_guarded_push_in(action, waypoints) -> None:
    """Raises _Reject (:attr:`FailureKind.GUARDED_LIFTED`) when ``action`` is a guarded lift whose push-in carries the
    object higher than ``LIFT`` (over a known object on the way across or in): pushed in at that height it would pass
    over a lower object hidden in its way and be lowered onto it; the guard senses the push, not the lowering."""
    if not isinstance(action, Suction) or not action.guarded or action.drag:
        return
    by = {w.label: w for w in waypoints}
    if "push in" not in by or "lower" not in by:
        return
    height = float(by["push in"].position[2] - by["lower"].position[2])
    if height > LIFT + 1e-6:
        raise _Reject(PlanningFailure(FailureKind.GUARDED_LIFTED, "push in", deviation=height))


def _reject_if_the_tool_hits(world, wp: ToolWaypoint, q, q_tight=None) -> None:
    """Raises _PoseReject when, at the waypoint's solution q, a body rigid with the tool meets the environment:
    every other solution of that tool pose meets it too. IK's default angle tolerance (0.01 rad) turns the tube's
    far end up to about 3 mm about the tool frame, so a tube that passes that close to an object may meet it at
    one solution and clear it at the exact pose: ``q_tight``, the pose solved again with the hold tolerances
    (:meth:`MotionPlanner._tight_or_reject`; None when there is none), decides then: the pose is rejected only when
    the tool meets the environment there too."""
    tool_hits = world.tool_environment_hits(q)
    if tool_hits and q_tight is not None:
        q, tool_hits = q_tight, world.tool_environment_hits(q_tight)
    if tool_hits:
        pairs = [(a, b) for a, b in world.collision_pairs(q) if a in tool_hits]
        raise _PoseReject(PlanningFailure(FailureKind.TOOL_COLLIDES, wp.label,
                                          hits=pairs_text(pairs) if pairs else f"{', '.join(tool_hits)} (environment)"))


def _carried_hits(world, qa, qb) -> str | None:
    """What the carried object meets on the segment qa -> qb, or None when the segment collides without it too
    (the robot is at fault). Named from the carried object's pose at ``CARRIED_PROBES`` configurations along
    the segment: the other objects whose footprint it overlaps (within the checker's margin) at an overlapping
    height, and the shelf when it leaves the bay; "the robot" when neither (it meets a link)."""
    from slax_drake.planning.world import CARRIED_MARGIN
    from slax_drake.scene.footprint import Footprint, clear_of

    if not world.edge_free_uncarried(qa, qb):
        return None
    obj, shelf = world.carried, world.scene.shelf
    names = []
    for s in np.linspace(0.0, 1.0, CARRIED_PROBES):
        X = world.carried_pose_S(qa + s * (qb - qa))
        moved = dataclasses.replace(obj, X_SO=X)
        fp = Footprint.of(moved)
        z0, z1 = X[2, 3] - obj.size[2] / 2 + world.carried_trim, X[2, 3] + obj.size[2] / 2
        for other in world.scene.objects:
            if other.name == obj.name or other.name in names or z0 >= other.size[2] + CARRIED_MARGIN:
                continue
            centre = np.array([[X[0, 3], X[1, 3]]])
            if not clear_of(fp.shape, centre, fp.yaw, (fp.half_x, fp.half_y), Footprint.of(other), CARRIED_MARGIN)[0]:
                names.append(other.name)
        ex, ey = fp.extents()
        m = CARRIED_MARGIN
        in_bay = X[1, 3] + ey > -shelf.depth / 2
        if "the shelf" not in names and in_bay and (z1 + m > shelf.height or z0 < m or abs(X[0, 3]) + ex + m > shelf.width / 2
                                                    or X[1, 3] + ey + m > shelf.depth / 2):
            names.append("the shelf")
    return ", ".join(names) if names else "the robot"


def _midway_rotation(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """The rotation halfway from Ra to Rb (Drake's quaternion slerp at 1/2; Ra itself when they are equal): the
    tool's orientation at a segment's midpoint when it turns along the segment (a turned carry)."""
    if np.array_equal(Ra, Rb):
        return Ra.copy()
    from pydrake.math import RotationMatrix

    qa, qb = RotationMatrix(Ra).ToQuaternion(), RotationMatrix(Rb).ToQuaternion()
    return RotationMatrix(qa.slerp(0.5, qb)).matrix()


def _distance_to_segment(p, a, b) -> float:
    ab = b - a
    L2 = float(ab @ ab)
    s = 0.0 if L2 == 0 else min(1.0, max(0.0, float((p - a) @ ab) / L2))
    return float(np.linalg.norm(p - (a + s * ab)))


def _rounded(timings: dict) -> dict:
    return {k: (round(v, 6) if isinstance(v, float) else v) for k, v in timings.items()}
