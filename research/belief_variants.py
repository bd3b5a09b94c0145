"""Runs slax-belief with extra constructor options on chosen Table I trials and prints, per trial, whether the
target was revealed, the steps, the cost, the simulator's notes (actions that did not go as planned) and the longest
decision (CPU s), then the count revealed. The trials are
the benchmark's (`slax-drake benchmark`): the same scene seed per (protocol seed, density, index), the registry's
policy with the protocol's horizon, privileged observation (``--observation camera``: the benchmark's camera mode,
rendered frames with label segmentation; ``--segmentation depth`` and ``--sensor-noise`` as the benchmark's),
ground-truth distributions, the first-order shelf simulator; only the
options differ. It is how the variants of issue 19 item 5 were measured one by one without a
registry row each.

    python research/belief_variants.py --options '{"room_weight": 1.0}' --trials 10:0-9 [--profile paper]
        [--policy slax-belief] [--seed 0] [--log] [--compare RESULTS_FOLDER [--compare-policy slax-belief]]
        [--observation camera [--segmentation depth] [--sensor-noise]] [--tool-rule FIELD=VALUE ...] [--stuck]
        [--known-target] [--see-hidden] [--true-extents | --true-extents-belief | --true-misfits | --true-grown]
        [--true-inflate M] [--fuse-extents]
        [--silhouette-growth PX] [--second-view LIFT:PITCH] [--no-shuttle-rule] [--plan-clearance M]
        [--placement-margin M]

``--stuck``: for each trial that ends with no feasible action, also the action model's feasible candidates on the
last arrangement the policy saw, how many of them each correction screened out and the action model's refusals by
kind, summed at the end (what ends the trials: the rules, or the corrections on the moves the rules leave).

``--known-target``: the policy is told where the target stands (its belief is the true placement alone, on its
lattice): what its search reaches when the belief is not the limit (the oracles know the whole scene; this knows only
the target). A diagnostic, never a policy: it reads the scene's hidden state. ``--see-hidden`` (privileged only):
its observation also lists the objects the camera cannot see, where they stand. ``--no-shuttle-rule``: the
no-shuttle correction off (the policy's ``shuttle_reveal`` None), to measure what that rule costs.
``--true-extents`` (camera only): each hypothesis the frame gives is replaced by the true object it shows, under
the hypothesis's name, where it stands (what the camera cannot see of the seen objects, told; the frame, its
segmentation, the target mask and the hidden objects stay the camera's): how much of the camera mode's loss the
seen objects' unseen extents make. A diagnostic, never a policy. ``--true-extents-belief``: the same objects only
where slax-belief judges where the target may stand (its ``placements``: clear of the seen objects); its actions
are planned and predicted on the camera's hypotheses, so the two flags split the loss between the belief and the
actions. ``--true-misfits``: only the hypotheses whose shape is not the object's (a box taken for a cylinder, or
the reverse) or whose yaw is more than 10 degrees off (modulo a quarter turn) are replaced. ``--true-grown``: each
box hypothesis grown, in its own axes, to hold its true object (what it leaves out added, its overhang and yaw
kept; :func:`~slax_drake.perception.tracking.fused_box`), the rest as the camera has them. ``--true-inflate M``
with ``--true-extents``: the true objects M metres larger on every side (an outline error of M, nothing else).
``--fuse-extents``
(camera only): the object tracker keeps what earlier frames showed of an unmoved box
(:class:`~slax_drake.perception.tracking.ObjectTracker`'s ``fuse_extents``). ``--silhouette-growth PX`` (camera
only): the estimator grows the extents on the silhouette sides by this many pixel footprints (its default 0.5).
``--second-view LIFT:PITCH`` (camera only): each box hypothesis grown by what a second frame shows of its object,
the camera raised LIFT m and pitched down PITCH deg (:class:`SecondView`; the frames associated by the render's
labels): what a second look would be worth.

``--plan-clearance M`` and ``--placement-margin M`` (m; camera mode is where they matter): the policy plans with a
margin for the estimate's error while the shelf simulator executes with the scenario's clearance. The first
enumerates every candidate with the action model's ``clearance`` M (a push stops M short of a neighbour, a placement
keeps M from every object and wall); the second keeps only a suction's placement ``clearance`` + M from every object.
Measurements of the policy, not of a variant: no registry row plans so.

``--compare``: a `slax-drake benchmark` results folder run with the same protocol seed; each trial also prints
the folder's outcome of ``--compare-policy`` for the same trial, and the flips (won: revealed here, not there;
lost: the reverse) are counted at the end.
"""

