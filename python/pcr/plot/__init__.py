"""Figures of pcr's results (matplotlib, pure Python), in the style of the paper's.

Every function takes data (CSV paths, DataFrames, arrays or pcr's results) and the robot (or its
name, for the title), draws into ``ax`` or ``fig`` when given (else a new Figure, which pyplot
does not hold), writes it when ``path`` is given (through a temporary file in the same directory
and a rename; never over one of its inputs) and returns the matplotlib Figure. Files are SI;
figures show mm, um (or nm), mrad (or urad), as their labels say.

- ``plot_map``: one quantity of a workspace map (`pcr map`'s CSV, ``pcr.workspace_map``) with the
  workspace border, the unstable and singular regions and the robot's home;
  ``plot_workspace_maps`` four of them; ``plot_workspace`` ``pcr.workspace``'s strain.
- ``plot_calibration_errors``: the paper's Figures 8 and 9.
- ``plot_trajectory_accuracy``: Figures 11 and 12, error vectors magnified by a printed factor;
  ``plot_spatial_path_accuracy`` a spatial robot's path in 3-D, both models.
- ``plot_sensitivity``: Table 2's ranking, the pose error each parameter can cause.
- ``plot_robot``: the rods and the platform in some configurations.
- ``demo_figures`` (``python -m pcr.plot DIR``): all of them for a `pcr demo` output directory.
"""
from __future__ import annotations

try:
    import matplotlib  # noqa: F401
except ModuleNotFoundError as _missing:
    raise ModuleNotFoundError(
        "pcr.plot needs matplotlib, which `pip install ./python` does not bring: "
        "pip install './python[plot]' (or pip install matplotlib)", name="matplotlib") from _missing

from ._accuracy import (plot_calibration_errors, plot_spatial_path_accuracy,  # noqa: E402
                        plot_trajectory_accuracy, read_calibration_errors,
                        read_spatial_trajectory, read_trajectory)
from ._demo import demo_figures, main  # noqa: E402
from ._maps import MAP_QUANTITIES, plot_map, read_map  # noqa: E402
from ._robot import plot_robot, plot_workspace, plot_workspace_maps  # noqa: E402
from ._sensitivity import plot_sensitivity  # noqa: E402

__all__ = ["MAP_QUANTITIES", "demo_figures", "main", "plot_calibration_errors", "plot_map",
           "plot_robot", "plot_sensitivity", "plot_spatial_path_accuracy",
           "plot_trajectory_accuracy", "plot_workspace", "plot_workspace_maps",
           "read_calibration_errors", "read_map", "read_spatial_trajectory", "read_trajectory"]
