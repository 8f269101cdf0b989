#pragma once
// Staged, bounded identification of a spatial robot from measured 6-D poses (Mauze et al. 2021,
// Section 5, in 3-D), with Ceres: the spatial counterpart of pcr/calib/calibrator.hpp.
//
// - Residuals: one block of six per configuration (Eq. 6 in 3-D), whitened by residual_scale:
//     [p_hat - p, w log(R^T R_hat)] / residual_scale
//   where (p_hat, R_hat) is the predicted marker pose ^S T_M = (^W T_S)^-1 FK(q) (^M T_P)^-1,
//   (p, R) the measured one and w the orientation weight (m/rad): position error plus a weighted
//   rotation angle, each component O(1) at the noise floor. Huber loss on each configuration's
//   whitened residual norm beyond its Huber scale, and outliers, as the planar calibration's
//   (one rule, src/calib/outlier_rule.hpp): each stage's Huber scale is robust_scale noise units,
//   or as many times the rows' median residual (over its value at the noise, 2.313 for six
//   whitened values) while the model is far from the data, and the stage is solved again while
//   that scale halves; a row beyond 100 times it at the stage's start (a measurement millimetres
//   off) is left out of the stage. At the result, the rows beyond the Huber scale are outliers:
//   named (SpatialCalibrationResult::outliers), and the rank, residual variance and covariance
//   are the other rows'. Measured on 60 rows of a hidden robot with 3 rows 1 mm off: the three
//   named, the validation rms against the truth as without them (docs/calibration.md).
// - Unknowns: the flat deviations of pcr/spatial/parameters.hpp, in half-width units (all O(1)
//   for Levenberg-Marquardt). A stage frees the kinds it names with a nonzero half-width; the
//   others are held. A free geometric or material parameter stays within bounds_scale
//   half-widths of its nominal value; the extrinsics carry no bounds (a result outside their
//   interval is a warning).
// - Derivatives are exact for the discrete model: FK converged in double (continued from the
//   configuration's last solution), then the implicit function theorem, d pose / d p =
//   -(dF/dz)^-1 dF/dp, where dF/dz is the shooting Jacobian at the solution and dF/dp comes rod by
//   rod from one pass of the rod's RK4 steps in ceres::Jet (its 16 parameters at once), the other
//   rods' tips held; the extrinsics and the pose enter the measurement through a Jet of 18. The
//   stages' iterations take the rods' Jets over a quarter of the RK4 steps (the derivative to
//   ~1e-7, relative: Levenberg-Marquardt's steps need no more, and the residuals stay exact);
//   the result's rank and uncertainty take the exact derivative.
// - Gauge: the directions no data can see (with gravity: a translation of the base with the
//   tracker, and a turn of both about the gravity axis; each rod's base and tip twisted
//   together; more without a load on the rods), and those the data see too little to place
//   within their intervals, are found at each stage's start: the right singular vectors of the
//   whitened Jacobian, in half-width units on the stage's free parameters, whose singular values
//   lie below one noise unit per half-width (or kRankThreshold of the largest). Each step is
//   restricted to their complement, so that they stay where the stage starts (the nominal
//   values, to first order), and Levenberg's damping is the same in every direction of
//   half-width units. The combinations the data cannot identify are named in the result.
// - Bounds (Eq. 7), by an active set: each stage solves without bounds, then holds every
//   geometric or material parameter past bounds_scale half-widths at its bound and solves the
//   others again, for up to four rounds.
// - Uncertainty: the pseudo-inverse of J^T J on the free parameters, from the SVD of the whitened
//   Jacobian at the result (the exact derivative), scaled by the residual variance (sum of
//   squares / (6 m - rank)): the standard deviations and the covariance, as the planar
//   calibration's. Computed only from a Jacobian that evaluated and is finite (Ceres' own
//   covariance crashes after a failed evaluation).
// - Platform load: a stage that frees "load" identifies a constant wrench on the platform (force
//   and moment in W, kSpatialLoadParameters values after the flat ones; a payload, a cable) with
//   the geometry, which would otherwise absorb it as far as its bounds allow. It is added to the
//   identified robot's external_force and external_moment, so that every prediction of
//   `identified` is made under it. Unbounded, as the planar load; its scale (the half-width of
//   its whitening) is, per component, the load that moves the nominal platform over the rows
//   (root mean square, Eq. 6's metric) as far as a clamp's position tolerance does (the mean
//   half-width of A and B). Not part of "all".

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pcr/calib/calibration_stages.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/solver.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace pcr {

/// The spatial stages' kinds: a per-rod kind of kSpatialParameterKinds ("E", "G", "d", "l",
/// "A_x", ..., "tip_rz"), a group ("A", "B", "base_rotation", "tip_rotation", "tracker",
/// "marker", "extrinsics"), "all" (every flat parameter), or "load" (the constant platform wrench,
/// kSpatialLoadParameters values; not in "all"). with_load_stage and frees_load
/// (pcr/calib/calibration_stages.hpp) apply to these stages too.
std::vector<CalibrationStage> default_spatial_stages();

/// Throws InputError naming `source` on an unknown kind or a non-positive bounds scale.
void validate_spatial_stages(const std::vector<CalibrationStage>& stages,
                             const std::string& source);

struct SpatialCalibrationOptions {
  std::vector<CalibrationStage> stages = default_spatial_stages();
  /// w of Eq. 6 (m/rad); NaN: residual_scale / 1.2e-6 rad, the ratio of the declared noises.
  double orientation_weight = std::numeric_limits<double>::quiet_NaN();
  /// Whitening of the residuals (m); NaN: spatial_default_noise_position of the nominal robot.
  double residual_scale = std::numeric_limits<double>::quiet_NaN();
  /// FK of every evaluation, to the Newton tolerance (chord_output_share 0) so that residuals are
  /// smooth in the parameters.
  SolverOptions fk = [] {
    SolverOptions options;
    options.chord_output_share = 0.0;
    options.check_stability = false;
    return options;
  }();
  int max_iterations = 100;          ///< per stage
  double function_tolerance = 1e-8;  ///< a stage stops below this relative decrease of the cost
  double robust_scale = 5.0;         ///< Huber loss beyond this many noise units; 0: none
  bool compute_covariance = true;
  /// Rows without an equilibrium on the nominal robot are left out (and listed in
  /// SpatialCalibrationResult::dropped, with a warning) instead of being an InputError.
  bool drop_unreachable = false;
  /// Progress lines (stage, iteration, cost); empty: silent.
  std::function<void(const std::string&)> progress;

  static constexpr OptionRange kMaxIterations{"max_iterations", 1, 100000};
  static constexpr OptionRange kFunctionTolerance{"function_tolerance", 0, 1};
  static constexpr OptionRange kRobustScale{"robust_scale", 0, 1e6};
  bool is_valid(std::string* error = nullptr) const;
};

struct SpatialStageReport {
  std::string name;
  std::vector<std::string> free_parameters;
  /// Directions held in its last round: the gauge and those not seen within their intervals
  /// (see the header).
  int unseen_directions = 0;
  double initial_cost = 0;  ///< 1/2 sum of the whitened squared residuals
  double final_cost = 0;
  int iterations = 0;
  double time_s = 0;
  std::string termination;  ///< Ceres' brief report
  bool usable = false;
};

struct SpatialParameterEstimate {
  std::string name;  ///< "l[1]", "tracker_rz" ...
  SpatialParameterId id{SpatialParameterKind::kLength, 0};
  double deviation = 0;  ///< identified, from the nominal value (SI, rad for a turn)
  double std_dev = 0;    ///< 0 when not free; NaN when not identifiable or not computed
  double half_width = 0;
  bool free = false;         ///< free in the last stage
  bool at_bound = false;     ///< held by its bound at the end
  bool identifiable = true;  ///< no share >= 0.1 in a direction the data cannot see
};

struct SpatialCalibrationResult {
  SpatialRobotParams<double> identified;  ///< the nominal robot moved by the deviations
  /// The nominal geometry with its extrinsics alone identified (the first stage's result when it
  /// frees the extrinsics alone, else a fit of its own): the nominal model of Tables 3 and 4, as
  /// the planar CalibrationResult::extrinsics_only.
  SpatialRobotParams<double> extrinsics_only;
  std::vector<SpatialStageReport> stages;
  /// Every flat parameter, in flat order, then the load's six (load_f_x, _y, _z in N, load_m_x,
  /// _y, _z in N m; deviation: the identified value) when a stage frees "load".
  std::vector<SpatialParameterEstimate> parameters;
  /// The identified constant platform load (in W; the moment about the platform origin), zero
  /// unless a stage frees "load"; `identified` carries it in external_force and external_moment
  /// (added to the nominal robot's).
  Eigen::Vector3d load_force = Eigen::Vector3d::Zero();
  Eigen::Vector3d load_moment = Eigen::Vector3d::Zero();
  bool load_identified = false;
  double orientation_weight = 0;  ///< resolved (m/rad)
  double residual_scale = 0;      ///< resolved (m)
  int free_count = 0;             ///< free parameters of the last stage
  int jacobian_rank = 0;          ///< numerical rank of the whitened Jacobian on them
  /// The combinations the data cannot identify (gauge directions included), in half-width
  /// units, in words ("+0.41 A_x[0] +0.41 A_x[1] ... +0.41 tracker_x").
  std::vector<std::string> unidentifiable;
  /// Of the whitened residuals at the result, outliers left out: ~1 at the noise floor.
  double residual_variance = std::numeric_limits<double>::quiet_NaN();
  /// The residual test (the planar CalibrationResult::residuals_exceed_noise): residual_variance
  /// lies more than 5 standard deviations of its chi-square estimate (6 rows - rank degrees of
  /// freedom, outliers left out) above 1: an unmodelled effect (a payload), outliers, wrong
  /// extrinsics or more noise than declared (one of `warnings` says so).
  bool residuals_exceed_noise = false;
  /// Rows left out (drop_unreachable): origin, joints and the nominal FK status.
  std::vector<std::string> dropped;
  /// Rows whose whitened residual norm at the result exceeds outlier_threshold: origin ("line
  /// 12", or "row 3" of a dataset without line numbers) and norm. The rank, residual variance
  /// and standard deviations are the other rows'.
  std::vector<std::string> outliers;
  /// The whitened residual norm beyond which a row is an outlier (robust_scale, or more while
  /// the rows' median is above the noise); 0 without a robust loss.
  double outlier_threshold = 0;
  /// The standard deviations and the covariance were computed (a Jacobian that evaluated, a
  /// finite residual variance, compute_covariance). True even when some directions are not
  /// identifiable: those parameters' entries are NaN.
  bool covariance_ok = false;
  /// Covariance of the identified deviations, in `parameters` order (names there), SI units (m,
  /// rad, Pa, N, N m), as the planar CalibrationResult::covariance: the pseudo-inverse of J^T J
  /// from the same SVD as the standard deviations (whitened Jacobian on the last stage's free
  /// parameters), times the residual variance, the half-widths scaled back. Its diagonal is
  /// std_dev^2; zero rows and columns for the parameters that are not free; NaN rows and columns
  /// for those that are not identifiable and, when it could not be computed (covariance_ok
  /// false), for every free parameter. The other entries leave out the unidentifiable directions.
  /// Empty without compute_covariance.
  Eigen::MatrixXd covariance;
  double rms_position = 0;  ///< m, of the measured positions at the result
  double rms_angle = 0;     ///< rad, of the measured orientations at the result
  std::vector<std::string> warnings;
  double time_s = 0;
};

/// Identifies `nominal` (with an uncertainty section) from `data` (rows in measurement order;
/// each row's FK is continued from the row before it on the nominal robot, then from its own last
/// solution as the parameters move). Throws InputError when the description has no uncertainty,
/// the data has another rod count or fewer values than a stage frees, a stage is invalid, or a
/// row has no equilibrium on the nominal robot (naming the row; without drop_unreachable).
SpatialCalibrationResult calibrate_spatial(const SpatialRobotDescription& nominal,
                                           const SpatialDataset& data,
                                           const SpatialCalibrationOptions& options = {});

/// One row's whitened residual (6, as the stages see it) at `nominal` moved by the flat deviations
/// `deviations` (SI units; num_spatial_parameters of them, or kSpatialLoadParameters more: a
/// platform load added to the external wrench), FK cold at q (from straight rods), and its exact
/// derivative by the implicit function theorem with respect to them (6 x deviations.size(), SI
/// units). False when FK does not converge at q or the size is neither.
bool spatial_measurement_jacobian(const SpatialRobotDescription& nominal,
                                  const std::vector<double>& deviations,
                                  const SpatialJointVector& q, const SpatialPose<double>& measured,
                                  double orientation_weight, double residual_scale,
                                  Eigen::Matrix<double, 6, 1>* residual, Eigen::MatrixXd* jacobian,
                                  const SolverOptions& fk = SolverOptions());

/// What `robot` predicts for each row of `data` (the measured marker poses): the position and
/// angle errors (m, rad) of each row, FK continued row to row from home; NaN for a row without an
/// equilibrium.
struct SpatialPredictionErrors {
  std::vector<double> position;
  std::vector<double> angle;
  double rms_position = 0, rms_angle = 0;  ///< over the rows with an equilibrium
  int failures = 0;
};
SpatialPredictionErrors spatial_prediction_errors(const SpatialRobotParams<double>& robot,
                                                  const SpatialDataset& data,
                                                  const SolverOptions& fk = SolverOptions());

}  // namespace pcr
