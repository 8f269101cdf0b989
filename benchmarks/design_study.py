#!/usr/bin/env python3
"""How many calibration configurations reach the noise floor: Poisson-disc against D-optimal.

For each seed S, count N and design (`pcr sample --design poisson-disc|d-optimal`), on the default
robot: `pcr sample --count N --validation-count 56 --seed S` (the validation set is the same
Poisson-disc set for both designs of a seed), `pcr simulate --seed S` on both sets (a virtual
robot whose truth is drawn from the nominal uncertainties, the paper's noise), then
`pcr_calibrate` with its default stages, and reads the identified model's e_p (Eq. 8) on the
validation set from the report. Prints one row per (N, design): mean over the seeds of the
validation mean and max e_p (um), the worst max over the seeds, and the rank and log det of the
design when D-optimal. Standard library only; every file goes to a temporary directory.

    python3 benchmarks/design_study.py [--build build] [--counts 15,20,30,45] [--seeds 1,2,3]
        [--designs poisson-disc,d-optimal] [--validation 56] [--csv out.csv]

Each (seed, N, design) runs three programs: about 10 to 60 s on one core (the D-optimal candidate
draw of 10 N Poisson-disc points dominates).
"""

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time

DESIGNS = ("poisson-disc", "d-optimal")


def run(command, cwd):
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit("failed: " + " ".join(command) + "\n" + done.stderr)
    return done.stderr


def one_case(build, source, seed, count, design, validation, work):
    pcr = os.path.join(build, "apps", "pcr")
    calibrate = os.path.join(build, "apps", "pcr_calibrate")
    start = time.monotonic()
    log = run([pcr, "sample", "--count", str(count), "--validation-count", str(validation),
               "--seed", str(seed), "--design", design, "--output", "cal-q.csv",
               "--validation-output", "val-q.csv"], work)
    sampled = time.monotonic()
    run([pcr, "simulate", "--seed", str(seed), "--configs", "cal-q.csv", "--output", "cal.csv",
         "--truth", "truth.json"], work)
    run([pcr, "simulate", "--seed", str(seed), "--configs", "val-q.csv", "--output", "val.csv"],
        work)
    run([calibrate, "--robot", os.path.join(source, "robots", "femto-3pf.json"), "--data",
         "cal.csv", "--validation", "val.csv", "--output", "identified.json", "--report",
         "report.json", "--quiet"], work)
    with open(os.path.join(work, "report.json")) as f:
        report = json.load(f)
    stats = report["table3"]["identified_model_validation_set"]["e_p_m"]
    design_info = re.search(r"rank (\d+), log det ([-0-9.e+]+)", log)
    for name in ("cal-q.csv", "val-q.csv", "cal.csv", "val.csv", "truth.json", "identified.json",
                 "report.json"):
        os.remove(os.path.join(work, name))
    return {
        "seed": seed, "count": count, "design": design,
        "mean_um": stats["mean"] * 1e6, "max_um": stats["max"] * 1e6,
        "rank": int(design_info.group(1)) if design_info else "",
        "log_det": float(design_info.group(2)) if design_info else "",
        "sample_s": sampled - start, "total_s": time.monotonic() - start,
    }


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default=os.path.join(here, "..", "build"))
    parser.add_argument("--counts", default="15,20,30,45")
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--designs", default=",".join(DESIGNS))
    parser.add_argument("--validation", type=int, default=56)
    parser.add_argument("--csv", help="also write every run's row to this CSV")
    args = parser.parse_args()
    source = os.path.abspath(os.path.join(here, ".."))
    build = os.path.abspath(args.build)
    counts = [int(c) for c in args.counts.split(",")]
    seeds = [int(s) for s in args.seeds.split(",")]
    designs = args.designs.split(",")
    rows = []
    with tempfile.TemporaryDirectory(prefix="pcr-design-") as work:
        for count in counts:
            for design in designs:
                for seed in seeds:
                    row = one_case(build, source, seed, count, design, args.validation, work)
                    rows.append(row)
                    print(f"# N={count} {design} seed={seed}: validation e_p mean "
                          f"{row['mean_um']:.4f} um, max {row['max_um']:.4f} um "
                          f"({row['total_s']:.0f} s)", file=sys.stderr, flush=True)
    print(f"Validation e_p of the identified model ({args.validation} Poisson-disc "
          f"configurations, seeds {args.seeds}), um")
    print("| N | design | mean (avg over seeds) | max (avg over seeds) | max (worst seed) |")
    print("|---|---|---|---|---|")
    for count in counts:
        for design in designs:
            runs = [r for r in rows if r["count"] == count and r["design"] == design]
            mean = sum(r["mean_um"] for r in runs) / len(runs)
            peak = sum(r["max_um"] for r in runs) / len(runs)
            worst = max(r["max_um"] for r in runs)
            print(f"| {count} | {design} | {mean:.4f} | {peak:.4f} | {worst:.4f} |")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            writer.writeheader()
            writer.writerows(rows)


if __name__ == "__main__":
    main()
