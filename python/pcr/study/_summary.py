"""The headline of a study's results, as the closing notes and papers quote it: how many trials
failed and why, the identified and nominal models' Table 3 over the trials, the rows named on
another equilibrium, the configurations the virtual robots could not measure, and the time."""
from __future__ import annotations

import math

from ._store import read_results
from ._trial import _TABLE3_SETS


def summary_rows(table):
    """One dict per Table 3 set over the successful trials: median and worst of the trials' mean
    position errors, worst maximum (m), branch-mismatch rows and the trials that have some."""
    ok = table[table["failure"].isna()]
    rows = []
    for s in _TABLE3_SETS:
        mean, worst = ok[f"table3.{s}.e_p_m.mean"], ok[f"table3.{s}.e_p_m.max"]
        mismatches = ok[f"table3.{s}.branch_mismatches"]
        rows.append({"set": s, "trials": int(mean.notna().sum()),
                     "mean_median_m": float(mean.median()), "mean_worst_m": float(mean.max()),
                     "max_worst_m": float(worst.max()),
                     "branch_mismatches": int(mismatches.sum()),
                     "trials_with_mismatches": int((mismatches > 0).sum())})
    return rows


def _um(value):
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) \
        else f"{value * 1e6:.4g}"


def summary(directory):
    """The summary of the results in `directory` (written by pcr-study run), in Markdown."""
    table = read_results(directory)
    failed = table[table["failure"].notna()]
    lines = [f"{len(table)} trials, {len(failed)} failed"]
    for reason, count in failed["failure"].value_counts().items():
        lines.append(f"- {count} x {reason}")
    lines += ["", "| Table 3 set | trials | mean e_p, median (um) | mean e_p, worst (um) | "
              "max e_p, worst (um) | branch mismatches (trials) |", "|---|---|---|---|---|---|"]
    for r in summary_rows(table):
        lines.append(f"| {r['set']} | {r['trials']} | {_um(r['mean_median_m'])} | "
                     f"{_um(r['mean_worst_m'])} | {_um(r['max_worst_m'])} | "
                     f"{r['branch_mismatches']} ({r['trials_with_mismatches']}) |")
    ok = table[table["failure"].isna()]
    if "noise.floor_position_m" in ok and ok["noise.floor_position_m"].notna().any():
        lines += ["", "| Table 3 set (spatial) | rms position, median (um) | rms position, worst "
                  "(um) | rms angle, median (urad) | rms angle, worst (urad) |",
                  "|---|---|---|---|---|"]
        for s in _TABLE3_SETS:
            p, a = ok[f"table3.{s}.rms_position_m"], ok[f"table3.{s}.rms_angle_rad"]
            lines.append(f"| {s} | {_um(p.median())} | {_um(p.max())} | {_um(a.median())} | "
                         f"{_um(a.max())} |")
        lines.append(f"| noise floor sqrt(3) sigma | {_um(ok['noise.floor_position_m'].median())}"
                     f" | | {_um(ok['noise.floor_angle_rad'].median())} | |")
    unreachable = ok["configurations.unreachable"]
    lines += ["", "configurations the virtual robots did not measure (no stable equilibrium "
              f"there): {int(unreachable.sum())} in {int((unreachable > 0).sum())} trials"]
    if "calibration.load_identified" in ok and ok["calibration.load_identified"].notna().any():
        lines.append(f"load identified in {int((ok['calibration.load_identified'] > 0).sum())} "
                     f"of {len(ok)} trials")
    seconds = ok["time.calibration_s"]
    if seconds.notna().any():
        lines.append(f"calibration time: median {seconds.median():.3g} s, "
                     f"largest {seconds.max():.3g} s")
    return "\n".join(lines) + "\n"
