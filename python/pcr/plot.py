"""Plots in the style of the paper's figures (matplotlib, pure Python).

Every function draws into ``ax`` (or a new figure), saves a PNG when ``path`` is given and
returns the matplotlib Figure. Lengths are shown in mm or um, angles in urad, as labelled.
"""
from __future__ import annotations

import numpy as np

import pcr

try:
    import matplotlib  # noqa: F401
except ModuleNotFoundError as _missing:
    raise ModuleNotFoundError(
        "pcr.plot needs matplotlib, which `pip install ./python` does not bring: "
        "pip install './python[plot]' (or pip install matplotlib)", name="matplotlib") from _missing


def _figure(ax, size=(6, 6)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=size)
    else:
        fig = ax.figure
    return fig, ax


def _finish(fig, path):
    if path is not None:
        fig.savefig(path, dpi=100)
    return fig


def _frame(ax, x, y, theta, length, label, colour):
    for angle, c in ((theta, "tab:red"), (theta + np.pi / 2, "tab:green")):
        ax.annotate("", xy=(x + length * np.cos(angle), y + length * np.sin(angle)), xytext=(x, y),
                    arrowprops=dict(arrowstyle="->", color=c, lw=1.2))
    ax.text(x, y, f" {label}", color=colour, fontsize=8, va="top")


def plot_robot(robot, configurations, ax=None, path=None, frames=True, **solve_args):
    """The rods' shapes, proximal clamps A_i(q), distal clamps B_i, the platform and the frames
    W and P, for one configuration or a sequence.

    configurations: a joint vector (n,) or an (N, n) array (m), solved by FK with shapes, or a
    Solution / list of Solutions obtained with ``shapes=True``.
    """
    fig, ax = _figure(ax)
    if isinstance(configurations, pcr.Solution):
        solutions = [configurations]
    elif isinstance(configurations, (list, tuple)) and configurations and isinstance(
            configurations[0], pcr.Solution):
        solutions = list(configurations)
    else:
        q = np.atleast_2d(np.asarray(configurations, dtype=float))
        solutions = [robot.forward(row, shapes=True, **solve_args) for row in q]
    mm = 1e3
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
            ax.plot(shape[:, 1] * mm, shape[:, 2] * mm, color=colours[i % 6], alpha=alpha, lw=1.5,
                    label=f"rod {i}" if k == len(solutions) - 1 else None)
            ax.plot(shape[0, 1] * mm, shape[0, 2] * mm, "s", color="k", ms=5, alpha=alpha)
            c, sn = np.cos(pose.theta), np.sin(pose.theta)
            bx = pose.x + c * limb.B[0] - sn * limb.B[1]
            by = pose.y + sn * limb.B[0] + c * limb.B[1]
            distal.append((bx, by))
        distal = np.array(distal + distal[:1])
        ax.fill(distal[:, 0] * mm, distal[:, 1] * mm, color="0.6", alpha=0.25 * alpha)
        ax.plot(distal[:, 0] * mm, distal[:, 1] * mm, "o-", color="0.3", ms=4, alpha=alpha)
        if frames and k == len(solutions) - 1:
            _frame(ax, pose.x * mm, pose.y * mm, pose.theta, 0.25 * scale * mm, "P", "0.2")
    if frames:
        _frame(ax, 0.0, 0.0, 0.0, 0.25 * scale * mm, "W", "k")
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"{robot.name}: {len(solutions)} configuration{'s' if many else ''}")
    ax.legend(loc="upper right", fontsize=8)
    return _finish(fig, path)


def plot_workspace(robot, theta=0.0, ax=None, path=None, result=None, **workspace_args):
    """The reachable positions of the platform at orientation ``theta`` (rad), from
    ``pcr.workspace`` (or a precomputed ``result`` of it), coloured by the max bending strain."""
    fig, ax = _figure(ax)
    ws = result if result is not None else pcr.workspace(robot, theta=theta, **workspace_args)
    mm = 1e3
    x, y = np.meshgrid(ws["x"] * mm, ws["y"] * mm)
    strain = np.where(ws["reachable"], ws["max_strain"], np.nan)
    mesh = ax.pcolormesh(x, y, strain * 100, shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="max bending strain (%)")
    ax.contour(x, y, ws["reachable"].astype(float), levels=[0.5], colors="k", linewidths=1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"{robot.name}: workspace at theta = {ws['theta']:.4g} rad\n"
                 f"({int(ws['reachable'].sum())} of {ws['reachable'].size} grid points reachable)",
                 fontsize=10)
    return _finish(fig, path)


