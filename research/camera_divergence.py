"""Where a policy's camera-mode Table I trials diverge from its privileged ones, and what its wasted actions ran
into. Prints Markdown.

    python research/camera_divergence.py CAMERA_FOLDER PRIVILEGED_FOLDER [--policy slax-belief]
        [--densities 8,10] [--config sim_configs/table1.yaml] [--profile paper] [--privileged-policy NAME]

Both folders hold ``trials/<policy>/DD_NNNN.json`` for the same scenes (same protocol seed). Per scene: both
outcomes, the first executed action that differs (actions name the true objects in both modes) and the number of
wasted actions (the simulator's notes). Every wasted action of a camera trial is then explained by replaying the
trial's executed actions on the true scene (drawn again from its seed; execution is deterministic): the objects
whose removal alone changes the action's outcome are what stopped it, and each is classed by what the policy's
camera had shown of it up to that step (the 160 px frame's labels, as the CameraObserver renders them):

- ``seen now``: the blocker is in the current frame: the policy had a hypothesis for it, and the true object
  reaches beyond the hypothesis (its unseen depth or an occluded side);
- ``seen before``: seen at an earlier step of the trial, wholly hidden now (the policy's memory of hidden objects);
- ``never seen``: no frame so far showed it (the privileged policy does not know it either);
- ``target``; ``walls`` (a placement beyond the walls: the true object is wider or stands elsewhere in x than its
  hypothesis); ``several`` (no single object's removal changes the outcome).
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import re
import sys
from pathlib import Path

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.errors import UserError
from slax_drake.shelf.actions import Push, Suction
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import execute, split_note
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.evaluation.table1 import protocol_scene
from slax_drake.evaluation.trial_records import read_trial_records

_PUSH = re.compile(r"push (\S+) d=([-+\d.]+)$")
_SUCTION = re.compile(r"suction (\S+) dx=([-+\d.]+) dz=([-+\d.]+)$")


def parse_action(text: str):
    """An executed action from its description (pushes and untilted suctions; the executor ignores ``q``)."""
    m = _PUSH.match(text)
    if m:
        return Push(m.group(1), (0.0, 0.0, 0.0), float(m.group(2)))
    m = _SUCTION.match(text)
    if m:
        return Suction(m.group(1), (0.0, 0.0, 0.0), float(m.group(2)), float(m.group(3)))
    raise ValueError(f"cannot parse action {text!r}")


def _outcome(scene, action, model):
    after, note = execute(scene, action, model)
    obj = after.object_named(action.name)
    return note, np.round(np.asarray(obj.center[:2], dtype=float), 6)


def blockers(scene, action, model) -> list[str]:
    """The obstacles (object names or "target") whose removal alone changes ``action``'s outcome on ``scene``."""
    note, end = _outcome(scene, action, model)
    found = []
    for o in scene.objects:
        if o.name == action.name:
            continue
        without = scene.with_objects(tuple(x for x in scene.objects if x.name != o.name))
        n2, e2 = _outcome(without, action, model)
        if n2 != note or not np.array_equal(e2, end):
            found.append(o.name)
    if scene.target is not None:
        n2, e2 = _outcome(dataclasses.replace(scene, target=None), action, model)
        if n2 != note or not np.array_equal(e2, end):
            found.append("target")
    return found


def classify_trial(scenario, trial: dict, model, width: int = 160) -> list[tuple[int, str, str]]:
    """(step, note kind, blocker class) for every wasted action of a camera trial (see the module docstring)."""
    density = trial["density"]
    scene = protocol_scene(scenario, density, trial["seed"])
    cam = scene.camera
    camera = cam.with_resolution(width, max(1, int(round(cam.height * width / cam.width))))
    names = [o.name for o in scene.objects]
    ever: set = set()
    out = []
    notes = {step: text for step, text in map(split_note, trial["notes"]) if step is not None}
    for k, text in enumerate(trial["actions"], start=1):
        _, labels = SceneRaycaster(scene, include_target=True).render(camera)
        now = {names[int(v) - 1] for v in np.unique(labels) if 1 <= v <= len(names)}
        ever |= now
        try:
            action = parse_action(text)
        except ValueError:
            continue
        if action.name not in names:
            if k in notes:
                out.append((k, "no object", "segment of the shelf"))
            continue
        if k in notes:
            kind = re.sub(r"[-+]\d\.\d+ m", "X m", re.sub(r"object_\d+", "OBJ", notes[k]))
            if "outside the walls" in kind:
                out.append((k, kind, "walls"))
            else:
                found = blockers(scene, action, model)
                if not found:
                    cls = "several"
                else:
                    b = found[0]
                    cls = ("target" if b == "target" else "seen now" if b in now else
                           "seen before" if b in ever else "never seen")
                out.append((k, kind, cls))
        scene, _ = execute(scene, action, model)
    return out


