"""The objects a physics benchmark's Drake trials lost, one row each, and what the trial made of it. Prints Markdown.

    python research/lost_objects.py PHYSICS_FOLDER [--policy slax-belief]

PHYSICS_FOLDER is a physics benchmark's result folder with its settings and trial files
(``physics_trials/POLICY/*.json``). An object is lost when the trial record names it toppled or dropped (tilted more
than 20 deg, or outside the bay, at the end). Per lost object: the trial's ending and whether it revealed the target;
the actions that moved it (its ``true_object``; 1-based, with the record's mismatch when one was recorded), or none
(another action's motion took it along: collateral); where it ended (x, y, z in the shelf frame S, m) and whether it
ended *beneath the bay*: its centre below the support surface while over the bay's floor (within the bay's width and
depth), i.e. it passed through the support board or hangs caught at its front edge; an object that fell off the shelf
lies on the room's floor, far lower, and outside the bay. The bay's size is the run's scenario's (``config`` of its
settings).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import ConfigError, PhysicsBenchmarkError, UserError
from slax_drake.evaluation.settings import physics_run
from slax_drake.evaluation.trial_records import analyse_trial_records
from slax_drake.scene.sampling import shelf_of

BENEATH_DEPTH = 0.30  # m: a centre this far below the support surface at most counts as beneath the bay (the room's
# floor is farther down)


def beneath_the_bay(pose: dict, width: float, depth: float) -> bool:
    """Whether a final pose (S, m) has its centre below the support surface, over the bay's floor."""
    return (-BENEATH_DEPTH < float(pose["z"]) < 0.0 and abs(float(pose["x"])) < width / 2.0
            and abs(float(pose["y"])) < depth / 2.0)


def lost_objects(drake: dict, width: float, depth: float) -> list[dict]:
    """One dict per object the Drake trial ``drake`` lost (see the module docstring): name, how (toppled, dropped),
    the actions that moved it [(1-based index, mismatch or None)], its final pose and whether it ended beneath the
    bay."""
    toppled, dropped = set(drake["toppled"]), set(drake["dropped"])
    rows = []
    for name in sorted(toppled | dropped):
        final = drake["final_objects"][name]
        moved_by = [(k, a.get("mismatch")) for k, a in enumerate(drake["actions"], 1) if a.get("true_object") == name]
        rows.append({"object": name, "how": " and ".join(w for w, s in (("toppled", toppled), ("dropped", dropped))
                                                          if name in s),
                     "moved_by": moved_by, "final": final, "beneath": beneath_the_bay(final, width, depth)})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", type=Path, help="a physics benchmark's result folder (with its trial files)")
    parser.add_argument("--policy", default="slax-belief")
    args = parser.parse_args(argv)
    try:
        settings, _ = physics_run(args.physics, args.policy)
        shelf = shelf_of(load_scenario(settings["config"]))
        records, found = analyse_trial_records(
            args.physics, args.policy, lambda record: lost_objects(record["drake"], shelf.width, shelf.depth),
            kind="physics_trials")
    except PhysicsBenchmarkError as e:  # names the folder
        print(f"error: {e}", file=sys.stderr)
        return 2
    except (ConfigError, UserError) as e:
        print(f"error: {args.physics}: {e}", file=sys.stderr)
        return 2
    rows = [(key, row) for key, lost in found.items() for row in lost]
    trials = {key for key, _ in rows}
    revealed = {key for key in trials if records[key]["drake"]["success"]}
    beneath = [key for key, row in rows if row["beneath"]]
    collateral = [key for key, row in rows if not row["moved_by"]]
    print(f"{args.policy}, {len(records)} Drake trials of `{args.physics}` (`{settings['config']}`): {len(rows)} objects "
          f"lost in {len(trials)} trials, {len(revealed)} of which revealed the target; {len(collateral)} lost "
          f"without an action on them; {len(beneath)} ended beneath the bay. Made by `python research/lost_objects.py "
          f"{args.physics} --policy {args.policy}`.\n")
    if rows:
        print("| trial | ending | object | lost | moved by actions (mismatch) | final x, y, z (m) | beneath the bay |")
        print("|---|---|---|---|---|---|---|")
        for key, row in rows:
            drake = records[key]["drake"]
            moved = ", ".join(f"{k}" + (f" ({m})" if m else "") for k, m in row["moved_by"]) or "none (collateral)"
            f = row["final"]
            print(f"| {key} | {drake['result']} | {row['object']} | {row['how']} | {moved} | "
                  f"{f['x']:+.3f}, {f['y']:+.3f}, {f['z']:+.3f} | {'yes' if row['beneath'] else 'no'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
