"""What happens after a suction is put back: is the same object suctioned again, and does that fail too? Reads the
trial files of `slax-drake benchmark` result folders (``trials/<policy>/DD_NNNN.json``: the executed actions and the
simulator's notes) and prints one Markdown row per folder.

    python research/put_back_followups.py FOLDER[:POLICY] [FOLDER[:POLICY] ...]

POLICY defaults to slax-belief. A put-back is a step whose note is the simulator's ``PUT_BACK`` ("could not place the
object: put back"; a lift weighed and put back as too heavy is not one); its follow-up is the next suction of the
same object in that trial (on the true object: trial files name true objects in both observation modes): "put back
again", "failed otherwise" (any other note on that step) or "as planned".
"""

from __future__ import annotations

import argparse
import collections
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import read_trial_records
from slax_drake.shelf.simulator import PUT_BACK, split_note


def followups(folder: Path, policy: str) -> collections.Counter:
    counts = collections.Counter()
    trials = read_trial_records(folder, policy, missing_ok=True)
    if not trials:
        raise UserError(f"{folder}: no trial files under trials/{policy}/")
    for stem, trial in trials.items():
        if not isinstance(trial.get("actions", []), list):
            path = folder / "trials" / policy / f"{stem}.json"
            raise UserError(f"{path}: not a trial file")
        notes = {step: text for step, text in map(split_note, trial.get("notes", [])) if step is not None}
        actions = trial.get("actions", [])
        counts["trials"] += 1
        for step, action in enumerate(actions, 1):
            if notes.get(step) != PUT_BACK:
                continue
            counts["put back"] += 1
            name = action.split()[1]
            later = [t for t, a in enumerate(actions, 1)
                     if t > step and a.startswith("suction") and a.split()[1] == name]
            if not later:
                continue
            counts["suctioned again"] += 1
            note = notes.get(later[0], "")
            counts["put back again" if note == PUT_BACK else "failed otherwise" if note else "as planned"] += 1
            counts["at the next step"] += later[0] == step + 1
    return counts


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", help="result folders, each optionally :POLICY")
    args = ap.parse_args(argv)
    try:
        rows = [(spec, followups(Path(spec.partition(":")[0]), spec.partition(":")[2] or "slax-belief"))
                for spec in args.folders]
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print("| folder | policy | trials | put back | same object suctioned again | ... put back again | ... failed "
          "otherwise | ... as planned | ... at the next step |")
    print("|---|---|---|---|---|---|---|---|---|")
    for spec, c in rows:
        folder, _, policy = spec.partition(":")
        print(f"| `{Path(folder).name}` | {policy or 'slax-belief'} | {c['trials']} | {c['put back']} | "
              f"{c['suctioned again']} | {c['put back again']} | {c['failed otherwise']} | {c['as planned']} | "
              f"{c['at the next step']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