import argparse
import collections
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.registry import make_policy
from slax_drake.errors import UserError
from slax_drake.shelf.actions import ActionModel
from slax_drake.shelf.simulator import CameraObserver, observe, run_trial
from slax_drake.shelf.tool import parse_tool_rules


def parse_trials(text: str) -> list[tuple[int, int]]:
    """"10:0-9,8:3" -> [(10, 0), ..., (10, 9), (8, 3)]."""
    out = []
    for part in text.split(","):
        density, _, indices = part.partition(":")
        lo, _, hi = indices.partition("-")
        out += [(int(density), i) for i in range(int(lo), int(hi or lo) + 1)]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--options", default="{}", help="JSON: constructor options added to the registry's")
    ap.add_argument("--trials", required=True, help="density:index or density:first-last, comma separated")
    ap.add_argument("--policy", default="slax-belief")
    ap.add_argument("--profile", default="paper")
    ap.add_argument("--seed", type=int, default=0, help="the protocol seed")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    ap.add_argument("--log", action="store_true", help="also print each action with its decision log")
    ap.add_argument("--compare", default=None, help="a results folder: print its outcome per trial and the flips")
    ap.add_argument("--compare-policy", default="slax-belief", help="the policy of --compare's trials")
    ap.add_argument("--observation", choices=("privileged", "camera"), default="privileged")
    ap.add_argument("--segmentation", choices=("labels", "depth"), default="labels",
                    help="with --observation camera: the render's labels or depth-only segmentation")
    ap.add_argument("--sensor-noise", action="store_true",
                    help="with --observation camera: the L515 noise model, seeded by the scene seed")
    ap.add_argument("--tool-rule", action="append", default=[], metavar="FIELD=VALUE",
                    help="override one rule of the profile, as the benchmark's --tool-rule; repeatable")
    ap.add_argument("--stuck", action="store_true",
                    help="per trial ending with no feasible action: the feasible candidates left, the corrections' "
                         "screening and the action model's refusals by kind")
    ap.add_argument("--known-target", action="store_true",
                    help="tell the policy where the target stands (its belief is the true placement alone): the "
                         "search's own ceiling, a diagnostic")
    ap.add_argument("--see-hidden", action="store_true",
                    help="privileged only: the observation lists every object, hidden ones too (a diagnostic)")
    ap.add_argument("--true-extents", action="store_true",
                    help="camera only: each hypothesis replaced by the true object it shows (a diagnostic)")
    ap.add_argument("--true-extents-belief", action="store_true",
                    help="camera only: the true objects only where slax-belief judges the target's placements")
    ap.add_argument("--true-misfits", action="store_true",
                    help="camera only: --true-extents for the hypotheses of the wrong shape or 10+ deg off in yaw")
    ap.add_argument("--silhouette-growth", type=float, default=None, metavar="PX",
                    help="camera only: the estimator's growth on the silhouette sides (pixel footprints)")
    ap.add_argument("--true-inflate", type=float, default=0.0, metavar="M",
                    help="with --true-extents: the true objects this much larger on every side (m)")
    ap.add_argument("--true-grown", action="store_true",
                    help="camera only: each box hypothesis grown to hold its true object (a diagnostic)")
    ap.add_argument("--second-view", default=None, metavar="LIFT:PITCH",
                    help="camera only: hypotheses grown by a second frame, the camera LIFT m higher, PITCH deg down")
    ap.add_argument("--fuse-extents", action="store_true",
                    help="camera only: the tracker keeps what earlier frames showed of an unmoved box")
    ap.add_argument("--no-shuttle-rule", action="store_true",
                    help="the no-shuttle correction off (shuttle_reveal None), to measure what it costs")
    ap.add_argument("--plan-clearance", type=float, default=None, metavar="M",
                    help="the policy enumerates its candidates with this clearance (m); the simulator executes with "
                         "the scenario's")
    ap.add_argument("--placement-margin", type=float, default=None, metavar="M",
                    help="the policy keeps a suction's placement this much (m) more than the clearance from every "
                         "object")
    args = ap.parse_args(argv)
    for flag, value in (("--plan-clearance", args.plan_clearance), ("--placement-margin", args.placement_margin)):
        if value is not None and not 0 <= value < 0.1:
            print(f"error: {flag} must be in [0, 0.1) m (got {value})", file=sys.stderr)
            return 2
    if args.true_inflate and (not args.true_extents or not 0 < args.true_inflate < 0.05):
        print("error: --true-inflate needs --true-extents and a margin in (0, 0.05) m", file=sys.stderr)
        return 2
    if args.see_hidden and args.observation != "privileged":
        print("error: --see-hidden needs the privileged observation", file=sys.stderr)
        return 2
    second_view = None
    if args.second_view is not None:
        try:
            second_view = tuple(float(v) for v in args.second_view.split(":"))
            if len(second_view) != 2 or not 0 <= second_view[1] < 90:
                raise ValueError
        except ValueError:
            print(f"error: --second-view must be LIFT:PITCH, metres and degrees in [0, 90) (got {args.second_view})",
                  file=sys.stderr)
            return 2
    if (args.true_extents or args.true_extents_belief or args.true_misfits or args.true_grown or args.fuse_extents
            or args.silhouette_growth is not None or second_view is not None) \
            and args.observation != "camera":
        print("error: --true-extents, --true-extents-belief, --true-misfits, --true-grown, --fuse-extents, "
              "--silhouette-growth and --second-view need --observation camera",
              file=sys.stderr)
        return 2
    try:
        tool_rules = parse_tool_rules(args.tool_rule, args.profile)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    compare = None
    if args.compare is not None:
        compare = Path(args.compare) / "trials" / args.compare_policy
        if not compare.is_dir():
            print(f"error: --compare: no folder {compare}", file=sys.stderr)
            return 2
    flips = {"won": [], "lost": []}
    try:
        options = json.loads(args.options)
        if not isinstance(options, dict):
            raise ValueError("a JSON object of option names and values")
    except ValueError as e:  # json.JSONDecodeError is a ValueError
        print(f"error: --options: {e}", file=sys.stderr)
        return 2
    scenario = load_scenario(args.config)
    try:  # the options are checked once, before the first trial
        probe = make_policy(args.policy, scenario, horizon=1, profile=args.profile, policy_options=options,
                            tool_overrides=tool_rules)
    except (TypeError, ValueError) as e:
        print(f"error: --options: {e}", file=sys.stderr)
        return 2
    if args.true_extents_belief and not hasattr(probe, "placements"):
        print(f"error: --true-extents-belief: {args.policy} keeps no belief of the target's placements",
              file=sys.stderr)
        return 2
    if args.known_target and not hasattr(probe, "placements"):
        print(f"error: --known-target: {args.policy} keeps no belief of the target's placements", file=sys.stderr)
        return 2
    margins = args.plan_clearance is not None or args.placement_margin is not None
    if margins and not hasattr(getattr(probe, "_action_model", None), "_model"):
        print(f"error: --plan-clearance / --placement-margin: {args.policy} is not slax-belief or one of its variants",
              file=sys.stderr)
        return 2
    size = tuple(scenario.target.sizes[0])
    revealed = 0
    stuck = {"endings": 0, "feasible": 0, "screened": collections.Counter(), "refused": collections.Counter()}
    trials = parse_trials(args.trials)
    for density, index in trials:
        seed = scene_seed(args.seed, density, index)
        scene = protocol_scene(scenario, density, seed)
        horizon = scenario.protocol.horizon_per_object * density
        policy = make_policy(args.policy, scenario, horizon=horizon, profile=args.profile, policy_options=options,
                             tool_overrides=tool_rules)
        observer = None
        if args.observation == "camera":
            observer = CameraObserver(scene.shelf, scene.camera, size, width=policy.observation_width,
                                      segmentation=args.segmentation, noise_seed=seed if args.sensor_noise else None)
        if args.fuse_extents:
            observer.tracker.fuse_extents = True
        if args.silhouette_growth is not None:
            from slax_drake.perception.estimator import EstimatorConfig

            observer.estimator = EstimatorConfig(silhouette_growth=args.silhouette_growth)
        seen = watch_last_arrangement(policy)
        if args.known_target:
            tell_target(policy, scene)
        if args.no_shuttle_rule:
            policy.shuttle_reveal = None
        if margins:
            plan_with_margin(policy, args.plan_clearance, args.placement_margin)
        t0 = time.process_time()
        if args.see_hidden:
            observer = SeeingHidden(policy)
        if args.true_extents:
            observer = TrueExtents(observer, inflate=args.true_inflate)
        if args.true_misfits:
            observer = TrueExtents(observer, misfits_only=True)
        if args.true_grown:
            observer = TrueExtents(observer, grown=True)
        if second_view is not None:
            observer = SecondView(observer, *second_view)
        if args.true_extents_belief:
            observer = TrueExtents(observer)
            observer.belief_only(policy)
        result = run_trial(scene, policy, horizon, threshold=scenario.target.visibility_threshold,
                           suction_cost=scenario.protocol.suction_cost, density=density, observer=observer)
        longest = max((d.get("seconds", 0.0) for d in policy.decision_log), default=0.0)
        revealed += bool(result.success)
        print(f"{density:02d}_{index:04d} revealed={result.success} steps={result.steps} cost={result.cost:.1f} "
              f"visible={result.visible_fraction:.2f} notes={len(result.notes)} cpu_s={time.process_time() - t0:.1f} "
              f"longest_decision_s={longest:.2f}" + earlier_outcome(compare, density, index, result.success, flips),
              flush=True)
        if args.stuck and result.reason == "no feasible action":
            print("   ", stuck_ending(policy, seen["known"], result.screened or {}, stuck), flush=True)
        if args.log:
            for action, log in zip(result.actions, policy.decision_log):
                keys = ("revealed", "value", "widened", "plan", "dead_ends", "put_back_explained")
                print("   ", action, {k: log[k] for k in keys if k in log})
    print(f"revealed {revealed} / {len(trials)} ({args.policy}, options {options})")
    if args.stuck and stuck["endings"]:
        n = stuck["endings"]
        print(f"{n} trials ended with no feasible action; at their last arrangement, per trial: "
              f"{stuck['feasible'] / n:.1f} feasible candidates, screened out "
              f"{ {k: round(v / n, 1) for k, v in stuck['screened'].most_common()} }, refused by the action model "
              f"{ {k: round(v / n, 1) for k, v in stuck['refused'].most_common()} }")
    if compare is not None:
        print(f"flips against {compare}: won {len(flips['won'])} ({' '.join(flips['won'])}), lost "
              f"{len(flips['lost'])} ({' '.join(flips['lost'])})")
    return 0


