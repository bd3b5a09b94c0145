"""Two `slax-drake benchmark` runs of the same Table I trials (the same protocol seed), e.g. a policy and its variant:
success per density in each, the scenes won and lost, and the moves back each made. Prints a Markdown table.

    python benchmarks/compare_variant_runs.py BASE_FOLDER[:POLICY] VARIANT_FOLDER[:POLICY]

POLICY defaults to slax-belief. Only the trials in both folders are compared (``trials/<policy>/DD_NNNN.json``).
Moves back are counted from the executed actions as the trial files name them (true objects in both observation
modes): a move back is an action whose commanded displacement along x (a push's d, a suction's dx; over 1 cm) has
the sign opposite to the last such action on the same object; an undo is a move back by no more than that last move
(+ 1 cm), so that the object ends no farther past where it stood than before.
"""

from __future__ import annotations

import argparse
import re
import sys

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import read_trial_records

DISPLACEMENT = re.compile(r"\b(?:d|dx)=([-+]?\d+\.\d+)")


def moves_back(actions) -> tuple[int, int]:
    """(moves back, undos) among ``actions`` (their descriptions, in order)."""
    last: dict = {}
    back = undo = 0
    for action in actions:
        parts = action.split()
        m = DISPLACEMENT.search(action)
        if len(parts) < 2 or m is None:
            continue
        name, dx = parts[1], float(m.group(1))
        if abs(dx) <= 0.01:
            continue
        if name in last and last[name] * dx < 0:
            back += 1
            undo += abs(dx) <= abs(last[name]) + 0.01
        last[name] = dx
    return back, undo


def load(spec: str) -> tuple[str, dict]:
    folder, _, policy = spec.partition(":")
    policy = policy or "slax-belief"
    trials = read_trial_records(folder, policy, missing_ok=True)
    if not trials:
        raise UserError(f"{folder}: no trial files under trials/{policy}/")
    bad = next((f"{folder}/trials/{policy}/{k}.json" for k, t in trials.items() if "success" not in t), None)
    if bad is not None:
        raise UserError(f"{bad}: not a trial file (no 'success')")
    return policy, trials


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base")
    ap.add_argument("variant")
    args = ap.parse_args(argv)
    try:
        (pa, a), (pb, b) = load(args.base), load(args.variant)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    keys = sorted(set(a) & set(b))
    if not keys:
        print("error: no trial in both folders", file=sys.stderr)
        return 2
    densities = sorted({int(k.split("_")[0]) for k in keys})
    back_a = {k: moves_back(a[k].get("actions", [])) for k in keys}  # (moves back, undos) per trial
    back_b = {k: moves_back(b[k].get("actions", [])) for k in keys}
    print(f"| objects | trials | {pa} | {pb} | won | lost | moves back ({pa} / {pb}) | undos ({pa} / {pb}) |")
    print("|---|---|---|---|---|---|---|---|")
    for n in densities + [None]:
        ks = [k for k in keys if n is None or int(k.split("_")[0]) == n]
        sa = sum(bool(a[k]["success"]) for k in ks)
        sb = sum(bool(b[k]["success"]) for k in ks)
        won = sum(bool(b[k]["success"]) and not a[k]["success"] for k in ks)
        lost = sum(bool(a[k]["success"]) and not b[k]["success"] for k in ks)
        ma, mb = [back_a[k] for k in ks], [back_b[k] for k in ks]
        print(f"| {'All' if n is None else n} | {len(ks)} | {100 * sa / len(ks):.2f} % | {100 * sb / len(ks):.2f} % "
              f"| {won} | {lost} | {sum(m[0] for m in ma)} / {sum(m[0] for m in mb)} "
              f"| {sum(m[1] for m in ma)} / {sum(m[1] for m in mb)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
