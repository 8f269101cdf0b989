"""Plots and summaries of a study's results: each outcome against each varied factor (box plots
over the trials of each level), the factors ranked by the share of the outcome's variance they
explain, and the parameters ranked by how their identification error follows the outcome."""
from __future__ import annotations

import os
import textwrap

import numpy as np

from .._files import write_atomically
from ._store import read_results, read_study

DEFAULT_OUTCOMES = ("table3.identified_model_validation_set.e_p_m.mean",
                    "table3.nominal_model_validation_set.e_p_m.mean",
                    "table3.identified_model_validation_set.e_theta_rad.mean",
                    "accuracy.square.identified.ap_p.mean")
# A spatial study's (pcr.study.spatial_outcome_columns): the rms errors, Table 4 on the helix.
SPATIAL_OUTCOMES = ("table3.identified_model_validation_set.rms_position_m",
                    "table3.nominal_model_validation_set.rms_position_m",
                    "table3.identified_model_validation_set.rms_angle_rad",
                    "accuracy.helix.identified.ap_p.mean")
# The outcomes drawn with the noise floor sqrt(3) sigma (a dashed line): rms errors.
_FLOORS = {"rms_position_m": "noise.floor_position_m", "rms_angle_rad": "noise.floor_angle_rad"}


def default_outcomes(table):
    """The planar outcomes when the table has them, else the spatial ones."""
    return DEFAULT_OUTCOMES if all(c in table.columns for c in DEFAULT_OUTCOMES) \
        else SPATIAL_OUTCOMES


_QUANTITIES = {  # an outcome's quantity -> (words, factor from SI, display unit)
    "e_p_m": ("position error e_p", 1e6, "µm"),
    "e_theta_rad": ("orientation error e_θ", 1e6, "µrad"),
    "e_angle_rad": ("orientation error e_θ", 1e6, "µrad"),
    "rms_position_m": ("rms position error", 1e6, "µm"),
    "rms_angle_rad": ("rms orientation error", 1e6, "µrad"),
    "ap_p": ("position accuracy AP_p", 1e6, "µm"),
    "ap_theta_abs": ("orientation accuracy |AP_θ|", 1e6, "µrad"),
    "rp_l": ("position repeatability RP_l", 1e6, "µm"),
    "rp_theta": ("orientation repeatability RP_θ", 1e6, "µrad"),
    "failed": ("configurations FK failed on", 1.0, "count"),
    "branch_mismatches": ("configurations on another branch", 1.0, "count"),
}


_OTHERS = {
    "configurations.calibration": ("calibration configurations", 1.0, "count"),
    "configurations.validation": ("validation configurations", 1.0, "count"),
    "configurations.unreachable": ("configurations not measured (no stable equilibrium)", 1.0,
                                   "count"),
    "calibration.iterations": ("calibration iterations", 1.0, "count"),
    "calibration.load_identified": ("platform load identified", 1.0, "1: yes"),
}


def outcome_label(column):
    """(words, factor from SI, display unit) of an outcome column:
    'table3.identified_model_validation_set.e_p_m.mean' -> ('mean position error e_p,
    identified model, validation set', 1e6, 'µm')."""
    parts = column.split(".")
    if parts[0] == "table3" and len(parts) >= 3 and parts[2] in _QUANTITIES:
        words, factor, unit = _QUANTITIES[parts[2]]
        model, _, which = parts[1].partition("_model_")
        stat = parts[3] + " " if len(parts) > 3 else ""
        return f"{stat}{words}, {model} model, {which.replace('_set', '')} set", factor, unit
    if parts[0] == "accuracy" and len(parts) == 5 and parts[3] in _QUANTITIES:
        words, factor, unit = _QUANTITIES[parts[3]]
        return f"{parts[4]} {words} on the {parts[1]}, {parts[2]} model", factor, unit
    if column in _OTHERS:
        return _OTHERS[column]
    if parts[0] == "time" or column == "time_s":
        return "time" + (f": {parts[1][:-2]}" if len(parts) == 2 else ""), 1.0, "s"
    return column, 1.0, ""


def _axis_label(column):
    words, _, unit = outcome_label(column)
    return textwrap.fill(f"{words} ({unit})" if unit else words, 34)


def _factor_axis(name):
    """A factor's axis label: its name in words and the first clause of its description."""
    from ._trial import FACTORS

    doc = FACTORS[name].doc.split(";")[0] if name in FACTORS else ""
    return name.replace("_", " ") + (f": {doc}" if doc else "")


