"""Workspace maps: one quantity of a `pcr map` grid (its CSV, or ``pcr.workspace_map``'s dict) over
the platform's positions at one orientation."""
from __future__ import annotations

import textwrap

import numpy as np

from ._common import (MM, figure_and_axes, load_robot, plain_ticks, read_csv, robot_name, save,
                      title)

# quantity -> (what it is, its colour bar's label, display unit, factor from SI to it); the
# columns of `pcr map`.
MAP_QUANTITIES = {
    "position_3sigma": ("predicted 3σ position error", "3σ position error", "µm", 1e6),
    "orientation_3sigma": ("predicted 3σ orientation error", "3σ orientation error", "µrad",
                           1e6),
    "worst_position": ("worst-case position error over the uncertainty intervals",
                       "worst-case position error", "µm", 1e6),
    "worst_orientation": ("worst-case orientation error over the uncertainty intervals",
                          "worst-case orientation error", "mrad", 1e3),
    "max_strain": ("largest bending strain of the rods", "max bending strain", "%", 100.0),
    "stability_margin": ("stability margin: the stiffness's eigenvalue nearest zero",
                         "stability margin", "EI/L", 1.0),
    "singularity": ("distance to a singularity: reciprocal condition number of the FK Jacobian",
                    "1/cond(J), 0 at a singularity", "dimensionless", 1.0),
}


def read_map(source):
    """A `pcr map` CSV (a path or a DataFrame, any row order) as a grid: x (nx,), y (ny,) in m,
    theta, and every other column as an (ny, nx) array (row j at y[j]), reachable and stable as
    booleans, as ``pcr.workspace_map`` returns it."""
    columns = read_csv(source)
    x, i = np.unique(columns["x"], return_inverse=True)
    y, j = np.unique(columns["y"], return_inverse=True)
    if len(x) * len(y) != len(i) or len(set(zip(i, j))) != len(i):
        raise ValueError(f"{source}: the rows do not make a grid ({len(i)} rows, {len(x)} x "
                         f"values, {len(y)} y values)")
    grid = {"x": x, "y": y, "theta": float(columns["theta"][0])}
    for name, values in columns.items():
        if name in ("x", "y", "theta"):
            continue
        cells = np.empty((len(y), len(x)), dtype=values.dtype)
        cells[j, i] = values
        grid[name] = cells.astype(bool) if name in ("reachable", "stable") else cells
    return grid


def _mark(ax, x, y, where, **style):
    """Fills the cells where `where` holds (hatched or coloured, as `style` says)."""
    if where.any():
        ax.contourf(x, y, where.astype(float), levels=[0.5, 1.5], **style)


def _draw_home(ax, robot):
    """The platform at home (q = 0): its reference point P and its outline through the distal
    clamps."""
    s = robot.forward(np.zeros(robot.num_limbs))
    p = s.pose
    c, sn = np.cos(p.theta), np.sin(p.theta)
    corners = np.array([[p.x + c * l.B[0] - sn * l.B[1], p.y + sn * l.B[0] + c * l.B[1]]
                        for l in robot.limbs])
    corners = np.vstack([corners, corners[:1]]) * MM
    ax.plot(corners[:, 0], corners[:, 1], "--", color="0.1", lw=1.0)
    ax.plot(p.x * MM, p.y * MM, "P", color="w", mec="k", ms=11, label="home (q = 0): platform P")