def first_difference(a: list, b: list):
    for k, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return k
    return None if len(a) == len(b) else min(len(a), len(b))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("camera")
    ap.add_argument("privileged")
    ap.add_argument("--policy", default="slax-belief")
    ap.add_argument("--privileged-policy", default=None, help="the policy's name in PRIVILEGED_FOLDER (default: --policy)")
    ap.add_argument("--densities", default="8,10")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    ap.add_argument("--profile", default="paper")
    args = ap.parse_args()
    privileged_policy = args.privileged_policy or args.policy
    try:
        camera_trials = read_trial_records(args.camera, args.policy, missing_ok=True)
        privileged_trials = read_trial_records(args.privileged, privileged_policy, missing_ok=True)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(2)
    scenario = load_scenario(args.config)
    totals = {}
    for density in (int(d) for d in args.densities.split(",")):
        model = make_policy(privileged_policy, scenario, horizon=2 * density,
                            profile=args.profile).action_model  # the executor's model (a registry name)
        print(f"\n## {density} objects\n")
        print("| scene | camera | privileged | first differing step: camera / privileged | wasted camera / priv. "
              "| camera's wasted actions: blocker class |")
        print("|---|---|---|---|---|---|")
        classes = {"fail": collections.Counter(), "all": collections.Counter()}
        for key in (k for k in camera_trials if k.startswith(f"{density:02d}_")):
            if key not in privileged_trials:
                continue
            c, p = camera_trials[key], privileged_trials[key]
            if c["seed"] != p["seed"]:
                path = Path(args.camera, "trials", args.policy, f"{key}.json")
                ppath = Path(args.privileged, "trials", privileged_policy, f"{key}.json")
                print(f"error: {path} and {ppath} are trials of different scenes (seeds {c['seed']}, {p['seed']})",
                      file=sys.stderr)
                raise SystemExit(2)
            k = first_difference(c["actions"], p["actions"])
            where = "same" if k is None else (
                f"{k + 1}: {c['actions'][k] if k < len(c['actions']) else '-'} / "
                f"{p['actions'][k] if k < len(p['actions']) else '-'}")
            wasted = classify_trial(scenario, c, model)
            counts = collections.Counter(cls for _, _, cls in wasted)
            classes["all"].update(counts)
            if not c["success"]:
                classes["fail"].update(counts)
            print(f"| {c['index']} | {'ok' if c['success'] else 'FAIL'} {c['steps']} | "
                  f"{'ok' if p['success'] else 'FAIL'} {p['steps']} | {where} | {len(c['notes'])} / {len(p['notes'])} "
                  f"| {', '.join(f'{v} {n}' for n, v in counts.most_common())} |")
        totals[density] = classes
    print("\n## Wasted camera actions by blocker class\n")
    print("| objects | trials | " + " | ".join(["seen now", "seen before", "never seen", "target", "walls", "several",
                                                  "segment of the shelf"]) + " |")
    print("|---|---|" + "---|" * 7)
    for density, classes in totals.items():
        for which in ("fail", "all"):
            c = classes[which]
            print(f"| {density} | {'failed' if which == 'fail' else 'all'} | " + " | ".join(
                str(c[k]) for k in ["seen now", "seen before", "never seen", "target", "walls", "several",
                                    "segment of the shelf"]) + " |")


if __name__ == "__main__":
    main()
