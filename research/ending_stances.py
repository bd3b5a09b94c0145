"""Would the robot standing elsewhere along the shelf have made the motions that ended its Drake trials "no feasible
motion"? For each trial folder (``slax-drake trial --out DIR``, e.g. ``--benchmark-scene 8:13``) whose trial ended
"no feasible motion": the candidates the motion planner refused at its last decision, planned again on that
decision's believed scene (its estimated objects, as the planner saw them) from the observation pose with the robot's
base moved DX along the shelf's x (the scene camera moved with the base, so the shelf and the objects stand shifted
the other way relative to the arm; :func:`reach_rule.plan_from_stances`). Prints Markdown: per trial, each refused
candidate, why, whether this code's planner plans it where the robot stood (a control: "yes" means the planner
changed since the trial was run) and the base shifts from which it plans.

    python research/ending_stances.py TRIAL_DIR [TRIAL_DIR ...] [--stances -0.2 -0.1 0.1 0.2]

A trial that ended otherwise is listed and skipped. Candidates are found again among the action model's feasible
actions on the decision's hypotheses by their description, else as check-action matches a move, else so without the
hidden-space rules (the trial's hidden space came from its frame, which the record does not keep; the planner does not
read it); one still not found is said so, with the model's reason.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from drake_divergence import shelf_step
from reach_rule import plan_from_stances


def believed_scene(folder: Path, entry: dict):
    """The scene the planner planned the decision ``entry`` (a trial.json ``steps_log`` entry) in: the trial's
    initial scene (shelf, camera) with the decision's hypotheses as its objects and no target."""
    from slax_drake.scene.io import load_scene
    from slax_drake.scene.model import SceneObject, planar_pose

    scene = load_scene(folder / "scene.json")
    objects = tuple(SceneObject(name, h["shape"], tuple(h["size"]), planar_pose(h["x"], h["y"], h["size"][2] / 2.0,
                                                                                  h["yaw"]))
                    for name, h in entry["hypotheses"].items())
    return dataclasses.replace(scene, objects=objects, target=None)


def check_spec(described: str) -> tuple:
    """A candidate's description ("push NAME d=D", "suction NAME dx=DX dz=DZ ...") as check-action's spec
    (:func:`slax_drake.hardware.check_action.parse_action`), read by :func:`drake_divergence.shelf_step`."""
    kind, name, d, dz = shelf_step(described)
    return ("push", name, d) if kind == "push" else ("suction", name, d, dz)


def trial_checker(scene, data: dict, **rules):
    """The action model and motion planner the trial planned with (its scenario's masses, its profile and recorded
    rules, its station) for ``scene``; ``rules`` override the recorded ones."""
    from slax_drake.config import load_scenario
    from slax_drake.hardware.check_action import make_checker
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import station_for

    tool = tool_config(load_scenario(data["config"]), data.get("profile", "station"),
                       **{**data.get("tool_rules", {}), **rules})
    station = data["station"]  # an absolute path where the trial ran; this checkout's when it is gone
    return make_checker(scene, station if Path(station).is_file() else station_for(data["config"]), tool=tool)


def _table(records, stances) -> None:
    """Prints the Markdown table and its summary for the trial ``records`` (folder, trial.json data, its last
    decision's entry, the believed scene of that decision)."""
    print("| trial | refused candidate | why | plans where the robot stood (this code) | plans from base shifts (m) |\n"
          "|---|---|---|---|---|")
    planned = planned_here = refused_total = trials_rescued = not_offered = 0
    for folder, data, entry, scene in records:
        if data.get("result") != "no feasible motion":
            print(f"| {folder.name} | (ended \"{data.get('result')}\") | | | |")
            continue
        checker = trial_checker(scene, data)
        unhidden = trial_checker(checker.scene, data, push_hidden_check=False, suction_hidden_rule="none")
        offered = {a.describe(): a for a in checker.model.enumerate(checker.scene.objects).feasible}
        rescued = False
        for rejected in entry.get("rejected", []):
            refused_total += 1
            why = f"{rejected.get('kind')} at the {rejected.get('waypoint')}"
            action, missing = offered.get(rejected["action"]), ""
            if action is None:  # the same move as check-action matches it (a push of that length, a placement within 1 cm)
                action, missing = checker.resolve(check_spec(rejected["action"]))
            if action is None:  # the trial's hidden space came from its frame, not from the hypotheses' shadows: the
                # move's geometry without the hidden-space rules (the planner does not read them)
                action, missing = unhidden.resolve(check_spec(rejected["action"]))
            if action is None:
                not_offered += 1
                print(f"| {folder.name} | {rejected['action']} | {why} | not offered on the hypotheses: {missing} | |")
                continue
            (_, shifts), = plan_from_stances(checker, [action], [0.0, *stances])
            here = 0.0 in shifts
            shifts = [dx for dx in shifts if dx != 0.0]
            planned_here += here
            if not here:  # the refusal reproduced: does another stance plan it?
                planned += bool(shifts)
                rescued |= bool(shifts)
            print(f"| {folder.name} | {rejected['action']} | {why} | {'yes' if here else 'no'} | "
                  f"{', '.join(f'{dx:+.2f}' for dx in shifts) or 'none'} |")
        trials_rescued += rescued
    reproduced = refused_total - planned_here - not_offered
    print(f"\nOf {refused_total} refused candidates, {not_offered} are not offered on the hypotheses again and "
          f"{planned_here} plan where the robot stood with this code (the trial's refusal not reproduced: the planner "
          f"changed since, or its start state or the recorded rounding of the hypotheses matters); of the "
          f"{reproduced} refusals reproduced, {planned} plan from some base shift "
          f"({', '.join(f'{dx:+.2f}' for dx in stances)} m). {trials_rescued} of the trials would have had a "
          "motion from another stance.")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trials", nargs="+", help="trial folders (each holds trial.json and scene.json)")
    parser.add_argument("--stances", type=float, nargs="+", default=[-0.2, -0.1, 0.1, 0.2],
                        help="base shifts along the shelf's x to try (m; not 0)")
    args = parser.parse_args(argv)
    if 0.0 in args.stances:
        print("error: --stances: 0 is where the robot stood, always tried; give the shifts", file=sys.stderr)
        return 2
    from slax_drake.errors import UserError

    records = []
    for folder in map(Path, args.trials):
        try:
            data = json.loads((folder / "trial.json").read_text())
            entry = data["steps_log"][-1]
            records.append((folder, data, entry, believed_scene(folder, entry)))
        except (OSError, ValueError, KeyError, IndexError) as e:
            print(f"error: {folder}: not a trial folder with trial.json and scene.json ({e})", file=sys.stderr)
            return 2
        except UserError as e:  # its scene file cannot be read
            print(f"error: {e}", file=sys.stderr)
            return 2

    try:
        _table(records, args.stances)
    except UserError as e:  # a scenario or station the trial names that cannot be read
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
