#pragma once
// Predicted accuracy of a calibrated robot, per configuration: how far the identified model's
// platform pose may be from the true one, given what the calibration left uncertain.
//
// - The covariance of the identified parameters (CalibrationResult::covariance, the "covariance"
//   block of the calibration report, read back by read_parameter_covariance).
// - Propagation at a solved configuration: Sigma_pose = J_p Sigma_p J_p^T, J_p = d ^W T_P / d p
//   by the implicit function theorem at that solution (pose_parameter_jacobian: no FK solve).
//   Reported as the 1 sigma and 3 sigma position error (the semi-major axis of the position
//   ellipse) and orientation error.
// - The worst case over the uncertainty intervals (the paper's Section 2.3, sensitivity times
//   half-width, here per configuration and summed over the parameters): the largest first-order
//   pose error of parameters anywhere inside their intervals.
//
// Which pose (PredictedAccuracyOptions::frame):
// - PoseFrame::kPlatform (default): the model's platform pose ^W T_P, in the model's frames. With
//   the calibration's limb-0 gauge (pcr/calib/calibrator.hpp), W and P are those of limb 0's
//   measured clamps, which the covariance holds exactly; the extrinsics do not move ^W T_P and
//   do not enter. This is the uncertainty of the geometry relative to limb 0, and it can be far
//   larger than what a camera sees: the other clamps are known only together with the
//   extrinsics. On the data of `pcr demo --calibration 40 --validation 12 --seed 3`,
//   identified by pcr_calibrate: 4.3 um and 84 urad (1 sigma) for ^W T_P, against 3.3 nm and
//   0.25 urad for the measurement below.
// - PoseFrame::kMeasurement: the pattern pose the camera measures, ^Se T_M = (^W T_Se)^-1 ^W T_P
//   (^M T_P)^-1 (Eq. 5), the extrinsics' covariance included: the quantity the calibration data
//   constrain, invariant under the gauge, and what an accuracy measured with that camera (the
//   paper's Section 6) compares against.
// Either is the error of the model's prediction. A measurement adds its own noise:
// PredictedAccuracyOptions::measurement_covariance, added as is, predicts the scatter of measured
// poses about the model's. The worst case is always of ^W T_P (the paper's Section 2.3).
//
// Cost: one RK4 pass with sensitivities and one LU at the solution, then 3 x p products; about
// 10 us per configuration for the default robot (bench_predicted_accuracy), so a 200 x 200
// workspace grid takes well under a second on top of its FK solves.

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/sensitivity.hpp"

namespace pcr {

/// Covariance of a robot's flat parameters (pcr/parameters.hpp), as a calibration identified them.
struct ParameterCovariance {
  /// parameter_name of each row: the flat parameters of a robot with num_limbs() limbs, in flat
  /// order, then "load_f_x", "load_f_y", "load_m_z" when the calibration identified the platform
  /// load (has_load()).
  std::vector<std::string> names;
  /// SI units (m, rad, Pa, N, N m and their products). Zero rows and columns: held parameters (not
  /// free, or gauge references). NaN rows and columns: not identifiable from the data (but zero
  /// at the held parameters' columns and rows: a held value has no covariance with any).
  Eigen::MatrixXd matrix;

