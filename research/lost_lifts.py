"""Which lifted suctions of a physics benchmark's Drake trials lost their object, against the moment the object's
true weight hangs off the cup, and what the cup's weighing made of them. Prints Markdown.

    python research/lost_lifts.py PHYSICS_FOLDER [--policy slax-belief]

For every lifted suction (``grip`` "lift") of the folder's Drake trials: the true object (the record's
``true_object``; a run recorded before it was kept is matched by the object nearest the action's ``before`` pose
among the scene's initial objects, an approximation for objects moved earlier in the trial, and says so), its true
mass and its held moment at the contact the action model picks on it where it stood (``before``; mass x g x the
horizontal distance from that contact to its centre: the hypothesis's contact differs by the estimate's error), the mass the planner reckoned with (the object's class median: what a hypothesis without a weighing
weighs, :func:`slax_drake.scene.mass.median_mass`), and whether the object was lost after it (toppled or dropped).
The lifts are counted per band of the true held moment: within the station's limit (``max_suction_moment`` of the
run's rules), over it but under the cup's lip moment (what the sealed lip resists), over the lip. A run whose trials
weighed their lifts (``weighed`` in the record) also gets the verdicts per band: carried, or put back and why.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import math
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import PhysicsBenchmarkError
from slax_drake.evaluation.settings import physics_run
from slax_drake.evaluation.physics import put_back_why
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.scene.camera import Camera
from slax_drake.scene.mass import median_mass
from slax_drake.scene.model import planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.shelf.actions import GRAVITY, ActionModel
from slax_drake.shelf.tool import tool_config
from slax_drake.station.scenario import load_station_scenario, station_for
from slax_drake.systems.guard import MIN_HELD_WEIGHT


def true_object(scene, action: dict):
    """(the scene object the lift acted on, whether it was matched by the nearest initial pose)."""
    objects = {o.name: o for o in scene.objects}
    name = action.get("true_object")
    if name in objects:
        return objects[name], False
    before = action.get("before")
    if before is None:
        return None, True
    nearest = min(scene.objects, key=lambda o: math.hypot(o.center[0] - before["x"], o.center[1] - before["y"]))
    return nearest, True


def band(moment: float, limit: float, lip: float) -> str:
    if moment <= limit:
        return f"within the limit (<= {limit:.2f} N m)"
    if moment <= lip:
        return f"over the limit, under the lip ({limit:.2f}-{lip:.2f} N m)"
    return f"over the lip (> {lip:.2f} N m)"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", type=Path, help="a physics benchmark's result folder")
    parser.add_argument("--policy", default="slax-belief")
    args = parser.parse_args(argv)
    try:
        settings, trials = physics_run(args.physics, args.policy)
    except PhysicsBenchmarkError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    config, seed = settings["config"], settings["seed"]
    scenario = load_scenario(config)
    recorded = settings.get("station")  # an absolute path where the run was made; this checkout's when it is gone
    station = load_station_scenario(recorded if recorded and Path(recorded).is_file() else station_for(config))
    limit = float((settings.get("tool_rules") or {}).get("max_suction_moment", station.suction.max_held_moment))
    lip = station.suction.lip_moment
    model = ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position,
                        tool_config(scenario, settings.get("profile", "station"), **(settings.get("tool_rules") or {})))
    rows, approximate = [], 0
    for path in trials:
        record = json.loads(path.read_text())
        scene = protocol_scene(scenario, record["density"], scene_seed(seed, record["density"], record["index"]))
        for k, a in enumerate(record["drake"]["actions"]):
            if a["type"] != "suction" or a.get("grip") != "lift":
                continue
            obj, guessed = true_object(scene, a)
            if obj is None:
                continue
            approximate += guessed
            before = a.get("before")
            if before is not None:  # where it stood when the cup took it
                obj = dataclasses.replace(obj, X_SO=planar_pose(before["x"], before["y"], obj.size[2] / 2,
                                                                before["yaw"]))
            contact = model.suction_contact(obj)
            lever = None if contact is None else math.hypot(obj.center[0] - contact[0], obj.center[1] - contact[1])
            median = median_mass(obj.shape, obj.size, scenario.physics)
            rows.append({"trial": path.stem, "step": k + 1, "object": obj.name, "shape": obj.shape,
                         "mass": obj.mass, "median": median, "lever": lever, "lost": bool(a.get("lost_after")),
                         "weighed": a.get("weighed"), "guessed": guessed})
    print(f"## Lifted suctions of `{args.physics}` ({args.policy}): {len(rows)}\n")
    print(f"Station limit {limit:.2f} N m, the cup's lip moment {lip:.2f} N m.")
    if approximate:
        print(f" {approximate} of them matched to their object by the nearest initial pose (the run did not record "
              "the true object).")
    masses = sorted(r["mass"] / r["median"] for r in rows if r["mass"])
    if masses:
        print(f" True mass over the class median the planner reckons with: median {masses[len(masses) // 2]:.2f}, "
              f"from {masses[0]:.2f} to {masses[-1]:.2f}.")
    print()
    counts = collections.defaultdict(collections.Counter)
    for r in rows:
        contact = r["lever"]
        if contact is None:  # no face the cup may take (not expected for an object it lifted)
            key = "no contact"
        else:
            key = band(r["mass"] * GRAVITY * contact, limit, lip)
        c = counts[key]
        c["lifts"] += 1
        c["lost"] += r["lost"]
        w = r["weighed"]
        if w is not None:
            c["weighed"] += 1
            c[f"put back: {put_back_why(w)}" if w.get("put_back") else "carried"] += 1
            c["lost after being carried"] += r["lost"] and not w.get("put_back")
    reads = [r["weighed"]["weight_n"] / (r["mass"] * GRAVITY) for r in rows
             if r["weighed"] is not None and r["weighed"]["weight_n"] >= MIN_HELD_WEIGHT]
    if reads:
        within = sum(abs(x - 1.0) <= 0.01 for x in reads)
        under = sorted(x for x in reads if x < 0.99)
        over = sorted(x for x in reads if x > 1.01)
        print(f"The weighing read {len(reads)} held loads: the true weight to within 1 % in {within}; "
              f"less in {len(under)}" + (f" ({under[0] * 100:.0f}-{under[-1] * 100:.0f} % of it)" if under else "")
              + f"; more in {len(over)}" + (f" (up to {over[-1] * 100:.0f} %)" if over else "") + ".\n")
    verdicts = sorted({k for c in counts.values() for k in c if k.startswith("put back")})
    weighed = any(c["weighed"] for c in counts.values())
    head = ["true held moment", "lifts", "lost"] + (["carried", *verdicts, "lost after being carried"] if weighed else [])
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    order = [band(0.0, limit, lip), band(limit + 1e-9, limit, lip), band(math.inf, limit, lip), "no contact"]
    for key in [k for k in order if k in counts]:
        c = counts[key]
        cells = [key, c["lifts"], c["lost"]] + ([c["carried"], *(c[v] for v in verdicts), c["lost after being carried"]]
                                                if weighed else [])
        print("| " + " | ".join(str(x) for x in cells) + " |")
    lost = [r for r in rows if r["lost"]]
    if lost:
        print("\nLost after a lift:\n")
        print("| trial | step | object | shape | true mass (kg) | class median (kg) | true held moment (N m) | weighed |")
        print("|---|---|---|---|---|---|---|---|")
        for r in lost:
            moment = "" if r["lever"] is None else f"{r['mass'] * GRAVITY * r['lever']:.2f}"
            w = r["weighed"]
            said = "" if w is None else (f"{w['weight_n']:.1f} N, {w['moment_nm']:.2f} N m"
                                         + (f", put back: {put_back_why(w)}" if w.get("put_back") else ", carried"))
            print(f"| {r['trial']} | {r['step']} | {r['object']}{' (nearest)' if r['guessed'] else ''} | {r['shape']} "
                  f"| {r['mass']:.2f} | {r['median']:.2f} | {moment} | {said} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
