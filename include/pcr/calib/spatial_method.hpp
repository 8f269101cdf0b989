#pragma once
// The paper's method on a virtual spatial robot, as one call (Sections 3 to 6 in 3-D), the
// spatial counterpart of pcr/calib/method.hpp and its stages: Table 2 (spatial_sensitivity) ->
// configurations (spatial_sample_configurations) -> simulated measurements -> staged
// identification (calibrate_spatial) -> Table 3 on both sets -> a square, a circle and a helix
// commanded with the nominal and the identified models and attained on the virtual robot, ISO
// 9283 in 3-D (Table 4). `pcr demo --robot FILE` runs it for a spatial robot file.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pcr/calib/method.hpp"  // MethodStage
#include "pcr/calib/spatial_accuracy.hpp"
#include "pcr/calib/spatial_calibration_report.hpp"
#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/calib/spatial_sampling.hpp"
#include "pcr/calib/spatial_sensitivity.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"

namespace pcr {

struct SpatialMethodResult;

struct SpatialMethodOptions {
  bool sensitivity = true;  ///< Table 2 of the nominal description
  SpatialSensitivityOptions sensitivity_options;
  /// The calibration configurations; the validation set is drawn with them.
  SpatialSamplingOptions sampling;
  int validation_count = kDefaultValidationCount;
  /// What the calibration identifies (the planar MethodOptions::model): the stages, the stages
  /// with the platform load ("load"), or the one of the two the validation set supports
  /// (calibrate_selecting_model). The stages by default: a spatial calibration takes seconds, and
  /// the selection may run it twice.
  CalibratedModel model = CalibratedModel::kStages;
  SpatialCalibrationOptions calibration;
  /// The paths, their centre and orientation relative to the centre pose: the nominal robot's
  /// platform pose ^W T_P at the middle of the sampling box (a path given about W's origin runs
  /// about where the robot works).
  SpatialSquarePath square;
  SpatialCirclePath circle;
  SpatialHelixPath helix;
  SpatialAccuracyOptions accuracy;
  /// Called as each stage begins, then as it ends with the result so far.
  std::function<void(MethodStage)> on_stage_begin;
  std::function<void(MethodStage, const SpatialMethodResult&)> on_stage_end;

  /// As SolverOptions::is_valid, over every stage's options (the paths' as "square.side").
  bool is_valid(std::string* error = nullptr) const;
};

/// One path commanded with one model.
struct SpatialPathAccuracy {
  std::string path;   ///< "square", "circle" or "helix"
  std::string model;  ///< "nominal" (its geometry, identified extrinsics) or "identified"
  SpatialAccuracyEvaluation evaluation;
};

struct SpatialMethodResult {
  std::optional<SpatialSensitivityReport> sensitivity;
  SpatialConfigurationSets configurations;  ///< as sampled
  /// The configurations the virtual robot measured, in the order it visited them.
  SpatialDataset calibration_data, validation_data;
  int unmeasured = 0;  ///< configurations of either set it did not measure
  SpatialCalibrationResult calibration;
  /// The selection (model "selected"): both fits and the decision; `calibration` is the chosen.
  std::optional<SpatialModelSelection> selection;
  SpatialCalibrationTable table;       ///< Table 3 on both sets
  SpatialRobotDescription identified;  ///< the nominal description with the identified parameters
  SpatialPose<double> centre;          ///< the paths' centre pose (see SpatialMethodOptions)
  /// The nominal model's square, circle and helix, then the identified model's.
  std::vector<SpatialPathAccuracy> accuracy;
  std::array<double, kMethodStages> seconds{};  ///< wall time of each stage (0: not run)

  /// The evaluation of `path` with `model`; std::out_of_range when it was not run.
  const SpatialAccuracyEvaluation& accuracy_of(const std::string& path,
                                               const std::string& model) const;
};

/// Runs the method on `robot` from the nominal description (with an uncertainty section): the
/// configurations are drawn and the models command on `nominal`, the virtual robot moves on its
/// truth. Throws InputError on invalid options, and what a stage throws when it cannot go on;
/// on_stage_begin names the stage it happened in.
SpatialMethodResult run_spatial_method(const SpatialRobotDescription& nominal,
                                       SpatialVirtualRobot& robot,
                                       const SpatialMethodOptions& options = {});

}  // namespace pcr