def _factor_label(name, value):
    from ._trial import FACTORS

    unit = FACTORS[name].unit
    if unit == "m" and isinstance(value, float):
        return f"{value * 1e6:g} µm"
    if unit == "rad" and isinstance(value, float):
        return f"{value * 1e3:g} mrad"
    return f"{value:g} {unit}".strip() if isinstance(value, float) else str(value)


def _robots(study):
    """The study's robot(s), for the titles."""
    robots = study.levels.get("robot") or [study.factors.get("robot", "default")]
    return ", ".join("the paper's (default)" if r == "default" else os.path.basename(str(r))
                     for r in robots)


def sensitivity(table, outcome, factors):
    """The share of the variance of log10(outcome) over the successful trials that each factor's
    levels explain (the correlation ratio eta^2: between-level over total sum of squares; for a
    full grid, the factor's first-order effect). Returns a DataFrame (factor, eta_squared,
    levels, trials), largest first."""
    import pandas as pd

    ok = table[table["failure"].isna() & (table[outcome] > 0)]
    y = np.log10(ok[outcome].to_numpy())
    total = float(np.sum((y - y.mean()) ** 2)) if len(y) else 0.0
    rows = []
    for f in factors:
        groups = ok.groupby(f, dropna=False)[outcome]
        between = sum(len(g) * (np.log10(g).mean() - y.mean()) ** 2 for _, g in groups)
        rows.append({"factor": f, "eta_squared": between / total if total > 0 else np.nan,
                     "levels": groups.ngroups, "trials": len(y)})
    return pd.DataFrame(rows).sort_values("eta_squared", ascending=False, ignore_index=True)


def parameter_ranking(table, outcome):
    """The parameters ranked by the Spearman correlation, over the successful trials, between
    the magnitude of their identification error (against the truth, in the calibration's gauge)
    and the outcome: the parameters whose error goes with a worse robot come first."""
    import pandas as pd

    ok = table[table["failure"].isna()]
    errors = [c for c in ok.columns if c.startswith("parameters.") and c.endswith(".error")]
    rows = []
    for c in errors:
        e = ok[c].abs()
        if e.notna().sum() < 3 or e.nunique() < 2:
            continue
        rows.append({"parameter": c[len("parameters."):-len(".error")],
                     "spearman": e.rank().corr(ok[outcome].rank()),  # (scipy-free)
                     "median_abs_error": float(e.median())})
    frame = pd.DataFrame(rows, columns=["parameter", "spearman", "median_abs_error"])
    return frame.sort_values("spearman", ascending=False, ignore_index=True)


def factors_figure(table, study, outcomes):
    """Each outcome (a row) against each varied factor (a column): a box per level over its
    successful trials (log scale when all are positive), in words and display units."""
    from ..plot._common import new_figure, plain_ticks

    factors = list(study.levels) or ["replicate"]
    ok = table[table["failure"].isna()]
    fig = new_figure((4.6 * len(factors) + 1.4, 3.3 * len(outcomes) + 0.4))
    axes = fig.subplots(len(outcomes), len(factors), squeeze=False)
    for j, f in enumerate(factors):
        levels = study.levels.get(f, sorted(table[f].unique()))
        for i, o in enumerate(outcomes):
            _, scale, _ = outcome_label(o)
            data = [ok.loc[ok[f] == v, o].dropna().to_numpy() * scale for v in levels]
            ax = axes[i][j]
            ax.boxplot([d if len(d) else [np.nan] for d in data], whis=(5, 95), showfliers=True)
            ax.set_xticks(range(1, len(levels) + 1),
                          [_factor_label(f, v) for v in levels], fontsize=8)
            floor = _FLOORS.get(o.split(".")[-1])
            if floor in ok.columns and ok[floor].notna().any():  # per level: noise may vary
                floors = [ok.loc[ok[f] == v, floor].median() * scale for v in levels]
                ax.hlines(floors, np.arange(len(levels)) + 0.55, np.arange(len(levels)) + 1.45,
                          colors="0.4", linestyles="--", linewidth=1, label="noise floor √3 σ")
                ax.legend(fontsize=7, loc="best")
            if all(len(d) and np.all(d > 0) for d in data):
                ax.set_yscale("log")
                plain_ticks(ax.yaxis, *ax.get_ylim())
            failed = [int((table[f] == v).sum() - len(d)) for v, d in zip(levels, data)]
            if any(failed):
                ax.set_title("failed trials: " + ", ".join(map(str, failed)), fontsize=8)
            ax.set_xlabel(textwrap.fill(_factor_axis(f), 60), fontsize=8)
            ax.set_ylabel(_axis_label(o), fontsize=8)
            ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"study {study.name}, robot {_robots(study)}: {len(table)} trials\n"
                 f"(boxes 25-75 %, whiskers 5-95 % of the successful trials)", fontsize=11)
    return fig


