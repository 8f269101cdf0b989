"""The figures of a `pcr demo` output directory, and the page that shows them.

    python -m pcr.plot pcr-demo

reads the demo's files and writes pcr-demo/figures/*.png and pcr-demo/figures.md, the page that
shows them section by section (report.md, which the demo writes, links to it). Nothing the demo
wrote is changed. `bash scripts/run.sh demo` runs it after `pcr demo`.
"""
from __future__ import annotations

import argparse
import os

import numpy as np

from .._files import write_atomically
from ._accuracy import plot_calibration_errors, plot_trajectory_accuracy
from ._common import load_robot, read_csv
from ._maps import MAP_QUANTITIES, plot_map, read_map
from ._robot import plot_robot

MAPS = ("position_3sigma", "stability_margin", "singularity", "max_strain")


def _robot_figure(d, robot, path):
    """Home and the three calibration configurations farthest from it, so the rods' bending
    shows."""
    columns = read_csv(os.path.join(d, "calibration.csv"))
    q = np.column_stack([columns[f"q{i + 1}"] for i in range(robot.num_limbs)])
    far = np.argsort(-np.abs(q).max(axis=1))[:3]
    return plot_robot(robot, np.vstack([np.zeros(robot.num_limbs), q[far]]), path=path)


def demo_figures(directory):
    """Draws the figures of a `pcr demo` output directory into directory/figures/ and writes
    directory/figures.md, which shows them. Returns the written paths."""
    d = os.fspath(directory)
    out = os.path.join(d, "figures")
    os.makedirs(out, exist_ok=True)
    robot = load_robot(os.path.join(d, "identified.json"))
    # The maps are the identified model's; the errors, the virtual robot's against each model.
    name = load_robot(os.path.join(d, "design.json")).name + " (virtual robot)"
    sections = []  # (heading, [(file, caption)])

    def figure(section, file, caption, draw):
        draw(os.path.join(out, file))
        if not sections or sections[-1][0] != section:
            sections.append((section, []))
        sections[-1][1].append((file, caption))

    figure("The identified robot", "robot.png",
           "Home and the three calibration configurations farthest from it.",
           lambda p: _robot_figure(d, robot, p))
    figure("Calibration (Table 3): errors per configuration", "calibration-errors.png",
           "The paper's Figures 8 and 9: each configuration's position and orientation error, "
           "nominal against identified model, on the calibration and validation sets.",
           lambda p: plot_calibration_errors(
               calibration=os.path.join(d, "calibration-errors.csv"), name=name, path=p))
    for path_name in ("square", "circle"):
        for model in ("nominal", "identified"):
            stem = f"{path_name}-{model}"
            source = os.path.join(d, f"accuracy-{stem}.csv")
            figure("Trajectory accuracy (Table 4)", f"accuracy-{stem}.png",
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

    text = [f"# pcr demo: figures of {name}\n",
            "Drawn by `python -m pcr.plot` from the files of this directory (the numbers: "
            "[report.md](report.md); the formats: docs/formats.md).\n"]
    written = []
    for heading, items in sections:
        text.append(f"## {heading}\n")
        for file, caption in items:
            text.append(f"![{file}](figures/{file})\n\n{caption}\n")
            written.append(os.path.join(out, file))
    page = os.path.join(d, "figures.md")
    write_atomically(page, "\n".join(text).encode())
    return written + [page]


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
