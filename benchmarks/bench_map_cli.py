#!/usr/bin/env python3
"""What `pcr map` costs, against the library's map (bench_map) on the same robot and grid.

Times the whole `pcr map` process (start-up, the stroke box's FK scan for the default range, the
solves, writing the CSV), best of --repeat runs, for the default robot (robots/femto-3pf.json)
and the same with a +-60 mm stroke (robots/femto-3pf-long-stroke.json, where most of the map lies
beyond the branch's folds), at --grid 50 and 200, on all cores; then runs bench_map's matching
cases (pcr::workspace_map with the default range, 2 threads) and prints both. Standard library
only.

    python3 benchmarks/bench_map_cli.py [--build build] [--repeat 3]
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROBOTS = {"default": ("femto-3pf.json", 0), "long stroke": ("femto-3pf-long-stroke.json", 1)}
GRIDS = (50, 200)


def best_seconds(command, repeat):
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=True)
        best = min(best, time.perf_counter() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default="build", help="the build directory (default: build)")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    pcr = os.path.join(args.build, "apps", "pcr")
    library = os.path.join(args.build, "benchmarks", "bench_map")
    for program in (pcr, library):
        if not os.access(program, os.X_OK):
            sys.exit(f"bench_map_cli.py: {program} not found (cmake --build {args.build} "
                     "--target pcr_cli pcr_full bench_map)")

    result = subprocess.run(
        [library, "--benchmark_filter=threads:2", "--benchmark_format=json",
         f"--benchmark_repetitions={args.repeat}", "--benchmark_report_aggregates_only=true"],
        capture_output=True, text=True, check=True).stdout
    library_s = {}
    for b in json.loads(result)["benchmarks"]:
        if b.get("aggregate_name") == "median" and "stability:1" in b["name"]:
            library_s[b["run_name"]] = b["real_time"] / 1e3  # ms -> s

    print(f"{'robot':<12} {'grid':>5} {'pcr map (s)':>12} {'library (s)':>12} {'reachable':>10}")
    with tempfile.TemporaryDirectory() as scratch:
        output = os.path.join(scratch, "map.csv")
        for name, (file, long_stroke) in ROBOTS.items():
            robot = os.path.join(ROOT, "robots", file)
            for grid in GRIDS:
                cli = best_seconds([pcr, "map", "--robot", robot, "--grid", str(grid), "--output",
                                    output], args.repeat)
                with open(output) as f:
                    next(f)
                    reachable = sum(line.split(",")[3] == "1" for line in f)
                key = (f"BM_WorkspaceMap/grid:{grid}/stability:1/long_stroke:{long_stroke}/"
                       "threads:2/real_time")
                lib = f"{library_s[key]:.3f}" if key in library_s else "-"
                print(f"{name:<12} {grid:>5} {cli:>12.3f} {lib:>12} {reachable:>10}")


if __name__ == "__main__":
    main()
