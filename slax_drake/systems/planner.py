"""PlannerSystem: the Bluction-DAR (or any registered) policy and the motion planner as a Drake LeafSystem.

It sees what a robot sees: its input ports are the PerceptionSystem's outputs and the robot's ``measured_state``,
plus the evaluator's ``stop`` (1.0 once the target is revealed; the referee's verdict, never a pose). No input
carries a true object pose or the render's labels of the occluders.

Every ``decision_period`` seconds an unrestricted update checks whether the robot is idle (its last motion
ended ``settle_time`` ago). When it is, the system decides:

1. it stops with "revealed" when ``stop`` says so, with "horizon" after H actions (its own budget);
2. the belief (:class:`~slax_drake.perception.belief.ObservedBelief`) from ``observation`` (depth, occluder
   segmentation, target mask, camera), ``hypotheses`` (the estimator's objects ``segment_<id>``, renamed by the
   object tracker to ``track_<k>``, stable across frames; :mod:`slax_drake.perception.tracking`) and
   ``occupancy_1d`` (P_t); a hypothetical action's distribution comes from the predicted frame (segments shifted
   in the image) through the same distribution source as P_t;
3. the policy (any :class:`~slax_drake.policies.protocol.Policy` that reads a
   :class:`~slax_drake.shelf.simulator.PolicyObservation`; the very code the shelf simulator runs) ranks the
   candidates on the hypotheses with ``decide``; the best one is planned against the believed scene
   (:class:`slax_drake.planning.planner.MotionPlanner`); an infeasible motion is logged with its
   reason and handed back with ``policy.exclude`` (the whole group when the tool could not reach the object), and
   the policy decides again (its next candidate). The planner touches the policy through the protocol only.

Guarded push-ins (``guard``, a :class:`slax_drake.systems.guard.Guard`; the trial gives one under
``suction_hidden_rule=guarded``): an extra input, ``measured_efforts`` (9: the joint efforts the station's
controllers apply), and a check every ``guard.period`` s. While a guarded suction's push-in plays, the contact
monitor compares the efforts with what the free arm and its carried weight need; when the force resisting the push
exceeds the stop force (the station's ``guarded_stop_force``; for a lift at most what the cup's seal holds over the
lever, :meth:`~slax_drake.systems.guard.Guard.stop_force`; for a drag plus its floor friction), the motion is replaced, from that instant, by the planner's stop
motion from the measured joint positions (:meth:`slax_drake.planning.planner.MotionPlanner.guarded_stop`: hold,
lower, release, back off, the planned way back); a stop at the support board's front edge (the carried object
hangs lower than planned) is made again higher instead (``MotionPlanner.edge_retry``), and an unguarded lift's
push-in from outside the bay is watched for that edge alone (:mod:`slax_drake.systems.guard`). The record (stopped
or completed, how far it pushed in, the peak force, an ``edge_stop``) is added to the action's log entry as
``guarded``. A lifted object is weighed at its lift
(:meth:`PlannerSystem._weigh`) and, under the ``weigh_drag_pull`` rule, a sideways drag along its pull
(:mod:`slax_drake.systems.drag_weigh`); each may be undone from there (``weighed``). It reads joint states and
efforts only.

Outputs: ``desired_state`` (18: q and v of ``PLANNED_JOINTS``, sampled from the running motion, else holding
the last pose), ``suction_command`` (1) and ``deciding`` (1: 1.0 at a tick where it decides; the evaluator records
the ground truth at exactly those ticks).

State: everything the trial accumulates lives in the context, in one abstract state value (:class:`TrialState`):
the running motion, the step count, the decision log (a tuple of dicts, for the trial record), the executed motions
(start time, PlannedMotion), the result ("revealed", "horizon", "no feasible action", ...) and the cost. An
initialization event resets it and the policy (``policy.reset``), so ``Simulator.Initialize`` on a reset context
replays the same trial. Read it with :meth:`PlannerSystem.trial_state`.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem

from slax_drake.perception.belief import ObservedBelief
from slax_drake.io import json_safe
from slax_drake.planning.planner import MotionPlanner
from slax_drake.policies.protocol import NO_REVEALING_PLAN
from slax_drake.shelf.actions import GRAVITY, Push, Suction, contact_lever
from slax_drake.shelf.distribution import support
from slax_drake.shelf.simulator import PolicyObservation
from slax_drake.scene.model import Scene
from slax_drake.station import robot as robot_model
from slax_drake.systems.drag_weigh import believed_pull, observe_pull, pull_record, start_pull
from slax_drake.systems.guard import (PutBack, edge_stop_cup_y, guard_record, least_lever, past_edge_band,
                                     push_in_forces, weigh_time, weigh_verdict)

MAX_PLAN_ATTEMPTS = 25


@dataclasses.dataclass(frozen=True)
class TrialState:
    """The planner system's abstract state (see the module docstring). Immutable: an update makes a new one, so
    copying it (Drake clones abstract state around every event) shares it instead of deep-copying the log."""

    motion: object = None  # PlannedMotion or None
    t_start: float = 0.0  # s, simulated time when ``motion`` started
    steps: int = 0  # actions started
    done: bool = False
    log: tuple = ()  # one dict per decision (the last one final), never mutated once appended
    motions: tuple = ()  # (start time s, PlannedMotion) per executed action
    result: str | None = None  # None while running
    cost: float = 0.0  # pushes 1, suctions ``suction_cost``
    guard: object = None  # GuardRun of the running guarded push-in (slax_drake.systems.guard), None otherwise
    weigh_at: float | None = None  # s from the motion's start at which its lifted object is weighed; None: not
    least_lever: float = 0.0  # m, the lifted object's least lever as the camera allows it (guard.least_lever)
    believed: object = None  # the believed Scene the running motion was planned in
    then: tuple | None = None  # (action, PlannedMotion) to start when the running motion ends, in the same action:
    # the drag after a lift weighed and put back (the ``drag_after_weighing`` rule)
    pull: object = None  # PullRun of the running sideways drag weighed along its pull (the ``weigh_drag_pull`` rule)

    def __deepcopy__(self, memo):
        return self


class PlannerSystem(LeafSystem):
    """See the module docstring. ``policy``: a :class:`~slax_drake.policies.protocol.Policy` reading a
    PolicyObservation, built with its action model; ``template``: the static world the robot knows (shelf and camera;
    its objects and target are ignored); ``source``: the distribution source of the predictions (the one the
    PerceptionSystem computes ``occupancy_1d`` with; :mod:`slax_drake.perception.belief`); ``width``, ``height``:
    the PerceptionSystem's working resolution; ``suction_cost``: psi, the cost of a suction (a push costs 1)."""

    def __init__(self, policy, planner: MotionPlanner, template: Scene, source, horizon: int, width: int,
                 height: int, decision_period: float = 0.1, settle_time: float = 0.5, on_step=None,
                 suction_cost: float = 1.3, guard=None):
        LeafSystem.__init__(self)
        if policy.needs_true_scene:
            raise ValueError(f"policy '{policy.name}' needs the true scene (an oracle): it cannot run on a station")
        from slax_drake.perception.belief import background_depth

        self.policy = policy
        from slax_drake.perception.tracking import ObjectTracker

        self.tracker = ObjectTracker()  # the objects seen so far, named stably across frames
        self._last_action = None  # the action executed since the last decision (named by a track)
        self.planner = planner
        self.template = Scene(template.shelf, template.camera, (), None)
        self.source = source
        self.horizon = horizon
        self.settle_time = settle_time
        self.suction_cost = suction_cost
        self.guard = guard
        self.on_step = on_step
        self._q_obs = planner.q_observation.copy()
        self._background = background_depth(template.shelf, template.camera.with_resolution(width, height))
        n = len(robot_model.PLANNED_JOINTS)
        self._measured = self.DeclareVectorInputPort("measured_state", 2 * n)
        self._observation = self.DeclareAbstractInputPort("observation", AbstractValue.Make(object()))
        self._hypotheses = self.DeclareAbstractInputPort("hypotheses", AbstractValue.Make(()))
        self._occupancy = self.DeclareVectorInputPort("occupancy_1d", width)
        self._stop = self.DeclareVectorInputPort("stop", 1)
        if guard is not None:
            self._efforts = self.DeclareVectorInputPort("measured_efforts", n)
        self._state = self.DeclareAbstractState(AbstractValue.Make(TrialState()))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)
        self.DeclarePeriodicUnrestrictedUpdateEvent(decision_period, 0.0, self._update)
        if guard is not None:
            self.DeclarePeriodicUnrestrictedUpdateEvent(guard.period, 0.0, self._watch)
        ticket = {self.abstract_state_ticket(self._state)} | {self.time_ticket()}
        self.DeclareVectorOutputPort("desired_state", BasicVector(2 * n), self._calc_desired,
                                     prerequisites_of_calc=ticket)
        self.DeclareVectorOutputPort("suction_command", BasicVector(1), self._calc_suction,
                                     prerequisites_of_calc=ticket)
        self.DeclareVectorOutputPort("deciding", BasicVector(1), self._calc_deciding, prerequisites_of_calc=ticket)

    def trial_state(self, root_context) -> TrialState:
        """The trial so far in ``root_context`` (the root diagram's context)."""
        return self.GetMyContextFromRoot(root_context).get_abstract_state(self._state).get_value()

    def _initialize(self, context, state):
        self.policy.reset(self.template)
        self.tracker.reset()
        self._last_action = None
        state.get_mutable_abstract_state(0).set_value(TrialState())

    # outputs ---------------------------------------------------------------------------------------------
    def _plan_state(self, context) -> TrialState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_desired(self, context, output):
        s = self._plan_state(context)
        if s.motion is None:
            q, v = self._q_obs, np.zeros(len(self._q_obs))
        else:
            q, v = s.motion.trajectory.value(context.get_time() - s.t_start)
        output.SetFromVector(np.concatenate([q, v]))

    def _calc_suction(self, context, output):
        s = self._plan_state(context)
        on = s.motion is not None and s.motion.suction_at(context.get_time() - s.t_start)
        output.SetAtIndex(0, 1.0 if on else 0.0)

    def _calc_deciding(self, context, output):
        output.SetAtIndex(0, 1.0 if self._idle(self._plan_state(context), context.get_time()) else 0.0)

    # decisions -------------------------------------------------------------------------------------------
    def _idle(self, s: TrialState, now: float) -> bool:
        """Whether the planner decides at ``now``: the trial runs and the robot settled after its last motion."""
        if s.done or s.then is not None:
            return False
        if s.motion is not None:
            return now >= s.t_start + s.motion.trajectory.duration + self.settle_time
        return now >= self.settle_time

    def _update(self, context, state):
        s = self._plan_state(context)
        now = context.get_time()
        if s.then is not None and now >= s.t_start + s.motion.trajectory.duration + self.settle_time:
            state.get_mutable_abstract_state(0).set_value(self._start_then(s, now))
        elif self._idle(s, now):
            state.get_mutable_abstract_state(0).set_value(self._decide(context, s, now))

    def _start_then(self, s: TrialState, now: float) -> TrialState:
        """Starts ``s.then`` (the drag after a put-back lift) at ``now``, within the same action: no new decision,
        no step counted; its start time goes into the action's ``weighed`` record. Its pull is not weighed
        (``weigh_drag_pull``): the action model checked its twist at the mass weighed at the lift."""
        action, motion = s.then
        self._last_action = action  # the tracker reads where the object went from the executed action
        weighed = s.log[-1]["weighed"]
        record = {**weighed, "drag_after_weighing": {**weighed["drag_after_weighing"], "started_at": round(now, 4)}}
        obj = next((o for o in s.believed.objects if o.name == action.name), None)
        guard = self._start_guard(action, obj, s.believed, motion)
        return dataclasses.replace(
            s, motion=motion, t_start=now, then=None, guard=guard, weigh_at=None, motions=s.motions + ((now, motion),),
            pull=None, log=s.log[:-1] + ({**s.log[-1], "weighed": record},))  # its twist checked at the weighed mass

    def _start_guard(self, action, obj, believed, motion):
        """The guard's run over ``motion`` (None without a guard): a suction's push-in forces from ``obj``, the
        believed object it moves; an unguarded lift's push-in from outside the bay is watched while a stop would be
        the board's front edge (``edge_only``), and not at all when it starts inside."""
        if self.guard is None:
            return None
        stop, expected = push_in_forces(action, obj, self.policy.action_model, self.guard.threshold,
                                        self.guard.lip_moment) if isinstance(action, Suction) else (None, 0.0)
        edge_only = isinstance(action, Suction) and not action.guarded and not action.drag
        run = self.guard.start(motion, self._cup_y(believed, motion), expected, stop, edge_only=edge_only)
        if run is None:
            return None
        edge = edge_stop_cup_y(action, obj, self.template.shelf, run.y_start)
        if edge_only and edge is None:
            return None
        return dataclasses.replace(run, edge_cup_y=edge)

    def _start_pull(self, motion):
        """The weighing of ``motion``'s pull when it is a sideways drag and the ``weigh_drag_pull`` rule is on (the
        efforts need the guard's input), else None."""
        if self.guard is None or not self.policy.action_model.tool.rules.weigh_drag_pull:
            return None
        return start_pull(self.guard, motion)

    def _decide(self, context, s: TrialState, now: float) -> TrialState:
        frame = self._observation.Eval(context)
        depth, labels = frame.depth, frame.segmentation
        entry = {"step": s.steps, "time": round(now, 4)}
        if self._stop.Eval(context)[0] >= 0.5:
            return self._finish(s, "revealed", entry, frame)
        if s.steps >= self.horizon:
            return self._finish(s, "horizon", entry, frame)
        measured = self._measured.Eval(context)[: len(self._q_obs)]
        hypotheses = self.tracker.update(self._hypotheses.Eval(context), self._last_action, frame, self.template)
        self._last_action = None
        p1d = np.array(self._occupancy.Eval(context), dtype=np.float64)
        belief = ObservedBelief(frame, self.template.shelf, self.source, background=self._background,
                                hypotheses=hypotheses, p1d=p1d, remembered=self.tracker.hidden())
        believed = self.template.with_objects(belief.known)
        obs = PolicyObservation(depth, labels, belief.known, belief.p1d, believed, belief)
        entry["hypotheses"] = {o.name: {"shape": o.shape, "size": [round(float(v), 4) for v in o.size],
                                        "x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                                        "yaw": round(float(o.yaw), 5)} for o in belief.known}
        entry["segment_of"] = {o.name: f"segment_{belief.segment_id(o.name)}" for o in belief.known}  # this frame's
        entry["remembered"] = {o.name: {"shape": o.shape, "size": [round(float(v), 4) for v in o.size],
                                        "x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                                        "yaw": round(float(o.yaw), 5),
                                        "uncertainty_m": round(self.tracker.uncertainty(o.name), 4)}
                               for o in belief.remembered}  # seen earlier, hidden now (the tracker's memory)
        policy = self.policy
        rejected = []
        t0, c0 = time.perf_counter(), time.process_time()
        motion, action, decide_s, decide_cpu_s, decision = None, None, 0.0, 0.0, None
        logged = len(getattr(policy, "decision_log", ()))  # the policy's own record of its decisions, if it keeps one
        for _ in range(MAX_PLAN_ATTEMPTS):
            td, cd = time.perf_counter(), time.process_time()
            decision = policy.decide(obs)
            action = decision.best
            decide_s += time.perf_counter() - td
            decide_cpu_s += time.process_time() - cd
            if action is None:
                break
            result = self.planner.plan(action, believed, q_start=measured)
            if result.feasible:
                motion = result
                break
            failure = result.failure
            rejected.append({"action": action.describe(), "reason": result.reason,
                             "kind": failure.kind.value if failure is not None else None,
                             "waypoint": failure.waypoint if failure is not None else None,
                             "planning_s": result.timings.get("total_s")})
            policy.exclude(action, result.reason, whole_group=result.failure.early)
            action = None
        if hasattr(policy, "decision_log"):  # this step's decisions (one more per candidate the planner rejected)
            entry["decision_log"] = json_safe(policy.decision_log[logged:])
        history = policy.history
        entry["support"] = support(history)
        entry["p1d"] = np.round(obs.p1d, 6).tolist()
        entry["history"] = np.round(history, 6).tolist()
        entry["rejected"] = rejected
        entry["decision_s"] = round(decide_s, 4)
        entry["planning_s"] = round(time.perf_counter() - t0 - decide_s, 4)
        # the process's CPU time planning (s): the figure of one core, whatever else shares the machine
        entry["planning_cpu_s"] = round(time.process_time() - c0 - decide_cpu_s, 4)
        if motion is None:
            entry.update(stop_record(policy, belief.known, rejected,
                                     decision.stop_reason if decision is not None and action is None else None))
            stop = decision.stop_reason if decision is not None and action is None else None
            result = "no feasible action" if not rejected else "no feasible motion"
            if stop is NO_REVEALING_PLAN and not rejected:
                result = NO_REVEALING_PLAN  # the policy stopped: no plan of it reveals the target
            return self._finish(s, result, entry, frame, hold=True)
        entry["action"] = _describe(action)
        # how the no-shuttle correction judged it (None: not a move back; Policy.reversal_rule)
        rule = getattr(policy, "reversal_rule", lambda a: None)(action)
        entry["action"]["reversal_rule"] = None if rule is None else str(rule)
        self._last_action = action
        entry["motion"] = {"duration_s": round(motion.trajectory.duration, 3), "timings": motion.timings,
                           "max_deviation_m": round(motion.max_deviation, 5),
                           "waypoint_times": motion.waypoint_times, "suction_intervals": motion.suction_intervals}
        entry["predicted_objects"] = _predicted(belief.known, action)
        guard = self._start_guard(action, next((o for o in belief.known if o.name == action.name), None), believed,
                                  motion)
        if self.on_step is not None:
            self.on_step(entry, depth, labels, frame.target_mask, history, obs.p1d)
        return dataclasses.replace(
            s, motion=motion, t_start=now, steps=s.steps + 1, log=s.log + (entry,), motions=s.motions + ((now, motion),),
            cost=s.cost + (1.0 if isinstance(action, Push) else self.suction_cost), guard=guard, believed=believed,
            weigh_at=weigh_time(motion) if self.guard is not None else None, pull=self._start_pull(motion),
            least_lever=next((least_lever(h, action.q[:2]) for h in belief.hypotheses
                              if getattr(h, "object", h).name == action.name), 0.0) if isinstance(action, Suction)
            else 0.0)

    # weighing a lifted object ----------------------------------------------------------------------------
    def _weigh(self, context, state, s: TrialState, t: float):
        """The lifted object weighed at the lift (one joint-state sample, :meth:`Guard.weigh`) and judged
        (:func:`~slax_drake.systems.guard.weigh_verdict`): when the cup holds nothing, when the moment it hangs off
        the cup exceeds the limit the action was planned under (the action model's ``max_suction_moment``), or when
        it does not hang free (the floor carries part of it: its seal is peeling), the lift is undone from here
        (:meth:`MotionPlanner.put_back`). An object too heavy or not hanging free is reckoned from now on with the
        mass its weighing implies (:meth:`Payload.mass_at`; not hanging free: at least the limit's at the believed
        lever), recorded on its track (:meth:`ObjectTracker.weighed`), so that the action model refuses to lift it
        again; when the cup held nothing, its suctions are excluded while it stands there (``policy.exclude``, the
        whole group: the seal let go at that face). The record goes into the action's log entry as ``weighed``."""
        n = len(self._q_obs)
        x = self._measured.Eval(context)
        payload = self.guard.weigh(t, s.motion, x[:n], x[n:], self._efforts.Eval(context))
        limit = float(self.policy.action_model.tool.rules.max_suction_moment)
        action = s.motion.action
        lever = self._believed_lever(s)
        why = weigh_verdict(payload, limit, s.least_lever)
        record = {"weight_n": round(payload.weight_n, 3), "moment_nm": round(payload.moment_nm, 4),
                  "lever_m": round(payload.moment_nm / payload.weight_n, 4) if payload.weight_n > 0 else None,
                  "believed_lever_m": round(lever, 4), "least_lever_m": round(s.least_lever, 4), "limit_nm": limit,
                  "put_back": why is not None}
        if why is None:
            state.get_mutable_abstract_state(0).set_value(dataclasses.replace(
                s, weigh_at=None, log=s.log[:-1] + ({**s.log[-1], "weighed": record},)))
            return
        record["why"] = why.value
        if why is PutBack.NOTHING_HELD:  # the cup does not hold it there: none of its suctions, while it stands there
            self.policy.exclude(action, "weighed at the lift: the cup held nothing (its seal let go)", whole_group=True)
        else:  # the cup cannot lift it free: reckoned at least at the limit from now on
            mass = payload.mass_at(lever)
            if why is PutBack.NOT_HANGING_FREE and lever > 0.0:
                mass = max(mass, 1.01 * limit / (GRAVITY * lever))
            record["mass_kg"] = round(mass, 4)
            self.tracker.weighed(action.name, record["mass_kg"])
        back = self.planner.put_back(s.motion, t)
        now = context.get_time()
        record["put_back_time"] = round(now, 4)
        record["put_back_motion"] = {"duration_s": round(back.trajectory.duration, 3),
                                     "waypoint_times": back.waypoint_times, "suction_intervals": back.suction_intervals}
        then, believed = None, s.believed
        if why is not PutBack.NOTHING_HELD:  # from now on the object weighs what the arm weighed
            believed = s.believed.with_objects(tuple(
                dataclasses.replace(o, mass=record["mass_kg"]) if o.name == action.name else o
                for o in s.believed.objects))
            if self.policy.action_model.tool.rules.drag_after_weighing:
                then, record["drag_after_weighing"] = self._drag_after_weighing(action, believed, back,
                                                                                record["mass_kg"])
        state.get_mutable_abstract_state(0).set_value(dataclasses.replace(
            s, motion=back, t_start=now, guard=None, weigh_at=None, motions=s.motions + ((now, back),), then=then,
            believed=believed, log=s.log[:-1] + ({**s.log[-1], "weighed": record},)))

    def _drag_after_weighing(self, lift, believed, back, mass: float) -> tuple[tuple | None, dict]:
        """The drag that puts the object of the put-back ``lift`` where the lift would have, planned from where the
        put-back motion ``back`` ends (the ``drag_after_weighing`` rule): ((drag, PlannedMotion) or None, its
        record). The action model must offer it on the arrangement the lift was planned in (``believed``, the lifted
        object at its weighed ``mass``, kg; :meth:`ActionModel.drag_instead`), and the planner must plan it."""
        drag, why = self.policy.action_model.drag_instead(believed.objects, lift, mass)
        if drag is None:
            return None, {"drag": None, "why": why}
        c0 = time.process_time()
        q_end = back.trajectory.value(back.trajectory.duration)[0]
        result = self.planner.plan(drag, believed, q_start=q_end)
        record = {"drag": _describe(drag), "planning_cpu_s": round(time.process_time() - c0, 4)}
        if not result.feasible:
            return None, {**record, "why": result.reason}
        record["motion"] = {"duration_s": round(result.trajectory.duration, 3), "timings": result.timings,
                            "waypoint_times": result.waypoint_times, "suction_intervals": result.suction_intervals}
        return (drag, result), record

    # the guarded push-in ---------------------------------------------------------------------------------
    def _cup_y(self, believed, motion):
        """q -> the cup's y (S, m) at planned joint positions q, on the planning world of ``believed``."""
        world = self.planner.world(believed)
        frame = motion.waypoints[0].frame if motion.waypoints else robot_model.CUP_TIP_FRAME
        return lambda q: float(world.tool_pose_S(q, frame).translation()[1])

    def _watch(self, context, state):
        """Every ``guard.period`` s: at a lifted suction's lift, the object weighed (:meth:`_weigh`); while a
        guarded push-in plays, one joint-state sample to the contact monitor; on contact, the motion is replaced by
        the planner's stop motion from the measured positions (hold, lower, release, back off, the planned way
        back). The records go into the action's log entry."""
        s = self._plan_state(context)
        if s.motion is not None and s.weigh_at is not None:  # a lift comes before its push-in
            t = context.get_time() - s.t_start
            if t >= s.weigh_at:
                self._weigh(context, state, s, t)
            return
        if s.motion is not None and s.pull is not None:  # a drag's pull comes before its push-in
            self._watch_pull(context, state, s)
            return
        run = s.guard
        if run is None or s.motion is None:
            return
        t = context.get_time() - s.t_start
        if t < run.t0:
            return
        n = len(self._q_obs)
        x = self._measured.Eval(context)
        if t > run.t1 or (run.edge_only and past_edge_band(run, self._cup_y(s.believed, s.motion)(x[:n]))):
            # completed: no contact all the way in, or an unguarded lift past the band where a stop is the edge
            log = s.log if run.edge_only else s.log[:-1] + ({**s.log[-1], "guarded": guard_record(run, False)},)
            state.get_mutable_abstract_state(0).set_value(dataclasses.replace(s, guard=None, log=log))
            return
        run = self.guard.observe(run, s.motion, t, x[:n], x[n:], self._efforts.Eval(context))
        if not run.monitor.stopped:
            state.get_mutable_abstract_state(0).set_value(dataclasses.replace(s, guard=run))
            return
        now = context.get_time()
        after, again, record = self.guard.stopped(run, s.motion, np.asarray(x[:n], float), self.planner, s.believed,
                                                  self._cup_y(s.believed, s.motion), now)
        if after is None:  # an unguarded lift's stop that is not the edge, or no retry: it goes on as planned
            state.get_mutable_abstract_state(0).set_value(dataclasses.replace(s, guard=None))
            return
        state.get_mutable_abstract_state(0).set_value(dataclasses.replace(
            s, motion=after, t_start=now, guard=again, motions=s.motions + ((now, after),),
            log=s.log[:-1] + ({**s.log[-1], "guarded": record},)))

    # weighing a drag along its pull ----------------------------------------------------------------------
    def _watch_pull(self, context, state, s: TrialState):
        """One joint-state sample of a sideways drag's pull (:mod:`slax_drake.systems.drag_weigh`); at the pull's
        end, the twist the slide across would ask of the seal with the friction measured: over the action model's
        ``max_drag_twist`` the drag is undone from there (:meth:`MotionPlanner.put_back`: pushed back to where it
        was sealed, released) and the object reckoned from then on with the mass the friction implies (its track,
        :meth:`ObjectTracker.weighed`: the action model drags it straight out and in only). The record goes into
        the action's log entry as ``weighed`` (``along`` "pull")."""
        t = context.get_time() - s.t_start
        run = s.pull
        if t < run.t_base:
            return
        n = len(self._q_obs)
        if t < run.t_decide:
            x = self._measured.Eval(context)
            run = observe_pull(self.guard, run, s.motion, t, x[:n], x[n:], self._efforts.Eval(context))
            state.get_mutable_abstract_state(0).set_value(dataclasses.replace(s, pull=run))
            return
        action = s.motion.action
        lever, shape = believed_pull(self._believed_object(s), action.q[:2])
        record = pull_record(run, lever, self.policy.action_model.tool.rules, shape)
        after = s
        if record["put_back"]:
            self.tracker.weighed(action.name, record["mass_kg"])
            back = self.planner.put_back(s.motion, t)
            now = context.get_time()
            record["put_back_time"] = round(now, 4)
            record["put_back_motion"] = {"duration_s": round(back.trajectory.duration, 3),
                                         "waypoint_times": back.waypoint_times,
                                         "suction_intervals": back.suction_intervals}
            after = dataclasses.replace(s, motion=back, t_start=now, guard=None, motions=s.motions + ((now, back),))
        state.get_mutable_abstract_state(0).set_value(dataclasses.replace(
            after, pull=None, log=s.log[:-1] + ({**s.log[-1], "weighed": record},)))

    @staticmethod
    def _believed_object(s: TrialState):
        """The running action's object in the believed scene it was planned in (None when that does not hold it)."""
        name = s.motion.action.name
        return next((o for o in s.believed.objects if o.name == name), None) if s.believed else None

    @classmethod
    def _believed_lever(cls, s: TrialState) -> float:
        """m: the floor-plane distance from the running suction's contact to its object's believed centre (0 when
        the believed scene does not hold it)."""
        obj = cls._believed_object(s)
        return 0.0 if obj is None else contact_lever(obj, s.motion.action.q[:2])

    def _finish(self, s: TrialState, result: str, entry: dict, frame, hold: bool = False) -> TrialState:
        """The trial ends with ``result``; ``hold``: no motion runs now (the robot holds the last motion's end
        pose), else the motion in progress, if any, plays out."""
        entry["final"] = True
        entry["result"] = result
        if self.on_step is not None:
            self.on_step(entry, frame.depth, frame.segmentation, frame.target_mask, self.policy.history, None)
        motion = None if hold else s.motion
        return dataclasses.replace(s, done=True, motion=motion, result=result, log=s.log + (entry,))


def stop_record(policy, known, rejected: list, stop_reason: str | None) -> dict:
    """Why a decision found no action to execute, for the trial record: ``stop_reason`` (the policy's, None when it
    gave none), ``refused`` (every candidate the action model refuses on the believed objects ``known``, as
    ``{"candidate", "kind", "reason"}``: the :class:`~slax_drake.shelf.actions.RefusalKind` value and its wording),
    ``feasible_left`` (the action model's feasible candidates there: those the policy did not take were excluded
    by it, e.g. by its corrections, or rejected by the motion planner), ``excluded`` (the policy's exclusions this
    trial, when it records them) and ``reasons``: per stage ("action model", "motion planner") and kind (the
    refusal kind, or the :class:`~slax_drake.planning.failures.FailureKind` value of each entry of ``rejected``)
    how many candidates, the most frequent first."""
    import collections

    cands = policy.action_model.enumerate(tuple(known))
    refused = [{"candidate": r.spec(), "kind": r.kind.value if r.kind is not None else None, "reason": r.reason}
               for r in cands.rejected]
    counts = collections.Counter(("action model", r["kind"]) for r in refused)
    counts.update(("motion planner", r.get("kind")) for r in rejected)
    reasons = [{"stage": stage, "kind": kind, "count": n}
               for (stage, kind), n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0][0], str(kv[0][1])))]
    out = {"stop_reason": stop_reason, "refused": refused, "feasible_left": len(cands.feasible), "reasons": reasons}
    exclusions = getattr(policy, "exclusions", None)
    if exclusions is not None:
        out["excluded"] = [{"action": a.describe(), "reason": why} for a, why in exclusions]
    screened = getattr(policy, "screened_counts", None)
    if screened is not None:  # why the policy took none of the feasible candidates, by correction
        out["screened"] = screened(tuple(known))
    return out


def _describe(action) -> dict:
    if isinstance(action, Push):
        return {"type": "push", "object": action.name, "q": list(action.q), "d": action.d,
                **({"turns": True} if action.turns else {})}
    return {"type": "suction", "object": action.name, "q": list(action.q), "dx": action.dx, "dz": action.dz,
            "yaw": action.yaw, "grip": action.grip, "guarded": bool(action.guarded)}


def _predicted(objects, action) -> dict:
    from slax_drake.shelf.actions import apply_action

    before = next(o for o in objects if o.name == action.name)
    moved = next(o for o in apply_action(tuple(objects), action) if o.name == action.name)
    out = {"object": action.name, "x": round(float(moved.center[0]), 5), "y": round(float(moved.center[1]), 5),
           "yaw": round(float(moved.yaw), 5)}
    if getattr(action, "turns", False):  # the quasi-static push's predicted turn of the object (rad)
        out["turn"] = round(math.remainder(float(moved.yaw) - float(before.yaw), 2.0 * math.pi), 5)
    return out
