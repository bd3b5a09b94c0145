"""The fast first-order shelf simulator: observe, execute an action, check the target's visibility.

What a non-oracle policy observes (:class:`PolicyObservation`): the depth and label images rendered at a coarse
resolution (``observation_width`` px wide) from the scene's camera, the 1D occupancy distribution of the true
scene from the :class:`DistributionModel`, and ``known``: every object of which at least one pixel is seen,
with its exact footprint (an idealised segmentation and shape fit). Objects no pixel of which is seen, and the
target, are not in the observation.

Execution (:func:`execute`) is first order: the moved object translates, nothing rotates or topples. The
simulator replays the action against the *true* scene, hidden objects and the target included: a blade lane
or suction path blocked by something the policy could not see leaves everything in place, and a push or a
placement stops ``clearance`` before the first true obstacle. So the simulator never creates an overlap.
A trial (:func:`run_trial`) succeeds when the target's visible fraction reaches v, and fails after H actions
or when the policy finds no feasible action.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from slax_drake.shelf.actions import (
    BLADE_CONTACT_CLEARANCE, GRAVITY, ActionModel, Push, Suction, apply_action, contact_lever, object_mass, pushed,
    weighed_mass,
)
from slax_drake.shelf.rules import RULES, drag_twist_limit
from slax_drake.scene.footprint import Footprint, clear_of, footprints_clear
from slax_drake.scene.model import Scene
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.sampling import target_visible_fraction


@dataclasses.dataclass(frozen=True)
class PolicyObservation:
    """What a non-oracle policy may use (see the module docstring)."""

    depth: np.ndarray  # (H, W) float32, metres along the optical axis
    labels: np.ndarray  # (H, W) int32: -1 nothing, 0 shelf, i + 1 for scene.objects[i]
    known: tuple  # the SceneObjects seen, in scene order
    p1d: np.ndarray  # (W_d,) the 1D occupancy distribution of the current state
    scene_template: Scene  # shelf and camera, and the known objects; never the target or hidden objects
    belief: object = None  # camera mode: the ObservedBelief that made ``known`` and ``p1d`` (predicts from the image)


def observe(scene: Scene, distribution_model, observation_width: int = 160) -> PolicyObservation:
    cam = scene.camera
    coarse = cam.with_resolution(observation_width, max(1, int(round(cam.height * observation_width / cam.width))))
    depth, labels = SceneRaycaster(scene).render(coarse)
    seen = set(int(v) - 1 for v in np.unique(labels) if v > 0)
    known = tuple(o for i, o in enumerate(scene.objects) if i in seen)
    p1d = distribution_model.distribution(scene.with_objects(scene.objects))
    template = dataclasses.replace(scene, objects=known, target=None)
    return PolicyObservation(depth, labels, known, p1d, template)


OBSERVATION_MODES = ("privileged", "camera")
SEGMENTATIONS = ("labels", "depth")


class CameraObserver:
    """The camera mode of the shelf simulator: the policy sees a rendered frame, nothing else.

    Per step: the scene (target included) is ray-cast at ``width`` px (the ray caster equals Drake's depth to
    1e-6 m) -> optional L515 noise (``noise_seed``; :func:`~slax_drake.perception.sensor_noise.l515_depth_noise`,
    step-indexed) -> the occluders' segmentation (``segmentation``: ``"labels"``, the render's object labels, the
    idealised segmentation; ``"depth"``, :func:`~slax_drake.perception.segmentation.segment_depth` on the depth
    alone) and the target mask (the render's target label, the stand-in for colour detection) -> the estimator's
    hypotheses and P_t from the frame (:class:`~slax_drake.perception.belief.ObservedBelief` with the ``source``
    distribution: ``"depth"`` or ``"network"``, the latter at the network's resolution).

    ``full_resolution``: the scene is ray-cast at the camera's own resolution (the L515's 640 x 480; the noise
    model applied there) and resampled to the working one by
    :func:`~slax_drake.perception.observation.resample_nearest`, as the Drake station's camera and PerceptionSystem
    make their frames, so that both simulators' policies decide on the same pixels; False (default): ray-cast at
    the working resolution, every pixel at its own centre. The two differ by 1/8 px at 640 -> 160, which is enough
    to change slax-belief's first decision in 37 of the physics benchmark's 80 scenes (docs/research/physics.md).

    :meth:`observe` also returns what only the simulator knows: which true object each hypothesis is (label
    segmentation: segment id = object index + 1; depth segmentation: the object most of the segment's pixels
    show), so that an action on a hypothesis is executed on that object.

    ``tracking`` (default): the hypotheses are associated with the objects seen in earlier frames of the trial
    (:class:`~slax_drake.perception.tracking.ObjectTracker`, told the action executed since the last frame through
    :meth:`executed`) and named by their tracks (``track_<k>``, stable across frames) instead of by segment;
    :meth:`start` begins a new trial. False: ``segment_<id>`` names, nothing carried between frames.
    ``estimator``: the estimator's tuning (an :class:`~slax_drake.perception.estimator.EstimatorConfig`; None: its
    defaults)."""

    def __init__(self, shelf, camera, target_size, source: str = "depth", width: int = 160,
                 segmentation: str = "labels", noise_seed: int | None = None, tracking: bool = True,
                 full_resolution: bool = False, estimator=None):
        from slax_drake.perception.belief import background_depth, make_source

        if segmentation not in SEGMENTATIONS:
            raise ValueError(f"segmentation must be one of {SEGMENTATIONS}, got {segmentation!r}")
        self.shelf = shelf
        self.source = make_source(source, shelf, target_size)
        if source == "network":
            w, h = self.source.resolution
        else:
            w, h = width, max(1, int(round(camera.height * width / camera.width)))
        self.camera = camera.with_resolution(w, h)
        self.render_camera = camera if full_resolution else self.camera  # the camera the scene is ray-cast with
        self.segmentation = segmentation
        self.noise_seed = noise_seed
        self.background = background_depth(shelf, self.camera)
        self.steps = 0
        from slax_drake.perception.tracking import ObjectTracker

        self.tracker = ObjectTracker() if tracking else None
        self._executed = None
        from slax_drake.perception.estimator import EstimatorConfig

        self.estimator = estimator if estimator is not None else EstimatorConfig()

    def start(self) -> None:
        """A new trial: the tracker forgets every object and the noise's step index starts again at 0."""
        if self.tracker is not None:
            self.tracker.reset()
        self._executed = None
        self.steps = 0

    def executed(self, action) -> None:
        """The action (named by a hypothesis of the last frame) executed since the last frame."""
        self._executed = action

    def weighed(self, action, hypotheses, true_object, model: ActionModel) -> float:
        """The lift ``action`` (named by a hypothesis among ``hypotheses``) was weighed on ``true_object`` and put
        back: returns the mass (kg) that explains the true held moment at the hypothesis's lever
        (:func:`~slax_drake.shelf.actions.weighed_mass`), which its track carries from the next frame on, as the
        Drake trial's planner records what its arm weighed."""
        hyp = next(o for o in hypotheses if o.name == action.name)
        weight = object_mass(true_object, model.tool.physics.object_density, model.tool.physics) * GRAVITY
        mass = weighed_mass(weight, model.held_moment(true_object, action.q[:2]), contact_lever(hyp, action.q[:2]))
        if self.tracker is not None:
            self.tracker.weighed(action.name, mass)
        return mass

    def weighed_pull(self, action, true_object, model: ActionModel) -> float:
        """The sideways drag ``action`` (named by a hypothesis) was weighed along its pull on ``true_object`` and
        pushed back: returns the mass (kg) its friction implies, the true mass (the floor's friction is the action
        model's ``drag_friction`` here), which its track carries from the next frame on, as the Drake trial's
        planner records what its arm felt (:mod:`slax_drake.systems.drag_weigh`)."""
        mass = object_mass(true_object, model.tool.physics.object_density, model.tool.physics)
        if self.tracker is not None:
            self.tracker.weighed(action.name, mass)
        return mass

    def observe(self, scene: Scene) -> tuple[PolicyObservation, dict]:
        from slax_drake.perception.belief import ObservedBelief
        from slax_drake.perception.observation import Observation as Frame
        from slax_drake.perception.observation import occluder_segmentation

        from slax_drake.perception.observation import resample_nearest

        depth, labels = SceneRaycaster(scene, include_target=True).render(self.render_camera)
        if self.noise_seed is not None:
            from slax_drake.perception.sensor_noise import l515_depth_noise

            depth = l515_depth_noise(depth, self.render_camera, self.noise_seed, self.steps)
        depth = resample_nearest(depth, self.camera.width, self.camera.height)
        labels = resample_nearest(labels, self.camera.width, self.camera.height)
        self.steps += 1
        n = len(scene.objects)
        target = labels == n + 1
        if self.segmentation == "labels":
            segments = np.where((labels >= 1) & (labels <= n), labels, 0)
        else:
            from slax_drake.perception.segmentation import segment_depth

            segments = segment_depth(depth, self.camera, self.shelf)
        segments = occluder_segmentation(segments, target)
        frame = Frame(depth, segments, target, self.camera, min_valid_fraction=0.0)
        hypotheses = None
        if self.tracker is not None:
            from slax_drake.perception.estimator import estimate_objects

            executed, self._executed = self._executed, None
            hypotheses = self.tracker.update(estimate_objects(frame, self.shelf, self.estimator), executed, frame,
                                             dataclasses.replace(scene, objects=(), target=None))
        belief = ObservedBelief(frame, self.shelf, self.source, background=self.background, hypotheses=hypotheses,
                                config=self.estimator,
                                remembered=None if self.tracker is None else self.tracker.hidden())
        names = {}
        for h in belief.hypotheses:
            owners = labels[segments == h.segment_id]
            owners = owners[(owners >= 1) & (owners <= n)]
            if len(owners):
                names[h.object.name] = scene.objects[int(np.bincount(owners).argmax()) - 1].name
        template = dataclasses.replace(scene, objects=belief.known, target=None)
        return PolicyObservation(depth, segments, belief.known, belief.p1d, template, belief), names


