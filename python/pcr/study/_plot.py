"""Plots and summaries of a study's results: each outcome against each varied factor (box plots
over the trials of each level), the factors ranked by the share of the outcome's variance they
explain, and the parameters ranked by how their identification error follows the outcome."""
from __future__ import annotations

import io
import os

import numpy as np

from ._store import read_results, read_study, write_atomically

DEFAULT_OUTCOMES = ("table3.identified_model_validation_set.e_p_m.mean",
                    "table3.nominal_model_validation_set.e_p_m.mean",
                    "table3.identified_model_validation_set.e_theta_rad.mean",
                    "accuracy.square.identified.ap_p.mean")


def _scale(column):
    """Display unit of an outcome: (factor, label) for um or urad."""
    if column.endswith((".e_p_m.mean", ".e_p_m.max")) or ".ap_p." in column or ".rp_l." in column:
        return 1e6, "um"
    if "theta" in column:
        return 1e6, "urad"
    return 1.0, ""


def _factor_label(name, value):
    from ._trial import FACTORS

    unit = FACTORS[name].unit
    if unit == "m" and isinstance(value, float):
        return f"{value * 1e6:g} um"
    if unit == "rad" and isinstance(value, float):
        return f"{value * 1e3:g} mrad"
    return f"{value:g} {unit}".strip() if isinstance(value, float) else str(value)


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


def _save(fig, path):
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    write_atomically(path, buffer.getvalue())


def plot(directory, output=None, outcomes=None):
    """Writes into `output` (default: directory/_plots) factors.png (each outcome against each
    varied factor: a box per level over its trials, log scale), sensitivity.png and .csv (the
    factors' eta^2 and the parameters' ranking for the first outcome) and summary.csv (count,
    failures and quantiles of every outcome per level). Returns the written paths."""
    try:
        import matplotlib.pyplot as plt
    except ModuleNotFoundError as e:
        raise ModuleNotFoundError("pcr-study plot needs matplotlib: pip install "
                                  "'./python[study]'", name="matplotlib") from e
    table = read_results(directory)
    if table.empty:
        raise ValueError(f"{directory}: no finished trial to plot yet")
    study = read_study(directory)
    outcomes = list(outcomes or DEFAULT_OUTCOMES)
    for o in outcomes:
        if o not in table.columns:
            raise ValueError(f"outcome {o!r}: no such column in {directory}")
    factors = list(study.levels) or ["replicate"]
    output = os.fspath(output) if output is not None else os.path.join(directory, "_plots")
    os.makedirs(output, exist_ok=True)
    ok = table[table["failure"].isna()]
    written = []

    fig, axes = plt.subplots(len(outcomes), len(factors), squeeze=False,
                             figsize=(4.5 * len(factors) + 1, 3.2 * len(outcomes)))
    for j, f in enumerate(factors):
        levels = study.levels.get(f, sorted(table[f].unique()))
        for i, o in enumerate(outcomes):
            scale, unit = _scale(o)
            data = [ok.loc[ok[f] == v, o].dropna().to_numpy() * scale for v in levels]
            ax = axes[i][j]
            ax.boxplot([d if len(d) else [np.nan] for d in data], whis=(5, 95), showfliers=True)
            ax.set_xticks(range(1, len(levels) + 1),
                          [_factor_label(f, v) for v in levels], fontsize=8)
            if all(len(d) and np.all(d > 0) for d in data):
                ax.set_yscale("log")
            failed = [int((table[f] == v).sum() - len(d)) for v, d in zip(levels, data)]
            if any(failed):
                ax.set_title("failed: " + ", ".join(map(str, failed)), fontsize=8)
            ax.set_xlabel(f)
            ax.set_ylabel(f"{o.split('.', 1)[1] if '.' in o else o}\n({unit})", fontsize=8)
            ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"study {study.name}: {len(table)} trials (boxes 25-75 %, whiskers 5-95 %)")
    fig.tight_layout()
    path = os.path.join(output, "factors.png")
    _save(fig, path)
    plt.close(fig)
    written.append(path)

    ranking = sensitivity(table, outcomes[0], factors)
    parameters = parameter_ranking(table, outcomes[0])
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 0.3 * max(len(parameters[:15]), 4) + 2))
    a.barh(ranking["factor"][::-1], ranking["eta_squared"][::-1])
    a.set_xlim(0, 1)
    a.set_xlabel("share of the variance of log10(outcome) (eta^2)")
    a.set_title("factors", fontsize=10)
    top = parameters[:15]
    b.barh(top["parameter"][::-1], top["spearman"][::-1])
    b.set_xlim(-1, 1)
    b.set_xlabel("Spearman correlation of |error| with the outcome")
    b.set_title("parameters (error against the truth)", fontsize=10)
    fig.suptitle(outcomes[0])
    fig.tight_layout()
    path = os.path.join(output, "sensitivity.png")
    _save(fig, path)
    plt.close(fig)
    written.append(path)

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
