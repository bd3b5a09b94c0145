"""How much a policy's decisions depend on how its camera frame is sampled, and which sampling Drake's trials see.
Prints Markdown.

    python research/frame_sampling.py PHYSICS_FOLDER [--shelf FOLDER ...] [--scenes-per-density 20]
        [--policy slax-belief]

The shelf simulator's camera mode ray-casts each frame at the policy's working resolution (160 x 120), every pixel
at its own centre; the Drake station renders at the camera's resolution (640 x 480) and its PerceptionSystem
resamples to the working one by the nearest pixel, which at 640 -> 160 is the pixel 1/8 px below and to the right
of the centre (``perception.observation.resample_nearest``). For each scene of PHYSICS_FOLDER (a physics
benchmark's result folder; its settings give the config, the protocol seed and the rules) this computes the policy's
first decision on both frames and compares them with each other and with the first action of the stored Drake trial
(trials whose first decision had no candidate rejected by the planner). With ``--shelf`` (Table I result folders
of the same scenes, policy and rules, e.g. one run with ``--full-resolution`` and one without), it also compares
each folder's trial outcomes with the Drake trials' scene by scene.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import PhysicsBenchmarkError
from slax_drake.evaluation.settings import physics_run
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import CameraObserver


def first_decision(scenario, density: int, seed: int, policy_name: str, rules: dict, profile: str,
                   full_resolution: bool) -> str | None:
    """The policy's first decision (``Action.describe()``) on the protocol scene, or None when it finds none."""
    scene = protocol_scene(scenario, density, seed)
    size = tuple(scenario.target.sizes[0])
    policy = make_policy(policy_name, scenario, perception="ground-truth",
                         horizon=scenario.protocol.horizon_per_object * density, tool_overrides=rules, profile=profile)
    observer = CameraObserver(scene.shelf, scene.camera, size, width=policy.observation_width,
                              full_resolution=full_resolution)
    policy.reset(scene)
    observer.start()
    obs, _ = observer.observe(scene)
    best = policy.decide(obs).best
    return None if best is None else best.describe()


def kind_and_amount(described: str | None) -> tuple | None:
    """("push", d) or ("suction", dx) from a described action ("push object_2 d=-0.145", ...), to 1 mm."""
    if described is None:
        return None
    words = described.split()
    return words[0], round(float(words[2].split("=")[1]), 3)


def drake_first(record: dict) -> tuple | None:
    """The stored Drake trial's first action as (kind, amount), None when it has none or the planner rejected a
    candidate before it (the policy then decided again)."""
    actions = record["drake"]["actions"]
    if not actions or actions[0].get("rejected_before"):
        return None
    a = actions[0]
    return ("push", round(a["d"], 3)) if a["type"] == "push" else ("suction", round(a["dx"], 3))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", type=Path, help="a physics benchmark's result folder")
    parser.add_argument("--shelf", type=Path, nargs="*", default=[], help="Table I result folders of the same scenes")
    parser.add_argument("--scenes-per-density", type=int, default=None, help="default: the folder's")
    parser.add_argument("--policy", default="slax-belief")
    args = parser.parse_args(argv)
    try:
        settings, trials = physics_run(args.physics, args.policy)
    except PhysicsBenchmarkError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    scenario = load_scenario(settings["config"])
    rules, profile, seed = settings.get("tool_rules") or {}, settings.get("profile", "station"), settings["seed"]
    records = [json.loads(p.read_text()) for p in trials]
    if args.scenes_per_density is not None:
        records = [r for r in records if r["index"] < args.scenes_per_density]
    counts = collections.Counter()
    for r in records:
        s = scene_seed(seed, r["density"], r["index"])
        working = first_decision(scenario, r["density"], s, args.policy, rules, profile, False)
        full = first_decision(scenario, r["density"], s, args.policy, rules, profile, True)
        counts["scenes"] += 1
        counts["same first decision"] += working == full
        drake = drake_first(r)
        if drake is not None:
            counts["Drake first actions"] += 1
            counts["Drake's = working-resolution frame's"] += kind_and_amount(working) == drake
            counts["Drake's = full-resolution frame's"] += kind_and_amount(full) == drake
    print(f"## First decisions of {args.policy} on {counts['scenes']} scenes of `{args.physics}`\n")
    print("| | count |\n|---|---|")
    print(f"| scenes | {counts['scenes']} |")
    print(f"| same first decision on the working-resolution and the full-resolution frame | "
          f"{counts['same first decision']} |")
    print(f"| Drake trials whose first decision had no candidate rejected | {counts['Drake first actions']} |")
    for key in ("Drake's = working-resolution frame's", "Drake's = full-resolution frame's"):
        print(f"| ... whose first action is the {key.split('= ')[1]} | {counts[key]} |")
    if args.shelf:
        print("\n## Outcomes beside the Drake trials\n")
        print("| shelf folder | scenes | same outcome as Drake | shelf revealed | Drake revealed | "
              "Drake, nothing lost |\n|---|---|---|---|---|---|")
        for folder in args.shelf:
            same = shelf_won = drake_won = kept = n = 0
            for r in records:
                path = folder / "trials" / args.policy / f"{r['density']:02d}_{r['index']:04d}.json"
                if not path.is_file():
                    continue
                shelf = json.loads(path.read_text())
                d = r["drake"]
                n += 1
                same += shelf["success"] == d["success"]
                shelf_won += shelf["success"]
                drake_won += d["success"]
                kept += d["success"] and not d["toppled"] and not d["dropped"]
            print(f"| `{folder}` | {n} | {same} | {shelf_won} | {drake_won} | {kept} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
