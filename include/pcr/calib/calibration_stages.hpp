#pragma once
// The identification's stages (Section 5): which parameters each frees, and their bounds (Eq. 7).

#include <cstddef>
#include <string>
#include <vector>

#include "pcr/robot_description.hpp"

namespace pcr {

struct CalibrationStage {
  std::string name;
  /// Kinds: a per-limb kind of kParameterKinds ("E", "d", "l", "A_x", "A_y", "alpha", "B_x",
  /// "B_y", "beta", "gamma", "precurvature"), "A", "B", "camera", "pattern", "extrinsics", "all"
  /// (the geometry and extrinsics), "load" (the constant platform load, kLoadParameters values;
  /// not in "all"). A spatial robot's stages take the spatial kinds (validate_spatial_stages,
  /// pcr/calib/spatial_calibrator.hpp), "load" among them (kSpatialLoadParameters values).
  std::vector<std::string> free;
  double bounds_scale = 1.0;
};

/// The paper's three stages.
std::vector<CalibrationStage> default_stages();

/// Whether a stage frees "load" (the calibration, planar or spatial, then identifies a constant
/// platform load).
bool frees_load(const std::vector<CalibrationStage>& stages);

/// The load model: `stages` with their last stage also freeing "load" (unchanged when a stage
/// frees it already).
std::vector<CalibrationStage> with_load_stage(std::vector<CalibrationStage> stages);

/// Throws InputError naming `source` on an unknown kind or a non-positive bounds scale.
void validate_stages(const std::vector<CalibrationStage>& stages, const std::string& source);

/// The number of parameters `stage` frees on `nominal` (which has an uncertainty section): those
/// its kinds name with a non-zero half-width (the others are held), and the platform load's three
/// for "load".
int free_parameter_count(const CalibrationStage& stage, const RobotDescription& nominal);

/// Throws InputError, naming `source`, when `rows` configurations give fewer measured values
/// (3 each) than a stage has free parameters: its least squares would be underdetermined whatever
/// the data. calibrate() checks it; a front-end may check it first to name its file.
void check_enough_measurements(const std::vector<CalibrationStage>& stages,
                               const RobotDescription& nominal, std::size_t rows,
                               const std::string& source);

/// Reads a stages file: {"stages": [{"name": ..., "free": [kinds], "bounds_scale": 1}, ...]} or
/// the bare list. Throws InputError naming the file, the field and the value.
std::vector<CalibrationStage> load_calibration_stages(const std::string& path);
/// The same file for a spatial robot: its kinds are the spatial ones (validate_spatial_stages,
/// pcr/calib/spatial_calibrator.hpp).
std::vector<CalibrationStage> load_spatial_calibration_stages(const std::string& path);

/// The flat half-widths of `uncertainty` for a robot with `num_limbs` limbs.
std::vector<double> parameter_half_widths(const RobotUncertainty& uncertainty, int num_limbs);

}  // namespace pcr
