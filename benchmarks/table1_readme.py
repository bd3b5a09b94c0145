"""Writes the README's Table I section from committed result folders (never typed by hand): for each folder, the
paper's layout (rows: objects 4 / 6 / 8 / 10 / All x success rate and median steps (IQR); a column per policy),
the paper's figure in parentheses, then the median action cost (pushes + psi suctions) of successful trials.

    python benchmarks/table1_readme.py docs/results/table1_paper docs/results/table1_station [--write README.md]

Without --write it prints the Markdown; with it, it replaces the text between the README's markers
``<!-- table1:begin -->`` and ``<!-- table1:end -->``.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from slax_drake.evaluation.table1 import PAPER_TABLE1, PAPER_TABLE1_STEPS
from slax_drake.io import write_text_atomic
from slax_drake.policies.registry import POLICY_NAMES

BEGIN, END = "<!-- table1:begin -->", "<!-- table1:end -->"
KEYS = ["4", "6", "8", "10", "all"]
NAMES = {"oracle-p": "Oracle-P", "oracle-p+s": "Oracle-P+S", "dar": "DAR", "der-3": "DER-3",
         "bluction-dar": "Bluction-DAR", "dar-literal": "DAR, literal", "bluction-dar-literal": "Bluction-DAR, literal"}


def median_costs(table: dict, policy: str) -> dict:
    """Per density key: the median action cost of the policy's successful trials (None when none)."""
    out = {}
    for key in KEYS:
        costs = [t["cost"] for t in table["trials"] if t["policy"] == policy and t["success"]
                 and (key == "all" or t["density"] == int(key))]
        out[key] = float(np.median(costs)) if costs else None
    return out


def section(folder: Path) -> str:
    table = json.loads((folder / "table1.json").read_text())
    meta = table.get("meta", {})
    order = {n: i for i, n in enumerate(POLICY_NAMES)}
    policies = sorted(table["policies"], key=lambda n: (order.get(n, len(order)), n))  # the registry's order
    head = [NAMES.get(p, p + (" (ours)" if p.startswith(("slax-", "bluction-la")) else "")) for p in policies]
    lines = [f"**Profile `{meta.get('profile', '?')}`** ({meta.get('scenes_per_density', '?')} scenes per density, "
             f"protocol seed {meta.get('seed', '?')}, {meta.get('perception', '?')} distributions, "
             f"{meta.get('observation', '?')} observation; `{folder}`):", "",
             "| No. | Metric | " + " | ".join(head) + " |", "|---|---|" + "---|" * len(policies)]
    for i, key in enumerate(KEYS):
        rates, steps = [], []
        for p in policies:
            e = table["policies"][p][key]
            paper = f" ({PAPER_TABLE1[p][i]})" if p in PAPER_TABLE1 else ""
            rates.append("-" if e["success_rate"] is None else f"{100 * e['success_rate']:.0f} %{paper}")
            ps = PAPER_TABLE1_STEPS.get(p)
            paper_s = f" ({ps[i][0]:g}, {ps[i][1]:g}-{ps[i][2]:g})" if ps else ""
            steps.append("-" if e["median_steps"] is None else
                         f"{e['median_steps']:g} ({e['iqr'][0]:g}-{e['iqr'][1]:g}){paper_s}")
        label = "All" if key == "all" else key
        lines.append(f"| {label} | Success rate | " + " | ".join(rates) + " |")
        lines.append(f"| {label} | Median steps (IQR) | " + " | ".join(steps) + " |")
    costs = {p: median_costs(table, p)["all"] for p in policies}
    lines.append("| All | Median action cost | " + " | ".join("-" if costs[p] is None else f"{costs[p]:.1f}"
                                                            for p in policies) + " |")
    lines.append("| All | Mean decision time per step (s) | " + " | ".join(
        "-" if table["policies"][p]["all"]["mean_decision_seconds"] is None
        else f"{table['policies'][p]['all']['mean_decision_seconds']:.3f}" for p in policies) + " |")
    statuses = {p: table["policies"][p]["all"].get("oracle_status") for p in policies}
    if any(statuses.values()):
        lines.append("")
        lines.append("Oracle searches per trial (proven optimal / proven infeasible within H / cut by time): " + "; ".join(
            f"{NAMES.get(p, p)}: " + ", ".join(f"{k} {v}" for k, v in s.items()) for p, s in statuses.items() if s) + ".")
    if meta.get("wall_seconds_this_run") is not None:
        lines.append(f"Last run into the folder: {meta.get('trials_run', '?')} trials in "
                     f"{meta['wall_seconds_this_run'] / 60:.1f} min wall with {meta.get('workers', '?')} worker(s).")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--write", type=Path, help="the README whose marked section to replace")
    args = ap.parse_args(argv)
    for folder in args.folders:
        if not (folder / "table1.json").is_file():
            print(f"error: {folder}/table1.json does not exist (run slax-drake benchmark --out {folder})",
                  file=sys.stderr)
            return 2
    text = ("The paper's figures in parentheses (success %; median steps, IQR). Median steps and action cost "
            "(pushes + psi suctions) over successful trials. Generated by `python benchmarks/table1_readme.py " + " ".join(
        str(f) for f in args.folders) + " --write README.md`.\n\n") + "\n".join(section(f) for f in args.folders)
    return print_or_write(text, args.write, BEGIN, END)


def replace_section(path: Path, begin: str, end: str, text: str) -> int:
    """Replaces what stands between the markers ``begin`` and ``end`` of the file at ``path`` with ``text``
    (atomically); 2 with a message when the file lacks them."""
    readme = path.read_text()
    if begin not in readme or end not in readme:
        print(f"error: {path} has no {begin} ... {end} section", file=sys.stderr)
        return 2
    head, rest = readme.split(begin, 1)
    _, tail = rest.split(end, 1)
    write_text_atomic(path, head + begin + "\n" + text + end + tail)
    return 0


def print_or_write(text: str, readme: Path | None, begin: str, end: str) -> int:
    """Prints ``text`` (no ``readme``) or puts it between the markers of ``readme`` (:func:`replace_section`)."""
    if readme is None:
        print(text, end="")
        return 0
    return replace_section(readme, begin, end, text)


if __name__ == "__main__":
    sys.exit(main())
