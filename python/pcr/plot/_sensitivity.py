"""The sensitivity ranking (the paper's Table 2): the pose error each parameter can cause."""
from __future__ import annotations

import os

import numpy as np

from ._common import angle_unit, length_unit, new_figure, plain_ticks, read_csv, save, title


def plot_sensitivity(source, path=None, fig=None, *, name=None, floor=None):
    """The ranking of Table 2 as bars, most influential first: the platform's position error
    (and orientation error) each parameter kind can cause over its uncertainty interval, its
    sensitivity times its half-width (`position_error_m`, `orientation_error_rad`), log scale.

    source: the sensitivity CSV of `pcr sensitivity --csv` or of `pcr demo` (a path or a
    DataFrame; planar or spatial: the columns param, half_width, position_error_m,
    orientation_error_rad, rank). name: the robot. floor: (position m, angle rad), the noise
    floor, drawn dashed: a parameter below it is not seen by the measurements.
    """
    inputs = [source] if isinstance(source, (str, os.PathLike)) else []
    c = read_csv(source)
    order = np.argsort(c["rank"])
    params = [str(p) for p in c["param"][order]]
    fig = fig if fig is not None else new_figure((11, 0.28 * len(params) + 1.6))
    axes = fig.subplots(1, 2, sharey=True)
    for ax, column, unit_of, what, col in (
            (axes[0], "position_error_m", length_unit, "position error", 0),
            (axes[1], "orientation_error_rad", angle_unit, "orientation error", 1)):
        values = np.asarray(c[column], dtype=float)[order]
        positive = values[values > 0]
        scale, unit = unit_of(positive.max() if len(positive) else 1.0)
        y = np.arange(len(params))
        ax.barh(y, np.where(values > 0, values, np.nan) * scale, color="tab:blue", log=True)
        if floor is not None:
            ax.axvline(floor[col] * scale, color="0.4", ls="--", lw=0.8,
                       label=f"noise floor {floor[col] * scale:.3g} {unit}")
            ax.legend(fontsize=8, loc="lower right")
        plain_ticks(ax.xaxis, *ax.get_xlim())
        ax.set_xlabel(f"{what} it can cause ({unit})")
        ax.grid(True, axis="x", which="both", alpha=0.3)
        ax.set_axisbelow(True)
    axes[0].set_yticks(np.arange(len(params)), params, fontsize=8)
    axes[0].invert_yaxis()  # most influential on top
    fig.suptitle(title(name, "sensitivity × uncertainty half-width of each parameter (Table 2), "
                       "most influential first"), fontsize=11)
    return save(fig, path, inputs)
