"""What every figure shares: reading tables, making and saving a figure, display units."""
from __future__ import annotations

import csv
import io
import math
import os

import numpy as np

from .._files import write_atomically

# Display units: files are SI, figures show what a reader thinks in.
MM = 1e3  # m -> mm


def read_csv(source):
    """The columns of a CSV file (a path), a pandas DataFrame or a mapping of columns, as a dict
    of numpy arrays: float where every value is a number, str otherwise."""
    if isinstance(source, (str, os.PathLike)):
        with open(source, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(line for line in f if line.strip() and line[0] != "#"))
        if not rows:
            raise ValueError(f"{os.fspath(source)}: an empty table")
        header, rows = rows[0], rows[1:]
        columns = {name: [r[k] for r in rows] for k, name in enumerate(header)}
    elif hasattr(source, "columns"):  # a DataFrame
        columns = {name: source[name].to_numpy() for name in source.columns}
    else:
        columns = dict(source)
    out = {}
    for name, values in columns.items():
        try:
            out[name] = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            out[name] = np.asarray(values, dtype=str)
    return out


def new_figure(size):
    """A Figure that pyplot does not hold (no global state, no leak when many are drawn; a
    notebook still shows it)."""
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def figure_and_axes(ax, size):
    if ax is None:
        fig = new_figure(size)
        return fig, fig.add_subplot()
    return ax.figure, ax


def save(fig, path, inputs=(), dpi=120):
    """Writes the figure to `path` (format from its extension) through a temporary file in the
    same directory and a rename; never over one of `inputs`. Returns the figure."""
    if path is None:
        return fig
    path = os.fspath(path)
    for source in inputs:
        if isinstance(source, (str, os.PathLike)) and os.path.exists(path) and os.path.samefile(
                path, source):
            raise ValueError(f"{path}: is an input of this figure; not overwritten")
    extension = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    buffer = io.BytesIO()
    fig.savefig(buffer, format=extension, dpi=dpi)
    write_atomically(path, buffer.getvalue())
    return fig


def plain_ticks(axis, lo, hi):
    """Tick labels as plain numbers (0.01, 0.015, 250, 10000) instead of powers of ten when the
    range [lo, hi] is within 1e-3 to 1e5; on a log axis, the ticks matplotlib would label."""
    from matplotlib.ticker import FuncFormatter, LogFormatterSciNotation

    class Plain(LogFormatterSciNotation):
        def __call__(self, x, pos=None):
            return f"{x:g}" if super().__call__(x, pos) else ""

    if not (1e-3 <= lo and hi < 1e5):
        return
    if axis.get_scale() == "log":
        axis.set_major_formatter(Plain())
        axis.set_minor_formatter(Plain(labelOnlyBase=False))
    else:
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))


def title(name, what):
    """'<robot name>: <what>', or what alone without a name."""
    return f"{name}: {what}" if name else what


def robot_name(robot, name=None):
    """The name for the titles: `name`, else the robot's (a pcr.Robot or its JSON file)."""
    if name is not None or robot is None:
        return name
    return load_robot(robot).name


def load_robot(robot):
    """A pcr.Robot (or SpatialRobot), or one loaded from its JSON file."""
    import pcr

    return pcr.Robot.load(os.fspath(robot)) if isinstance(robot, (str, os.PathLike)) else robot


def length_unit(largest):
    """(scale, unit) for lengths in m whose largest is `largest`: um from 0.1 um, else nm."""
    return (1e6, "µm") if largest >= 1e-7 else (1e9, "nm")


def angle_unit(largest):
    """(scale, unit) for angles in rad whose largest is `largest`: mrad from 0.1 mrad, else
    urad."""
    return (1e3, "mrad") if largest >= 1e-4 else (1e6, "µrad")


def nice_below(value):
    """The largest of 1, 2, 5 x 10^k not above `value` (> 0)."""
    exponent = math.floor(math.log10(value))
    for mantissa in (5, 2, 1):
        if mantissa * 10.0**exponent <= value:
            return mantissa * 10.0**exponent
    return 10.0**exponent


def format_factor(k):
    """A magnification as printed: 20, 5000, 2 000 000."""
    return f"{k:,.0f}".replace(",", " ") if k >= 1 else f"{k:g}"


def calibration_joints(source):
    """The joints (N, n) of a dataset CSV (a `pcr demo` calibration.csv: q1..qn, then the pose)."""
    columns = read_csv(source)
    names = sorted((c for c in columns if c[:1] == "q" and c[1:].isdigit()),
                   key=lambda c: int(c[1:]))
    return np.column_stack([columns[c] for c in names])


def farthest_from_home(q, count=3):
    """The `count` rows of the joints q (N, n) farthest from home (q = 0), largest |q_i| first:
    those whose rods bend most."""
    return q[np.argsort(-np.abs(q).max(axis=1))[:count]]


class FigurePage:
    """The figures of a directory and the page that shows them section by section (figures.md):
    ``figure`` draws one into DIR/figures/, ``write`` writes the page."""

    def __init__(self, directory):
        self.directory = os.fspath(directory)
        self.out = os.path.join(self.directory, "figures")
        os.makedirs(self.out, exist_ok=True)
        self.sections = []  # (heading, [(file, caption)])

    def figure(self, section, file, caption, draw):
        """draw(path) writes the figure at DIR/figures/file, shown under `section`."""
        draw(os.path.join(self.out, file))
        if not self.sections or self.sections[-1][0] != section:
            self.sections.append((section, []))
        self.sections[-1][1].append((file, caption))

    def write(self, heading, notes=()):
        """Writes DIR/figures.md; returns the figures' paths and the page's."""
        text = [f"# {heading}\n",
                "Drawn by `python -m pcr.plot` from the files of this directory (the numbers: "
                "[report.md](report.md); the formats: docs/formats.md).\n", *notes]
        written = []
        for section, items in self.sections:
            text.append(f"## {section}\n")
            for file, caption in items:
                text.append(f"![{file}](figures/{file})\n\n{caption}\n")
                written.append(os.path.join(self.out, file))
        page = os.path.join(self.directory, "figures.md")
        write_atomically(page, "\n".join(text).encode())
        return written + [page]