def on_true_object(action, hypotheses, scene: Scene, true_name: str):
    """An action chosen on a hypothesis, as executed on the true object ``true_name``: a push moves it by the same
    ``d``; a suction moves it by the same planar displacement (the cup holds the front face: the placement ``dz``
    the policy chose for the hypothesis's centre is shifted by the true centre's offset from it)."""
    if isinstance(action, Suction):
        hyp = next(o for o in hypotheses if o.name == action.name)
        true = next(o for o in scene.objects if o.name == true_name)
        dz = action.dz + float(true.center[1] - hyp.center[1])
        return dataclasses.replace(action, name=true_name, dz=dz)
    return dataclasses.replace(action, name=true_name)


def observation_for(policy, scene: Scene, observer: CameraObserver | None = None):
    """What ``policy`` decides on in the shelf simulator: the true scene for a policy that declares
    ``needs_true_scene`` (an oracle, always privileged), else the PolicyObservation from its own distribution
    model (privileged: ``observer`` None) or from the camera frame (``observer``'s :meth:`CameraObserver.observe`)."""
    if policy.needs_true_scene:
        return scene
    if observer is not None:
        return observer.observe(scene)[0]
    return observe(scene, policy.distribution, policy.observation_width)


WEIGHED_PUT_BACK = "weighed at the lift and put back"  # the note that opens a lift undone as too heavy
PUT_BACK = "could not place the object: put back"  # the note of a suction whose way in stopped short of the bay


