"""Accuracy: the errors per configuration of the calibration (the paper's Figures 8 and 9) and along
a trajectory (Figures 11 and 12)."""
from __future__ import annotations

import os

import numpy as np

import pcr

from ._common import (MM, angle_unit, format_factor, length_unit, new_figure, nice_below,
                      plain_ticks, read_csv, save, title)

_MODEL_COLOURS = {"nominal": "tab:red", "identified": "tab:blue"}


def read_calibration_errors(source):
    """The demo's calibration-errors.csv (a path or a DataFrame) as {set: {model: (e_p, e_theta)}}
    in configuration order (m, rad), for ``plot_calibration_errors``. A spatial robot's has
    e_angle (the angle of the orientation error) for e_theta."""
    c = read_csv(source)
    if "e_theta" not in c:
        c["e_theta"] = c["e_angle"]
    out = {}
    for set_name in dict.fromkeys(c["set"]):
        out[set_name] = {}
        for model in ("nominal", "identified"):
            rows = np.flatnonzero((c["set"] == set_name) & (c["model"] == model))
            rows = rows[np.argsort(c["configuration"][rows])]
            out[set_name][model] = (c["e_p"][rows], c["e_theta"][rows])
    return out


def plot_calibration_errors(nominal=None, identified=None, calibration=None, validation=None,
                            path=None, fig=None, *, name=None, floor=None):
    """Position and orientation errors per configuration of the nominal and identified models,
    on the calibration set and (optionally) the validation set: the paper's Figures 8 and 9.
    Log scale, in um and urad.

    calibration, validation: (q (N, n) m, measured ^Se T_M (N, 3)) pairs, solved with the
    models `nominal` and `identified` (pcr.Robot), or precomputed {"nominal": (e_p, e_theta),
    "identified": (e_p, e_theta)} dicts (m, rad). calibration may instead be the demo's
    calibration-errors.csv (a path or a DataFrame): both sets come from it (a spatial robot's:
    its e_angle, the angle of the orientation error, for e_theta). name: the robot, for the
    title. floor: (position m, angle rad), the noise floor, drawn dashed.
    """
    inputs = []
    angle = "orientation error |e_θ|"
    if isinstance(calibration, (str, os.PathLike)) or hasattr(calibration, "columns"):
        inputs.append(calibration)
        if "e_angle" in read_csv(calibration):
            angle = "orientation error e_angle"
        sets = read_calibration_errors(calibration)
        calibration, validation = sets["calibration"], sets.get("validation")
    sets = [("calibration", calibration)]
    if validation is not None:
        sets.append(("validation", validation))
    fig = fig if fig is not None else new_figure((11, 3.6 * len(sets) + 0.6))
    axes = fig.subplots(len(sets), 2, squeeze=False)
    for row, (label, data) in enumerate(sets):
        if isinstance(data, dict):
            errors = data
        else:
            q, measured = data
            errors = {"nominal": pcr.pose_errors_per_configuration(nominal, q, measured),
                      "identified": pcr.pose_errors_per_configuration(identified, q, measured)}
        for col, (unit, factor, what) in enumerate((("µm", 1e6, "position error e_p"),
                                                    ("µrad", 1e6, angle))):
            ax = axes[row, col]
            for model, marker in (("nominal", "o"), ("identified", "s")):
                e = np.abs(np.asarray(errors[model][col], dtype=float)) * factor
                ax.semilogy(np.arange(1, len(e) + 1), e, marker, ms=3, label=f"{model} model "
                            f"(mean {np.nanmean(e):.3g} {unit})")
            if floor is not None:
                ax.axhline(floor[col] * factor, color="0.4", ls="--", lw=0.8,
                           label=f"noise floor {floor[col] * factor:.3g} {unit}")
            plain_ticks(ax.yaxis, *ax.get_ylim())
            ax.set_xlabel(f"configuration of the {label} set")
            ax.set_ylabel(f"{what} ({unit})")
            ax.set_title(f"{label} set: {what}", fontsize=9)
            ax.legend(fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title(name, "errors per configuration before (nominal) and after (identified) "
                       "calibration"), fontsize=11)
    return save(fig, path, inputs)