class SeeingHidden:
    """``--see-hidden``: an observer for :func:`~slax_drake.shelf.simulator.run_trial` that gives the policy the
    privileged observation (:func:`~slax_drake.shelf.simulator.observe`) with every object of the true scene listed,
    hidden ones too, where it stands. It names no hypotheses (``observe`` returns None for the names), so the trial
    executes the policy's actions on the objects they name, as in privileged mode."""

    def __init__(self, policy):
        self.policy = policy

    def start(self) -> None:
        pass

    def observe(self, scene):
        obs = observe(scene, self.policy.distribution, self.policy.observation_width)
        objects = tuple(scene.objects)
        return dataclasses.replace(obs, known=objects, scene_template=obs.scene_template.with_objects(objects)), None


class TrueExtents:
    """``--true-extents``: a camera observer (:class:`~slax_drake.shelf.simulator.CameraObserver`) whose
    observations list, for each hypothesis of the frame, the true object it shows (its footprint, height and pose)
    under the hypothesis's name; a second hypothesis of the same object is dropped. Everything else (the frame, its
    segments and target mask, P_t, the tracker's hidden objects) is the camera's, and the trial executes the
    policy's actions on the objects they name through the observer's names, as in camera mode."""

    def __init__(self, camera, misfits_only: bool = False, grown: bool = False, inflate: float = 0.0):
        self.camera = camera
        self.inflate = float(inflate)  # --true-inflate: the true objects this much (m) larger on every side
        self.misfits_only = misfits_only  # --true-misfits: replace only hypotheses of the wrong shape or yaw
        self.grown = grown  # --true-grown: grow each box hypothesis to hold its object instead
        self.told = None  # the last observation with the true objects (belief_only)
        self.only_belief = False

    def belief_only(self, policy) -> None:
        """``--true-extents-belief``: :meth:`observe` returns the camera's observation, and ``policy.placements``
        judges the target's placements on the true objects of the frame (the remembered hypotheses and the others
        as the policy has them)."""
        self.only_belief = True
        placements = policy.placements

        def told(obs):
            true = {o.name: o for o in self.told.known}
            known = tuple(true.get(o.name, o) for o in obs.known if o.name in true or o.remembered)
            return placements(dataclasses.replace(obs, known=known,
                                                  scene_template=obs.scene_template.with_objects(known)))

        policy.placements = told

    def __getattr__(self, name):
        if name == "camera":
            raise AttributeError(name)
        return getattr(self.camera, name)

    def replacement(self, hypothesis, truth):
        """What stands for ``hypothesis`` (of the true object ``truth``) in the observation; None: itself."""
        if self.misfits_only and not misfit(hypothesis, truth):
            return None
        if self.grown:
            from slax_drake.perception.tracking import fused_box

            return fused_box(truth, hypothesis)
        if self.inflate:
            size = (truth.size[0] + 2 * self.inflate, truth.size[1] + 2 * self.inflate, truth.size[2])
            return dataclasses.replace(truth, size=size)
        return truth

    def observe(self, scene):
        from slax_drake.perception.belief import ObservedBelief

        obs, names = self.camera.observe(scene)
        belief = obs.belief
        true = {o.name: o for o in scene.objects}
        hypotheses, shown = [], set()
        for h in belief.hypotheses:
            truth = true.get(names.get(h.object.name))
            told = None if truth is None else self.replacement(h.object, truth)
            if told is None:
                hypotheses.append(h)
            elif truth.name not in shown:
                shown.add(truth.name)
                hypotheses.append(dataclasses.replace(h, object=dataclasses.replace(told, name=h.object.name)))
        told = ObservedBelief(belief.observation, belief.shelf, belief.source, background=belief.background,
                              hypotheses=hypotheses, p1d=belief.p1d, remembered=belief.remembered)
        known = told.known
        self.told = dataclasses.replace(obs, known=known, scene_template=obs.scene_template.with_objects(known),
                                        p1d=told.p1d, belief=told)
        return (obs if self.only_belief else self.told), names


