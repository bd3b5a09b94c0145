"""One search step for a real robot from one camera frame: ``slax-drake plan-step``.

Inputs (files, as a robot's driver writes them):

- the station scenario (YAML): the robot, the shelf, the camera model (through its ``scene_config``), the cup;
- the depth frame: ``.npy`` float32/float64 metres along the optical axis, or a 16-bit ``.png`` in millimetres
  (the RealSense convention), 0 = no return; any resolution with the camera's aspect ratio;
- the target mask: a ``.png`` (or ``.npy``) of the frame's size, non-zero where the target's colour was detected;
- the joint state: JSON ``{"joint_names": [...], "positions": [...]}`` holding at least the nine planned joints
  (``slax_drake.station.robot.PLANNED_JOINTS``; radians, metres for the torso and the tool shaft), or
  ``{name: position}``;
- optionally the history: the previous ``step.json`` (or its ``metadata.plan_step.history``): P'_{t-1}, the step
  count, the tracked objects and the frames of the earlier steps with what was decided on them. Those steps are
  replayed through the same perception and policy before this one (:mod:`slax_drake.hardware.step_memory`), so the
  policy remembers its search as in a simulated trial: a push that moved nothing is not planned again, an object is
  not moved back and forth, no arrangement already observed is returned to.

What it does, with nothing but the frame: the frame is validated (:class:`~slax_drake.perception.observation.
Observation`: an unusable frame -- wrong size or type, millimetres given as metres, mostly no returns -- is refused
with one line, exit code 2), resampled to the policies' working resolution (160 px wide, nearest pixel), segmented
from depth alone, turned into object hypotheses by the estimator and into P_t (hidden target placements judged from
the depth image); the policy (Bluction-DAR by default) ranks the actions on the hypotheses, predicting each one's
distribution from the shifted segments; the best one is planned by the motion planner against the believed scene
(the hypotheses and the shelf) from the measured joint state, Ruckig-timed, exported in the export format
(:mod:`slax_drake.hardware.trajectory_file`, ros-json) and checked by the independent checker
(:func:`slax_drake.hardware.check.check_trajectory`: Fetch limits, jerk, continuity, collisions with the believed
scene). A candidate whose motion fails planning or the check is excluded and the next one is tried.

Output ``step.json``: the trajectory document (``slax-drake check-trajectory step.json`` reads it; the believed
scene is embedded for its collision check), with ``metadata.plan_step``: the chosen action, its hypothesis, the
hypotheses, the check report, timings and the updated history, and ``guarded_push_in``: for a guarded suction (a
placement reaching into space the camera cannot see, on a station with ``guarded_placement``) the push-in's time
window and stop force (also in the motion's ``action``, where the checker reads it), which the arm's controller
must run as a guarded move; None for any other action; ``edge_watch``: for an unguarded lift whose object comes
into the bay from outside, the first part of its push-in the controller watches for the board's front edge
(a stop there: rise and push in again); and ``weigh``: what the controller weighs and when it undoes
the action, for a lift at its lift (the load the cup holds) and, under the ``weigh_drag_pull`` rule, for a sideways
drag along its pull (the floor's friction, against the most the cup's twist limit allows); None for any other
action. When no action is left it still writes the file, with no motion and the reason.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path

import numpy as np

from slax_drake.errors import PlanStepError
from slax_drake.perception.observation import resample_nearest

WORKING_WIDTH = 160
MAX_CANDIDATES = 25
# m: depth segmentation's margin from the shelf's panels for a real (noisy) frame: the L515's range noise and
# offset (a few mm at 1 m) otherwise turn back-panel and floor pixels into thin spurious segments.
PANEL_MARGIN = 0.015
# m^2: the estimator's footprint overlap allowed between hypotheses; the exported scene (the checker's world) must
# hold no two bodies interpenetrating by more than 1 mm (slax_drake.scene.io), a looser area bound lets through.
HYPOTHESIS_OVERLAP = 1e-6
# rad (m for the torso): a measured joint this far beyond its limit (encoder noise at a hard stop) is still taken
JOINT_LIMIT_TOLERANCE = 1e-3


@dataclasses.dataclass
class StepResult:
    """What one step produced: the exported trajectory (None when nothing is executable), the action's
    description, the reason when there is none, and the timings (s)."""

    trajectory: object
    action: dict | None
    reason: str | None
    timings: dict
    visibility: dict | None = None  # StepPlanner.target_visibility of the frame


def _existing(path: str | Path, what: str) -> Path:
    path = Path(path)
    if not path.is_file():
        raise PlanStepError(f"{path}: no such {what} file")
    return path


def _load_npy(path: Path) -> np.ndarray:
    try:
        return np.load(path, allow_pickle=False)
    except (ValueError, OSError) as e:
        raise PlanStepError(f"{path}: not a numpy array file ({e})") from None


def _load_json(path: Path, what: str):
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise PlanStepError(f"{path}: no such {what} file") from None
    except (OSError, json.JSONDecodeError) as e:
        raise PlanStepError(f"{path}: not valid JSON ({e})") from None


def read_depth(path: str | Path) -> np.ndarray:
    """A depth frame in metres (float32): ``.npy`` (float metres) or 16-bit ``.png`` (millimetres)."""
    path = _existing(path, "depth")
    if path.suffix.lower() == ".npy":
        depth = _load_npy(path)
        if depth.ndim != 2:
            raise PlanStepError(f"{path}: a depth frame must be a 2D array (rows, columns), got shape {depth.shape}")
        return depth  # dtype and units are checked by Observation
    if path.suffix.lower() == ".png":
        import cv2

        image = cv2.imread(str(path), cv2.IMREAD_ANYDEPTH | cv2.IMREAD_UNCHANGED)
        if image is None:
            raise PlanStepError(f"{path}: not a readable PNG")
        if image.ndim != 2 or image.dtype != np.uint16:
            raise PlanStepError(f"{path}: a depth PNG must be single-channel 16-bit millimetres, got "
                                f"{image.dtype} with shape {image.shape}")
        return image.astype(np.float32) / 1000.0
    raise PlanStepError(f"{path}: depth must be .npy (metres) or .png (16-bit millimetres)")


def read_mask(path: str | Path) -> np.ndarray:
    """The target mask (bool): non-zero pixels of a ``.png`` (any channel) or ``.npy``."""
    path = _existing(path, "target-mask")
    if path.suffix.lower() == ".npy":
        mask = _load_npy(path)
    else:
        import cv2

        mask = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if mask is None:
            raise PlanStepError(f"{path}: not a readable image")
    mask = np.asarray(mask)
    if mask.ndim == 3:
        mask = mask.any(axis=2)
    if mask.ndim != 2:
        raise PlanStepError(f"{path}: a target mask must be a 2D image, got shape {mask.shape}")
    return mask != 0


def read_joint_state(path: str | Path) -> np.ndarray:
    """The nine planned joints' positions (PLANNED_JOINTS order) from the joint-state JSON."""
    from slax_drake.station.robot import PLANNED_JOINTS

    path = Path(path)
    doc = _load_json(path, "joint-state")
    if isinstance(doc, dict) and "joint_names" in doc and "positions" in doc:
        names, values = doc["joint_names"], doc["positions"]
        if not isinstance(names, list) or not isinstance(values, list) or len(names) != len(values):
            raise PlanStepError(f"{path}: joint_names and positions must be lists of one length")
        doc = dict(zip(names, values))
    if not isinstance(doc, dict):
        raise PlanStepError(f"{path}: expected {{\"joint_names\": [...], \"positions\": [...]}} or {{name: position}}")
    missing = [n for n in PLANNED_JOINTS if n not in doc]
    if missing:
        raise PlanStepError(f"{path}: joint state lacks {', '.join(missing)}")
    try:
        q = np.array([float(doc[n]) for n in PLANNED_JOINTS])
    except (TypeError, ValueError):
        raise PlanStepError(f"{path}: joint positions must be numbers") from None
    if not np.all(np.isfinite(q)):
        raise PlanStepError(f"{path}: joint positions must be finite")
    return q


