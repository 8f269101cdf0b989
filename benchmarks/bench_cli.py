#!/usr/bin/env python3
"""What `pcr fk` and `pcr ik` cost per row, against the library's solves and a plain RK4 residual.

Writes a smooth joint path for the default robot (a circle in joint space, 10 um from row to row),
times `pcr fk` on it, start-up, parsing and writing included; takes the poses it printed as the
path of `pcr ik` and times that; then runs bench_fk_path on the same files: the library's warm FK
and IK along the paths (as pcr fk and pcr ik solve their rows) and a plain three-rod RK4-64
residual. Prints the per-row costs and the ratios (targets: CLI / library <= 1.3 for both,
pcr fk / plain residual <= 0.5), and the start-up of `pcr fk` (mean of 50 runs on a one-row input)
with the number of shared libraries it loads. Standard library only; times are the best of
--repeat runs.

    python3 benchmarks/bench_cli.py [--build build] [--rows 20000] [--repeat 3]
"""

import argparse
import csv
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

STEP_M = 10e-6  # joint-space distance from row to row
RADIUS_M = 2e-3  # the circle's joints: RADIUS_M cos(phi - 2 pi i / 3), i = 0, 1, 2


def write_path(path, rows):
    # |dq/dphi| = RADIUS_M sqrt(3/2) on this circle.
    dphi = STEP_M / (RADIUS_M * math.sqrt(1.5))
    with open(path, "w") as f:
        f.write("q1,q2,q3\n")
        for k in range(rows):
            phi = k * dphi
            f.write(",".join(repr(RADIUS_M * math.cos(phi - 2 * math.pi * i / 3))
                             for i in range(3)) + "\n")


def best_seconds(command, repeat, stdin=subprocess.DEVNULL):
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(command, stdin=stdin, stdout=subprocess.DEVNULL, check=True)
        best = min(best, time.perf_counter() - start)
    return best


def mean_seconds(command, runs):
    start = time.perf_counter()
    for _ in range(runs):
        subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, check=True)
    return (time.perf_counter() - start) / runs


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default="build", help="the build directory (default: build)")
    parser.add_argument("--rows", type=int, default=20000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    pcr = os.path.join(args.build, "apps", "pcr")
    library = os.path.join(args.build, "benchmarks", "bench_fk_path")
    for program in (pcr, library):
        if not os.access(program, os.X_OK):
            sys.exit(f"bench_cli.py: {program} not found (cmake --build {args.build} "
                     "--target pcr_cli bench_fk_path)")

    with tempfile.TemporaryDirectory() as scratch:
        path = os.path.join(scratch, "path.csv")
        write_path(path, args.rows)
        output = os.path.join(scratch, "fk.csv")
        cli_us = best_seconds([pcr, "fk", "--path", "--input", path, "--output", output],
                              args.repeat) / args.rows * 1e6
        poses = os.path.join(scratch, "poses.csv")
        with open(output) as fk, open(poses, "w") as f:
            rows = csv.DictReader(fk)
            f.write("x,y,theta\n")
            for row in rows:
                f.write(f"{row['x']},{row['y']},{row['theta']}\n")
        ik_output = os.path.join(scratch, "ik.csv")
        ik_us = best_seconds([pcr, "ik", "--path", "--input", poses, "--output", ik_output],
                             args.repeat) / args.rows * 1e6
        measured = subprocess.run([library, path, str(args.repeat), poses], capture_output=True,
                                  text=True, check=True).stdout
        # An empty input is an error (no data rows): start-up is timed on the home row.
        one_row = os.path.join(scratch, "home.csv")
        with open(one_row, "w") as f:
            f.write("q1,q2,q3\n0,0,0\n")
        startup_ms = mean_seconds([pcr, "fk", "--input", one_row, "--output", output], 50) * 1e3
    values = dict(line.split() for line in measured.splitlines())
    sequence_us = float(values["fk_sequence_us"])
    ik_sequence_us = float(values["ik_sequence_us"])
    residual_us = float(values["plain_rk4_64_residual_us"])
    libraries = "?"
    if shutil.which("ldd"):
        ldd = subprocess.run(["ldd", pcr], capture_output=True, text=True).stdout
        libraries = str(len(ldd.splitlines()))

    print(f"joint path: {args.rows} rows, {STEP_M * 1e6:g} um apart (default robot)")
    print(f"pcr fk start-up, one row (mean of 50):     {startup_ms:.2f} ms, "
          f"{libraries} shared libraries (ldd)")
    print(f"pcr fk, whole run / rows:                  {cli_us:.2f} us/row")
    print(f"library warm FK (ForwardSequence):         {sequence_us:.2f} us/row")
    print(f"library, forward_kinematics_or_cold:       {float(values['fk_or_cold_us']):.2f} us/row")
    print(f"plain three-rod RK4-64 residual (-O2):     {residual_us:.2f} us")
    print(f"pcr ik, whole run / rows:                  {ik_us:.2f} us/row")
    print(f"library warm IK (InverseSequence):         {ik_sequence_us:.2f} us/row")
    print(f"CLI / library warm FK:        {cli_us / sequence_us:.2f}  (target <= 1.3)")
    print(f"CLI / library warm IK:        {ik_us / ik_sequence_us:.2f}  (target <= 1.3)")
    print(f"CLI / plain RK4-64 residual:  {cli_us / residual_us:.2f}  (target <= 0.5)")


if __name__ == "__main__":
    main()