def lift_over_limit(obj, action, model: ActionModel) -> float | None:
    """The moment (N m) the true object ``obj`` hangs off the cup when ``action`` is a lift (not a drag) and that
    moment exceeds the action model's ``max_suction_moment`` (what the arm weighs at the lift and puts back), else
    None."""
    if not isinstance(action, Suction) or action.drag:
        return None
    moment = model.held_moment(obj, action.q[:2])
    return moment if RULES["max_suction_moment"].refuses(model.tool.rules.max_suction_moment, moment) else None


PULL_PUT_BACK = "weighed along the pull and pushed back"  # the note that opens a drag undone as twisting off the cup


def drag_over_twist(obj, action, model: ActionModel) -> float | None:
    """The twist (N m) a drag ``action`` that slides the true object ``obj`` across (d_x != 0) asks of the seal,
    ``drag_safety_factor`` x ``drag_friction`` x its true weight x the lever (the held moment: :meth:`held_moment`),
    when the ``weigh_drag_pull`` rule is on and that twist exceeds its face's limit (``max_drag_twist``, times
    ``drag_twist_flat_factor`` for a box: :func:`~slax_drake.shelf.rules.drag_twist_limit`; what the arm feels along
    the pull and pushes back, :mod:`slax_drake.systems.drag_weigh`), else None."""
    rules = model.tool.rules
    if not rules.weigh_drag_pull or not isinstance(action, Suction) or not action.drag or abs(action.dx) < 1e-9:
        return None
    twist = rules.drag_safety_factor * rules.drag_friction * model.held_moment(obj, action.q[:2])
    return twist if twist > drag_twist_limit(rules, obj.shape) else None


