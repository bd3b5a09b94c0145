"""What made the suctions of camera-mode Table I trials fail at the front of the bay ("could not place the object:
put back"), replayed on the true scene. Prints Markdown.

    python research/put_back_causes.py FOLDER [--policy slax-belief] [--densities 8,10] [--scenes N]
        [--config sim_configs/table1.yaml]

FOLDER holds a `slax-drake benchmark` camera-mode run (``settings.json`` and ``trials/<policy>/DD_NNNN.json``; the
render's labels, no sensor noise, the frames at the policy's width). Each trial is replayed step by step: the true
scene is drawn again from its seed, the shelf simulator's CameraObserver renders and tracks each frame as the
benchmark did (told the executed action on its hypothesis), and the trial's actions are executed again (the
executor is deterministic). At each put-back the placement is executed again on altered scenes, in this order, and
the first that places the object names the cause:

- ``carried object``: the carried object replaced by its hypothesis (its estimate of this frame): the true object
  reaches beyond what the frame showed of it;
- ``seen neighbour``: every object seen in the frame replaced by its hypothesis: a seen neighbour reaches beyond
  its estimate (or several seen objects together);
- ``target``: the target removed as well;
- else an object not in the frame stops it (the first such object whose removal alone changes the outcome; a seen
  object's estimate may share the blame, e.g. the carried object cannot be lowered onto it short of the unseen
  one): ``seen before`` (an earlier frame of the trial showed it), ``never seen``, or ``several`` (no single
  object not in the frame).

``on the policy's own estimates``: the same placement executed on the frame's hypotheses alone (what the policy
planned on; every put-back should be placed there). ``replay`` counts the steps whose replayed frame gave the
executed object a track other than the one the trial's decision named (0 when the replay is faithful).
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import UserError
from slax_drake.evaluation.table1 import protocol_scene
from slax_drake.evaluation.trial_records import read_trial_records
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.actions import Suction
from slax_drake.shelf.simulator import PUT_BACK, CameraObserver, execute, split_note

sys.path.insert(0, str(Path(__file__).resolve().parent))
from camera_divergence import blockers, parse_action  # noqa: E402  (the research scripts' shared helpers)

CAUSES = ("carried object", "seen neighbour", "target", "seen before", "never seen", "several")


def _placed(scene, action, model) -> bool:
    """Whether ``action`` on ``scene`` moves its object (placed, perhaps stopped short; not left where it stood)."""
    after, _ = execute(scene, action, model)
    before = next(o for o in scene.objects if o.name == action.name)
    moved = next(o for o in after.objects if o.name == action.name)
    return bool((before.center[:2] != moved.center[:2]).any())


def _as(hypothesis, name: str):
    return dataclasses.replace(hypothesis, name=name)


def put_back_causes(scenario, trial: dict, model, width: int) -> tuple[list[str], collections.Counter]:
    """(the cause of each put-back of ``trial``, in order; counts of the replay checks)."""
    scene = protocol_scene(scenario, trial["density"], trial["seed"])
    observer = CameraObserver(scene.shelf, scene.camera, tuple(scenario.target.sizes[0]), width=width)
    observer.start()
    notes = {step: text for step, text in map(split_note, trial["notes"]) if step is not None}
    log = trial.get("decision_log") or []
    causes, checks, ever = [], collections.Counter(), set()
    for k, text in enumerate(trial["actions"], start=1):
        observation, names = observer.observe(scene)
        ever |= set(names.values())
        try:
            action = parse_action(text)
        except ValueError:
            break
        track = {true: hyp for hyp, true in names.items()}.get(action.name)
        if track is None:
            checks["replay: the executed object has no track"] += 1
            break
        planned = (log[k - 1].get("plan") or [""])[0].split() if k - 1 < len(log) else []
        if len(planned) > 1 and planned[1] != track:
            checks["replay: another track than the decision's"] += 1
        hypotheses = {names[h.name]: h for h in observation.known if h.name in names}
        true = next(o for o in scene.objects if o.name == action.name)
        hyp = hypotheses[action.name]
        on_hypothesis = (dataclasses.replace(action, dz=action.dz - float(true.center[1] - hyp.center[1]))
                         if isinstance(action, Suction) else action)
        if k in notes and notes[k] == PUT_BACK:
            own = dataclasses.replace(scene, objects=tuple(observation.known), target=None)
            checks["placed on the policy's own estimates" if _placed(
                own, dataclasses.replace(on_hypothesis, name=track), model)
                else "put back on the policy's own estimates too"] += 1
            carried = scene.with_objects(tuple(_as(hyp, o.name) if o.name == action.name else o
                                               for o in scene.objects))
            seen = scene.with_objects(tuple(_as(hypotheses[o.name], o.name) if o.name in hypotheses else o
                                            for o in scene.objects))
            no_target = dataclasses.replace(seen, target=None)
            if _placed(carried, on_hypothesis, model):
                causes.append("carried object")
            elif _placed(seen, on_hypothesis, model):
                causes.append("seen neighbour")
            elif _placed(no_target, on_hypothesis, model):
                causes.append("target")
            else:
                found = [b for b in blockers(no_target, on_hypothesis, model) if b not in hypotheses]
                causes.append("several" if not found else "seen before" if found[0] in ever else "never seen")
        observer.executed(dataclasses.replace(on_hypothesis, name=track))
        scene, _ = execute(scene, action, model)
    return causes, checks


def _densities(text: str) -> list[int]:
    try:
        return [int(d) for d in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of object counts: {text!r}") from None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder")
    ap.add_argument("--policy", default="slax-belief")
    ap.add_argument("--densities", type=_densities, default=[8, 10])
    ap.add_argument("--scenes", type=int, default=None, help="the first N scenes per density (default: all)")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    args = ap.parse_args()
    if args.scenes is not None and args.scenes < 1:
        ap.error("--scenes must be 1 or more")
    try:
        settings = json.loads(Path(args.folder, "settings.json").read_text())
        trials = read_trial_records(args.folder, args.policy, missing_ok=True)
    except (OSError, ValueError, UserError) as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(2)
    camera = settings.get("camera") or {}
    if settings.get("observation") != "camera" or camera.get("segmentation") != "labels" or camera.get(
            "sensor_noise") or camera.get("full_resolution"):
        print(f"error: {args.folder} is not a camera-mode run with the render's labels, no noise, at the policy's "
              "width (what this replay renders)", file=sys.stderr)
        raise SystemExit(2)
    scenario = load_scenario(args.config)
    print(f"# Put-backs of {args.policy} in {args.folder}\n")
    print("| objects | trials | put back | " + " | ".join(CAUSES) + " | replay checks |")
    print("|---|---|---|" + "---|" * len(CAUSES) + "---|")
    for density in args.densities:
        policy = make_policy(args.policy, scenario, horizon=2 * density, profile=settings.get("profile"),
                             tool_overrides=settings.get("tool_rules") or None)
        keys = sorted(k for k in trials if k.startswith(f"{density:02d}_"))[:args.scenes]
        causes, checks = collections.Counter(), collections.Counter()
        for key in keys:
            found, seen = put_back_causes(scenario, trials[key], policy.action_model, policy.observation_width)
            causes.update(found)
            checks.update(seen)
        total = sum(causes.values())
        print(f"| {density} | {len(keys)} | {total} | " + " | ".join(
            f"{causes[c]} ({100 * causes[c] / max(total, 1):.0f} %)" for c in CAUSES) + " | " + ", ".join(
            f"{n} {v}" for v, n in sorted(checks.items())) + " |")


if __name__ == "__main__":
    main()
