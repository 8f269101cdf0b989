#pragma once
// Sensitivity analysis of a spatial robot: the paper's Table 2 (Section 2.3) in 3-D, the spatial
// counterpart of pcr/calib/sensitivity.hpp.
//
// Configurations: the 3^n grid of joint values around `centre` with a step of `step` (default
// 1 mm), minus its centre: 728 FK solves for six rods (about 3.5 ms each with its derivative on
// the reference robot, 2.5 s in all; no smaller design needed).
// Derivatives: exact, by the implicit function theorem (spatial_measurement_jacobian), of a pose
// with respect to each flat deviation of pcr/spatial/parameters.hpp. Which pose:
// - kPlatform (default): the platform pose ^W T_P itself, the robot's own sensitivity as the
//   paper's Table 2 (the extrinsics do not move the platform: their rows are left out). Computed
//   as the measured pose of the description with identity extrinsics, where ^S T_M = ^W T_P.
// - kMeasured: the marker pose ^S T_M the measuring system reports (position in S), the extrinsic
//   kinds (tracker_*, marker_*) as rows too: what a calibration from those measurements sees.
//   The marker's offset from P turns every rotation of the platform into a motion of the
//   measured position as well.
// Rows: the 16 per-rod kinds of kSpatialParameterKinds (E, G, d, l, A_x ... tip_rz), each the max
// over the rods (one rod's parameter at a time: the spatial description has no shared E or d),
// then with kMeasured the 12 extrinsic kinds. Values per row, max over configurations (and rods):
// |dx/dp|, |dy/dp|, |dz/dp| (position components), |dpos/dp| (its norm) and |dphi/dp| (the norm of
// the rotation vector's derivative: the angle per unit of p). Ranking: position error = max of
// |dpos/dp| h_p over configurations and rods, h_p the parameter's half-width (the rod's own),
// orientation error = max |dphi/dp| h_p; sorted by position error (ties: orientation error).

#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/option_range.hpp"
#include "pcr/solver.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace pcr {

/// The joint range of a spatial robot where none is given (its description has no strokes): each
/// rod pushed out by 0 to 10 mm from its length at q = 0 (the reference robot's rods are 0.4 m).
inline constexpr double kSpatialDefaultJointMin = 0.0;    ///< m
inline constexpr double kSpatialDefaultJointMax = 10e-3;  ///< m

/// Which pose the spatial sensitivity differentiates (see above).
enum class SpatialSensitivityPose { kPlatform, kMeasured };

struct SpatialSensitivityOptions {
  double step = 1e-3;  ///< m, grid step around the centre
  /// m; empty: the middle of the default joint range (kSpatialDefaultJointMin, ...Max) per rod.
  SpatialJointVector centre;
  SpatialSensitivityPose pose = SpatialSensitivityPose::kPlatform;
  SolverOptions solver = [] {
    SolverOptions options;
    options.check_stability = false;  // the derivatives do not need it
    return options;
  }();

  /// As the planar SensitivityOptions::kStep.
  static constexpr OptionRange kStep{"step", 1e-6, 0.01, "m"};
  /// Each joint of the centre: beyond a metre, a unit typo (mm typed as m).
  static constexpr OptionRange kCentre{"centre", -1, 1, "m"};
  bool is_valid(std::string* error = nullptr) const {
    if (!kStep.check(step, error)) return false;
    for (Eigen::Index i = 0; i < centre.size(); ++i) {
      if (!kCentre.check(centre(i), error)) return false;
    }
    return solver.is_valid(error);
  }
};

struct SpatialSensitivityRow {
  std::string kind;  ///< a name of kSpatialParameterKinds: "E", "A_x", "tracker_rz" ...
  double dx = 0, dy = 0, dz = 0;  ///< max |d position component / d p| (m per unit of p)
  double dposition = 0;           ///< max |d position / d p| (norm)
  double dangle = 0;              ///< max |d rotation vector / d p| (rad per unit of p)
  double half_width = 0;          ///< the largest half-width of this kind over the rods (SI)
  double position_error = 0;      ///< m, max |d position / d p| h
  double orientation_error = 0;   ///< rad, max |d rotation vector / d p| h
};

struct SpatialSensitivityReport {
  double step = 0;
  SpatialSensitivityPose pose = SpatialSensitivityPose::kPlatform;
  std::vector<SpatialJointVector> configurations;
  std::vector<SpatialSensitivityRow> rows;  ///< kSpatialParameterKinds order
  std::vector<int> ranking;                 ///< indices into rows, most influential first
  double time_s = 0;                        ///< wall time of the FK solves and derivatives
};

/// The 3^n grid around `centre` (empty: the default range's middle) minus its centre. Throws
/// InputError on a step outside kStep or a centre of another size than the rods.
std::vector<SpatialJointVector> spatial_sensitivity_configurations(
    int num_rods, double step, const SpatialJointVector& centre);

/// d pose / d (flat deviations) at q (6 rows: position in m, rotation vector in rad;
/// num_spatial_parameters columns, SI units) for `pose`: spatial_measurement_jacobian at the
/// nominal description (kPlatform: with identity extrinsics). False when FK does not converge.
bool spatial_pose_parameter_jacobian(const SpatialRobotDescription& robot,
                                     const SpatialJointVector& q, SpatialSensitivityPose pose,
                                     Eigen::MatrixXd* jacobian,
                                     const SolverOptions& solver = SolverOptions());

/// The table (see above). Throws InputError on bad options (naming the field), std::runtime_error
/// naming the configuration when FK fails.
SpatialSensitivityReport spatial_sensitivity(
    const SpatialRobotDescription& robot,
    const SpatialSensitivityOptions& options = SpatialSensitivityOptions());

std::string spatial_sensitivity_table_text(const SpatialSensitivityReport& report);
std::string spatial_sensitivity_csv(const SpatialSensitivityReport& report);
std::string spatial_sensitivity_json(const SpatialSensitivityReport& report);

}  // namespace pcr