DRAGGED_INSTEAD = "dragged instead"  # the note's part after a put-back lift that became a drag (drag_after_weighing)


def drag_after_weighing(scene: Scene, note: str, model: ActionModel, hypotheses, lift: Suction, mass: float,
                        true_name: str) -> tuple[Scene, str]:
    """After the lift ``lift`` (named by a hypothesis among ``hypotheses``) was weighed at ``mass`` kg and put back
    (``note``), the same action goes on as the drag to the same placement when the ``drag_after_weighing`` rule
    is on and the action model offers it on ``hypotheses`` (:meth:`ActionModel.drag_instead`), executed on the
    true object ``true_name``; returns the scene and the note (``note; dragged instead[: the drag's note]``)."""
    if not model.tool.rules.drag_after_weighing:
        return scene, note
    drag, _ = model.drag_instead(hypotheses, lift, mass)
    if drag is None:
        return scene, note
    # its mass weighed at the lift, the drag's twist was checked with it: the arm does not weigh its pull again
    scene, drag_note = execute(scene, on_true_object(drag, hypotheses, scene, true_name), model, weigh_pull=False)
    return scene, f"{note}; {DRAGGED_INSTEAD}" + (f": {drag_note}" if drag_note else "")


def execute(scene: Scene, action, model: ActionModel, weigh_pull: bool = True) -> tuple[Scene, str]:
    """Applies ``action`` to the true scene; returns the new scene and a note ("" when it went as planned). A lifted
    suction whose true object hangs more off the cup than the action model's ``max_suction_moment`` (its true mass:
    what the arm weighs at the lift) is put back where it stood (note ``WEIGHED_PUT_BACK``); under the
    ``weigh_drag_pull`` rule, unless ``weigh_pull`` is False (the drag after a weighed lift: its mass is known), so is
    a sideways drag whose slide would twist its true object off the cup (note ``PULL_PUT_BACK``)."""
    t = model.tool
    shelf = scene.shelf
    names = [o.name for o in scene.objects]
    if action.name not in names:
        return scene, f"{action.name} does not exist"
    i = names.index(action.name)
    obj = scene.objects[i]
    fp = Footprint.of(obj)
    obstacles = [(o.name, Footprint.of(o)) for j, o in enumerate(scene.objects) if j != i]
    heights = [o.size[2] for j, o in enumerate(scene.objects) if j != i]
    if scene.target is not None:
        obstacles.append(("target", Footprint.of(scene.target.as_object())))
        heights.append(scene.target.size[2])
    half = (fp.half_x, fp.half_y)
    ex, ey = fp.extents()

    def clear_at(centers, lane=None, lane_half=None, lifted=False) -> np.ndarray:
        """(M,) bool: the object at each of ``centers`` (M, 2) is clear of every obstacle (lifted: of those it
        does not pass over), and so is the blade's ``lane`` when given."""
        ok = np.ones(len(centers), dtype=bool)
        for (_, other), h in zip(obstacles, heights):
            if lifted and model.passes_over(obj, h):
                continue
            ok &= clear_of(fp.shape, centers, fp.yaw, half, other, t.physics.clearance)
            if lane is not None:
                ok &= clear_of("box", lane, 0.0, lane_half, other, BLADE_CONTACT_CLEARANCE)
        return ok

    def first_blocked(centers, lane=None, lane_half=None, lifted=False) -> int:
        """The index of the first of ``centers`` where :func:`clear_at` fails; ``len(centers)`` when none does."""
        bad = np.flatnonzero(~clear_at(centers, lane, lane_half, lifted))
        return int(bad[0]) if len(bad) else len(centers)

    if isinstance(action, Push):
        sign = 1 if action.d > 0 else -1
        rects = model.push_swept_rects(fp, sign)
        for name, other in obstacles:
            for rx, ry, hx, hy in rects:
                if not clear_of("box", np.array([[rx, ry]]), 0.0, (hx, hy), other, BLADE_CONTACT_CLEARANCE)[0]:
                    return scene, f"blade blocked by {name}"
        n = max(1, int(math.ceil(abs(action.d) / t.grid.cell)))
        s = np.linspace(0.0, action.d, n + 1)[1:]
        # the true object at each step: translated, or turning as the quasi-static model has it when the model's
        # push_turn rule says pushed boxes turn (whatever shape the policy took the object for)
        turning = t.rules.push_turn == "quasi-static"
        if turning:
            steps = [pushed(obj, dataclasses.replace(action, d=float(v), turns=True)) for v in s]
            step_fps = [Footprint.of(o) for o in steps]
            ok = np.array([abs(f.x) + f.extents()[0] <= shelf.width / 2 - t.physics.clearance + 1e-12
                           for f in step_fps])  # within the side walls
        else:
            xs = fp.x + s
            ok = np.abs(xs) + ex <= shelf.width / 2 - t.physics.clearance + 1e-12
            centers = np.column_stack([xs, np.full(n, fp.y)])
        for _, other in obstacles:
            if turning:
                ok &= np.array([footprints_clear(f, other, t.physics.clearance) for f in step_fps])
            else:
                ok &= clear_of(fp.shape, centers, fp.yaw, half, other, t.physics.clearance)
            for rx, ry, hx, hy in rects:
                ok &= clear_of("box", np.column_stack([rx + s, np.full(n, ry)]), 0.0, (hx, hy), other,
                               BLADE_CONTACT_CLEARANCE)
        bad = np.flatnonzero(~ok)
        k = int(bad[0]) if len(bad) else n
        if k == 0:
            return scene, "pushed object blocked at once"
        moved = steps[k - 1] if turning else obj.moved_to(float(xs[k - 1]), fp.y)
        note = "" if k == n else f"push stopped after {s[k - 1]:+.3f} m by an unseen obstacle"
        return scene.with_objects(scene.objects[:i] + (moved,) + scene.objects[i + 1:]), note

    if isinstance(action, Suction) and action.drag:
        twist = drag_over_twist(obj, action, model) if weigh_pull else None
        if twist is not None:  # felt along the pull (as the Drake trial's planner does) and pushed straight back
            return scene, (f"{PULL_PUT_BACK}: sliding {obj.name} across would twist it {twist:.2f} N m > "
                           f"{drag_twist_limit(t.rules, obj.shape):.2f} N m")
        return _execute_drag(scene, i, action, model, clear_at)

    if isinstance(action, Suction):
        moment = lift_over_limit(obj, action, model)
        if moment is not None:
            # the arm weighs what it lifted (as the Drake trial's planner does from its joint efforts) and puts back
            # an object that hangs more off the cup than the lift was planned for
            return scene, (f"{WEIGHED_PUT_BACK}: {obj.name} hangs {moment:.2f} N m off the cup > "
                           f"{t.rules.max_suction_moment:.2f} N m")
        y_out = -shelf.depth / 2 - ey - t.grid.cell
        n_out = max(1, int(math.ceil((fp.y - y_out) / t.grid.cell)))
        ys = np.linspace(fp.y, y_out, n_out + 1)[1:]
        if first_blocked(np.column_stack([np.full(n_out, fp.x), ys]), lifted=True) < n_out:
            return scene, "path out blocked by an unseen obstacle"
        x_new = fp.x + action.dx
        if abs(x_new) + ex > shelf.width / 2 - t.physics.clearance + 1e-9:
            return scene, "placement outside the walls"
        n_in = max(1, int(math.ceil((action.dz - y_out) / t.grid.cell)))
        ys = np.linspace(y_out, action.dz, n_in + 1)[1:]
        path_in = np.column_stack([np.full(n_in, x_new), ys])
        k = first_blocked(path_in, lifted=True)
        if k > 0:  # lowered where it stopped it would land on something it passed over: back out along the way in
            landing = np.flatnonzero(clear_at(path_in[:k]))  # where it can be lowered, before the stop
            k = int(landing[-1]) + 1 if len(landing) else 0
        y_final = ys[k - 1] if k > 0 else None
        if y_final is None or y_final - ey < -shelf.depth / 2 + t.physics.clearance - 1e-9:
            # stopped before the whole object is back inside the bay: it is put back where it was
            return scene, PUT_BACK
        moved = obj.moved_to(float(x_new), float(y_final))
        note = "" if k == n_in else ("guarded placement stopped on contact" if action.guarded
                                     else "placement stopped early by an unseen obstacle")
        return scene.with_objects(scene.objects[:i] + (moved,) + scene.objects[i + 1:]), note
    raise TypeError(f"not an action: {action!r}")