  int num_limbs() const;
  bool has_load() const;
  /// Whether parameter k's variance is known (not NaN).
  bool known(int k) const { return matrix(k, k) == matrix(k, k); }
};

/// The covariance of a calibration result, named by its parameters (empty when the calibration
/// did not compute it).
ParameterCovariance parameter_covariance(const CalibrationResult& result);

/// Reads the "covariance" block of a calibration report (pcr calibrate's REPORT.json, written by
/// calibration_report_json):
///   "covariance": {"parameters": [names], "units": "SI, flat order", "matrix": [[...], ...]}
/// with null for NaN. Throws InputError naming the file, the field and the value when the file
/// has no such block, the matrix is not square or not as large as the names, the names are not
/// the flat parameters of a robot (with `num_limbs` limbs when it is > 0; then optionally the
/// load's), an entry is null (NaN) where neither variance is, or not null where one variance is
/// null and the other parameter is not held (variance 0; its entries must be 0), the matrix is not
/// symmetric beyond rounding (1e-9 of sqrt(C_ii C_jj)), a variance is negative, or the matrix is
/// not positive semi-definite (an eigenvalue of its correlation matrix below -1e-9).
ParameterCovariance read_parameter_covariance(const std::string& report_path, int num_limbs = 0);

/// The same checks on a parsed block: `json_text` is a whole report (or any JSON object with a
/// "covariance" field); `source` names it in messages.
ParameterCovariance parse_parameter_covariance(const std::string& json_text,
                                               const std::string& source, int num_limbs = 0);

/// The checks of read_parameter_covariance on a covariance built in code (names, shape, NaN
/// pattern, symmetry, positive semi-definiteness); `source` names it in messages.
void validate_parameter_covariance(const ParameterCovariance& covariance, const std::string& source,
                                   int num_limbs = 0);

/// How a prediction came out.
enum class PredictionStatus {
  kOk,
  /// The solution did not converge or its Jacobian is singular: nothing is computed (NaN).
  kNoJacobian,
  /// A parameter that moves the pose (a limb parameter, the load when the covariance has it, the
  /// extrinsics in PoseFrame::kMeasurement) has a NaN variance, not identifiable from the
  /// calibration data: the pose covariance is that of the other parameters alone, a lower bound.
  /// The worst case is computed.
  kNotIdentifiable,
  /// The covariance is empty (names and matrix): only the worst case is computed.
  kNoCovariance,
};
const char* to_string(PredictionStatus status);

/// The pose whose error is predicted (see the header comment).
enum class PoseFrame {
  kPlatform,     ///< ^W T_P in the model's frames (limb-0 gauge)
  kMeasurement,  ///< ^Se T_M, the pattern pose in the camera frame, extrinsics included
};

struct PredictedAccuracyOptions {
  PoseFrame frame = PoseFrame::kPlatform;
  /// The constant platform load the solution was solved under (CalibrationResult::load). Its
  /// uncertainty enters when the covariance has the load's rows (has_load()).
  PlatformLoad<double> load;
  /// Covariance of a measurement of the platform pose (x, y, theta: m^2, m rad, rad^2), added to
  /// the model's: zero (the default) predicts the model's pose error alone; the camera's
  /// repeatability, diag(s_p^2, s_p^2, s_theta^2), the scatter of a measured pose about the
  /// model's prediction.
  Eigen::Matrix3d measurement_covariance = Eigen::Matrix3d::Zero();
  /// Half-widths of the flat parameters' uncertainty intervals (parameter_half_widths of the
  /// description's uncertainty), for the worst case; empty: no worst case.
  std::vector<double> half_widths;
  /// Only its settings of the shooting problem's scale are used: the step count is the solution's.
  SolverOptions solver;
};

namespace internal {
inline constexpr double kNotComputed = std::numeric_limits<double>::quiet_NaN();
}

struct PredictedAccuracy {
  PredictionStatus status = PredictionStatus::kNoJacobian;
  bool ok() const { return status == PredictionStatus::kOk; }

  /// Sigma_pose of (x, y, theta) of the pose in options.frame: m^2, m rad, rad^2 (plus the
  /// measurement covariance).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Constant(internal::kNotComputed);
  /// 1 sigma position error (m): sqrt of the largest eigenvalue of the 2 x 2 position block, the
  /// semi-major axis of the 1 sigma ellipse: the standard deviation of the position error along
  /// its worst direction (position_axis). 3 sigma: three times it, which bounds the error along
  /// any one direction at 99.7 %; the 3 sigma ellipse itself holds 98.9 % of a Gaussian error.
  double position_1sigma = internal::kNotComputed, position_3sigma = internal::kNotComputed;
  Eigen::Vector2d position_axis =
      Eigen::Vector2d::Constant(internal::kNotComputed);  ///< unit, the major axis
  /// Orientation error (rad): sqrt(Sigma_theta_theta), and three times it.
  double orientation_1sigma = internal::kNotComputed, orientation_3sigma = internal::kNotComputed;

  /// Worst case over the uncertainty intervals, to first order (NaN without half-widths):
  /// sum_k |d(x, y, theta)/d p_k| h_k (m, m, rad), each component attained by the corner
  /// p_k = nominal_k + sign(d component / d p_k) h_k.
  Eigen::Vector3d worst_components = Eigen::Vector3d::Constant(internal::kNotComputed);
  /// The largest |(dx, dy)| of parameters inside the intervals (m): the farthest vertex of the
  /// zonotope {J_xy dp : |dp_k| <= h_k}, attained by the corner dp_k = sign(u . J_xy,k) h_k with
  /// u = worst_position_direction. At most hypot(worst_components x, y), at least their max.
  double worst_position = internal::kNotComputed;
  Eigen::Vector2d worst_position_direction =
      Eigen::Vector2d::Constant(internal::kNotComputed);  ///< unit
  double worst_orientation = internal::kNotComputed;      ///< rad, worst_components(2)
};

/// Predicted accuracy at `solution`, a converged FK solution of `robot` (the identified model)
/// under options.load: the pose covariance from `covariance` (which may be empty) and, with
/// options.half_widths, the worst case. No FK solve, no heap beyond the result's. Throws
/// InputError when the covariance is not square, not of a robot with robot.num_limbs limbs, or the
/// half-widths are not num_parameters(n) non-negative values; numerical outcomes are the status.
PredictedAccuracy predicted_accuracy(
    const RobotParams<double>& robot, const ForwardSolution& solution,
    const ParameterCovariance& covariance,
    const PredictedAccuracyOptions& options = PredictedAccuracyOptions());

}  // namespace pcr
