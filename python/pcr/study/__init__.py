"""Design and tolerance studies: Monte Carlo over virtual robots, run on Dask.

A study is a table of trials. Each trial draws a virtual robot from its factors (tolerances,
camera noise, number and choice of calibration configurations, unmodelled effects, the design)
and its seed, runs the whole method on it (sample, measure, calibrate in three stages, validate,
evaluate the square and the circle by ISO 9283) and gives one row of outcomes, named as in pcr's
JSON report, in SI units. A spatial robot file runs the spatial method (its Table 3, the square,
the circle and the helix in 3-D).

    import pcr.study
    table = pcr.study.run("tolerance", "tolerance-results")   # a pandas DataFrame
    pcr.study.plot("tolerance-results")

Built-in studies: ``builtin_studies()`` (TOML files in pcr/study/studies). The console command
``pcr-study run|plot|summary|list`` does the same. Needs the [study] extra: pip install './python[study]'.
"""
from __future__ import annotations

try:
    import distributed as _distributed  # noqa: F401
    import pandas as _pandas  # noqa: F401
    import pyarrow as _pyarrow  # noqa: F401
except ModuleNotFoundError as _missing:
    raise ModuleNotFoundError(
        f"pcr.study needs {_missing.name}, which `pip install ./python` does not bring: "
        "pip install './python[study]' (dask, distributed, pandas, pyarrow)",
        name=_missing.name) from _missing

from ._definition import Study, Trial, builtin_studies  # noqa: E402
from ._run import Progress, run  # noqa: E402
from ._store import read_results, read_study  # noqa: E402
from ._trial import FACTORS, outcome_columns, run_trial, spatial_outcome_columns  # noqa: E402

__all__ = ["FACTORS", "Progress", "Study", "Trial", "builtin_studies", "outcome_columns",
           "plot", "read_results", "read_study", "run", "run_trial", "sensitivity",
           "spatial_outcome_columns", "summary"]


def plot(directory, output=None, outcomes=None):
    """Plots of a study's results (matplotlib); see ``pcr.study._plot.plot``."""
    from ._plot import plot as _plot

    return _plot(directory, output, outcomes)


def sensitivity(table, outcome, factors):
    """The share of the variance of log10(outcome) each factor explains; see
    ``pcr.study._plot.sensitivity``."""
    from ._plot import sensitivity as _sensitivity

    return _sensitivity(table, outcome, factors)


def summary(directory):
    """The headline of a study's results in Markdown; see ``pcr.study._summary.summary``."""
    from ._summary import summary as _summary

    return _summary(directory)
