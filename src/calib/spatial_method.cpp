// The paper's method on a virtual spatial robot, as one call (see pcr/calib/spatial_method.hpp).
#include "pcr/calib/spatial_method.hpp"

#include <stdexcept>
#include <utility>

#include "method_internal.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace pcr {

bool SpatialMethodOptions::is_valid(std::string* error) const {
  return (!sensitivity || sensitivity_options.is_valid(error)) && sampling.is_valid(error) &&
         MethodOptions::kValidationCount.check(validation_count, error) &&
         calibration.is_valid(error) && square.is_valid(error, "square.") &&
         circle.is_valid(error, "circle.") && helix.is_valid(error, "helix.") &&
         accuracy.is_valid(error);
}

const SpatialAccuracyEvaluation& SpatialMethodResult::accuracy_of(const std::string& path,
                                                                  const std::string& model) const {
  for (const SpatialPathAccuracy& a : accuracy) {
    if (a.path == path && a.model == model) return a.evaluation;
  }
  throw std::out_of_range("run_spatial_method: no accuracy of the " + path + " with the " + model +
                          " model");
}

SpatialMethodResult run_spatial_method(const SpatialRobotDescription& nominal,
                                       SpatialVirtualRobot& robot,
                                       const SpatialMethodOptions& options) {
  require_valid(options, "run_spatial_method");
  SpatialMethodResult result;
  calib_internal::StageRunner<SpatialMethodOptions, SpatialMethodResult> stage(options, result);
  const int n = nominal.params.num_rods;

  if (options.sensitivity) {
    stage.run(MethodStage::kSensitivity, [&] {
      result.sensitivity = spatial_sensitivity(nominal, options.sensitivity_options);
    });
  }

  stage.run(MethodStage::kSampling, [&] {
    result.configurations =
        spatial_sample_configurations(nominal, options.sampling, options.validation_count);
  });

  stage.run(MethodStage::kMeasurement, [&] {
    result.calibration_data = calib_internal::measured_rows<SpatialDataset>(
        robot, result.configurations.calibration, n, "calibration", &result.unmeasured);
    result.validation_data = calib_internal::measured_rows<SpatialDataset>(
        robot, result.configurations.validation, n, "validation", &result.unmeasured);
  });

  stage.run(MethodStage::kCalibration, [&] {
    if (options.model == CalibratedModel::kSelected) {
      result.selection = calibrate_selecting_model(nominal, result.calibration_data,
                                                   result.validation_data, options.calibration);
      result.calibration = result.selection->chosen();
    } else {
      SpatialCalibrationOptions o = options.calibration;
      if (options.model == CalibratedModel::kLoad) o.stages = with_load_stage(o.stages);
      result.calibration = calibrate_spatial(nominal, result.calibration_data, o);
    }
    result.identified = nominal;
    result.identified.params = result.calibration.identified;
  });

  stage.run(MethodStage::kValidation, [&] {
    // The selection tabulated both fits on both sets already.
    result.table = result.selection
                       ? result.selection->chosen_table()
                       : spatial_calibration_table(result.calibration, result.calibration_data,
                                                   result.validation_data, options.calibration.fk);
  });

  stage.run(MethodStage::kAccuracy, [&] {
    // The paths about the nominal robot's platform at the middle of the sampling box.
    const SpatialSamplingResult& box = result.configurations.spread.configurations.empty()
                                           ? result.configurations.candidates
                                           : result.configurations.spread;
    const SpatialJointVector middle = 0.5 * (box.box_min + box.box_max);
    const SpatialForwardSolution at_middle =
        spatial_forward_kinematics(nominal.params, middle, options.accuracy.command.solver);
    if (!is_equilibrium(at_middle.summary)) {
      throw std::runtime_error(
          "the nominal robot has no equilibrium at the middle of the joint "
          "box, the paths' centre (" +
          std::string(to_string(at_middle.summary.status)) + ")");
    }
    result.centre = at_middle.pose;
    const auto about_centre = [&](std::vector<SpatialPose<double>> path) {
      for (SpatialPose<double>& pose : path) pose = result.centre * pose;
      return path;
    };
    const std::pair<const char*, std::vector<SpatialPose<double>>> paths[] = {
        {"square", about_centre(spatial_square_path(options.square))},
        {"circle", about_centre(spatial_circle_path(options.circle))},
        {"helix", about_centre(spatial_helix_path(options.helix))}};
    for (const bool identified : {false, true}) {
      const SpatialRobotParams<double>& model =
          identified ? result.calibration.identified : result.calibration.extrinsics_only;
      // Each model's IK starts from its equilibrium at the middle of the box, continued from the
      // nominal robot's there: the cold start does not solve every robot.
      SpatialAccuracyOptions o = options.accuracy;
      o.command.start = spatial_forward_kinematics(model, middle, at_middle, o.command.solver);
      if (!is_equilibrium(o.command.start->summary)) o.command.start.reset();
      for (const auto& [path_name, path] : paths) {
        result.accuracy.push_back({path_name, identified ? "identified" : "nominal",
                                   evaluate_on_spatial_virtual_robot(model, robot, path, o)});
      }
    }
  });
  return result;
}

}  // namespace pcr
