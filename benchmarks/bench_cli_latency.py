"""Command-line latency: median wall time of ``slax-drake --help``, ``slax-drake trial --help`` and an argument
error (``slax-drake trial --objects three``), each in a fresh process, over several runs.

    python benchmarks/bench_cli_latency.py [--runs 9]

Runs ``python -m slax_drake.cli`` with this interpreter (the ``slax-drake`` console script is the same entry
point); the first run of each case is a warm-up (file cache) and not counted. Aim: under 0.5 s each.
"""

import argparse
import statistics
import subprocess
import sys
import time

CASES = (
    ("slax-drake --help", ["--help"], 0),
    ("slax-drake trial --help", ["trial", "--help"], 0),
    ("slax-drake trial --objects three", ["trial", "--objects", "three"], 2),
)


def wall_time(argv: list[str], expected_code: int) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "slax_drake.cli", *argv], capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if proc.returncode != expected_code:
        raise SystemExit(f"slax-drake {' '.join(argv)} exited {proc.returncode}, expected {expected_code}:\n"
                         f"{proc.stderr}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=9, help="counted runs per case (default: 9)")
    args = parser.parse_args()
    print(f"{'command':<36} {'median s':>9} {'min s':>7} {'max s':>7}")
    for label, argv, code in CASES:
        wall_time(argv, code)
        times = [wall_time(argv, code) for _ in range(args.runs)]
        print(f"{label:<36} {statistics.median(times):>9.3f} {min(times):>7.3f} {max(times):>7.3f}")


if __name__ == "__main__":
    main()
