"""Compares every trial file of two runs of the same Table I trials (e.g. before and after a change meant to make a
policy faster without changing any decision): each trial's JSON, all keys but the timing ones, must be identical.

    python benchmarks/compare_trial_outputs.py OLD_FOLDER NEW_FOLDER [--policies slax-belief] [--allow-capped]

Each folder is a ``slax-drake benchmark --out`` folder (its ``trials/<policy>/<density>_<index>.json``). Timing keys
(``trial_seconds``, ``decision_seconds`` and ``seconds`` at any depth, e.g. inside ``decision_log``) are left out of
the comparison. Prints one line per trial that differs (the first differing field), with differences that a
per-decision CPU cap explains (a decision up to the first differing one has ``capped`` set in either run: a faster
implementation looks at more nodes there) listed apart, then a count; exits 1 when any trial differs or is in one
folder only (with ``--allow-capped``, only when a difference is not explained by a cap). A folder without trial
files, or no trial in both, is refused (one line, exit 2): an empty comparison would pass.
"""

import argparse
import sys
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import read_trial_records, without_keys

TIMING_KEYS = frozenset({"trial_seconds", "decision_seconds", "seconds"})


def load(folder: Path, policies: list[str] | None) -> dict:
    """{"<policy>/<density>_<index>": the trial's JSON} of a benchmark folder (``policies`` None: every policy)."""
    out = {}
    for root in sorted((folder / "trials").iterdir()):
        if root.is_dir() and (policies is None or root.name in policies):
            records = read_trial_records(folder, root.name)
            out.update({f"{root.name}/{stem}": record for stem, record in records.items()})
    return out


def first_difference(old, new, path: str = "") -> str | None:
    """The path of the first field where ``old`` and ``new`` differ, with both values; None when equal."""
    if isinstance(old, dict) and isinstance(new, dict):
        for k in list(old) + [k for k in new if k not in old]:
            if k not in old or k not in new:
                return f"{path}.{k}: only in {'new' if k not in old else 'old'}"
            found = first_difference(old[k], new[k], f"{path}.{k}")
            if found:
                return found
        return None
    if isinstance(old, list) and isinstance(new, list):
        for i, (o, n) in enumerate(zip(old, new)):
            found = first_difference(o, n, f"{path}[{i}]")
            if found:
                return found
        return None if len(old) == len(new) else f"{path}: {len(old)} -> {len(new)} entries"
    return None if old == new else f"{path}: {str(old)[:60]} -> {str(new)[:60]}"


def first_differing_decision(old: dict, new: dict) -> int:
    """The index of the first decision whose log or action differs (the number of decisions when none does)."""
    logs_o, logs_n = old.get("decision_log", []), new.get("decision_log", [])
    acts_o, acts_n = old.get("actions", []), new.get("actions", [])
    for i in range(max(len(logs_o), len(logs_n), len(acts_o), len(acts_n))):
        pick = lambda seq: seq[i] if i < len(seq) else None  # noqa: E731
        if pick(logs_o) != pick(logs_n) or pick(acts_o) != pick(acts_n):
            return i
    return max(len(logs_o), len(logs_n))


def capped_before(trial: dict, last: int) -> bool:
    """Whether any decision up to index ``last`` of the trial's log hit the per-decision CPU cap."""
    return any(isinstance(d, dict) and d.get("capped") for d in trial.get("decision_log", [])[: last + 1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--policies", default=None, help="comma separated (default: every policy in the folders)")
    ap.add_argument("--allow-capped", action="store_true", help="exit 0 when every difference is a capped one")
    args = ap.parse_args(argv)
    for folder in (args.old, args.new):
        if not (folder / "trials").is_dir():
            print(f"error: {folder} holds no trial files (not a slax-drake benchmark --out folder)", file=sys.stderr)
            return 2
    policies = args.policies.split(",") if args.policies else None
    try:
        old, new = load(args.old, policies), load(args.new, policies)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    both = sorted(set(old) & set(new))
    if not both:
        print(f"error: no trial in both {args.old} and {args.new}", file=sys.stderr)
        return 2
    differ, capped = [], []
    for key in both:
        o, n = without_keys(old[key], TIMING_KEYS), without_keys(new[key], TIMING_KEYS)
        found = first_difference(o, n)
        if found is None:
            continue
        i = first_differing_decision(o, n)
        line = f"{key}: decision {i}: {found}"
        (capped if capped_before(o, i) or capped_before(n, i) else differ).append(line)
    only = [f"{key}: only in {'old' if key in old else 'new'}" for key in sorted(set(old) ^ set(new))]
    for line in differ + only:
        print("DIFFERS", line)
    for line in capped:
        print("DIFFERS AFTER A CAPPED DECISION", line)
    print(f"{len(both)} trials in both: {len(both) - len(differ) - len(capped)} identical (timing aside), "
          f"{len(differ)} differ, {len(capped)} differ after a capped decision; {len(only)} in one folder only")
    return 1 if differ or only or (capped and not args.allow_capped) else 0


if __name__ == "__main__":
    sys.exit(main())