def plot_map(source, quantity="position_3sigma", robot=None, *, name=None, log=None, ax=None,
             path=None):
    """One quantity of a workspace map (``MAP_QUANTITIES``) over the platform's positions, in the
    display unit of the colour bar (log scale when the values span a decade or more, or as
    `log` says; its range: the values' over the positions with an equilibrium, the stable ones
    for the stability margin), with labelled iso-lines at the colour bar's ticks.

    Marked: the workspace border (joints within the stroke; outside it hatched: the equilibrium
    exists but a joint is beyond its stroke), the unstable equilibria (red cross-hatch), the
    positions with no equilibrium (IK failed, e.g. singular: grey). With `robot` (a pcr.Robot or
    its JSON file), its home: the platform's reference point and outline at q = 0. The title
    names the robot (`name`, else the robot's name).

    source: a `pcr map` CSV (path or DataFrame), ``read_map``'s or ``pcr.workspace_map``'s dict.
    """
    import matplotlib
    from matplotlib.colors import ListedColormap, LogNorm, Normalize
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    m = source if isinstance(source, dict) else read_map(source)
    if quantity not in MAP_QUANTITIES:
        raise ValueError(f"quantity {quantity!r}: one of {', '.join(MAP_QUANTITIES)}")
    what, short, unit, factor = MAP_QUANTITIES[quantity]
    robot = load_robot(robot) if robot is not None else None
    fig, ax = figure_and_axes(ax, (7.0, 6.4))
    x, y = m["x"] * MM, m["y"] * MM
    reach, stable = np.asarray(m["reachable"], bool), np.asarray(m["stable"], bool)
    found = np.isfinite(m["max_strain"])  # an equilibrium, in the stroke or not
    values = np.asarray(m[quantity], dtype=float) * factor
    shown = found & np.isfinite(values) & (stable if quantity == "stability_margin" else True)
    data = np.where(shown, values, np.nan)
    if not shown.any():
        raise ValueError(f"{quantity}: no value in this map (`pcr map --covariance` fills the "
                         "predicted errors, --worst-case the worst case)")
    lo, hi = np.nanmin(data), np.nanmax(data)
    if log is None:
        log = lo > 0 and hi >= 10 * lo
    norm = LogNorm(lo, hi) if log else Normalize(lo, hi)
    mesh = ax.pcolormesh(x, y, data, norm=norm, cmap="viridis", shading="nearest")
    bar = fig.colorbar(mesh, ax=ax, label=f"{short} ({unit})", shrink=0.9)
    plain_ticks(bar.ax.yaxis, lo, hi)
    ticks = [t for t in bar.get_ticks() if lo < t < hi]
    if ticks:
        lines = ax.contour(x, y, data, levels=ticks, linewidths=0.6,
                           colors=["w" if norm(t) < 0.4 else "0.15" for t in ticks])
        ax.clabel(lines, fmt=lambda v: f"{v:g}", fontsize=7)

    handles = [Line2D([], [], color="k", lw=1.5, label="workspace border (joints in the stroke)")]
    if (found & ~reach).any():
        with matplotlib.rc_context({"hatch.color": "0.25", "hatch.linewidth": 0.5}):
            _mark(ax, x, y, found & ~reach, colors="none", hatches=["//"])
        handles.append(Patch(facecolor="none", edgecolor="0.25", hatch="//",
                             label="outside the stroke"))
    if (found & ~stable).any():
        with matplotlib.rc_context({"hatch.color": "tab:red"}):
            _mark(ax, x, y, found & ~stable, colors="none", hatches=["xx"])
        ax.contour(x, y, (found & ~stable).astype(float), levels=[0.5], colors="tab:red")
        handles.append(Patch(facecolor="none", edgecolor="tab:red", hatch="xx",
                             label="unstable equilibrium"))
    if (~found).any():
        statuses = sorted(set(np.asarray(m["status"])[~found])) if "status" in m else []
        ax.pcolormesh(x, y, np.where(found, np.nan, 1.0), cmap=ListedColormap(["0.6"]),
                      shading="nearest")
        handles.append(Patch(color="0.6", label=textwrap.fill(
            "no equilibrium (IK: " + (", ".join(statuses) if statuses else "failed") + ")", 40)))
    if reach.any() and not reach.all():
        ax.contour(x, y, reach.astype(float), levels=[0.5], colors="k", linewidths=1.5)
    if robot is not None:
        _draw_home(ax, robot)
        handles.append(Line2D([], [], marker="P", ls="", color="w", mec="k", ms=9,
                              label="home (q = 0): platform P, outline dashed"))
    step_x = (x[1] - x[0]) / 2 if len(x) > 1 else 0.5
    step_y = (y[1] - y[0]) / 2 if len(y) > 1 else 0.5
    ax.set_xlim(x[0] - step_x, x[-1] + step_x)
    ax.set_ylim(y[0] - step_y, y[-1] + step_y)
    ax.set_aspect("equal")
    ax.set_xlabel("platform position x (mm)")
    ax.set_ylabel("platform position y (mm)")
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2,
              fontsize=8, frameon=False)
    ax.set_title(textwrap.fill(title(robot_name(robot, name), what), 64)
                 + f"\nat θ = {m['theta'] * 1e3:.4g} mrad", fontsize=10)
    return save(fig, path, inputs=[source] if not isinstance(source, dict) else [])
