// The paper's method as one call on a virtual robot (see pcr/calib/method.hpp).
#include "pcr/calib/method.hpp"

#include <stdexcept>
#include <utility>

#include "method_internal.hpp"
#include "pcr/calib/predicted_accuracy.hpp"

namespace pcr {
namespace {

constexpr const char* kStageNames[kMethodStages] = {
    "sensitivity", "sampling", "measurement", "calibration", "validation", "accuracy", "maps"};

using StageRunner = calib_internal::StageRunner<MethodOptions, MethodResult>;

/// The rows the virtual robot measured, visited in the order an experiment would take them.
Dataset measured_rows(VirtualRobot& robot, const std::vector<JointVector>& configurations,
                      const char* set, int* unmeasured) {
  return calib_internal::measured_rows<Dataset>(robot, configurations,
                                                robot.nominal().params.num_limbs, set, unmeasured);
}

}  // namespace

const char* to_string(MethodStage stage) { return kStageNames[static_cast<int>(stage)]; }

std::string calibrated_model_name(CalibratedModel model) {
  switch (model) {
    case CalibratedModel::kStages:
      return "stages";
    case CalibratedModel::kLoad:
      return "load";
    case CalibratedModel::kSelected:
      return "selected";
  }
  return "?";
}

CalibratedModel parse_calibrated_model(const std::string& name) {
  for (CalibratedModel m :
       {CalibratedModel::kStages, CalibratedModel::kLoad, CalibratedModel::kSelected}) {
    if (calibrated_model_name(m) == name) return m;
  }
  throw InputError("model: expected 'stages', 'load' or 'selected', got '" + name + "'");
}

bool MethodOptions::is_valid(std::string* error) const {
  return (!sensitivity || sensitivity_options.is_valid(error)) && sampling.is_valid(error) &&
         kValidationCount.check(validation_count, error) && calibration.is_valid(error) &&
         square.is_valid(error, "square.") && circle.is_valid(error, "circle.") &&
         accuracy.is_valid(error) && (!workspace_map || map.is_valid(error));
}

const AccuracyEvaluation& MethodResult::accuracy_of(const std::string& path,
                                                    const std::string& model) const {
  for (const PathAccuracy& a : accuracy) {
    if (a.path == path && a.model == model) return a.evaluation;
  }
  throw std::out_of_range("run_method: no accuracy of the " + path + " with the " + model +
                          " model");
}

MethodResult run_method(const RobotDescription& nominal, VirtualRobot& robot,
                        const MethodOptions& options) {
  require_valid(options, "run_method");
  MethodResult result;
  StageRunner stage(options, result);

  if (options.sensitivity) {
    stage.run(MethodStage::kSensitivity, [&] {
      result.sensitivity = sensitivity_analysis(nominal, options.sensitivity_options);
    });
  }

  stage.run(MethodStage::kSampling, [&] {
    result.configurations =
        sample_configurations(nominal, options.sampling, options.validation_count);
  });

  stage.run(MethodStage::kMeasurement, [&] {
    result.calibration_data =
        measured_rows(robot, result.configurations.calibration, "calibration", &result.unmeasured);
    result.validation_data =
        measured_rows(robot, result.configurations.validation, "validation", &result.unmeasured);
  });

  const std::vector<CalibrationSample> calibration = calibration_samples(result.calibration_data);
  const std::vector<CalibrationSample> validation = calibration_samples(result.validation_data);
  stage.run(MethodStage::kCalibration, [&] {
    if (options.model == CalibratedModel::kSelected) {
      result.selection =
          calibrate_selecting_model(nominal, calibration, validation, options.calibration);
      result.calibration = result.selection->chosen();
    } else {
      CalibrationOptions o = options.calibration;
      if (options.model == CalibratedModel::kLoad) o.stages = with_load_stage(o.stages);
      result.calibration = calibrate(nominal, calibration, o);
    }
    result.identified = nominal;
    result.identified.params = result.calibration.identified;
    result.truth_in_gauge =
        in_calibration_gauge(result.calibration, nominal.params, robot.truth().params);
  });

  stage.run(MethodStage::kValidation, [&] {
    // The selection tabulated both fits on both sets already.
    result.table = result.selection
                       ? result.selection->chosen_table()
                       : calibration_table(result.calibration, calibration, validation);
  });

  stage.run(MethodStage::kAccuracy, [&] {
    const std::pair<const char*, std::vector<Pose2<double>>> paths[] = {
        {"square", square_path(options.square)}, {"circle", circle_path(options.circle)}};
    for (const auto& [path_name, path] : paths) {
      for (const bool identified : {false, true}) {
        // Each model commands under the load it knows of: the identified one under its
        // identified load (none unless the load model was fitted), the nominal under none.
        AccuracyOptions o = options.accuracy;
        o.command.step.load = identified ? result.calibration.load : PlatformLoad<double>();
        const RobotParams<double>& model =
            identified ? result.calibration.identified : result.calibration.extrinsics_only;
        result.accuracy.push_back({path_name, identified ? "identified" : "nominal",
                                   evaluate_on_virtual_robot(model, robot, path, o)});
      }
    }
  });

  if (options.workspace_map) {
    stage.run(MethodStage::kWorkspaceMap, [&] {
      // The calibration's covariance predicts each point's error as the camera would measure it.
      WorkspaceMapOptions o = options.map;
      PredictedAccuracyOptions accuracy;
      accuracy.frame = PoseFrame::kMeasurement;
      accuracy.load = result.calibration.load;
      o.load = result.calibration.load;
      o.accuracy = predicted_accuracy_of_points(result.identified.params,
                                                parameter_covariance(result.calibration), accuracy);
      result.map = workspace_map(result.identified.params, o);
      result.rotation_range =
          rotation_range(result.identified.params, 0.0, 0.0, o.theta, o.solver, o.load);
    });
  }
  return result;
}

}  // namespace pcr
