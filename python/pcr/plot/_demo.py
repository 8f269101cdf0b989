"""The figures of a `pcr demo` output directory, and the page that shows them.

    python -m pcr.plot pcr-demo

reads the demo's files and writes pcr-demo/figures/*.png and pcr-demo/figures.md, the page that
shows them section by section (report.md, which the demo writes, links to it). A spatial robot's
demo (`pcr demo --robot SPATIAL.json`, nominal.json's "kind": "spatial") has its own figures: the
robot in 3-D, Table 2's ranking, Table 3's errors, Table 4's square, circle and helix in 3-D.
Nothing the demo wrote is changed. `bash scripts/run.sh demo` runs it after `pcr demo`.
"""
from __future__ import annotations

import argparse
import json
import math
import os

import numpy as np

from ._accuracy import (plot_calibration_errors, plot_spatial_path_accuracy,
                        plot_trajectory_accuracy)
from ._common import FigurePage, calibration_joints, farthest_from_home, load_robot
from ._maps import MAP_QUANTITIES, plot_map, read_map
from ._robot import plot_robot
from ._sensitivity import plot_sensitivity

MAPS = ("position_3sigma", "stability_margin", "singularity", "max_strain")
_ROBOT = "The identified robot"
_ROBOT_CAPTION = "Home and the three calibration configurations farthest from it."
_TABLE3 = "Calibration (Table 3): errors per configuration"
_TABLE3_CAPTION = ("The paper's Figures 8 and 9: each configuration's position and orientation "
                   "error, nominal against identified model, on the calibration and validation "
                   "sets.")
_TABLE4 = "Trajectory accuracy (Table 4)"


def _robot_figure(d, robot, path):
    """Home and the three calibration configurations farthest from it, so the rods' bending
    shows."""
    far = farthest_from_home(calibration_joints(os.path.join(d, "calibration.csv")))
    return plot_robot(robot, np.vstack([np.zeros(robot.num_limbs), far]), path=path)


def _spatial_robot_figure(d, robot, path):
    """The spatial _robot_figure. A cold start need not find an identified robot's home (as in
    the spatial method): it starts from the nominal robot's, then each configuration from
    home."""
    nominal = load_robot(os.path.join(d, "nominal.json"))
    n = robot.num_rods
    home = robot.forward(np.zeros(n), warm_start=nominal.forward(np.zeros(n)), shapes=True)
    far = farthest_from_home(calibration_joints(os.path.join(d, "calibration.csv")))
    solutions = [home] + [robot.forward(q, warm_start=home, shapes=True) for q in far]
    return plot_robot(robot, [s for s in solutions if s.converged], path=path)


def _is_spatial(d):
    """A spatial robot's demo: its nominal.json says "kind": "spatial"."""
    nominal = os.path.join(d, "nominal.json")
    if not os.path.isfile(nominal):
        return False
    with open(nominal, encoding="utf-8") as f:
        return json.load(f).get("kind") == "spatial"


def demo_figures(directory):
    """Draws the figures of a `pcr demo` output directory into directory/figures/ and writes
    directory/figures.md, which shows them. Returns the written paths."""
    d = os.fspath(directory)
    if _is_spatial(d):
        return _spatial_demo_figures(d)
    page = FigurePage(d)
    figure = page.figure
    robot = load_robot(os.path.join(d, "identified.json"))
    # The maps are the identified model's; the errors, the virtual robot's against each model.
    name = load_robot(os.path.join(d, "design.json")).name + " (virtual robot)"
    figure(_ROBOT, "robot.png", _ROBOT_CAPTION, lambda p: _robot_figure(d, robot, p))
    figure(_TABLE3, "calibration-errors.png", _TABLE3_CAPTION,
           lambda p: plot_calibration_errors(
               calibration=os.path.join(d, "calibration-errors.csv"), name=name, path=p))
    for path_name in ("square", "circle"):
        for model in ("nominal", "identified"):
            stem = f"{path_name}-{model}"
            source = os.path.join(d, f"accuracy-{stem}.csv")
            figure(_TABLE4, f"accuracy-{stem}.png",
                   f"The {path_name} commanded with the {model} model (the paper's Figures 11 "
                   "and 12): error vectors magnified by the factor printed.",
                   lambda p, s=source, path_name=path_name, model=model: plot_trajectory_accuracy(
                       s, name=name, label=f"{path_name}, {model} model", path=p))
    grid = read_map(os.path.join(d, "map-identified.csv"))
    for quantity in MAPS:
        if not np.isfinite(np.asarray(grid[quantity], dtype=float)).any():
            continue
        what = MAP_QUANTITIES[quantity][0]
        figure("Where the identified robot can work", f"map-{quantity.replace('_', '-')}.png",
               f"{what[0].upper() + what[1:]} (map-identified.csv, column `{quantity}`) over the "
               "platform's positions, the identified robot's home drawn over it.",
               lambda p, quantity=quantity: plot_map(grid, quantity, robot, path=p))
    return page.write(f"pcr demo: figures of {name}")