def _execute_drag(scene: Scene, i: int, action: Suction, model: ActionModel, clear_at) -> tuple[Scene, str]:
    """A drag (:attr:`Suction.drag`) on the true scene: the object slides on the floor, pulled toward the camera to
    :meth:`ActionModel.drag_pull_y`, across by d_x, pushed in to d_z, in ``cell`` steps. Blocked on the way out or
    across, it is pushed back where it was (nothing moves); blocked on the way in, it rests where it stopped."""
    t, shelf = model.tool, scene.shelf
    obj = scene.objects[i]
    fp = Footprint.of(obj)
    ex, _ = fp.extents()
    y_pull = min(fp.y, model.drag_pull_y(fp))
    x_new = fp.x + action.dx
    if abs(x_new) + ex > shelf.width / 2 - t.physics.clearance + 1e-9:
        return scene, "placement outside the walls"

    def line(a, b) -> np.ndarray:
        n = max(1, int(math.ceil(float(np.hypot(b[0] - a[0], b[1] - a[1])) / t.grid.cell)))
        return np.linspace(a, b, n + 1)[1:]

    out = line((fp.x, fp.y), (fp.x, y_pull))
    if not clear_at(out).all():
        return scene, "drag: path out blocked by an unseen obstacle"
    across = line((fp.x, y_pull), (x_new, y_pull))
    if not clear_at(across).all():
        return scene, "drag: path across blocked by an unseen obstacle"
    way_in = line((x_new, y_pull), (x_new, action.dz))
    ok = clear_at(way_in)
    k = int(np.flatnonzero(~ok)[0]) if not ok.all() else len(way_in)
    x_end, y_end = (way_in[k - 1] if k > 0 else (x_new, y_pull))
    moved = obj.moved_to(float(x_end), float(y_end))
    note = "" if k == len(way_in) else ("drag: guarded placement stopped on contact" if action.guarded
                                        else "drag: placement stopped early by an unseen obstacle")
    return scene.with_objects(scene.objects[:i] + (moved,) + scene.objects[i + 1:]), note


