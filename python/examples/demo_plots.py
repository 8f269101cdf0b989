"""The plots of a `pcr demo` output directory (the paper's Figures 8, 9, 11 and 12, and the robot).

    python python/examples/demo_plots.py pcr-demo

Reads the demo's files (identified.json, calibration.csv, calibration-errors.csv,
accuracy-*.csv) and writes PNGs into pcr-demo/plots/. `bash scripts/run.sh demo` runs it after
`pcr demo`.
"""
from __future__ import annotations

import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

import pcr  # noqa: E402
import pcr.plot  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def calibration_errors(rows, set_name):
    """{"nominal": (e_p, e_theta), "identified": (...)} of one set, in configuration order (m, rad)."""
    out = {}
    for model in ("nominal", "identified"):
        picked = [r for r in rows if r["set"] == set_name and r["model"] == model]
        picked.sort(key=lambda r: int(r["configuration"]))
        out[model] = (np.array([float(r["e_p"]) for r in picked]),
                      np.array([float(r["e_theta"]) for r in picked]))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", help="output directory of `pcr demo`")
    args = parser.parse_args(argv)
    d = args.directory
    plots = os.path.join(d, "plots")
    os.makedirs(plots, exist_ok=True)
    written = []

    robot = pcr.Robot.load(os.path.join(d, "identified.json"))
    q = np.loadtxt(os.path.join(d, "calibration.csv"), delimiter=",", skiprows=1,
                   usecols=range(robot.num_limbs))
    # Home and the three configurations farthest from it, so the rods' bending shows.
    far = np.argsort(-np.abs(q).max(axis=1))[:3]
    configurations = np.vstack([np.zeros(robot.num_limbs), q[far]])
    written.append(os.path.join(plots, "robot.png"))
    pcr.plot.plot_robot(robot, configurations, path=written[-1])

    errors = read_csv(os.path.join(d, "calibration-errors.csv"))
    written.append(os.path.join(plots, "calibration-errors.png"))
    pcr.plot.plot_calibration_errors(None, None, calibration_errors(errors, "calibration"),
                                     calibration_errors(errors, "validation"), path=written[-1])

    for path_name in ("square", "circle"):
        for model in ("nominal", "identified"):
            name = f"accuracy-{path_name}-{model}"
            rows = read_csv(os.path.join(d, name + ".csv"))
            commanded = np.array([[float(r["x_c"]), float(r["y_c"]), float(r["theta_c"])]
                                  for r in rows])
            barycentres = np.array([[float(r["x_bar"]), float(r["y_bar"]), float(r["theta_bar"])]
                                    for r in rows])
            written.append(os.path.join(plots, name + ".png"))
            fig = pcr.plot.plot_trajectory_accuracy(commanded, barycentres, path=None)
            fig.suptitle(f"{path_name}, {model} model: ISO 9283 barycentre of each pose")
            fig.tight_layout()
            fig.savefig(written[-1], dpi=100)

    for p in written:
        print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
