"""The options of a decision side by side: one row per physics results folder (and policy), from its physics.json.

    python research/decision_options.py docs/results/physics_belief_household_20580ad \
        docs/results/physics_belief_household_stall_stop_1ee6ea4 ...

Each argument is a folder written by ``slax-drake benchmark --physics`` (or kept in ``docs/results``), optionally
``FOLDER:POLICY`` for one of its policies (default: every policy it holds). A row counts, from the folder's trial
records: the Drake trials revealed with nothing lost (no object toppled or dropped) and revealed at all, the shelf
simulator's reveals beside them, the actions executed and the share that went as the action model predicted, the
trials that ended "no feasible motion", the objects toppled and dropped at the end (the two counts summed: an
object fallen out of the bay and lying tilted counts in both; the summary keeps counts, not names) and the stalls
(trials, and of them revealed after the stall). It prints a Markdown table (docs/research/decisions.md holds its output).
"""

import argparse
import json
import sys
from pathlib import Path

HEADER = ("| folder | policy | trials | Drake: nothing lost | revealed | shelf simulator | actions (as predicted) | "
          "no feasible motion | toppled + dropped | stalled (revealed after) |")


def rows(folder: Path, policy: str | None = None) -> list[str]:
    """The table's rows for ``folder``'s physics.json (one per policy, or ``policy``'s); ValueError when the file
    is missing, unreadable or holds no trial of ``policy``."""
    path = folder / "physics.json"
    try:
        data = json.loads(path.read_text())
        trials = data["trials"]
        names = sorted({t["policy"] for t in trials}) if policy is None else [policy]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise ValueError(f"{path}: unreadable physics record ({type(e).__name__}: {e})") from None
    out = []
    for name in names:
        mine = [t for t in trials if t.get("policy") == name]
        if not mine:
            raise ValueError(f"{path}: no Drake trials of {name}")
        summary = (data.get("policies") or {}).get(name, {}).get("all", {})
        n = len(mine)
        clean = sum(bool(t.get("drake_clean_success")) for t in mine)
        revealed = sum(bool(t.get("drake_success")) for t in mine)
        shelf = sum(bool(t.get("shelf_success")) for t in mine)
        actions = sum(int(t.get("drake_steps", 0)) for t in mine)
        judged, matched = summary.get("actions_judged"), summary.get("actions_matched")
        predicted = f" ({100 * matched / judged:.0f} %)" if judged else ""
        no_motion = sum(t.get("drake_result") == "no feasible motion" for t in mine)
        lost = sum(int(t.get("toppled", 0)) + int(t.get("dropped", 0)) for t in mine)
        stalled = [t for t in mine if isinstance(t.get("stall"), list) and t["stall"][0] is not None]
        after = sum(bool(t.get("drake_success")) for t in stalled)
        recorded = all(isinstance(t.get("stall"), list) for t in mine)  # runs before 2b8e52a recorded no stalls
        stall_text = f"{len(stalled)} ({after})" if recorded else "-"
        out.append(f"| `{folder.name}` | `{name}` | {n} | **{clean}** ({100 * clean / n:.4g} %) | {revealed} | {shelf} | "
                   f"{actions}{predicted} | {no_motion} | {lost} | {stall_text} |")
    return out


def table(specs) -> str:
    """The Markdown table for ``specs`` (``FOLDER`` or ``FOLDER:POLICY``)."""
    lines = [HEADER, "|" + "---|" * HEADER.count(" | ") + "---|"]
    for spec in specs:
        folder, _, policy = str(spec).partition(":")
        lines += rows(Path(folder), policy or None)
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="+", metavar="FOLDER[:POLICY]")
    args = ap.parse_args(argv)
    try:
        print(table(args.folders))
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
