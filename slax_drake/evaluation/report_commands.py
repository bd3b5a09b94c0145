"""``slax-drake report``: the documentation's results pages and the README's headline table, generated from the
result folders that ``slax-drake benchmark`` writes."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "report",
        help="write the docs' results pages (and the README's headline table) from benchmark result folders",
        description="Read benchmark result folders and write the results pages under DOCS/results/: a folder "
        "holding table1.json feeds the Table I page, a privileged and a camera folder of the same protocol the "
        "observation-modes comparison, a folder holding physics.json the physics-benchmark page (and, for the "
        "Table II scenario, the Table II page). Every table names the command, profile and observation mode it was "
        "made with, and every page the report command that regenerates it. With --readme, the first Table I "
        "folder's success rates replace the README's headline table between <!-- results:begin --> and "
        "<!-- results:end -->.",
    )
    p.add_argument("results", nargs="+", type=Path, metavar="RESULTS",
                   help="result folders of slax-drake benchmark (the first Table I folder gives the headline)")
    p.add_argument("--docs", type=Path, default=None, metavar="DIR",
                   help="documentation folder: the pages go to DIR/results/ (e.g. docs/)")
    p.add_argument("--readme", type=Path, default=None, metavar="FILE",
                   help="README whose marked headline table to replace (e.g. README.md)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from slax_drake.evaluation.report import write_report

    for path in write_report(args.results, args.docs, args.readme):
        print(f"wrote {path}")
    return 0