def _barycentres(commanded, cycles):
    """ISO 9283 barycentre and position repeatability RP_l (l_bar + 3 S_l) of each pose's
    attained poses (a list of (R_k, 3) arrays), theta averaged about the commanded one."""
    barycentres, rp_l = [], []
    for c, a in zip(commanded, cycles):
        d = a[:, 2] - c[2]
        b = [a[:, 0].mean(), a[:, 1].mean(), c[2] + np.mean(np.arctan2(np.sin(d), np.cos(d)))]
        distance = np.hypot(a[:, 0] - b[0], a[:, 1] - b[1])
        barycentres.append(b)
        rp_l.append(distance.mean() + 3 * distance.std(ddof=1) if len(a) > 1 else np.nan)
    return np.array(barycentres).reshape(-1, 3), np.array(rp_l)


def read_trajectory(source):
    """(commanded (N, 3), attained, rp_l (N,) or None) from a CSV (a path or a DataFrame): the
    per-pose statistics of `pcr accuracy --format csv` (the demo's accuracy-*.csv: attained = the
    barycentres (N, 3), rp_l its column) or the measured poses (`pcr accuracy --poses`, the
    demo's attained-*.csv: attained = a list of each pose's (R_k, 3) cycles, rp_l None)."""
    c = read_csv(source)
    if "x_bar" in c:
        order = np.argsort(c["pose"])
        return (np.column_stack([c["x_c"], c["y_c"], c["theta_c"]])[order],
                np.column_stack([c["x_bar"], c["y_bar"], c["theta_bar"]])[order],
                c["rp_l"][order] if "rp_l" in c else None)
    if not {"pose", "x_c", "x"} <= set(c):
        raise ValueError(f"{source}: neither per-pose statistics (x_bar) nor measured poses "
                         "(pose, x_c, x)")
    poses = np.unique(c["pose"])
    first = [np.flatnonzero(c["pose"] == k)[0] for k in poses]
    commanded = np.column_stack([c["x_c"], c["y_c"], c["theta_c"]])[first]
    attained = np.column_stack([c["x"], c["y"], c["theta"]])
    return commanded, [attained[c["pose"] == k] for k in poses], None


def _as_trajectory(commanded, attained):
    """(commanded (N, 3), barycentres (N, 3), rp_l (N,) or None, the input files)."""
    inputs, rp_l = [], None
    if attained is None:
        if isinstance(commanded, (str, os.PathLike)) or hasattr(commanded, "columns"):
            inputs.append(commanded)
            commanded, attained, rp_l = read_trajectory(commanded)
        elif hasattr(commanded, "attained") and hasattr(commanded, "commanded"):  # evaluation
            commanded, attained = commanded.commanded, commanded.attained
        elif hasattr(commanded, "barycentre"):  # Iso9283Result
            commanded, attained, rp_l = commanded.commanded, commanded.barycentre, commanded.rp_l
        else:
            raise ValueError("attained: required unless commanded is a CSV, an "
                             "AccuracyEvaluation or an Iso9283Result")
    commanded = np.atleast_2d(np.asarray(commanded, dtype=float))
    if isinstance(attained, list) or (np.ndim(attained) == 3 and len(attained) == len(commanded)
                                      and np.shape(attained)[2] == 3):
        cycles = [np.asarray(a, dtype=float).reshape(-1, 3) for a in attained]
        if len(cycles) == len(commanded):
            attained, rp_l = _barycentres(commanded, cycles)
    attained = np.atleast_2d(np.asarray(attained, dtype=float))
    if commanded.shape != attained.shape or commanded.shape[1] != 3:
        raise ValueError(f"commanded, attained: expected two (N, 3) arrays, got "
                         f"{commanded.shape} and {attained.shape}")
    return commanded, attained, rp_l, inputs