@dataclasses.dataclass
class TrialResult:
    seed: int
    density: int
    policy: str
    success: bool
    steps: int
    cost: float
    pushes: int
    suctions: int
    reason: str  # "revealed", "horizon", "no action", or the policy's own reason
    decision_seconds: list
    actions: list  # descriptions of the actions taken
    notes: list  # execution notes (unseen obstacles)
    visible_fraction: float
    visible_fractions: list = dataclasses.field(default_factory=list)
    """The target's visible fraction before each decision (the true scene's, the simulator's knowledge only)."""
    # when the policy found no action: how many of the action model's feasible candidates each of its corrections
    # screened out ({why: count}, the policy's ``screened_counts``; None otherwise)
    screened: dict | None = None

    def to_dict(self) -> dict:
        out = dataclasses.asdict(self)
        if out["screened"] is None:  # the record of every other trial keeps its fields
            del out["screened"]
        return out


def step_note(step: int, text: str) -> str:
    """A trial's note on its ``step``-th action (from 1), as :func:`run_trial` records it: ``"step N: text"``."""
    return f"step {step}: {text}"


def split_note(note: str) -> tuple[int | None, str]:
    """A note of :func:`run_trial` as (N, text) (:func:`step_note`); (None, note) for a note without a step."""
    head, sep, text = note.partition(": ")
    if sep and head.startswith("step ") and head[5:].isdigit():
        return int(head[5:]), text
    return None, note