def _spatial_demo_figures(d):
    """demo_figures for a spatial robot's demo (`pcr demo --robot SPATIAL.json`): the robot in
    3-D, Table 2's ranking, Table 3's errors per configuration, Table 4's paths in 3-D."""
    page = FigurePage(d)
    figure = page.figure
    robot = load_robot(os.path.join(d, "identified.json"))
    name = load_robot(os.path.join(d, "nominal.json")).name + " (virtual robot)"
    with open(os.path.join(d, "report.json"), encoding="utf-8") as f:
        noise = json.load(f).get("noise")
    # The rms of the measurement noise alone (sigma per axis, three axes): no model does better.
    floor = (math.sqrt(3) * noise["position_m"], math.sqrt(3) * noise["angle_rad"]) if noise \
        else None
    figure(_ROBOT, "robot.png", _ROBOT_CAPTION, lambda p: _spatial_robot_figure(d, robot, p))
    figure("Sensitivity (Table 2)", "sensitivity.png",
           "The pose error each parameter can cause over its uncertainty interval (sensitivity "
           "× half-width, sensitivity.csv), most influential first; the noise floor dashed.",
           lambda p: plot_sensitivity(os.path.join(d, "sensitivity.csv"), name=name,
                                      floor=floor, path=p))
    notes = []
    errors = os.path.join(d, "calibration-errors.csv")
    if os.path.isfile(errors):
        figure(_TABLE3, "calibration-errors.png",
               _TABLE3_CAPTION + " The dashed line: the noise floor (√3 σ, the rms error of the "
               "measurement noise alone).",
               lambda p: plot_calibration_errors(calibration=errors, name=name, floor=floor,
                                                 path=p))
    else:
        notes.append("(Table 3's errors per configuration are not drawn: no "
                     "calibration-errors.csv, which `pcr demo` writes since it draws the spatial "
                     "figures; run it again.)\n")
    for path_name in ("square", "circle", "helix"):
        sources = [os.path.join(d, f"accuracy-{path_name}-{m}.csv")
                   for m in ("nominal", "identified")]
        figure(_TABLE4, f"accuracy-{path_name}.png",
               f"The {path_name} commanded with the nominal and the identified model, in 3-D: "
               "the attained barycentres' errors magnified by the factors printed, and the "
               "accuracy AP_p and orientation error of each pose for both models.",
               lambda p, s=sources, path_name=path_name: plot_spatial_path_accuracy(
                   *s, name=name, label=path_name, path=p))
    return page.write(f"pcr demo: figures of {name}", notes)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m pcr.plot",
                                     description="the figures of a `pcr demo` output directory: "
                                     "DIR/figures/*.png and DIR/figures.md")
    parser.add_argument("directory", help="output directory of `pcr demo`")
    args = parser.parse_args(argv)
    if not os.path.isfile(os.path.join(args.directory, "report.json")):
        parser.error(f"{args.directory}: not a `pcr demo` output (no report.json)")
    for path in demo_figures(args.directory):
        print(f"wrote {path}")
    return 0