class SecondView(TrueExtents):
    """``--second-view LIFT:PITCH``: a camera observer whose hypotheses are grown by what a second frame shows of the
    same objects: the camera raised by LIFT metres and pitched down PITCH degrees (a Fetch raises its torso and
    tilts its head), ray-cast at the working resolution, label segmentation; each box hypothesis of the first frame
    becomes the least rectangle in its own axes holding both frames' estimates of its object
    (:func:`~slax_drake.perception.tracking.fused_box`: where the yaws agree and the footprints overlap), the rest
    stay as the first frame has them. Objects only the second frame shows are not added. The frames are associated by
    the render's labels (the idealised segmentation of camera mode): a diagnostic of what a second look is worth.
    Both frames are estimated with the wrapped observer's tuning (``estimator``)."""

    def __init__(self, camera, lift: float, pitch_deg: float):
        super().__init__(camera)
        self.lift, self.pitch_deg = float(lift), float(pitch_deg)
        self._second: dict = {}  # true object name -> its estimate from the second frame

    def replacement(self, hypothesis, truth):
        from slax_drake.perception.tracking import fused_box

        other = self._second.get(truth.name)
        return None if other is None else fused_box(other, hypothesis)

    def observe(self, scene):
        from slax_drake.perception.estimator import estimate_objects
        from slax_drake.perception.observation import labelled_frame
        from slax_drake.scene.camera import camera_pose
        from slax_drake.scene.raycast import SceneRaycaster

        first = self.camera.camera
        position = first.position + np.array([0.0, 0.0, self.lift])
        second = dataclasses.replace(first, X_SC=camera_pose(position, self.pitch_deg))
        depth, labels = SceneRaycaster(scene, include_target=True).render(second)
        frame = labelled_frame(depth, labels, len(scene.objects), second)
        self._second = {scene.objects[h.segment_id - 1].name: h.object
                        for h in estimate_objects(frame, scene.shelf, self.camera.estimator)}
        return super().observe(scene)


