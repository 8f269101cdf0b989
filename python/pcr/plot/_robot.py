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


_COLOURS = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink"]


def _solutions(robot, configurations, solution_type, solve_args):
    """The solutions to draw: given (one or a list, solved with shapes=True), or solved by FK
    with shapes from a joint vector (n,) or an (N, n) array."""
    if isinstance(configurations, solution_type):
        return [configurations]
    if isinstance(configurations, (list, tuple)) and configurations and isinstance(
            configurations[0], solution_type):
        return list(configurations)
    q = np.atleast_2d(np.asarray(configurations, dtype=float))
    return [robot.forward(row, shapes=True, **solve_args) for row in q]


def _configurations_title(robot, count):
    many = count > 1
    return title(robot.name, f"{count} configuration{'s' if many else ''}"
                 + (" (the last one darkest)" if many else ""))


def plot_robot(robot, configurations, ax=None, path=None, frames=True, **solve_args):
    """The rods' shapes, proximal clamps A_i(q), distal clamps B_i, the platform and the frames
    W and P, for one configuration or a sequence.

    robot: a pcr.Robot or a pcr.SpatialRobot, or its JSON file. configurations: a joint vector
    (n,) or an (N, n) array (m), solved by FK with shapes, or a Solution (SpatialSolution) / list
    of them obtained with ``shapes=True``. A spatial robot is drawn in 3-D (mplot3d; an ``ax``
    given must be one, ``projection="3d"``): its rods, the holes or clamps they leave the base
    from, the platform's polygon through its attachments and the frames W and P.
    """
    robot = load_robot(robot)
    if isinstance(robot, pcr.SpatialRobot):
        return _plot_spatial_robot(robot, configurations, ax, path, frames, solve_args)
    fig, ax = figure_and_axes(ax, (6.4, 6.4))
    solutions = _solutions(robot, configurations, pcr.Solution, solve_args)
    scale = max(l.l for l in robot.limbs)
    many = len(solutions) > 1
    for k, s in enumerate(solutions):
        if s.shapes is None:
            continue
        alpha = 0.35 + 0.65 * (k + 1) / len(solutions) if many else 1.0
        pose = s.pose
        distal = []
        for i, (limb, shape) in enumerate(zip(robot.limbs, s.shapes)):
            ax.plot(shape[:, 1] * MM, shape[:, 2] * MM, color=_COLOURS[i % 6], alpha=alpha, lw=1.5,
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
    ax.set_title(_configurations_title(robot, len(solutions)))
    ax.legend(loc="upper right", fontsize=8)
    return save(fig, path)


def _frame_3d(ax, origin, rotation, length, label, colour):
    for axis, c in zip(rotation.T, ("tab:red", "tab:green", "tab:blue")):
        end = origin + length * axis
        ax.plot(*np.transpose([origin, end]) * MM, color=c, lw=1.2)
    ax.text(*(origin * MM), f" {label}", color=colour, fontsize=8)


def _plot_spatial_robot(robot, configurations, ax, path, frames, solve_args):
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    if ax is None:
        fig = new_figure((7.0, 6.4))
        ax = fig.add_subplot(projection="3d")
    elif getattr(ax, "name", "") != "3d":
        raise ValueError(f"ax: a spatial robot is drawn on a 3-D axes (projection='3d'), got "
                         f"{getattr(ax, 'name', type(ax).__name__)!r}")
    fig = ax.figure
    solutions = _solutions(robot, configurations, pcr.SpatialSolution, solve_args)
    rods = robot.rods
    scale = max(rod.length for rod in rods)
    many = len(solutions) > 1
    points = [np.array([rod.A for rod in rods])]  # what the axes' limits must hold
    for k, s in enumerate(solutions):
        if s.shapes is None:
            continue
        alpha = 0.35 + 0.65 * (k + 1) / len(solutions) if many else 1.0
        for i, shape in enumerate(s.shapes):
            ax.plot(*shape[:, 1:4].T * MM, color=_COLOURS[i % 6], alpha=alpha, lw=1.5,
                    label=f"rod {i}" if k == len(solutions) - 1 else None)
            ax.plot(*shape[:1, 1:4].T * MM, "s", color="k", ms=4, alpha=alpha)  # hole or clamp
            points.append(shape[:, 1:4])
        distal = s.position + np.array([rod.B for rod in rods]) @ s.rotation.T
        ax.add_collection3d(Poly3DCollection([distal * MM], facecolor="0.6",
                                             alpha=0.25 * alpha, edgecolor="0.3"))
        ax.plot(*distal.T * MM, "o", color="0.3", ms=4, alpha=alpha)
        if frames and k == len(solutions) - 1:
            _frame_3d(ax, s.position, s.rotation, 0.25 * scale, "P", "0.2")
    if frames:
        _frame_3d(ax, np.zeros(3), np.eye(3), 0.25 * scale, "W", "k")
    # Equal scales on the three axes: the rods' bending is seen as it is.
    every = np.vstack(points) * MM
    centre = 0.5 * (every.min(axis=0) + every.max(axis=0))
    half = 0.5 * max(float(np.ptp(every, axis=0).max()), 1e-9)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.set_title(_configurations_title(robot, len(solutions)))
    ax.legend(loc="upper left", fontsize=8)
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
