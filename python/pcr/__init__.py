"""pcr: planar parallel continuum robots (Mauze et al. 2021) and spatial ones (the continuum
Stewart-Gough robot), Python bindings.

All quantities are SI: metres, radians, newtons, pascals. The C++ library does the work
(``pcr._pcr``); this package re-exports it and adds small pure-Python conveniences
(``Robot.replace``, ``Robot.with_limb``, ``workspace``).
Plots live in ``pcr.plot`` (matplotlib, imported on demand).
"""
from __future__ import annotations

import copy as _copy

import numpy as _np

from ._pcr import (  # noqa: F401
    BatchResult,
    Extrinsics,
    Limb,
    LimbUncertainty,
    Pose,
    Robot,
    Solution,
    SolverOptions,
    SolveStatus,
    SpatialBatchResult,
    SpatialLimb,
    SpatialRobot,
    SpatialSolution,
    Uncertainty,
    __version__,
    compose_poses,
    has_calibration,
)

if has_calibration:
    from ._pcr import (  # noqa: F401
        CalibrationOptions,
        CalibrationResult,
        CalibrationTable,
        GaugeDirection,
        MODEL_SELECTION_T,
        ModelSelection,
        ParameterEstimate,
        PoseErrorStats,
        SpatialModelSelection,
        StageReport,
        VirtualRobot,
        admissible_configuration,
        calibrate,
        calibrate_selecting_model,
        calibrate_spatial,
        calibration_table,
        default_spatial_stages,
        default_stages,
        load_calibration_stages,
        parameter_names,
        platform_parameter_jacobian,
        poisson_disc_sample,
        pose_errors,
        pose_errors_per_configuration,
        read_configurations,
        read_dataset,
        rotation_range,
        sample_configurations,
        sensitivity,
        sensitivity_configurations,
        simulate_spatial_measurements,
        with_load_stage,
        workspace_map,
        write_configurations,
        write_dataset,
    )
    # Trajectories and ISO 9283 accuracy (pcr/trajectory.hpp, pcr/calib/accuracy.hpp).
    from ._pcr import (  # noqa: F401
        PAPER_CIRCLE_DIAMETER,
        PAPER_SQUARE_SIDE,
        AccuracyEvaluation,
        Iso9283Result,
        circle_path,
        command_path,
        evaluate_on_virtual_robot,
        iso9283,
        iso9283_json,
        iso9283_table,
        load_measured_csv,
        load_path_csv,
        measured_to_csv,
        square_path,
    )
    # Predicted accuracy of a calibrated robot (pcr/calib/predicted_accuracy.hpp); also
    # Robot.predicted_accuracy.
    from ._pcr import (  # noqa: F401
        ParameterCovariance,
        read_parameter_covariance,
    )
    # The method as one call on a virtual robot, what pcr demo runs (pcr/calib/method.hpp).
    from ._pcr import (  # noqa: F401
        MethodResult,
        run_method,
    )
    # The same on a virtual spatial robot (pcr/calib/spatial_method.hpp).
    from ._pcr import (  # noqa: F401
        SpatialMethodResult,
        SpatialVirtualRobot,
        run_spatial_method,
    )

from ._pcr import has_vision  # noqa: E402,F401

if has_vision:
    # Measurement from camera images (pcr::vision).
    from ._pcr import (  # noqa: F401
        Camera,
        CameraCalibration,
        MountLayout,
        RobotMeasurement,
        SweepResult,
        calibrate_camera,
        default_mounts,
        load_camera,
        load_mounts,
        measure_robot,
        measure_sweep,
        measured_description,
        mount_tags,
        read_image,
        render_chessboard,
        render_robot,
        write_png,
    )


def _replace(self, **changes):
    """A copy with some attributes changed, e.g. ``robot.replace(name="b", E=70e9)``."""
    out = _copy.copy(self)
    for name, value in changes.items():
        if not hasattr(out, name):
            raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")
        setattr(out, name, value)
    return out


for _cls in (Robot, Limb, Pose, Extrinsics, Uncertainty, LimbUncertainty, SolverOptions,
             SpatialRobot, SpatialLimb) + (
        (CalibrationOptions,) if has_calibration else ()):
    _cls.replace = _replace


def _with_limb(self, index, **changes):
    """A copy of the robot with limb ``index`` changed, e.g. ``robot.with_limb(1, l=0.0301)``."""
    out = self.copy()
    limbs = out.limbs
    if not -len(limbs) <= index < len(limbs):
        raise IndexError(f"limb index {index} out of range for {len(limbs)} limbs")
    for name, value in changes.items():
        if not hasattr(limbs[index], name):
            raise AttributeError(f"Limb has no attribute {name!r}")
        setattr(limbs[index], name, value)
    return out


Robot.with_limb = _with_limb


def _batch(solve, rows_are):
    def batch(self, rows, **solve_args):
        rows = _np.asarray(rows, dtype=float)
        if rows.ndim != 2:
            raise ValueError(f"expected an (N, {rows_are}) array, one row per solve; got shape "
                             f"{rows.shape}")
        return solve(self, rows, **solve_args)

    batch.__doc__ = (f"{solve.__name__}(rows) for an (N, {rows_are}) array, typed: always a "
                     f"BatchResult (a 1-D array is refused rather than solved as one {rows_are}). "
                     f"Keywords as {solve.__name__}.")
    return batch


Robot.forward_batch = _batch(Robot.forward, "n")
Robot.inverse_batch = _batch(Robot.inverse, "3")
SpatialRobot.forward_batch = _batch(SpatialRobot.forward, "n")
SpatialRobot.inverse_batch = _batch(SpatialRobot.inverse, "3")  # positions; orientations by keyword


def workspace(robot, theta=0.0, half_width=None, resolution=41, centre=(0.0, 0.0), **solve_args):
    """The reachable set at a fixed orientation on a (resolution x resolution) grid of positions
    around ``centre`` (m): ``workspace_map`` over that square.

    half_width (m) defaults to 1.3 times the largest actuator stroke. Returns workspace_map's
    dict: ``x``, ``y`` (resolution,) grid axes (m), ``reachable`` (resolution, resolution) bool
    [iy, ix] (an equilibrium within the strokes), ``stable``, ``q`` (resolution, resolution, n)
    joints (m, NaN where IK found no equilibrium), ``max_strain``, ``stability_margin``,
    ``singularity``, ``theta``, the areas.
    """
    if not has_calibration:
        raise RuntimeError("pcr.workspace needs pcr's calibration library (workspace_map), which "
                           "this build of the module lacks")
    if half_width is None:  # the platform can travel a little further than one stroke
        half_width = 1.3 * max(max(abs(l.q_range[0]), abs(l.q_range[1])) for l in robot.limbs)
    if resolution < 2:
        raise ValueError(f"resolution: expected at least 2, got {resolution}")
    span = (centre[0] - half_width, centre[0] + half_width, centre[1] - half_width,
            centre[1] + half_width)
    return workspace_map(robot, theta=theta, grid=resolution, range=span, **solve_args)
