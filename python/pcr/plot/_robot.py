"""The robot itself: its rods and platform in given configurations, and where it can work."""
from __future__ import annotations

import numpy as np

import pcr

from ._common import MM, figure_and_axes, load_robot, new_figure, save, title
from ._maps import plot_map


def _frame(ax, x, y, theta, length, label, colour):
    for angle, c in ((theta, "tab:red"), (theta + np.pi / 2, "tab:green")):
        ax.annotate("", xy=(x + length * np.cos(angle), y + length * np.sin(angle)), xytext=(x, y),
                    arrowprops=dict(arrowstyle="->", color=c, lw=1.2))
    ax.text(x, y, f" {label}", color=colour, fontsize=8, va="top")


def plot_robot(robot, configurations, ax=None, path=None, frames=True, **solve_args):
    """The rods' shapes, proximal clamps A_i(q), distal clamps B_i, the platform and the frames
    W and P, for one configuration or a sequence.

    robot: a pcr.Robot or its JSON file. configurations: a joint vector (n,) or an (N, n) array
    (m), solved by FK with shapes, or a Solution / list of Solutions obtained with
    ``shapes=True``.
    """
    robot = load_robot(robot)
    fig, ax = figure_and_axes(ax, (6.4, 6.4))
    if isinstance(configurations, pcr.Solution):
        solutions = [configurations]
    elif isinstance(configurations, (list, tuple)) and configurations and isinstance(
            configurations[0], pcr.Solution):
        solutions = list(configurations)
    else:
        q = np.atleast_2d(np.asarray(configurations, dtype=float))
        solutions = [robot.forward(row, shapes=True, **solve_args) for row in q]
    scale = max(l.l for l in robot.limbs)
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink"]
    many = len(solutions) > 1
    for k, s in enumerate(solutions):
        if s.shapes is None:
            continue
        alpha = 0.35 + 0.65 * (k + 1) / len(solutions) if many else 1.0
        pose = s.pose
        distal = []
        for i, (limb, shape) in enumerate(zip(robot.limbs, s.shapes)):
            ax.plot(shape[:, 1] * MM, shape[:, 2] * MM, color=colours[i % 6], alpha=alpha, lw=1.5,
                    label=f"rod {i}" if k == len(solutions) - 1 else None)
            ax.plot(shape[0, 1] * MM, shape[0, 2] * MM, "s", color="k", ms=5, alpha=alpha)
            c, sn = np.cos(pose.theta), np.sin(pose.theta)
            bx = pose.x + c * limb.B[0] - sn * limb.B[1]
            by = pose.y + sn * limb.B[0] + c * limb.B[1]
            distal.append((bx, by))
        distal = np.array(distal + distal[:1])
        ax.fill(distal[:, 0] * MM, distal[:, 1] * MM, color="0.6", alpha=0.25 * alpha)
        ax.plot(distal[:, 0] * MM, distal[:, 1] * MM, "o-", color="0.3", ms=4, alpha=alpha)
        if frames and k == len(solutions) - 1:
            _frame(ax, pose.x * MM, pose.y * MM, pose.theta, 0.25 * scale * MM, "P", "0.2")
    if frames:
        _frame(ax, 0.0, 0.0, 0.0, 0.25 * scale * MM, "W", "k")
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(title(robot.name, f"{len(solutions)} configuration{'s' if many else ''}"
                       + (" (the last one darkest)" if many else "")))
    ax.legend(loc="upper right", fontsize=8)
    return save(fig, path)


def plot_workspace(robot, theta=0.0, ax=None, path=None, result=None, **workspace_args):
    """The reachable positions of the platform at orientation ``theta`` (rad), from
    ``pcr.workspace`` (or a precomputed ``result`` of it), coloured by the max bending strain."""
    fig, ax = figure_and_axes(ax, (6.4, 6.0))
    ws = result if result is not None else pcr.workspace(robot, theta=theta, **workspace_args)
    x, y = np.meshgrid(ws["x"] * MM, ws["y"] * MM)
    strain = np.where(ws["reachable"], ws["max_strain"], np.nan)
    mesh = ax.pcolormesh(x, y, strain * 100, shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="largest bending strain of the rods (%)")
    ax.contour(x, y, ws["reachable"].astype(float), levels=[0.5], colors="k", linewidths=1)
    ax.set_aspect("equal")
    ax.set_xlabel("platform position x (mm)")
    ax.set_ylabel("platform position y (mm)")
    ax.set_title(title(robot.name, f"workspace at θ = {ws['theta'] * 1e3:.4g} mrad\n"
                       f"({int(ws['reachable'].sum())} of {ws['reachable'].size} grid points "
                       "reachable)"), fontsize=10)
    return save(fig, path)


def plot_workspace_maps(robot, result=None, path=None, fig=None, **map_args):
    """Where the robot can work at one orientation, from ``pcr.workspace_map`` (or a precomputed
    ``result`` of it): four ``plot_map`` panels, the stability margin, the distance to a
    singularity, the max bending strain and the predicted 3-sigma position error (when the map
    has it, else the orientation's worst case when it has that, else none)."""
    m = result if result is not None else pcr.workspace_map(robot, **map_args)
    quantities = ["stability_margin", "singularity", "max_strain"]
    for extra in ("position_3sigma", "worst_position"):
        if np.isfinite(np.asarray(m[extra], dtype=float)).any():
            quantities.append(extra)
            break
    fig = fig if fig is not None else new_figure((14, 13))
    axes = fig.subplots(2, 2).ravel()
    for ax, quantity in zip(axes, quantities):
        plot_map(m, quantity, robot, name="", ax=ax)  # the robot's name is in the suptitle
    for ax in axes[len(quantities):]:
        ax.set_visible(False)
    fig.suptitle(title(robot.name, f"workspace at θ = {m['theta'] * 1e3:.4g} mrad; reachable "
                       f"{m['reachable_area'] * 1e6:.4g} mm², stable "
                       f"{m['stable_area'] * 1e6:.4g} mm²"), fontsize=11)
    return save(fig, path)
