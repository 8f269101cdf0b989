#pragma once
// The paper's method after the measurement of the nominal robot, as one call on a virtual robot
// (Sections 3 to 6): sensitivity -> sampling -> simulated measurements -> staged calibration ->
// validation (Table 3) -> trajectories and ISO 9283 accuracy (Table 4) -> workspace maps. `pcr
// demo` and a study's trial (pcr.study) both run it, so that the method is written once: they
// differ only in how they make the nominal description and the virtual robot, and in what they
// report of the result.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pcr/calib/accuracy.hpp"
#include "pcr/calib/calibration_report.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/calib/virtual_robot.hpp"
#include "pcr/calib/workspace_map.hpp"
#include "pcr/trajectory.hpp"

namespace pcr {

/// The stages of run_method, in the order they run.
enum class MethodStage {
  kSensitivity,   ///< Table 2 of the nominal description (MethodOptions::sensitivity)
  kSampling,      ///< the calibration and validation configurations
  kMeasurement,   ///< the virtual robot measures both sets, each in visiting order
  kCalibration,   ///< the staged identification (MethodOptions::model)
  kValidation,    ///< Table 3 on both sets
  kAccuracy,      ///< the square and the circle with both models (Table 4)
  kWorkspaceMap,  ///< maps of the identified robot (MethodOptions::workspace_map)
};
inline constexpr int kMethodStages = 7;
/// "sensitivity", "sampling", "measurement", "calibration", "validation", "accuracy", "maps".
const char* to_string(MethodStage stage);

/// What the calibration identifies: the options' stages (the paper's by default), those stages
/// with the last also freeing a constant platform load, or the one of the two the validation set
/// supports (calibrate_selecting_model).
enum class CalibratedModel { kStages, kLoad, kSelected };
std::string calibrated_model_name(CalibratedModel model);  ///< "stages", "load", "selected"
/// InputError naming the value unless it is one of calibrated_model_name's.
CalibratedModel parse_calibrated_model(const std::string& name);

struct MethodResult;

struct MethodOptions {
  bool sensitivity = true;  ///< run the sensitivity analysis
  SensitivityOptions sensitivity_options;
  /// The calibration configurations (count, design, seed, ...); the validation set is drawn with
  /// them (sample_configurations).
  SamplingOptions sampling;
  int validation_count = kDefaultValidationCount;
  CalibratedModel model = CalibratedModel::kSelected;
  CalibrationOptions calibration;
  /// The paths commanded with both models; accuracy.command.step.load is the model's own (none
  /// for the nominal, the identified load for the identified), whatever is set here.
  SquarePath square;
  CirclePath circle;
  AccuracyOptions accuracy;
  bool workspace_map = true;  ///< map the identified robot (and its rotation range at the centre)
  /// The map's grid, range and solver; its load and predicted accuracy are the calibration's.
  WorkspaceMapOptions map;
  /// Called as each stage begins, then as it ends with the result so far (may be empty).
  std::function<void(MethodStage)> on_stage_begin;
  std::function<void(MethodStage, const MethodResult&)> on_stage_end;

  static constexpr OptionRange kValidationCount{"validation_count", 1, 100000};
  /// As SolverOptions::is_valid, over every stage's options (named by their fields; the paths'
  /// as "square.num_poses").
  bool is_valid(std::string* error = nullptr) const;
};

/// One path commanded with one model.
struct PathAccuracy {
  std::string path;   ///< "square" or "circle"
  std::string model;  ///< "nominal" (measured geometry, identified extrinsics) or "identified"
  AccuracyEvaluation evaluation;
};

struct MethodResult {
  std::optional<SensitivityReport> sensitivity;
  ConfigurationSets configurations;  ///< as sampled
  /// The configurations the virtual robot measured (it holds a stable equilibrium there), in the
  /// order it visited them, with the measured poses.
  Dataset calibration_data, validation_data;
  int unmeasured = 0;  ///< configurations of either set it did not measure
  /// CalibratedModel::kSelected: both fits and the test; otherwise empty.
  std::optional<ModelSelection> selection;
  CalibrationResult calibration;  ///< the chosen fit
  CalibrationTable table;         ///< its Table 3 on both sets
  RobotDescription identified;    ///< the nominal description with the identified parameters
  /// The virtual robot's truth moved along the gauge the calibration fixed (in_calibration_gauge):
  /// its parameters compare one by one with calibration.parameters.
  RobotParams<double> truth_in_gauge;
  std::vector<PathAccuracy> accuracy;  ///< square then circle, each nominal then identified
  std::optional<WorkspaceMap> map;     ///< at options.map.theta
  RotationRange rotation_range;        ///< at the centre of W (x = y = 0), with map
  std::array<double, kMethodStages> seconds{};  ///< wall time of each stage (0: not run)

  /// The evaluation of `path` with `model`; std::out_of_range when it was not run.
  const AccuracyEvaluation& accuracy_of(const std::string& path, const std::string& model) const;
};

/// Runs the method on `robot` from the nominal description (measured, or the design): the
/// configurations are drawn and the models commanded on `nominal`, the virtual robot moves on its
/// truth. Throws InputError on invalid options, and what a stage throws when it cannot go on (no
/// configuration of a set measured, FK failing in the sensitivity, ...): on_stage_begin names the
/// stage it happened in. A calibration stage that does not converge is not an error: see
/// calibration.stages.
MethodResult run_method(const RobotDescription& nominal, VirtualRobot& robot,
                        const MethodOptions& options = MethodOptions());

}  // namespace pcr