def read_history(path: str | Path | None) -> dict | None:
    """The history a previous step wrote: ``{"policy", "steps", "history": [P'_(t-1)]}``; from a step.json or a
    file holding that dict."""
    if path is None:
        return None
    path = Path(path)
    doc = _load_json(path, "history")
    if isinstance(doc, dict) and "metadata" in doc:
        doc = (doc.get("metadata") or {}).get("plan_step", {}).get("history")
    if not isinstance(doc, dict) or not isinstance(doc.get("history"), list):
        raise PlanStepError(f"{path}: no history (expected a step.json written by plan-step, or "
                            "{\"policy\": ..., \"steps\": k, \"history\": [...]})")
    return doc


class StepPlanner:
    """Everything that does not change between frames: the station, the camera, the policy, the motion planner.
    ``perceive`` and ``decide`` are the timed part of a step (benchmarks/bench_plan_step.py); ``plan_step`` adds
    motion planning, export and the check."""

    def __init__(self, station_path: str | Path, policy: str = "bluction-dar", width: int = WORKING_WIDTH,
                 tool_rules: dict | None = None):
        from slax_drake.config import load_scenario
        from slax_drake.perception.belief import DepthDistribution, background_depth
        from slax_drake.policies.registry import make_policy
        from slax_drake.scene.camera import Camera
        from slax_drake.scene.sampling import shelf_of
        from slax_drake.station.scenario import load_station_scenario
        from slax_drake.systems.trial import station_tool_rules

        self.station_path = str(station_path)
        self.station = load_station_scenario(station_path)
        self.scenario = load_scenario(self.station.scene_config)
        self.camera = Camera.from_config(self.scenario.camera)
        self.shelf = shelf_of(self.scenario)
        # the rules it plans with: the station's, ``tool_rules`` (--tool-rule) on top
        self.tool_rules = station_tool_rules(self.station, tool_rules)
        self.policy_name = policy
        self.policy = make_policy(policy, self.scenario, tool_overrides=self.tool_rules)
        if self.policy.needs_true_scene:
            raise PlanStepError(f"policy '{policy}' needs the true scene (an oracle): it cannot plan from a frame")
        self.target_size = tuple(self.scenario.target.sizes[0])
        height = max(1, int(round(self.camera.height * width / self.camera.width)))
        self.working = self.camera.with_resolution(width, height)
        self.source = DepthDistribution(self.shelf, self.target_size)
        self.background = background_depth(self.shelf, self.working)
        self._motion_planner = None
        self.tracker = None  # the object tracker of the last perceive (its state goes into the step file)

    def frame_camera(self, depth: np.ndarray):
        """The camera at the frame's resolution (same aspect as the station camera's, else refused)."""
        h, w = depth.shape
        if w * self.camera.height != h * self.camera.width:
            raise PlanStepError(f"depth frame {w}x{h} does not have the camera's aspect "
                                f"({self.camera.width}x{self.camera.height})")
        return self.camera.with_resolution(w, h)

    def working_frame(self, depth: np.ndarray, mask: np.ndarray, joint_state=None):
        """(depth, target mask) at the policies' working resolution (nearest pixel) after validating the frame
        (:class:`~slax_drake.perception.observation.Observation`; raises ObservationError for an unusable one)."""
        from slax_drake.perception.observation import Observation

        camera = self.frame_camera(np.asarray(depth))
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != np.asarray(depth).shape:
            raise PlanStepError(f"target mask of shape {mask.shape} and depth frame of shape {np.shape(depth)} differ")
        full = Observation(depth, np.zeros(mask.shape, np.int32), mask, camera, joint_state)  # validates the frame
        w, h = self.working.width, self.working.height
        return resample_nearest(full.depth, w, h), resample_nearest(full.target_mask, w, h)

    def perceive(self, depth: np.ndarray, mask: np.ndarray, joint_state=None, history: dict | None = None,
                 replayed=None):
        """Frame -> (the policy's PolicyObservation, the ObservedBelief). Raises ObservationError for an unusable
        frame. The hypotheses are named by the objects tracked so far (:class:`~slax_drake.perception.tracking.
        ObjectTracker`) and the action last planned: ``replayed`` (the tracker and the last action :meth:`replay`
        left), else the tracker's state and the action in ``history`` (``tracks`` and ``action``, as the previous
        step wrote them), else a new tracker. The updated state is written by this step."""
        from slax_drake.perception.tracking import ObjectTracker

        small_depth, small_mask = self.working_frame(depth, mask, joint_state)
        if replayed is not None:
            self.tracker, last = replayed
        else:
            tracks = (history or {}).get("tracks")
            self.tracker = ObjectTracker.from_dict(tracks) if isinstance(tracks, dict) else ObjectTracker()
            last = _action_of((history or {}).get("action"))
        return self._perceive_working(small_depth, small_mask, joint_state, last)

    def _perceive_working(self, small_depth, small_mask, joint_state, last):
        """:meth:`perceive` on a frame already at the working resolution, with ``self.tracker`` and the action
        ``last`` planned before it (None: none)."""
        from slax_drake.perception.belief import ObservedBelief
        from slax_drake.perception.estimator import EstimatorConfig, estimate_objects
        from slax_drake.perception.observation import Observation, occluder_segmentation
        from slax_drake.perception.segmentation import segment_depth
        from slax_drake.shelf.simulator import PolicyObservation
        from slax_drake.scene.model import Scene

        segments = occluder_segmentation(segment_depth(small_depth, self.working, self.shelf, margin=PANEL_MARGIN),
                                         small_mask)
        frame = Observation(small_depth, segments, small_mask, self.working, joint_state, min_valid_fraction=0.0)
        config = EstimatorConfig(overlap_tolerance=HYPOTHESIS_OVERLAP)
        hypotheses = self.tracker.update(estimate_objects(frame, self.shelf, config), last, frame,
                                         Scene(self.shelf, self.working, (), None))
        belief = ObservedBelief(frame, self.shelf, self.source, background=self.background, hypotheses=hypotheses,
                                config=config, remembered=self.tracker.hidden())
        believed = Scene(self.shelf, self.camera, belief.known, None)
        return PolicyObservation(small_depth, segments, belief.known, belief.p1d, believed, belief), belief

    def replay(self, history: dict | None):
        """Rebuilds the policy's memory of this search (:mod:`slax_drake.hardware.step_memory`): the steps recorded
        in ``history["frames"]`` are perceived and decided again in order, each candidate the planner rejected there
        excluded again, and each must choose the action that step chose (else PlanStepError: the history was
        written by another policy or code version). Leaves the policy as it stood after the last recorded step and
        returns (the tracker, the last step's action), or None when the history records no frames (a first step,
        or a history of an older plan-step, which carries only P'_(t-1) and the tracks)."""
        from slax_drake.hardware.step_memory import decode_frame
        from slax_drake.perception.tracking import ObjectTracker
        from slax_drake.systems.planner import _describe

        frames = (history or {}).get("frames") or []
        if not frames:
            return None
        if history.get("policy") not in (None, self.policy_name):
            raise PlanStepError(f"the history was planned by policy '{history.get('policy')}', this step by "
                                f"'{self.policy_name}': give the same --policy (or start a new history)")
        recorded = history.get("tool_rules")  # None: a history written before plan-step recorded its rules
        if recorded is not None and recorded != self.tool_rules:
            differ = "; ".join(f"{k}: {recorded.get(k)!r} there, {self.tool_rules.get(k)!r} here"
                               for k in sorted(set(recorded) | set(self.tool_rules))
                               if recorded.get(k) != self.tool_rules.get(k))
            raise PlanStepError(f"the history was planned with other action-model rules than this step ({differ}): "
                                "give the same --tool-rule (or start a new history)")
        self.tracker, last = ObjectTracker(), None  # _perceive_working updates self.tracker
        for k, record in enumerate(frames, 1):
            depth, mask, q = decode_frame(record, k)
            if depth.shape != (self.working.height, self.working.width):
                raise PlanStepError(f"history step {k}: a {depth.shape[1]}x{depth.shape[0]} frame, this planner works "
                                    f"at {self.working.width}x{self.working.height}")
            observation, _ = self._perceive_working(depth, mask, q, last)
            if k == 1:
                self.policy.reset(observation.scene_template)
            decision = self.policy.decide(observation)
            for rejected in record.get("rejected") or []:
                if not isinstance(rejected, dict):
                    raise PlanStepError(f"history step {k}: a rejected candidate must be a record, got {rejected!r}")
                if decision.best is None or _describe(decision.best) != rejected.get("candidate"):
                    raise _diverged(k, decision.best, rejected.get("candidate"))
                self.policy.exclude(decision.best, str(rejected.get("reason")), bool(rejected.get("whole_group")))
                decision = self.policy.decide(observation)
            if decision.best is None or _describe(decision.best) != record.get("action"):
                raise _diverged(k, decision.best, record.get("action"))
            last = decision.best
        return self.tracker, last

    def decide(self, observation, history: dict | None = None):
        """The policy's Decision on ``observation``, after restoring ``history`` (P'_{t-1})."""
        self.policy.reset(observation.scene_template)
        if history is not None and history["history"]:  # an empty one: P'_(t-1) not carried (a new history)
            previous = np.asarray(history["history"], dtype=float)
            if previous.shape != np.shape(observation.p1d):
                raise PlanStepError(f"history has {previous.size} columns, this step's distribution "
                                    f"{np.size(observation.p1d)} (another resolution or policy?)")
            self.policy.resume(previous)
        return self.policy.decide(observation)

    @property
    def motion_planner(self):
        if self._motion_planner is None:
            from slax_drake.planning.planner import MotionPlanner
            from slax_drake.shelf.tool import tool_config

            self._motion_planner = MotionPlanner(self.station, tool_config(self.scenario, **self.tool_rules))
        return self._motion_planner

    def check_joint_state(self, q, source: str = "joint state") -> None:
        """PlanStepError when a planned joint lies outside the station robot's position limits by more than
        ``JOINT_LIMIT_TOLERANCE`` (no motion can start there)."""
        from slax_drake.station.robot import PLANNED_JOINTS
        from slax_drake.station.scenario import joint_position_limits

        lower, upper = joint_position_limits(self.station)
        for name, value in zip(PLANNED_JOINTS, np.asarray(q, float)):
            lo, hi = lower.get(name, -np.inf), upper.get(name, np.inf)
            if not lo - JOINT_LIMIT_TOLERANCE <= value <= hi + JOINT_LIMIT_TOLERANCE:
                raise PlanStepError(f"{source}: {name} = {value:g} lies outside its limits [{lo:g}, {hi:g}] (rad, "
                                    "m for the torso): no motion can start there")

    def target_visibility(self, depth, mask) -> dict:
        """How much of the target the frame shows: ``seen`` (mask pixels), ``expected`` (the pixels the target's
        known size covers, unoccluded, standing on the shelf floor where the mask's centre is seen, at the mask's
        median depth: its front face at that depth; ray-cast like the referee's count), ``share`` = seen /
        expected (None when the mask is empty or has no valid depth) and ``revealed``: share >= the scenario's
        ``target.visibility_threshold`` v."""
        from slax_drake.scene.model import Scene, Target
        from slax_drake.scene.raycast import SceneRaycaster

        depth = np.asarray(depth, float)
        mask = np.asarray(mask, bool)
        threshold = float(self.scenario.target.visibility_threshold)
        seen = int(np.count_nonzero(mask))
        valid = mask & np.isfinite(depth) & (depth > 0)
        if not valid.any():
            return {"seen": seen, "expected": None, "share": None, "revealed": False, "threshold": threshold}
        camera = self.frame_camera(depth)
        z = float(np.median(depth[valid]))
        rows, cols = np.nonzero(valid)
        u, v = float(np.mean(cols)) + 0.5, float(np.mean(rows)) + 0.5
        point_C = np.array([(u - camera.cx) / camera.fx * z, (v - camera.cy) / camera.fy * z, z, 1.0])
        point_S = np.asarray(camera.X_SC, float) @ point_C
        sx, sy, sz = self.target_size
        X_ST = np.eye(4)
        X_ST[:3, 3] = [point_S[0], point_S[1] + sy / 2.0, sz / 2.0]
        alone = Scene(self.shelf, camera, (), Target(tuple(self.target_size), X_ST))
        _, labels = SceneRaycaster(alone, include_target=True).render(camera)
        expected = int(np.count_nonzero(labels == 1))
        share = seen / expected if expected else None
        return {"seen": seen, "expected": expected, "share": share, "threshold": threshold,
                "revealed": share is not None and share >= threshold}

    def plan_step(self, depth, mask, q, history: dict | None = None, source: str | None = None,
                  collision_step: float = 0.005) -> StepResult:
        """Perceive, decide, plan, export and check (module docstring). A target already revealed (its visible
        share, :meth:`target_visibility`, at least v) plans nothing."""
        from slax_drake.hardware.check import check_trajectory
        from slax_drake.hardware.collision import CollisionWorld
        from slax_drake.systems.planner import _describe

        self.check_joint_state(q)
        timings = {}
        t0 = time.perf_counter()
        replayed = self.replay(history)
        timings["replay_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        observation, belief = self.perceive(depth, mask, q, history, replayed)
        visibility = self.target_visibility(depth, mask)
        timings["perception_s"] = time.perf_counter() - t0
        frame = (observation.depth, observation.belief.observation.target_mask, q)  # recorded for the next step
        if visibility["revealed"]:
            reason = (f"the target is revealed: {visibility['share']:.0%} of the {visibility['expected']} pixels "
                      f"its size covers are seen (v = {visibility['threshold']:.0%})")
            return self._nothing(q, source, belief, observation, [], history, timings, reason, visibility)
        t0 = time.perf_counter()
        decision = self.decide(observation, history) if replayed is None else self.policy.decide(observation)
        timings["decision_s"] = time.perf_counter() - t0
        believed = observation.scene_template
        rejected, reason = [], decision.stop_reason
        t0 = time.perf_counter()
        world = None
        for _ in range(MAX_CANDIDATES):
            action = decision.best
            if action is None:
                reason = decision.stop_reason or reason or "no feasible action"
                break
            motion = self.motion_planner.plan(action, believed, q_start=q)
            if motion.feasible:
                traj = self._export(action, motion, belief, q, source)
                guarded = self._guarded_push_in(action, motion, belief.known, believed.shelf)
                edge_watch = self._edge_watch(action, motion, belief.known, believed.shelf)
                if guarded is not None:  # the checker reads it from the motion (hardware.check)
                    traj.motions[0].action["guarded_push_in"] = dict(guarded)
                weigh = self._weigh_at_lift(action, motion, belief) or self._weigh_along_pull(action, motion, belief)
                world = world or CollisionWorld(self.station, believed)
                report = check_trajectory(traj, world, collision_step=collision_step)
                if report.ok:
                    timings["planning_s"] = time.perf_counter() - t0
                    traj.metadata["plan_step"] = self._record(action, belief, observation, rejected, report,
                                                              history, timings, visibility=visibility, frame=frame)
                    traj.metadata["plan_step"]["guarded_push_in"] = guarded
                    traj.metadata["plan_step"]["edge_watch"] = edge_watch
                    traj.metadata["plan_step"]["weigh"] = weigh
                    return StepResult(traj, traj.metadata["plan_step"]["action"], None, timings, visibility)
                why, early, kind, waypoint = "check: " + report.summary().splitlines()[-1], False, "check", None
            else:
                why, early = motion.reason, motion.failure.early  # failed before the tool reached the object
                kind, waypoint = motion.failure.kind.value, motion.failure.waypoint
            rejected.append({"action": action.describe(), "candidate": _describe(action), "reason": why, "kind": kind,
                             "waypoint": waypoint, "whole_group": bool(early)})
            self.policy.exclude(action, why, whole_group=early)
            decision = self.policy.decide(observation)
            reason = "no feasible motion"
        timings["planning_s"] = time.perf_counter() - t0
        result = self._nothing(q, source, belief, observation, rejected, history, timings, reason, visibility)
        from slax_drake.systems.planner import stop_record

        # why no action was planned: the action model's refusals and the planner's rejections by kind
        record = stop_record(self.policy, observation.known, rejected, decision.stop_reason)
        result.trajectory.metadata["plan_step"].update({k: v for k, v in record.items() if k != "excluded"})
        return result

    def _nothing(self, q, source, belief, observation, rejected, history, timings, reason, visibility):
        """The step file of a step that plans no motion, with ``reason``."""
        from slax_drake.hardware.trajectory_file import ExportedTrajectory

        empty = ExportedTrajectory([], {"source": source, "station": self.station_path,
                                        "initial_positions": list(map(float, q))})
        empty.metadata["plan_step"] = self._record(None, belief, observation, rejected, None, history, timings,
                                                   reason, visibility)
        return StepResult(empty, None, reason, timings, visibility)

    # ---------------------------------------------------------------------------------------------------------
    def _export(self, action, motion, belief, q, source):
        """The planned motion in the export format (one motion from t = 0; the planner's 1 ms records, every 10th
        and the last)."""
        from slax_drake.hardware.export import export_trial
        from slax_drake.scene.model import Scene
        from slax_drake.systems.planner import _describe

        record = motion.trajectory  # from the measured joint state q, at rest, 1 ms records
        poses = {o.name: {"x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                          "yaw": round(float(o.yaw), 5)} for o in belief.known}
        data = {
            "executed_trajectory": record.to_dict(stride=10, keep_times=[0.0]),
            "actions": [{**_describe(action), "motion": {"duration_s": round(motion.trajectory.duration, 3),
                                                         "suction_intervals": motion.suction_intervals}}],
            "steps_log": [{"time": 0.0, "action": _describe(action), "poses_before": poses, "lost": [],
                           "hypotheses": {o.name: {"shape": o.shape, "size": [float(v) for v in o.size],
                                                   "x": float(o.center[0]), "y": float(o.center[1]),
                                                   "yaw": float(o.yaw)} for o in belief.known}}],
            "station": self.station_path, "config": self.station.scene_config, "policy": self.policy_name,
        }
        data["actions"][0]["motion"]["duration_s"] = float(motion.trajectory.duration)
        believed = Scene(self.shelf, self.camera, belief.known, None)
        exported = export_trial(data, rate=None, source=source, scene=believed)
        exported.metadata["initial_positions"] = list(map(float, q))
        return exported

    def _guarded_push_in(self, action, motion, known, shelf) -> dict | None:
        """What the arm's controller must do for a guarded suction (None for any other action): the push-in
        (``t_start_s`` to ``t_end_s``, s from the trajectory's start) runs as a guarded move that stops when the
        force resisting the push, estimated from the joint efforts, exceeds ``stop_force_n``; for a drag, first
        over twice ``expected_resistance_n`` (its floor friction turning over) and, once the cup has pushed in
        ``rebase_after_m``, over a baseline taken again there; then it holds, releases and backs out the way it
        came (:mod:`slax_drake.systems.guard`, ``MotionPlanner.guarded_stop``). A lift stopped before the cup has
        pushed in ``edge_retry_within_m`` (0: never) met the board's front edge (the object hangs lower than
        planned): it holds, rises ``edge_retry_rise_m``, pushes in again that much higher, as guarded, lowers to the
        plan's lowering and goes on with the plan, once (``MotionPlanner.edge_retry``). The trajectory after the
        push-in is what follows when nothing stops it."""
        from slax_drake.planning.planner import EDGE_RETRY_RISE
        from slax_drake.systems.guard import DRAG_REBASE_TRAVEL, push_in_forces, push_in_window

        window = push_in_window(motion)
        if window is None:
            return None
        obj = next((o for o in known if o.name == action.name), None)
        stop, expected = push_in_forces(action, obj, self.policy.action_model, self.station.guarded_stop_force,
                                        self.station.suction.lip_moment)
        within = _edge_within(action, motion, obj, shelf)
        return {"t_start_s": round(window[0], 4), "t_end_s": round(window[1], 4), "stop_force_n": round(stop, 3),
                "expected_resistance_n": round(expected, 3),
                "rebase_after_m": DRAG_REBASE_TRAVEL if expected > 0.0 else 0.0,
                "edge_retry_within_m": round(within, 4), "edge_retry_rise_m": EDGE_RETRY_RISE if within > 0 else 0.0}

    def _edge_watch(self, action, motion, known, shelf) -> dict | None:
        """What the arm's controller must watch on an unguarded lift's push-in that comes into the bay from outside
        (None for any other action, or one whose object starts inside): the push-in (``t_start_s`` to
        ``t_end_s``) runs as planned, but a force resisting it over ``stop_force_n`` (from the joint efforts, as a
        guarded push-in's) before the cup has pushed in ``within_m`` is the board's front edge: hold, rise
        ``rise_m``, push in again that much higher (not watched), lower to the plan's lowering and go on
        (``MotionPlanner.edge_retry``); a stop past ``within_m`` is not watched for."""
        from slax_drake.planning.planner import EDGE_RETRY_RISE
        from slax_drake.shelf.actions import Suction
        from slax_drake.systems.guard import push_in_forces, push_in_of

        if not isinstance(action, Suction) or action.guarded or action.drag:
            return None
        window = push_in_of(motion.waypoint_times)
        obj = next((o for o in known if o.name == action.name), None)
        within = 0.0 if window is None else _edge_within(action, motion, obj, shelf)
        if within <= 0.0:
            return None
        stop, _ = push_in_forces(action, obj, self.policy.action_model, self.station.guarded_stop_force,
                                 self.station.suction.lip_moment)
        return {"t_start_s": round(window[0], 4), "t_end_s": round(window[1], 4), "stop_force_n": round(stop, 3),
                "within_m": round(within, 4), "rise_m": EDGE_RETRY_RISE}

    def _weigh_at_lift(self, action, motion, belief) -> dict | None:
        """What the arm's controller must do at a lifted suction's lift (None for any other action): at ``t_s`` (s
        from the trajectory's start; the arm at rest with its object 1 cm up) weigh the load the cup holds from the
        joint efforts (weight and held moment, :meth:`slax_drake.systems.guard.EffortModel.payload`) and, when the
        verdict says so (:func:`~slax_drake.systems.guard.weigh_verdict`: under ``min_weight_n`` nothing is held;
        over ``limit_nm``; a lever under ``free_hang_share`` of ``least_lever_m``), play the trajectory backward from
        there to its start, switching the suction off where it came on back at the seal (what
        ``MotionPlanner.put_back`` makes in a Drake trial). The trajectory after ``t_s`` is what follows when the
        object hangs as planned."""
        from slax_drake.systems.guard import FREE_HANG_SHARE, MIN_HELD_WEIGHT, least_lever, weigh_time

        t = weigh_time(motion)
        limit = float(self.policy.action_model.tool.rules.max_suction_moment)
        if t is None or not math.isfinite(limit):
            return None
        hyp = next((h for h in belief.hypotheses if h.object.name == action.name), None)
        return {"t_s": round(t, 4), "limit_nm": limit, "min_weight_n": MIN_HELD_WEIGHT,
                "least_lever_m": round(least_lever(hyp, action.q[:2]), 4) if hyp is not None else 0.0,
                "free_hang_share": FREE_HANG_SHARE}

    def _weigh_along_pull(self, action, motion, belief) -> dict | None:
        """What the arm's controller must do on a sideways drag's pull under the ``weigh_drag_pull`` rule (None for
        any other action; :mod:`slax_drake.systems.drag_weigh`): fit the effort baseline at ``t_base_s`` (the
        "approach", the free arm at rest), estimate the force resisting the cup along the pull (S -y) from the joint
        efforts between ``t_start_s`` and ``t_end_s``, counting the samples once the cup has pulled
        ``sliding_after_m`` and until ``end_margin_m`` before the pull's end, and at ``t_decide_s`` (at rest at the
        pull's end) compare their median with ``max_friction_n`` (the twist limit over the safety factor and the
        believed lever); over it, play the trajectory backward from there to its start, switching the suction off
        where it came on back at the seal (``MotionPlanner.put_back`` in a Drake trial). The trajectory after
        ``t_decide_s`` is what follows when the friction is within it."""
        from slax_drake.shelf.rules import drag_twist_limit
        from slax_drake.systems.drag_weigh import ALONG_PULL, END_MARGIN, SLIDING_TRAVEL, believed_pull, pull_window

        rules = self.policy.action_model.tool.rules
        window = pull_window(motion) if rules.weigh_drag_pull else None
        if window is None:
            return None
        lever, shape = believed_pull(next((o for o in belief.known if o.name == action.name), None), action.q[:2])
        limit = drag_twist_limit(rules, shape)
        t_base, t0, t1, t_decide = window
        return {"along": ALONG_PULL, "t_base_s": round(t_base, 4), "t_start_s": round(t0, 4), "t_end_s": round(t1, 4),
                "t_decide_s": round(t_decide, 4), "sliding_after_m": SLIDING_TRAVEL, "end_margin_m": END_MARGIN,
                "lever_m": round(lever, 4), "limit_nm": round(limit, 4),
                "safety_factor": float(rules.drag_safety_factor),
                "max_friction_n": round(limit / (rules.drag_safety_factor * lever), 3) if lever > 0.0 else None}

    def _record(self, action, belief, observation, rejected, report, history, timings, reason=None,
                visibility=None, frame=None) -> dict:
        """The step file's ``metadata.plan_step``; its ``history`` is what the next step reads: P'_t, the tracker's
        state, the action planned and, per step that planned one, its ``frame`` (working-resolution depth, target
        mask, joint state) with the candidates rejected on it (:mod:`slax_drake.hardware.step_memory`)."""
        from slax_drake.hardware.step_memory import encode_frame
        from slax_drake.shelf.distribution import support
        from slax_drake.systems.planner import _describe

        steps = int(history.get("steps", 0)) if history else 0
        h = self.policy.history
        frames = list((history or {}).get("frames") or [])
        if action is not None and frame is not None:
            frames.append({**encode_frame(*frame), "rejected": rejected, "action": _describe(action)})
        return {
            "action": None if action is None else _describe(action),
            "reason": reason,
            "policy": self.policy_name,
            "hypotheses": {hyp.object.name: {"shape": hyp.object.shape,
                                             "size": [round(float(v), 4) for v in hyp.object.size],
                                             "x": round(float(hyp.object.center[0]), 5),
                                             "y": round(float(hyp.object.center[1]), 5),
                                             "yaw": round(float(hyp.object.yaw), 5), "pixels": hyp.pixels}
                           for hyp in belief.hypotheses},
            "target_pixels": int(np.count_nonzero(observation.belief.observation.target_mask)),
            "target_visibility": visibility,
            "support": support(h) if h is not None else None,
            "rejected": rejected,
            "check": None if report is None else {"ok": report.ok, "checked": report.checked},
            "timings_s": {k: round(v, 4) for k, v in timings.items()},
            "tool_rules": dict(self.tool_rules),
            "history": {"policy": self.policy_name, "tool_rules": dict(self.tool_rules),
                        "steps": steps + (1 if action is not None else 0),
                        "history": [] if h is None else [float(v) for v in h],
                        "tracks": self.tracker.to_dict() if getattr(self, "tracker", None) is not None else None,
                        "action": None if action is None else _describe(action), "frames": frames},
        }


def _diverged(step: int, chosen, recorded) -> PlanStepError:
    from slax_drake.systems.planner import _describe

    chosen = None if chosen is None else _describe(chosen)
    return PlanStepError(f"history step {step}: replaying it chooses {chosen} "
                         f"where that step chose {recorded} (a history of another policy or code version, or a "
                         "decision cut short by the policy's time budget; plan without --history to start afresh)")


def _action_of(doc):
    """The action a step.json's ``action`` describes (None for none or an unreadable one)."""
    from slax_drake.shelf.actions import Push, Suction

    if not isinstance(doc, dict):
        return None
    try:
        if doc.get("type") == "push":
            return Push(str(doc["object"]), tuple(float(v) for v in doc["q"]), float(doc["d"]),
                        turns=bool(doc.get("turns", False)))
        if doc.get("type") == "suction":
            return Suction(str(doc["object"]), tuple(float(v) for v in doc["q"]), float(doc["dx"]),
                           float(doc["dz"]), float(doc.get("yaw", 0.0)))
    except (KeyError, TypeError, ValueError):
        return None
    return None


def plan_step_files(station: str, depth: str, mask: str, joint_state: str, out: str, history: str | None = None,
                    policy: str = "bluction-dar", tool_rules: dict | None = None) -> StepResult:
    """``slax-drake plan-step``: reads the files, plans one step, writes ``out`` atomically (ros-json).
    ``tool_rules``: rule overrides on top of the station's (``--tool-rule``)."""
    from slax_drake.hardware.trajectory_file import dumps
    from slax_drake.io import write_text_atomic

    q = read_joint_state(joint_state)
    previous = read_history(history)
    frame = read_depth(depth)
    target = read_mask(mask)
    planner = StepPlanner(station, policy=policy, tool_rules=tool_rules)
    planner.check_joint_state(q, joint_state)
    result = planner.plan_step(frame, target, q, previous, source=str(depth))
    write_text_atomic(Path(out), dumps(result.trajectory, "ros-json"))
    return result


@dataclasses.dataclass
class TrialDecision:
    """One decision of a recorded trial (:func:`trial_decision`): the trial's record ``data``, its decisions (the
    ``steps_log`` entries made at a decision), this one's ``entry`` and 1-based ``step``, the trial's
    ``initial_scene`` and the ``scene`` as it stood at this decision."""

    data: dict
    decisions: list
    entry: dict
    step: int
    initial_scene: object
    scene: object


def trial_decision(trial_dir: str | Path, step: int | None = None) -> TrialDecision:
    """Decision ``step`` (1-based, as the trial's lines "step N/H" count; default the last, where a trial that
    ended with no action stopped) of the trial in ``trial_dir``, with its scene as it stood then: each object at the
    planar pose (x, y, yaw in the shelf frame S) the trial recorded before that decision (``poses_before``; an
    object that had toppled stands upright there). PlanStepError (exit 2) for a missing or unreadable trial.json or
    scene.json, or a step the trial does not hold."""
    from slax_drake.scene.io import load_scene

    trial_dir = Path(trial_dir)
    data = _load_json(_existing(trial_dir / "trial.json", "trial"), "trial")
    scene = load_scene(_existing(trial_dir / "scene.json", "scene"))
    decisions = [e for e in data.get("steps_log", []) if isinstance(e, dict) and "time" in e]
    step = len(decisions) if step is None else int(step)
    if not 1 <= step <= len(decisions):
        raise PlanStepError(f"--step {step}: the trial in {trial_dir} has decisions 1 to {len(decisions)}")
    entry = decisions[step - 1]
    poses = entry.get("poses_before") or {}
    objects = tuple(o if poses.get(o.name) is None else o.moved_to(poses[o.name]["x"], poses[o.name]["y"],
                                                                  poses[o.name]["yaw"]) for o in scene.objects)
    return TrialDecision(data, decisions, entry, step, scene, dataclasses.replace(scene, objects=objects))


@dataclasses.dataclass
class TrialStepInputs:
    """The files of plan-step's inputs built from a simulated trial's decision (:func:`inputs_from_trial`)."""

    station: str
    depth: Path
    target_mask: Path
    joint_state: Path
    time_s: float  # the decision's simulated time
    history: Path | None = None  # the objects tracked up to the previous decision and its action (None: step 1)
    tool_rules: dict | None = None  # the rules the trial planned with (its record's), as overrides of the station's
    policy: str | None = None  # the policy the trial ran (None: a record without it)


def inputs_from_trial(trial_dir: str | Path, step: int, out_dir: str | Path) -> TrialStepInputs:
    """plan-step's inputs at decision ``step`` (1-based, as the trial's lines "step N/H" count) of the trial in
    ``trial_dir``, written to ``out_dir`` as a robot's driver would write them:

    - ``depth.npy``: the depth image the trial's perception received at that decision (``step_depth.npz``; m);
    - ``target_mask.png``: the target's pixels in that image, ray-cast from the trial's scene with each object where
      the trial recorded it at that decision (its planar pose; an object that had toppled is drawn upright);
    - ``joint_state.json``: the commanded joint positions at that moment (``executed_trajectory``).

    - ``history.json`` (from decision 2 on): the objects the trial's tracker held at the previous decision (seen
      and remembered, by their tracked names) and the action taken there, so that plan-step names the objects as
      the trial did (``--history``). P'_(t-1) is not carried over (plan-step starts the policy's history afresh:
      its working resolution may differ from the trial's).

    The station is the trial's."""
    from slax_drake.io import write_bytes_atomic, write_text_atomic
    from slax_drake.scene.raycast import SceneRaycaster
    from slax_drake.station.robot import PLANNED_JOINTS

    trial_dir = Path(trial_dir)
    decision = trial_decision(trial_dir, step)
    data, entry, decisions, at_step, scene = (decision.data, decision.entry, decision.decisions, decision.scene,
                                              decision.initial_scene)
    depth_file = _existing(trial_dir / "step_depth.npz", "step-depth")
    try:
        with np.load(depth_file) as f:
            times, depths = np.asarray(f["times"], float), np.asarray(f["depth"], np.float32)
    except (OSError, KeyError, ValueError) as e:
        raise PlanStepError(f"{depth_file}: unreadable ({e})") from None
    k = int(np.argmin(np.abs(times - float(entry["time"]))))
    if abs(times[k] - float(entry["time"])) > 1e-3:
        raise PlanStepError(f"{depth_file}: holds no depth image of decision {step} (t = {entry['time']} s)")
    depth = depths[k]
    h, w = depth.shape
    _, labels = SceneRaycaster(at_step, include_target=True).render(scene.camera.with_resolution(w, h))
    mask = labels == len(at_step.objects) + 1
    et = data.get("executed_trajectory") or {}
    try:
        t, q = np.asarray(et["times"], float), np.asarray(et["positions"], float)
        names = list(et["joint_names"])
        q_now = {n: float(np.interp(float(entry["time"]), t, q[:, names.index(n)])) for n in PLANNED_JOINTS}
    except (KeyError, ValueError, IndexError, TypeError) as e:
        raise PlanStepError(f"{trial_dir / 'trial.json'}: executed_trajectory is malformed ({e})") from None
    import cv2

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    import io as _io

    buf = _io.BytesIO()
    np.save(buf, depth)
    write_bytes_atomic(out_dir / "depth.npy", buf.getvalue())
    ok, png = cv2.imencode(".png", (mask * 255).astype(np.uint8))
    write_bytes_atomic(out_dir / "target_mask.png", png.tobytes())
    write_text_atomic(out_dir / "joint_state.json", json.dumps(
        {"joint_names": list(PLANNED_JOINTS), "positions": [q_now[n] for n in PLANNED_JOINTS]}, indent=1))
    history = None
    if step > 1:
        previous = decisions[step - 2]
        tracks = []
        for hidden, table in ((False, previous.get("hypotheses") or {}), (True, previous.get("remembered") or {})):
            for name, h in table.items():
                if not str(name).startswith("track_") or "shape" not in h or "size" not in h:
                    continue  # a trial recorded without the tracker
                tracks.append({"name": name, "shape": h["shape"], "size": h["size"], "x": h["x"], "y": h["y"],
                               "z": float(h["size"][2]) / 2, "yaw": h.get("yaw", 0.0),
                               "uncertainty": h.get("uncertainty_m", 0.0), "hidden": hidden, "frames": 1})
        if tracks:
            numbers = [int(t["name"].split("_")[-1]) for t in tracks if t["name"].split("_")[-1].isdigit()]
            doc = {"policy": data.get("policy"), "steps": step - 1, "history": [],
                   "tracks": {"next_id": max(numbers, default=0) + 1, "frames": step - 1, "tracks": tracks},
                   "action": previous.get("action")}
            history = out_dir / "history.json"
            write_text_atomic(history, json.dumps(doc, indent=1))
    return TrialStepInputs(str(data.get("station") or ""), out_dir / "depth.npy", out_dir / "target_mask.png",
                           out_dir / "joint_state.json", float(entry["time"]), history,
                           recorded_rules(data.get("tool_rules"), str(data.get("station") or "")),
                           data.get("policy") if isinstance(data.get("policy"), str) else None)


def recorded_rules(recorded, station_path: str) -> dict | None:
    """The overrides with which a StepPlanner on ``station_path`` plans with exactly a trial's recorded
    ``tool_rules`` (the rules it planned with, less those at the station profile's values): the record, and the
    profile's value for each rule of the station's that the record leaves out (overridden back to the profile's);
    None when the trial recorded none."""
    from slax_drake.shelf.tool import ToolConfig
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.trial import station_tool_rules

    if not isinstance(recorded, dict) or not station_path:
        return None
    defaults = ToolConfig.build("station")
    station = station_tool_rules(load_station_scenario(station_path))
    return {**{k: defaults.value(k) for k in station if k not in recorded}, **recorded}


def _edge_within(action, motion, obj, shelf) -> float:
    """m: how far the cup of a lifted suction's ``motion`` pushes in before its object's back (as ``obj`` is
    believed) is :data:`~slax_drake.systems.guard.EDGE_BAND` past the opening: a stop before that is the board's
    front edge (:func:`~slax_drake.systems.guard.edge_stop_cup_y`); 0 for a drag or a push-in that starts inside."""
    from slax_drake.systems.guard import edge_stop_cup_y

    labels = [w.label for w in motion.waypoints]
    y_start = float(motion.waypoints[labels.index("push in") - 1].position[1])  # the cup where the push-in starts
    edge = edge_stop_cup_y(action, obj, shelf, y_start)
    return 0.0 if edge is None else max(0.0, edge - y_start)