def plot_workspace_maps(robot, result=None, path=None, fig=None, **map_args):
    """Where the robot can work at one orientation, from ``pcr.workspace_map`` (or a precomputed
    ``result`` of it): reachable positions split into stable and unstable equilibria, the
    stability margin, the distance to a singularity, and the predicted 3-sigma position error
    when the map has one (else the max bending strain). Each panel outlines the workspace."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap, LogNorm, SymLogNorm

    m = result if result is not None else pcr.workspace_map(robot, **map_args)
    if fig is None:
        fig = plt.figure(figsize=(11, 9.5))
    axes = fig.subplots(2, 2).ravel()
    mm = 1e3
    x, y = np.meshgrid(m["x"] * mm, m["y"] * mm)
    reach = m["reachable"]
    inside = lambda values: np.where(reach, values, np.nan)  # noqa: E731
    kind = np.where(reach, np.where(m["stable"], 2.0, 1.0), np.nan)
    panels = [
        (kind, "reachable: stable (green) / unstable (red)",
         dict(cmap=ListedColormap(["tab:red", "tab:green"]), vmin=0.5, vmax=2.5), None),
        (inside(m["stability_margin"]), "stability margin (EI/L units)",
         dict(cmap="RdYlGn", norm=SymLogNorm(linthresh=1.0)), "margin"),
        (inside(m["singularity"]), "singularity: reciprocal condition number of the FK Jacobian",
         dict(cmap="magma", norm=LogNorm()), "sigma_min"),
    ]
    accuracy = inside(m["position_3sigma"])
    if np.isfinite(accuracy).any():
        panels.append((accuracy * 1e6, "predicted 3-sigma position error (um)",
                       dict(cmap="viridis"), "um"))
    else:
        panels.append((inside(m["max_strain"]) * 100, "max bending strain (%)",
                       dict(cmap="viridis"), "%"))
    for ax, (values, title, style, label) in zip(axes, panels):
        finite = values[np.isfinite(values)]
        if "norm" in style and isinstance(style["norm"], LogNorm):
            positive = finite[finite > 0]
            if positive.size == 0:
                style = dict(cmap=style["cmap"])
            else:
                style["norm"] = LogNorm(vmin=positive.min(), vmax=positive.max())
        mesh = ax.pcolormesh(x, y, values, shading="nearest", **style)
        if label is not None:
            fig.colorbar(mesh, ax=ax, label=label)
        if reach.any() and not reach.all():
            ax.contour(x, y, reach.astype(float), levels=[0.5], colors="k", linewidths=1)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_title(title, fontsize=9)
    fig.suptitle(f"{robot.name}: workspace at theta = {m['theta']:.4g} rad; reachable "
                 f"{m['reachable_area'] * 1e6:.4g} mm^2, stable {m['stable_area'] * 1e6:.4g} mm^2",
                 fontsize=11)
    return _finish(fig, path)


def plot_calibration_errors(nominal, identified, calibration, validation=None, path=None,
                            fig=None):
    """Position and orientation errors per configuration of the nominal and identified models,
    on the calibration set and (optionally) the validation set: the paper's Figures 8 and 9.

    calibration, validation: (q (N, n) m, measured ^Se T_M (N, 3)) pairs, or precomputed
    {"nominal": (e_p, e_theta), "identified": (e_p, e_theta)} dicts (m, rad).
    """
    import matplotlib.pyplot as plt

    sets = [("calibration", calibration)]
    if validation is not None:
        sets.append(("validation", validation))
    if fig is None:
        fig = plt.figure(figsize=(10, 3.2 * len(sets)))
    axes = fig.subplots(len(sets), 2, squeeze=False)
    for row, (label, data) in enumerate(sets):
        if isinstance(data, dict):
            errors = data
        else:
            q, measured = data
            errors = {"nominal": pcr.pose_errors_per_configuration(nominal, q, measured),
                      "identified": pcr.pose_errors_per_configuration(identified, q, measured)}
        for col, (unit, factor, name) in enumerate((("um", 1e6, "position error e_p"),
                                                     ("urad", 1e6, "orientation error e_theta"))):
            ax = axes[row, col]
            for model, marker in (("nominal", "o"), ("identified", "s")):
                e = np.asarray(errors[model][col]) * factor
                ax.semilogy(np.arange(1, len(e) + 1), e, marker, ms=3, label=f"{model} "
                            f"(mean {np.nanmean(e):.3g} {unit})")
            ax.set_xlabel(f"{label} configuration")
            ax.set_ylabel(f"{name} ({unit})")
            ax.legend(fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return _finish(fig, path)


def _barycentre(commanded, attained):
    """ISO 9283 mean of (N, R, 3) attained poses, theta averaged about the commanded one."""
    d = attained[..., 2] - commanded[:, None, 2]
    theta = commanded[:, 2] + np.mean(np.arctan2(np.sin(d), np.cos(d)), axis=1)
    return np.column_stack([attained[..., 0].mean(axis=1), attained[..., 1].mean(axis=1), theta])


def plot_trajectory_accuracy(commanded, attained=None, path=None, fig=None):
    """Accuracy along a trajectory (the paper's Figures 11 and 12): position error (um) and
    orientation error (urad) per pose.

    Either (N, 3) arrays of commanded and attained poses (x m, y m, theta rad); or attained as an
    (N, R, 3) array of R cycles per pose, whose ISO 9283 barycentres are compared; or, alone, the
    result of ``pcr.evaluate_on_virtual_robot`` (an AccuracyEvaluation) or of ``pcr.iso9283``
    (an Iso9283Result: its barycentres).
    """
    import matplotlib.pyplot as plt

    cloud = None
    if attained is None:
        if hasattr(commanded, "attained") and hasattr(commanded, "commanded"):  # evaluation
            commanded, attained = commanded.commanded, commanded.attained
        elif hasattr(commanded, "barycentre"):  # Iso9283Result
            commanded, attained = commanded.commanded, commanded.barycentre
        else:
            raise ValueError("attained: required unless commanded is an AccuracyEvaluation or "
                             "an Iso9283Result")
    commanded = np.atleast_2d(np.asarray(commanded, dtype=float))
    attained = np.asarray(attained, dtype=float)
    if attained.ndim == 3 and attained.shape[0] == commanded.shape[0] and attained.shape[2] == 3:
        cloud = attained.reshape(-1, 3)
        attained = _barycentre(commanded, attained)
    attained = np.atleast_2d(attained)
    if commanded.shape != attained.shape or commanded.shape[1] != 3:
        raise ValueError(f"commanded, attained: expected two (N, 3) arrays, got "
                         f"{commanded.shape} and {attained.shape}")
    e_p = np.hypot(*(attained[:, :2] - commanded[:, :2]).T) * 1e6
    e_t = np.arctan2(np.sin(attained[:, 2] - commanded[:, 2]),
                     np.cos(attained[:, 2] - commanded[:, 2])) * 1e6
    if fig is None:
        fig = plt.figure(figsize=(10, 6))
    ax_path, ax_p, ax_t = fig.subplots(3, 1)
    ax_path.plot(commanded[:, 0] * 1e3, commanded[:, 1] * 1e3, "k-", lw=1, label="commanded")
    if cloud is not None:
        ax_path.plot(cloud[:, 0] * 1e3, cloud[:, 1] * 1e3, ",", color="0.6", label="cycles")
    ax_path.plot(attained[:, 0] * 1e3, attained[:, 1] * 1e3, ".", ms=3,
                 label="attained" if cloud is None else "attained (barycentre)")
    ax_path.set_xlabel("x (mm)")
    ax_path.set_ylabel("y (mm)")
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.legend(fontsize=8)
    idx = np.arange(1, len(e_p) + 1)
    ax_p.plot(idx, e_p, ".-", ms=3)
    ax_p.set_ylabel("position error (um)")
    ax_p.set_title(f"mean {np.mean(e_p):.3g} um, max {np.max(e_p):.3g} um", fontsize=9)
    ax_t.plot(idx, e_t, ".-", ms=3, color="tab:orange")
    ax_t.set_ylabel("orientation error (urad)")
    ax_t.set_xlabel("pose")
    fig.tight_layout()
    return _finish(fig, path)
