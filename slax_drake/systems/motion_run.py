"""One planned motion executed open loop in the Drake station, for tests and benchmarks of single actions.

:func:`run_motion` builds the station with the scene's objects (no camera), feeds the motion's joint trajectory
(``desired_state``) and suction schedule (``suction_command``) from t = 0, starting at the observation pose, and
returns the manipulated object's pose in the shelf frame S at the requested times and at the end (the motion's
end plus ``settle`` seconds).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem


class MotionSource(LeafSystem):
    """``desired_state`` (q, v of the planned joints) and ``suction_command`` of a PlannedMotion, by time."""

    def __init__(self, motion):
        LeafSystem.__init__(self)
        self.motion = motion
        n = len(motion.trajectory.names)
        self.DeclareVectorOutputPort("desired_state", BasicVector(2 * n), self._state)
        self.DeclareVectorOutputPort("suction_command", BasicVector(1), self._suction)

    def _state(self, context, out):
        q, v = self.motion.trajectory.value(context.get_time())
        out.SetFromVector(np.concatenate([q, v]))

    def _suction(self, context, out):
        out.SetAtIndex(0, 1.0 if self.motion.suction_at(context.get_time()) else 0.0)


def run_motion(station_scenario, scene, motion, name: str, times=(), settle: float = 1.0) -> dict:
    """{time or "end": {"x", "y", "z", "yaw", "tilt_deg"}} of object ``name`` (S; m, rad, deg from upright) while
    ``motion`` runs in the station on ``scene``."""
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    from slax_drake.station.plant import shelf_pose
    from slax_drake.systems.station import MakeStation

    builder = DiagramBuilder()
    station = builder.AddSystem(MakeStation(station_scenario, scene, camera=False))
    source = builder.AddSystem(MotionSource(motion))
    builder.Connect(source.GetOutputPort("desired_state"), station.GetInputPort("desired_state"))
    builder.Connect(source.GetOutputPort("suction_command"), station.GetInputPort("suction_command"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    plant = station.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = shelf_pose(station_scenario, scene.camera).inverse()
    body = plant.GetBodyByName(name)

    def pose():
        X = (X_SW @ plant.EvalBodyPoseInWorld(plant_context, body)).GetAsMatrix4()
        return {"x": float(X[0, 3]), "y": float(X[1, 3]), "z": float(X[2, 3]), "yaw": math.atan2(X[1, 0], X[0, 0]),
                "tilt_deg": math.degrees(math.acos(min(1.0, abs(float(X[2, 2])))))}

    out = {}
    for t in sorted(times):
        simulator.AdvanceTo(t)
        out[t] = pose()
    simulator.AdvanceTo(motion.trajectory.duration + settle)
    out["end"] = pose()
    return out


class GuardedMotionSource(LeafSystem):
    """As :class:`MotionSource`, with the guarded push-in of the PlannerSystem (:mod:`slax_drake.systems.guard`):
    reads ``measured_state`` and ``measured_efforts`` every ``guard.period`` s while the push-in plays and, on
    contact, plays what :meth:`~slax_drake.systems.guard.Guard.stopped` makes from the measured positions instead
    (the planner's stop motion, or at the board's front edge its push-in again higher); an unguarded lift's push-in
    from outside the bay is watched only while a stop would be the board's edge. ``believed``: the Scene the motion
    was planned in. :meth:`record` is the guard's record (:func:`slax_drake.systems.guard.guard_record`)."""

    def __init__(self, motion, planner, believed, guard, expected: float = 0.0, threshold: float | None = None):
        from pydrake.common.value import AbstractValue

        LeafSystem.__init__(self)
        self.planner, self.believed, self.guard = planner, believed, guard
        world = planner.world(believed)
        frame = motion.waypoints[0].frame
        self._cup_y = lambda q: float(world.tool_pose_S(q, frame).translation()[1])
        n = len(motion.trajectory.names)
        self._n = n
        self._measured = self.DeclareVectorInputPort("measured_state", 2 * n)
        self._efforts = self.DeclareVectorInputPort("measured_efforts", n)
        from slax_drake.systems.guard import edge_stop_cup_y

        action = motion.action
        edge_only = action.kind == "suction" and not action.guarded and not action.drag  # watched at the edge only
        run = guard.start(motion, self._cup_y, expected, threshold, edge_only=edge_only)
        if run is not None:
            obj = next((o for o in believed.objects if o.name == action.name), None)
            edge = edge_stop_cup_y(action, obj, believed.shelf, run.y_start)
            run = None if edge_only and edge is None else dataclasses.replace(run, edge_cup_y=edge)
        start = (motion, 0.0, run, None)
        self._state = self.DeclareAbstractState(AbstractValue.Make(start))
        self.DeclarePeriodicUnrestrictedUpdateEvent(guard.period, 0.0, self._watch)
        ticket = {self.abstract_state_ticket(self._state)} | {self.time_ticket()}
        self.DeclareVectorOutputPort("desired_state", BasicVector(2 * n), self._desired, prerequisites_of_calc=ticket)
        self.DeclareVectorOutputPort("suction_command", BasicVector(1), self._suction, prerequisites_of_calc=ticket)

    def state(self, context):
        return context.get_abstract_state(self._state).get_value()

    def record(self, context) -> dict | None:
        return self.state(context)[3]

    def _desired(self, context, out):
        motion, t0, _, _ = self.state(context)
        q, v = motion.trajectory.value(context.get_time() - t0)
        out.SetFromVector(np.concatenate([q, v]))

    def _suction(self, context, out):
        motion, t0, _, _ = self.state(context)
        out.SetAtIndex(0, 1.0 if motion.suction_at(context.get_time() - t0) else 0.0)

    def _watch(self, context, state):
        from slax_drake.systems.guard import guard_record, past_edge_band

        motion, t0, run, record = self.state(context)
        if run is None:
            return
        t = context.get_time() - t0
        if t < run.t0:
            return
        x = self._measured.Eval(context)
        if t > run.t1 or (run.edge_only and past_edge_band(run, self._cup_y(x[:self._n]))):
            done = record if run.edge_only else guard_record(run, stopped=False)
            state.get_mutable_abstract_state(0).set_value((motion, t0, None, done))
            return
        run = self.guard.observe(run, motion, t, x[:self._n], x[self._n:], self._efforts.Eval(context))
        if not run.monitor.stopped:
            state.get_mutable_abstract_state(0).set_value((motion, t0, run, None))
            return
        now = context.get_time()
        after, again, record = self.guard.stopped(run, motion, np.asarray(x[:self._n], float), self.planner,
                                                  self.believed, self._cup_y, now)
        if after is None:  # an unguarded lift goes on as planned
            state.get_mutable_abstract_state(0).set_value((motion, t0, None, None))
            return
        state.get_mutable_abstract_state(0).set_value((after, now, again, None if again is not None else record))