def misfit(hypothesis, truth) -> bool:
    """Whether ``hypothesis`` has another shape than the object ``truth`` it shows, or, both boxes, a yaw more
    than 10 degrees off modulo a quarter turn."""
    if hypothesis.shape != truth.shape:
        return True
    if truth.shape != "box":
        return False
    turn = (hypothesis.yaw - truth.yaw) % (np.pi / 2)
    return min(turn, np.pi / 2 - turn) > np.radians(10.0)


class MarginModel(ActionModel):
    """``--placement-margin``: an action model whose suction placements keep ``placement_margin`` (m) more than the
    clearance from every object (:attr:`ActionModel.placement_clearance`); the shelf simulator's execution reads no
    placement test, so it executes as the scenario's model."""

    def __init__(self, base: ActionModel, placement_margin: float):
        super().__init__(base.shelf, base.eye, base.tool)
        self.placement_margin = placement_margin

    @property
    def placement_clearance(self) -> float:
        return self.tool.physics.clearance + self.placement_margin


class EnumerateWith:
    """``--plan-clearance``: the action model ``base`` (what the simulator executes with and the policy predicts
    with), whose candidates are those ``planning`` (the same model with another clearance) enumerates."""

    def __init__(self, base: ActionModel, planning: ActionModel):
        self._base, self._planning = base, planning

    def __getattr__(self, name):
        if name in ("_base", "_planning"):
            raise AttributeError(name)
        return getattr(self._base, name)

    def enumerate(self, *args, **kwargs):
        return self._planning.enumerate(*args, **kwargs)