def run_trial(scene: Scene, policy, horizon: int, threshold: float = 0.80, suction_cost: float = 1.3,
              density: int | None = None, max_seconds: float | None = None,
              observer: CameraObserver | None = None) -> TrialResult:
    """Rolls ``policy`` out on ``scene`` until the target is revealed, H actions are spent or no action is left.

    ``policy`` implements :class:`~slax_drake.policies.protocol.Policy`: it decides on :func:`observation_for` the
    scene (the PolicyObservation, or the true scene for an oracle) and its best candidate is executed with its own
    action model. ``observer``: the camera mode for a non-oracle policy (its actions name hypotheses, executed on the
    true object each hypothesis is); None: privileged."""
    policy.reset(scene)
    if observer is not None:
        observer.start()
    seconds, actions, notes, fractions = [], [], [], []
    pushes = suctions = 0
    reason = "horizon"
    screened = None
    fraction = target_visible_fraction(scene)
    start = time.perf_counter()
    for _ in range(horizon):
        if fraction >= threshold:
            break
        fractions.append(round(float(fraction), 6))
        t0 = time.perf_counter()
        names = None
        if observer is not None and not policy.needs_true_scene:
            observation, names = observer.observe(scene)
        else:
            observation = observation_for(policy, scene)
        decision = policy.decide(observation)
        action = decision.best
        seconds.append(time.perf_counter() - t0)
        if action is None:
            reason = decision.stop_reason or "no action"
            counts = getattr(policy, "screened_counts", None)
            screened = counts() if counts is not None else None
            break
        if names is not None:  # camera mode: the hypothesis's true object (the executor's knowledge only)
            observer.executed(action)
            true_name = names.get(action.name)
            if true_name is None:
                actions.append(action.describe())
                notes.append(step_note(len(actions), f"{action.name} is no object (a segment of the shelf)"))
                pushes, suctions = (pushes + 1, suctions) if isinstance(action, Push) else (pushes, suctions + 1)
                continue
            chosen = action
            action = on_true_object(action, observation.known, scene, true_name)
        true_object = next((o for o in scene.objects if o.name == action.name), None)
        mass = None  # kg: what the arm weighed of a lift it puts back (camera mode)
        if names is not None and true_object is not None:  # what the arm weighs goes on the object's track
            if lift_over_limit(true_object, action, policy.action_model) is not None:  # execute puts it back
                mass = observer.weighed(chosen, observation.known, true_object, policy.action_model)
            elif drag_over_twist(true_object, action, policy.action_model) is not None:  # execute pushes it back
                observer.weighed_pull(chosen, true_object, policy.action_model)
        scene, note = execute(scene, action, policy.action_model)
        if mass is not None:  # execute put it back (the same lift_over_limit), note WEIGHED_PUT_BACK
            scene, note = drag_after_weighing(scene, note, policy.action_model, observation.known, chosen, mass,
                                              true_name)
        actions.append(action.describe())
        if note:
            notes.append(step_note(len(actions), note))
        if isinstance(action, Push):
            pushes += 1
        else:
            suctions += 1
        fraction = target_visible_fraction(scene)
        if max_seconds is not None and time.perf_counter() - start > max_seconds:
            reason = "time limit"
            break
    success = fraction >= threshold
    if success:
        reason = "revealed"
    return TrialResult(
        seed=int(scene.seed) if scene.seed is not None else -1, density=int(density or len(scene.objects)),
        policy=policy.name, success=bool(success), steps=pushes + suctions,
        cost=round(pushes + suction_cost * suctions, 6), pushes=pushes, suctions=suctions, reason=reason,
        decision_seconds=[round(s, 6) for s in seconds], actions=actions, notes=notes,
        visible_fraction=round(float(fraction), 6), visible_fractions=fractions, screened=screened,
    )


def objects_overlap(scene: Scene, clearance: float = 0.0) -> list[tuple[str, str]]:
    """Pairs of objects (and the target) whose footprints overlap (by more than -clearance); for checks."""
    from slax_drake.scene.footprint import footprints_clear

    items = [(o.name, Footprint.of(o)) for o in scene.objects]
    if scene.target is not None:
        items.append(("target", Footprint.of(scene.target.as_object())))
    bad = []
    for a in range(len(items)):
        for b in range(a + 1, len(items)):
            if not footprints_clear(items[a][1], items[b][1], clearance):
                bad.append((items[a][0], items[b][0]))
    return bad


__all__ = ["PolicyObservation", "TrialResult", "apply_action", "execute", "objects_overlap", "observation_for",
           "observe", "run_trial"]
