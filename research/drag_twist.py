"""Which sideways drags of a physics benchmark's Drake trials held their object, against the twist the action model
checks (``max_drag_twist``) reckoned with the object's true mass and with quantiles of its class's mass. Prints
Markdown.

    python research/drag_twist.py PHYSICS_FOLDER [--policy slax-belief] [--quantiles 0.5,0.75,0.9]

For every drag with d_x != 0 (``grip`` "drag": translated along x on the shelf floor) of the folder's Drake trials:
the true object (the record's ``true_object``), its lever (the horizontal distance from the contact the action model
picks on it where it stood, ``before``, to its centre), the twist the model checks, ``drag_safety_factor`` x
``drag_friction`` x m g x lever, with m its true mass and with m at each quantile of its class's log-uniform
distribution (what the model reckons an unweighed hypothesis with: the ``mass_quantile`` rule, 0.5 by default), and
whether the drag matched the prediction (the record's ``mismatch``). Then, per mass, how many of the failed and of
the held drags a check against the run's ``max_drag_twist`` would have refused.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import PhysicsBenchmarkError
from slax_drake.evaluation.settings import physics_run
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.scene.camera import Camera
from slax_drake.scene.mass import quantile_mass
from slax_drake.scene.model import planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.shelf.actions import GRAVITY, ActionModel, contact_lever
from slax_drake.shelf.tool import tool_config
from slax_drake.systems.drag_weigh import is_pull_record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", type=Path, help="a physics benchmark's result folder")
    parser.add_argument("--policy", default="slax-belief")
    parser.add_argument("--quantiles", default="0.5,0.75,0.9", help="class-mass quantiles to reckon with (0-1)")
    args = parser.parse_args(argv)
    try:
        quantiles = [float(q) for q in args.quantiles.split(",")]
        if not all(0.0 <= q <= 1.0 for q in quantiles):
            raise ValueError("a quantile outside 0-1")
    except ValueError as e:
        print(f"error: --quantiles {args.quantiles!r}: {e}", file=sys.stderr)
        return 2
    try:
        settings, trials = physics_run(args.physics, args.policy)
    except PhysicsBenchmarkError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    config, seed = settings["config"], settings["seed"]
    scenario = load_scenario(config)
    tool = tool_config(scenario, settings.get("profile", "station"), **(settings.get("tool_rules") or {}))
    model = ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position, tool)
    rules = tool.rules
    mu = rules.drag_safety_factor * rules.drag_friction
    limit = rules.max_drag_twist
    rows = []
    for path in trials:
        record = json.loads(path.read_text())
        scene = protocol_scene(scenario, record["density"], scene_seed(seed, record["density"], record["index"]))
        objects = {o.name: o for o in scene.objects}
        for k, a in enumerate(record["drake"]["actions"]):
            if a.get("grip") != "drag" or abs(a.get("dx", 0.0)) < 1e-9 or a.get("outcome") is None:
                continue
            obj, before = objects.get(a.get("true_object")), a.get("before")
            if obj is None or before is None:
                continue
            obj = dataclasses.replace(obj, X_SO=planar_pose(before["x"], before["y"], obj.size[2] / 2, before["yaw"]))
            contact = model.suction_contact(obj)
            if contact is None:
                continue
            lever = contact_lever(obj, contact)
            twist = [mu * m * GRAVITY * lever for m in
                     [obj.mass] + [quantile_mass(obj.shape, obj.size, scenario.physics, q) for q in quantiles]]
            weighed = a.get("weighed") if is_pull_record(a.get("weighed")) else None
            rows.append({"trial": path.stem, "step": k + 1, "object": obj.name, "shape": obj.shape, "mass": obj.mass,
                         "dx": a["dx"], "held": not a.get("mismatch"), "mismatch": a.get("mismatch"), "twist": twist,
                         "pull": weighed, "true_friction": rules.drag_friction * obj.mass * GRAVITY, "lever": lever})
    print(f"## Drags along x of `{args.physics}` ({args.policy}): {len(rows)}\n")
    print(f"The check: {rules.drag_safety_factor:g} x {rules.drag_friction:g} x m g x lever <= {limit:.3f} N m "
          "(`max_drag_twist`).\n")
    names = ["true mass"] + [f"class q{q:g}" for q in quantiles]
    print("| trial | step | object | shape | true mass (kg) | d_x (m) | outcome | "
          + " | ".join(f"twist at {n} (N m)" for n in names) + " |")
    print("|---|---|---|---|---|---|---|" + "---|" * len(names))
    for r in rows:
        print(f"| {r['trial']} | {r['step']} | {r['object']} | {r['shape']} | {r['mass']:.2f} | {r['dx']:+.2f} | "
              f"{'held' if r['held'] else r['mismatch']} | " + " | ".join(f"{t:.2f}" for t in r["twist"]) + " |")
    failed = [r for r in rows if not r["held"]]
    held = [r for r in rows if r["held"]]
    print(f"\n{len(failed)} failed, {len(held)} held. Refused by the check reckoned with each mass:\n")
    print("| mass | failed drags refused | held drags refused |\n|---|---|---|")
    for i, n in enumerate(names):
        print(f"| {n} | {sum(r['twist'][i] > limit for r in failed)} of {len(failed)} | "
              f"{sum(r['twist'][i] > limit for r in held)} of {len(held)} |")
    pulled = [r for r in rows if r["pull"] is not None and r["pull"].get("friction_n") is not None]
    if pulled:  # the weigh_drag_pull rule: the friction the arm felt along the pull against the true mass's
        print(f"\n### Weighed along the pull (`weigh_drag_pull`): {len(pulled)}\n")
        print("The friction the arm measured while pulling the object out, against the action model's "
              f"{rules.drag_friction:g} x m g with the true mass, and the twist with each, against {limit:.3f} N m. "
              "A drag pushed back counts as \"put back\" (it did not go where predicted).\n")
        print("| trial | step | object | shape | true mass (kg) | measured friction (N) | mu m g, true mass (N) | ratio | "
              "twist measured (N m) | twist at true mass (N m) | pushed back | outcome |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in pulled:
            w = r["pull"]
            print(f"| {r['trial']} | {r['step']} | {r['object']} | {r['shape']} | {r['mass']:.2f} | "
                  f"{w['friction_n']:.2f} | {r['true_friction']:.2f} | {w['friction_n'] / r['true_friction']:.2f} | "
                  f"{w['twist_nm']:.2f} | {r['twist'][0]:.2f} | {'yes' if w['put_back'] else 'no'} | "
                  f"{'held' if r['held'] else r['mismatch']} |")
        ratios = sorted(r["pull"]["friction_n"] / r["true_friction"] for r in pulled)
        back = [r for r in pulled if r["pull"]["put_back"]]
        print(f"\nMeasured over true friction: median {ratios[len(ratios) // 2]:.2f}, range {ratios[0]:.2f}-"
              f"{ratios[-1]:.2f}. Pushed back {len(back)}, of which the true mass's twist was over the limit in "
              f"{sum(r['twist'][0] > limit for r in back)}; slid across {len(pulled) - len(back)}, of which it was "
              f"over the limit in {sum(r['twist'][0] > limit for r in pulled if not r['pull']['put_back'])}.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