def run_guarded_motion(station_scenario, scene, believed, motion, planner, names, expected: float = 0.0,
                       settle: float = 1.0) -> tuple[dict, dict]:
    """Runs a suction's ``motion`` (planned by ``planner`` in ``believed``) in the station on the true ``scene`` with
    the guard the PlannerSystem gives it (a guarded push-in; an unguarded lift's watch at the board's edge); returns
    ({name: {"x", "y", "z", "yaw", "tilt_deg"}} of the objects ``names`` at the end, in S; the guard's record, None
    when nothing was recorded)."""
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    from slax_drake.station.plant import shelf_pose
    from slax_drake.systems.guard import Guard
    from slax_drake.systems.station import MakeStation

    X_WS = shelf_pose(station_scenario, scene.camera)
    guard = Guard(station_scenario, X_WS.rotation().matrix(), station_scenario.guarded_stop_force)
    builder = DiagramBuilder()
    station = builder.AddSystem(MakeStation(station_scenario, scene, camera=False))
    threshold = None
    action = motion.action
    if not action.drag:  # a lift: the stop force the cup's hold allows (the PlannerSystem's rule)
        from slax_drake.shelf.actions import ActionModel
        from slax_drake.systems.guard import held_moment

        obj = next(o for o in believed.objects if o.name == action.name)
        model = ActionModel(believed.shelf, believed.camera.position, planner.tool)
        threshold = guard.stop_force(held_moment(model, obj, action), float(action.q[2]))
    source = builder.AddSystem(GuardedMotionSource(motion, planner, believed, guard, expected, threshold))
    builder.Connect(source.GetOutputPort("desired_state"), station.GetInputPort("desired_state"))
    builder.Connect(source.GetOutputPort("suction_command"), station.GetInputPort("suction_command"))
    builder.Connect(station.GetOutputPort("measured_state"), source.GetInputPort("measured_state"))
    builder.Connect(station.GetOutputPort("measured_efforts"), source.GetInputPort("measured_efforts"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    source_context = source.GetMyContextFromRoot(context)
    t_end = motion.trajectory.duration
    while True:
        played, t0, _, _ = source.state(source_context)
        t_end = t0 + played.trajectory.duration
        if context.get_time() >= t_end + settle - 1e-9:
            break
        simulator.AdvanceTo(min(t_end + settle, context.get_time() + 1.0))
    plant = station.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = X_WS.inverse()
    out = {}
    for name in names:
        X = (X_SW @ plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName(name))).GetAsMatrix4()
        out[name] = {"x": float(X[0, 3]), "y": float(X[1, 3]), "z": float(X[2, 3]), "yaw": math.atan2(X[1, 0], X[0, 0]),
                     "tilt_deg": math.degrees(math.acos(min(1.0, abs(float(X[2, 2])))))}
    return out, source.record(source_context)