def plot_trajectory_accuracy(commanded, attained=None, path=None, fig=None, *, name=None,
                             label=None, magnification=None):
    """Accuracy along a trajectory (the paper's Figures 11 and 12): the commanded path with each
    pose's position error drawn as a vector magnified by a printed factor (chosen so that the
    largest is about a seventh of the path's size, unless `magnification` is given) and a scale
    arrow; the position error AP_p per pose, with the repeatability RP_l when the cycles (or
    the per-pose statistics) give it; the orientation error AP_theta per pose.

    commanded: (N, 3) commanded poses (x m, y m, theta rad) with attained (N, 3), or (N, R, 3)
    cycles per pose (their ISO 9283 barycentres are compared), or a list of (R_k, 3); or, alone,
    a CSV of `pcr accuracy` (``read_trajectory``), the result of
    ``pcr.evaluate_on_virtual_robot`` (an AccuracyEvaluation) or of ``pcr.iso9283`` (its
    barycentres). name: the robot; label: the path and model (e.g. "square, identified model").
    """
    commanded, attained, rp_l, inputs = _as_trajectory(commanded, attained)
    error = attained[:, :2] - commanded[:, :2]
    e_p = np.hypot(error[:, 0], error[:, 1])
    e_t = np.arctan2(np.sin(attained[:, 2] - commanded[:, 2]),
                     np.cos(attained[:, 2] - commanded[:, 2]))
    size = max(np.ptp(commanded[:, 0]), np.ptp(commanded[:, 1]), 1e-6)
    k = magnification or (nice_below(0.15 * size / e_p.max()) if e_p.max() > 0 else 1.0)
    shown = [e_p] + ([rp_l] if rp_l is not None else [])
    scale, unit = length_unit(np.nanmax(np.concatenate(shown)))

    fig = fig if fig is not None else new_figure((12, 5.6))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.1, 1])
    ax_path = fig.add_subplot(grid[:, 0])
    ax_p = fig.add_subplot(grid[0, 1])
    ax_t = fig.add_subplot(grid[1, 1], sharex=ax_p)
    c = commanded[:, :2] * MM
    ax_path.plot(c[:, 0], c[:, 1], "-", color="0.7", lw=0.8)
    ax_path.plot(c[:, 0], c[:, 1], ".", color="k", ms=4, label="commanded pose")
    factor = format_factor(k)
    arrows = ax_path.quiver(c[:, 0], c[:, 1], error[:, 0] * MM, error[:, 1] * MM, color="tab:red",
                            angles="xy", scale_units="xy", scale=1 / k, width=0.005,
                            label=f"error of the attained barycentre (× {factor})")
    ax_path.update_datalim(c + k * error * MM)
    ax_path.autoscale_view()
    reference = nice_below(e_p.max()) if e_p.max() > 0 else 1e-6
    ax_path.quiverkey(arrows, 0.72, 1.03, reference * MM,
                      f"{reference * scale:g} {unit} (× {factor})", labelpos="E",
                      fontproperties={"size": 8})
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set_xlabel("x (mm)")
    ax_path.set_ylabel("y (mm)")
    ax_path.legend(fontsize=8, loc="center")
    ax_path.set_title(f"position errors magnified × {factor}", fontsize=9, loc="left")

    pose = np.arange(1, len(e_p) + 1)
    ax_p.plot(pose, e_p * scale, ".-", ms=4, label="accuracy AP_p")
    if rp_l is not None:
        ax_p.plot(pose, rp_l * scale, ".--", ms=3, color="tab:gray", label="repeatability RP_l")
    ax_p.set_ylabel(f"position ({unit})")
    ax_p.set_title(f"AP_p: mean {e_p.mean() * scale:.3g} {unit}, max {e_p.max() * scale:.3g} "
                   f"{unit}", fontsize=9)
    ax_p.legend(fontsize=8)
    t_scale, t_unit = angle_unit(np.abs(e_t).max())
    ax_t.plot(pose, e_t * t_scale, ".-", ms=4, color="tab:orange")
    ax_t.axhline(0, color="0.5", lw=0.6)
    ax_t.set_ylabel(f"orientation error AP_θ ({t_unit})")
    ax_t.set_xlabel("pose along the path")
    for ax in (ax_p, ax_t):
        ax.grid(True, alpha=0.3)
    fig.suptitle(title(name, (f"{label}: " if label else "") + "ISO 9283 accuracy of each pose "
                       "(barycentre of its cycles minus the commanded pose)"), fontsize=11)
    return save(fig, path, inputs)


def read_spatial_trajectory(source):
    """The per-pose statistics of a spatial robot's path (the spatial demo's accuracy-*.csv, a path
    or a DataFrame) in pose order: {"commanded": (N, 3), "barycentre": (N, 3) (m), "ap_p" (N,)
    (m), "ap_angle" (N,) (rad, |(AP_a, AP_b, AP_c)|, the angle of the orientation error),
    "rp_l" (N,) (m)}."""
    c = read_csv(source)
    order = np.argsort(c["pose"])
    return {"commanded": np.column_stack([c["x_c"], c["y_c"], c["z_c"]])[order],
            "barycentre": np.column_stack([c["x_bar"], c["y_bar"], c["z_bar"]])[order],
            "ap_p": c["ap_p"][order],
            "ap_angle": np.linalg.norm(np.column_stack([c["ap_a"], c["ap_b"], c["ap_c"]]),
                                       axis=1)[order],
            "rp_l": c["rp_l"][order]}


