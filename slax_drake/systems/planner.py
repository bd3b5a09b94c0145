"""PlannerSystem: the Bluction-DAR (or any registered) policy and the motion planner as a Drake LeafSystem.

Every ``decision_period`` seconds an unrestricted update checks whether the robot is idle (its last motion
ended ``settle_time`` ago). When it is, the system observes through its input ports and decides:

1. the objects' poses from ``body_poses`` (shelf frame S via the station's X_WS; yaw about z); an object whose
   z axis tilts more than 20 deg counts as toppled, one outside the bay as dropped (neither is moved again);
2. the target's visible fraction from ``label_image``: its pixels over the pixels the target covers with no
   occluder (ray-cast once); the trial stops with success at v (0.80), or after H = 2n actions;
3. the observation for the policy: ``depth_image``; the objects seen (any pixel in ``label_image``, the
   idealised segmentation of the shelf simulator) with their poses; P_t from the policy's distribution model on
   the current objects (ground truth; the PerceptionSystem's ``occupancy_1d`` is not wired in yet);
4. the policy (any :class:`~slax_drake.policies.protocol.Policy` that reads an Observation; the very code the shelf
   simulator runs) ranks the candidates with ``decide``; the best one is planned
   (:class:`slax_drake.planning.planner.MotionPlanner`); an infeasible motion is logged with its reason and
   handed back with ``policy.exclude`` (the whole group when the tool could not reach the object), and the policy
   decides again (its next candidate). The planner touches the policy through the protocol only.

Outputs: ``desired_state`` (18: q and v of ``PLANNED_JOINTS``, sampled from the running motion, else holding
the last pose) and ``suction_command`` (1).

State: everything the trial accumulates lives in the context, in one abstract state value (:class:`TrialState`):
the running motion, the step count, the decision log (a tuple of dicts, for the trial record), the executed motions
(start time, PlannedMotion), the result ("revealed", "horizon", "no feasible action", ...), the last visible
fraction and the cost. An initialization event resets it and the policy (``policy.reset``), so
``Simulator.Initialize`` on a reset context replays the same trial. Read it with :meth:`PlannerSystem.trial_state`.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I

from slax_drake.planning.planner import MotionPlanner
from slax_drake.policies.actions import Push
from slax_drake.policies.distribution import support
from slax_drake.policies.simulator import Observation
from slax_drake.scene.model import Scene, planar_pose
from slax_drake.station import robot as robot_model

TOPPLE_ANGLE = math.radians(20.0)
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
    visible_fraction: float = 0.0  # at the last decision
    cost: float = 0.0  # pushes 1, suctions ``suction_cost``

    def __deepcopy__(self, memo):
        return self


class PlannerSystem(LeafSystem):
    """See the module docstring. ``policy``: a :class:`~slax_drake.policies.protocol.Policy` reading an
    Observation, built with its action model; ``scene``: the trial's initial scene (its objects' names and
    shapes, the camera); ``body_indices``: the plant's BodyIndex of each scene object (scene order) and of the
    target; ``suction_cost``: psi, the cost of a suction (a push costs 1)."""

    def __init__(self, policy, planner: MotionPlanner, scene: Scene, body_indices, target_body, X_WS,
                 horizon: int, threshold: float = 0.80, decision_period: float = 0.1, settle_time: float = 0.5,
                 image_size=(640, 480), on_step=None, suction_cost: float = 1.3):
        LeafSystem.__init__(self)
        if policy.needs_true_scene:
            raise ValueError(f"policy '{policy.name}' needs the true scene (an oracle): it cannot run on a station")
        self.policy = policy
        self.planner = planner
        self.scene = scene
        self.body_indices = list(body_indices)
        self.target_body = target_body
        self.X_SW = X_WS.inverse()
        self.horizon = horizon
        self.threshold = threshold
        self.settle_time = settle_time
        self.suction_cost = suction_cost
        self.on_step = on_step
        self._q_obs = planner.q_observation.copy()
        self._target_pixels = None  # a cache of a pure function of the scene and image size, not trial state
        n = len(robot_model.PLANNED_JOINTS)
        w, h = image_size
        self._measured = self.DeclareVectorInputPort("measured_state", 2 * n)
        self._depth = self.DeclareAbstractInputPort("depth_image", AbstractValue.Make(ImageDepth32F(w, h)))
        self._labels = self.DeclareAbstractInputPort("label_image", AbstractValue.Make(ImageLabel16I(w, h)))
        self._poses = self.DeclareAbstractInputPort("body_poses", AbstractValue.Make([X_WS]))
        self._state = self.DeclareAbstractState(AbstractValue.Make(TrialState()))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)
        self.DeclarePeriodicUnrestrictedUpdateEvent(decision_period, 0.0, self._update)
        self.DeclareVectorOutputPort("desired_state", BasicVector(2 * n), self._calc_desired,
                                     prerequisites_of_calc={self.abstract_state_ticket(self._state)} | {self.time_ticket()})
        self.DeclareVectorOutputPort("suction_command", BasicVector(1), self._calc_suction,
                                     prerequisites_of_calc={self.abstract_state_ticket(self._state)} | {self.time_ticket()})

    def trial_state(self, root_context) -> TrialState:
        """The trial so far in ``root_context`` (the root diagram's context)."""
        return self.GetMyContextFromRoot(root_context).get_abstract_state(self._state).get_value()

    def _initialize(self, context, state):
        self.policy.reset(self.scene)
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

    # decisions -------------------------------------------------------------------------------------------
    def _update(self, context, state):
        s = self._plan_state(context)
        now = context.get_time()
        if s.done:
            return
        if s.motion is not None:
            t_end = s.t_start + s.motion.trajectory.duration
            if now < t_end + self.settle_time:
                return
        elif now < self.settle_time:
            return
        state.get_mutable_abstract_state(0).set_value(self._decide(context, s, now))

    def current_scene(self, context) -> tuple[Scene, list[str]]:
        """The objects as they stand now (planar poses in S) and the names of toppled or dropped objects."""
        poses = self._poses.Eval(context)
        objects, lost = [], []
        shelf = self.scene.shelf
        for obj, index in zip(self.scene.objects, self.body_indices):
            X_SO = (self.X_SW @ poses[int(index)]).GetAsMatrix4()
            z_axis = X_SO[:3, 2]
            c = X_SO[:3, 3]
            tilt = math.acos(min(1.0, max(-1.0, abs(z_axis[2]))))
            inside = abs(c[0]) < shelf.width / 2 and abs(c[1]) < shelf.depth / 2 and -0.02 < c[2] < shelf.height
            if tilt > TOPPLE_ANGLE or not inside:
                lost.append(obj.name)
            yaw = math.atan2(X_SO[1, 0], X_SO[0, 0])
            objects.append(dataclasses.replace(obj, X_SO=planar_pose(float(c[0]), float(c[1]), obj.size[2] / 2.0, yaw)))
        return self.scene.with_objects(tuple(objects)), lost

    def target_visible_fraction(self, labels: np.ndarray) -> float:
        """Target pixels in the label image over the target's pixels with no occluder (ray-cast once)."""
        target_label = len(self.scene.objects) + 1
        if self._target_pixels is None:
            from slax_drake.scene.raycast import SceneRaycaster

            h, w = labels.shape
            alone = self.scene.with_objects(())
            _, lab = SceneRaycaster(alone, include_target=True).render(self.scene.camera.with_resolution(w, h))
            self._target_pixels = max(1, int(np.count_nonzero(lab == 1)))
        return float(np.count_nonzero(labels == target_label)) / self._target_pixels

    def _decide(self, context, s: TrialState, now: float) -> TrialState:
        depth = np.array(self._depth.Eval(context).data[:, :, 0], dtype=np.float32)
        raw = np.array(self._labels.Eval(context).data[:, :, 0], dtype=np.int32)
        n_obj = len(self.scene.objects)
        labels = np.where((raw >= 0) & (raw <= n_obj + 1), raw, -1)
        fraction = self.target_visible_fraction(labels)
        s = dataclasses.replace(s, visible_fraction=fraction)
        measured = self._measured.Eval(context)[: len(self._q_obs)]
        scene_now, lost = self.current_scene(context)
        entry = {"step": s.steps, "time": round(now, 4), "visible_fraction": round(fraction, 4), "lost": lost,
                 "poses_before": {o.name: {"x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                                           "yaw": round(float(o.yaw), 5)} for o in scene_now.objects}}
        if fraction >= self.threshold:
            return self._finish(s, "revealed", entry, depth, labels)
        if s.steps >= self.horizon:
            return self._finish(s, "horizon", entry, depth, labels)
        seen = set(int(v) - 1 for v in np.unique(labels) if 0 < v <= n_obj)
        known = tuple(o for i, o in enumerate(scene_now.objects) if i in seen and o.name not in lost)
        policy = self.policy
        p1d = policy.distribution.distribution(scene_now.with_objects(tuple(o for o in scene_now.objects if o.name not in lost)))
        template = dataclasses.replace(scene_now, objects=known, target=None)
        obs = Observation(depth, labels, known, p1d, template)
        rejected = []
        t0 = time.perf_counter()
        motion, action, decide_s = None, None, 0.0
        for _ in range(MAX_PLAN_ATTEMPTS):
            td = time.perf_counter()
            action = policy.decide(obs).best
            decide_s += time.perf_counter() - td
            if action is None:
                break
            result = self.planner.plan(action, scene_now, q_start=measured)
            if result.feasible:
                motion = result
                break
            rejected.append({"action": action.describe(), "reason": result.reason,
                             "planning_s": result.timings.get("total_s")})
            policy.exclude(action, result.reason, whole_group=result.reason.startswith(EARLY_FAILURES))
            action = None
        history = policy.history
        entry["support"] = support(history)
        entry["p1d"] = np.round(obs.p1d, 6).tolist()
        entry["history"] = np.round(history, 6).tolist()
        entry["rejected"] = rejected
        entry["decision_s"] = round(decide_s, 4)
        entry["planning_s"] = round(time.perf_counter() - t0 - decide_s, 4)
        if motion is None:
            return self._finish(s, "no feasible action" if not rejected else "no feasible motion", entry, depth,
                                labels)
        entry["action"] = _describe(action)
        entry["motion"] = {"duration_s": round(motion.trajectory.duration, 3), "timings": motion.timings,
                           "max_deviation_m": round(motion.max_deviation, 5),
                           "waypoint_times": motion.waypoint_times, "suction_intervals": motion.suction_intervals}
        entry["predicted_objects"] = _predicted(scene_now.objects, action)
        if self.on_step is not None:
            self.on_step(entry, depth, labels, history, obs.p1d)
        return dataclasses.replace(
            s, motion=motion, t_start=now, steps=s.steps + 1, log=s.log + (entry,), motions=s.motions + ((now, motion),),
            cost=s.cost + (1.0 if isinstance(action, Push) else self.suction_cost))

    def _finish(self, s: TrialState, result: str, entry: dict, depth, labels) -> TrialState:
        entry["final"] = True
        entry["result"] = result
        if self.on_step is not None:
            self.on_step(entry, depth, labels, self.policy.history, None)
        motion = None if result.startswith("no feasible") else s.motion  # hold the last motion's end pose
        return dataclasses.replace(s, done=True, motion=motion, result=result, log=s.log + (entry,))


# A planning failure before the tool reaches the object (its waypoint label leads the reason): no action of that
# group (pushes of the object in that direction, or its suctions) can run from here.
EARLY_FAILURES = ("pre-approach", "insert", "approach", "segment to pre-approach", "segment to insert",
                  "segment to approach", "seal")


def _describe(action) -> dict:
    if isinstance(action, Push):
        return {"type": "push", "object": action.name, "q": list(action.q), "d": action.d}
    return {"type": "suction", "object": action.name, "q": list(action.q), "dx": action.dx, "dz": action.dz}


def _predicted(objects, action) -> dict:
    from slax_drake.policies.actions import apply_action

    moved = next(o for o in apply_action(tuple(objects), action) if o.name == action.name)
    return {"object": action.name, "x": round(float(moved.center[0]), 5), "y": round(float(moved.center[1]), 5),
            "yaw": round(float(moved.yaw), 5)}
