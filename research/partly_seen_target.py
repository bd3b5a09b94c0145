"""Failed trials in which the target was partly seen and not finished, and what the policy did after first seeing
it. Prints Markdown.

    python research/partly_seen_target.py FOLDER [--policy slax-belief] [--compare FOLDER2 --compare-policy NAME]

FOLDER holds a benchmark's ``trials/<policy>/DD_NNNN.json`` (``slax-drake benchmark``; a shelf-simulator trial
records ``visible_fractions``, the target's true visible fraction before each decision: the simulator's knowledge,
never the policy's). A trial "saw" the target when that fraction was above 0 before some decision. Per failed
trial that saw it: the decision it was first seen at, the fractions, the decisions whose belief collapsed onto it
(slax-belief's ``decision_log`` records ``target_seen``), and each action after it with the simulator's note.
With ``--compare``: the scenes one folder reveals and the other does not, and the totals of both.
"""

from __future__ import annotations

import argparse
import collections
import re
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import read_trial_records
from slax_drake.shelf.simulator import split_note


def first_seen(trial: dict) -> int | None:
    """The index of the first decision before which some of the target was visible (None: never, or not
    recorded)."""
    return next((i for i, v in enumerate(trial.get("visible_fractions", [])) if v > 0), None)


def note_kind(note: str) -> str:
    """A simulator note without its step, numbers and object names: ``"step 4: push stopped after -0.085 m by an
    unseen obstacle"`` -> ``"push stopped after X m by an unseen obstacle"``."""
    text = split_note(note)[1]
    return re.sub(r"\b(object|track|segment)_\d+\b", "OBJ", re.sub(r"[-+]?\d+\.\d+", "X", text))


def notes_after_sight(trials: dict) -> tuple[int, collections.Counter]:
    """Over ``trials`` (failed, partly seen): the actions taken from the first decision that saw the target on, and
    their simulator notes counted by :func:`note_kind`."""
    actions, kinds = 0, collections.Counter()
    for t in trials.values():
        k0 = first_seen(t)
        actions += len(t["actions"]) - k0
        for note in t["notes"]:
            step = split_note(note)[0]
            if step is not None and step > k0:
                kinds[note_kind(note)] += 1
    return actions, kinds


def report(trials: dict, title: str) -> list[str]:
    lines = [f"## {title}", ""]
    failed = {k: t for k, t in trials.items() if not t["success"]}
    seen_failed = {k: t for k, t in failed.items() if first_seen(t) is not None}
    seen_ok = sum(1 for t in trials.values() if t["success"] and first_seen(t) is not None)
    lines.append(f"{len(trials)} trials, {len(trials) - len(failed)} revealed ({seen_ok} of them after a partly seen "
                 f"target), {len(failed)} failed, {len(seen_failed)} of those with the target partly seen.")
    if seen_failed:
        actions, kinds = notes_after_sight(seen_failed)
        lines.append(f"From their first sight on they took {actions} actions; {sum(kinds.values())} of them met "
                     f"something the policy's estimate did not hold (the simulator's notes): "
                     + "; ".join(f"{kind} {n}" for kind, n in kinds.most_common()) + ".")
    lines.append("")
    for key, t in seen_failed.items():
        fr = t["visible_fractions"]
        k0 = first_seen(t)
        collapsed = sum(1 for log in t.get("decision_log", [])[k0:] if log.get("target_seen"))
        lines.append(f"- `{key}` ({t['reason']}): first seen before decision {k0 + 1} at {fr[k0]:.2f}, at most "
                     f"{max(fr):.2f}, {t['visible_fraction']:.2f} at the end; belief collapsed at {collapsed} of the "
                     f"{len(fr) - k0} decisions after; fractions {' '.join(f'{v:.2f}' for v in fr)}")
        for i in range(k0, len(t["actions"])):
            notes = [text for step, text in map(split_note, t["notes"]) if step == i + 1]
            lines.append(f"    - {i + 1}: `{t['actions'][i]}`{' (' + '; '.join(notes) + ')' if notes else ''}")
    lines.append("")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--policy", default="slax-belief")
    parser.add_argument("--compare", type=Path, default=None)
    parser.add_argument("--compare-policy", default=None)
    args = parser.parse_args(argv)
    runs = [(args.folder, args.policy)]
    if args.compare is not None:
        runs.append((args.compare, args.compare_policy or args.policy))
    loaded = []
    for folder, policy in runs:
        try:
            trials = read_trial_records(folder, policy, missing_ok=True)
        except UserError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        if not trials:
            print(f"error: no trial files in {folder / 'trials' / policy}", file=sys.stderr)
            return 2
        loaded.append(trials)
    out = []
    for (folder, policy), trials in zip(runs, loaded):
        out += report(trials, f"{folder} ({policy})")
    if len(loaded) == 2:
        a, b = loaded
        common = sorted(set(a) & set(b))
        out += ["## Compared", "",
                f"Revealed by the second only: {', '.join(k for k in common if b[k]['success'] and not a[k]['success']) or 'none'}; "
                f"by the first only: {', '.join(k for k in common if a[k]['success'] and not b[k]['success']) or 'none'}; "
                f"the same actions in {sum(a[k]['actions'] == b[k]['actions'] for k in common)} of {len(common)} scenes.",
                ""]
        for (folder, policy), trials in zip(runs, loaded):
            ts = [trials[k] for k in common]
            out.append(f"- {policy} ({folder}): {sum(t['success'] for t in ts)} revealed, {sum(t['steps'] for t in ts)} "
                       f"actions, {sum(len(t['notes']) for t in ts)} simulator notes (wasted actions)")
        out.append("")
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