def plan_with_margin(policy, clearance: float | None, placement_margin: float | None) -> None:
    """``--plan-clearance`` / ``--placement-margin``: swaps the action model inside slax-belief's wrapper
    (``policy._action_model._model``, the one its enumeration reads) for one that plans with the margin."""
    wrapper = policy._action_model
    base = wrapper._model

    def with_margin(model: ActionModel):
        return MarginModel(model, placement_margin) if placement_margin is not None else model

    model = with_margin(base)
    if clearance is not None:
        tool = dataclasses.replace(base.tool, physics=dataclasses.replace(base.tool.physics, clearance=clearance))
        model = EnumerateWith(model, with_margin(base.with_tool(tool)))
    wrapper._model = model


def tell_target(policy, scene) -> None:
    """``--known-target``: wraps ``policy.placements`` (slax-belief's belief of where the target may stand; main
    checks that the policy has one before the first trial) to return the scene's true target placement alone,
    rounded to the policy's lattice (the wrapped method still runs: it keeps the policy's bookkeeping of consistent
    placements)."""
    step = policy.grid_step
    truth = np.round(np.array([[scene.target.X_ST[0, 3], scene.target.X_ST[1, 3]]]) / step) * step
    placements = policy.placements

    def told(obs):
        placements(obs)
        return truth.copy()

    policy.placements = told


def watch_last_arrangement(policy) -> dict:
    """Wraps ``policy.decide`` to keep the objects of the last observation it decided on (``["known"]``)."""
    seen = {"known": ()}
    decide = policy.decide

    def watched(obs):
        seen["known"] = tuple(obs.known)
        return decide(obs)

    policy.decide = watched
    return seen


def stuck_ending(policy, known, screened: dict, totals: dict) -> str:
    """One line on a trial that ended with no feasible action on the objects ``known``: the action model's feasible
    candidates there, ``screened`` (the trial record's counts per correction) and the refusals by kind; added to
    ``totals``."""
    found = policy.action_model.enumerate(tuple(known))
    refused = collections.Counter(r.kind.value if r.kind is not None else "other" for r in found.rejected)
    totals["endings"] += 1
    totals["feasible"] += len(found.feasible)
    totals["screened"].update(screened)
    totals["refused"].update(refused)
    return (f"no feasible action: {len(found.feasible)} feasible, screened out {screened}, refused "
            f"{dict(refused.most_common())}")


def earlier_outcome(folder, density: int, index: int, success: bool, flips: dict) -> str:
    """" (there: revealed=...)" from ``folder``'s trial file, recording a flip in ``flips``; "" without a folder,
    " (there: no trial)" when the folder has not this trial."""
    if folder is None:
        return ""
    name = f"{density:02d}_{index:04d}"
    path = folder / f"{name}.json"
    if not path.is_file():
        return " (there: no trial)"
    there = bool(json.loads(path.read_text())["success"])
    if there != bool(success):
        flips["won" if success else "lost"].append(name)
    return f" (there: revealed={there})"


if __name__ == "__main__":
    sys.exit(main())