def plot_spatial_path_accuracy(nominal, identified, path=None, fig=None, *, name=None,
                               label=None):
    """A spatial robot's path commanded with the nominal and the identified model (Table 4 in
    3-D): the commanded poses' positions in 3-D with each model's attained barycentres, their
    errors magnified by a factor per model (printed; the largest error about a seventh of the
    path's size); the accuracy AP_p per pose of both models with their repeatability RP_l, and
    the angle of the orientation error |AP_abc| per pose. Log scales: the models differ by
    orders of magnitude.

    nominal, identified: the spatial demo's accuracy-<path>-<model>.csv (paths or DataFrames;
    ``read_spatial_trajectory``). name: the robot; label: the path ("helix").
    """
    inputs = [s for s in (nominal, identified) if isinstance(s, (str, os.PathLike))]
    models = {"nominal": read_spatial_trajectory(nominal),
              "identified": read_spatial_trajectory(identified)}
    commanded = models["nominal"]["commanded"]
    size = max(float(np.ptp(commanded, axis=0).max()), 1e-6)
    shown = np.concatenate([np.concatenate([m["ap_p"], m["rp_l"]]) for m in models.values()])
    scale, unit = length_unit(np.nanmax(shown))

    fig = fig if fig is not None else new_figure((13, 6.0))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.15, 1])
    ax3 = fig.add_subplot(grid[:, 0], projection="3d")
    ax_p = fig.add_subplot(grid[0, 1])
    ax_a = fig.add_subplot(grid[1, 1], sharex=ax_p)
    c = commanded * MM
    ax3.plot(*c.T, ".-", color="k", ms=4, lw=0.8, label="commanded")
    points = [c]
    for model, m in models.items():
        error = m["barycentre"] - m["commanded"]
        largest = np.linalg.norm(error, axis=1).max()
        k = nice_below(0.15 * size / largest) if largest > 0 else 1.0
        shown_at = (m["commanded"] + k * error) * MM
        ax3.plot(*shown_at.T, ".-", color=_MODEL_COLOURS[model], ms=3, lw=0.8,
                 label=f"attained, {model} model (errors × {format_factor(k)})")
        points.append(shown_at)
    every = np.vstack(points)  # equal scales on the three axes: the path is seen as it is
    centre = 0.5 * (every.min(axis=0) + every.max(axis=0))
    half = 0.5 * max(float(np.ptp(every, axis=0).max()), 1e-9)
    for set_limits, middle in zip((ax3.set_xlim, ax3.set_ylim, ax3.set_zlim), centre):
        set_limits(middle - half, middle + half)
    ax3.set_box_aspect((1, 1, 1))
    ax3.set_xlabel("x (mm)")
    ax3.set_ylabel("y (mm)")
    ax3.set_zlabel("z (mm)")
    ax3.legend(fontsize=8, loc="upper left")

    pose = np.arange(1, len(commanded) + 1)
    t_scale, t_unit = angle_unit(max(m["ap_angle"].max() for m in models.values()))
    for model, m in models.items():
        colour = _MODEL_COLOURS[model]
        ax_p.semilogy(pose, m["ap_p"] * scale, ".-", ms=4, color=colour,
                      label=f"AP_p, {model} (mean {m['ap_p'].mean() * scale:.3g} {unit})")
        ax_p.semilogy(pose, m["rp_l"] * scale, ":", lw=1, color=colour,
                      label=f"RP_l, {model}")
        ax_a.semilogy(pose, m["ap_angle"] * t_scale, ".-", ms=4, color=colour,
                      label=f"{model} (mean {m['ap_angle'].mean() * t_scale:.3g} {t_unit})")
    ax_p.set_ylabel(f"position ({unit})")
    ax_p.set_title("accuracy AP_p and repeatability RP_l of each pose", fontsize=9)
    ax_a.set_ylabel(f"|AP_abc| ({t_unit})")
    ax_a.set_title("orientation error of each pose (the angle of AP_a, AP_b, AP_c)", fontsize=9)
    ax_a.set_xlabel("pose along the path")
    for ax in (ax_p, ax_a):
        plain_ticks(ax.yaxis, *ax.get_ylim())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title(name, (f"{label}: " if label else "") + "ISO 9283 accuracy in 3-D of each "
                       "pose (barycentre of its cycles minus the commanded pose)"), fontsize=11)
    return save(fig, path, inputs)
