"""Table II of the paper beside the Drake trials of its protocol: prints a Markdown table from a physics
benchmark's physics.json (``slax-drake benchmark --physics --config sim_configs/table2.yaml``).

    python benchmarks/table2_compare.py docs/results/table2_physics/physics.json

The paper's column (Sec. VI-B, Table II: 3 physical shelves per density, the real Fetch): DER-3 0/3, 2/3, 1/3 and
Bluction-DAR 3/3, 3/3, 3/3 at 8, 10 and 12 objects.
"""

import json
import sys

PAPER = {"der-3": {"8": (0, 3), "10": (2, 3), "12": (1, 3)},
         "bluction-dar": {"8": (3, 3), "10": (3, 3), "12": (3, 3)}}


def main(path: str) -> None:
    summary = json.loads(open(path).read())
    rows = {}
    for t in summary["trials"]:
        rows.setdefault((t["policy"], str(t["density"])), []).append(t)
    print("| objects | policy | paper (real Fetch) | Drake: success | Drake: nothing lost | shelf simulator, same "
          "scenes | Drake endings |")
    print("|---|---|---|---|---|---|---|")
    for policy in PAPER:
        total = {"paper": [0, 0], "drake": 0, "clean": 0, "shelf": 0, "n": 0}
        for n in ("8", "10", "12"):
            sel = rows.get((policy, n), [])
            if not sel:
                continue
            won, of = PAPER[policy][n]
            drake = sum(t["drake_success"] for t in sel)
            clean = sum(t["drake_clean_success"] for t in sel)
            shelf = sum(t["shelf_success"] for t in sel)
            endings = {}
            for t in sel:
                key = t["drake_result"].split(":")[0]
                endings[key] = endings.get(key, 0) + 1
            print(f"| {n} | {policy} | {won}/{of} | {drake}/{len(sel)} | {clean}/{len(sel)} | {shelf}/{len(sel)} | "
                  + ", ".join(f"{k} {v}" for k, v in sorted(endings.items())) + " |")
            total["paper"][0] += won
            total["paper"][1] += of
            total["drake"] += drake
            total["clean"] += clean
            total["shelf"] += shelf
            total["n"] += len(sel)
        if total["n"]:
            print(f"| all | {policy} | {total['paper'][0]}/{total['paper'][1]} | {total['drake']}/{total['n']} | "
                  f"{total['clean']}/{total['n']} | {total['shelf']}/{total['n']} | |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/results/table2_physics/physics.json")