def sensitivity_figure(table, study, outcome):
    """The factors ranked by eta^2 of log10(outcome) and the parameters by the Spearman
    correlation of their |error| with it."""
    from ..plot._common import new_figure

    ranking = sensitivity(table, outcome, list(study.levels) or ["replicate"])
    parameters = parameter_ranking(table, outcome)
    fig = new_figure((11, 0.3 * max(len(parameters[:15]), 4) + 2.4))
    a, b = fig.subplots(1, 2)
    a.barh([f.replace("_", " ") for f in ranking["factor"][::-1]], ranking["eta_squared"][::-1])
    a.set_xlim(0, 1)
    a.set_xlabel("share of the variance of log10(outcome), η²")
    a.set_title("factors", fontsize=10)
    top = parameters[:15]
    b.barh(top["parameter"][::-1], top["spearman"][::-1])
    b.set_xlim(-1, 1)
    b.set_xlabel("Spearman correlation of |error| with the outcome")
    b.set_title("parameters (error against the truth)", fontsize=10)
    if top.empty:  # a spatial study's rows: no truth in the calibration's gauge to compare with
        b.set_yticks([])
        b.text(0.5, 0.5, "no parameter errors in these rows", ha="center", va="center",
               transform=b.transAxes)
    fig.suptitle(f"study {study.name}, robot {_robots(study)}: what sets the\n"
                 f"{outcome_label(outcome)[0]}", fontsize=11)
    return fig, ranking, parameters


def plot(directory, output=None, outcomes=None):
    """Writes into `output` (default: directory/_plots) factors.png (each outcome against each
    varied factor: a box per level over its trials, log scale), sensitivity.png and .csv (the
    factors' eta^2 and the parameters' ranking for the first outcome) and summary.csv (count,
    failures and quantiles of every outcome per level). Returns the written paths."""
    try:
        import matplotlib  # noqa: F401
    except ModuleNotFoundError as e:
        raise ModuleNotFoundError("pcr-study plot needs matplotlib: pip install "
                                  "'./python[study]'", name="matplotlib") from e
    from ..plot._common import save

    table = read_results(directory)
    if table.empty:
        raise ValueError(f"{directory}: no finished trial to plot yet")
    study = read_study(directory)
    outcomes = list(outcomes or default_outcomes(table))
    for o in outcomes:
        if o not in table.columns:
            raise ValueError(f"outcome {o!r}: no such column in {directory}")
    factors = list(study.levels) or ["replicate"]
    output = os.fspath(output) if output is not None else os.path.join(directory, "_plots")
    os.makedirs(output, exist_ok=True)
    written = [os.path.join(output, "factors.png"), os.path.join(output, "sensitivity.png")]
    save(factors_figure(table, study, outcomes), written[0], dpi=100)
    fig, ranking, parameters = sensitivity_figure(table, study, outcomes[0])
    save(fig, written[1], dpi=100)

    text = "# factors: eta^2 of log10(" + outcomes[0] + ")\n" + ranking.to_csv(index=False)
    text += "# parameters: Spearman correlation of |error| with it\n"
    text += parameters.to_csv(index=False)
    path = os.path.join(output, "sensitivity.csv")
    write_atomically(path, text.encode())
    written.append(path)

    summary = []
    for f in factors:
        for v, group in table.groupby(f, dropna=False):
            good = group[group["failure"].isna()]
            for o in outcomes:
                q = good[o].quantile([0.05, 0.25, 0.5, 0.75, 0.95]).to_numpy()
                summary.append([f, v, o, len(group), len(group) - len(good), *q])
    import pandas as pd

    frame = pd.DataFrame(summary, columns=["factor", "level", "outcome", "trials", "failed",
                                           "q05", "q25", "median", "q75", "q95"])
    path = os.path.join(output, "summary.csv")
    write_atomically(path, frame.to_csv(index=False).encode())
    written.append(path)
    return written
