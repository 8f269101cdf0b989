#pragma once
// Staged, bounded identification of a robot description from measured poses (Mauze et al. 2021,
// Section 5), with Ceres.
//
// - Residuals: PoseMeasurementError (pcr/calib/cost.hpp), one per configuration.
// - Bounds (Eq. 7) on the geometry: nominal +- bounds_scale * half-width, from the nominal
//   description's uncertainty section. Parameters with a zero half-width are never free. The
//   extrinsics carry no bounds: they start from a closed-form registration of the data (Eq. 5 on
//   the nominal geometry's poses), whatever the guess; a result outside their declared interval
//   is a warning.
// - Stages (default: the paper's three): (1) extrinsics; (2) l, A, B, alpha + extrinsics; (3) every
//   parameter with a nonzero half-width. Free parameters through a manifold that spans them in
//   half-width units (all O(1) for Levenberg-Marquardt), bounds on the flat values.
// - Gauge. With no load on the platform, these motions change no prediction:
//     proximal: a rigid motion G of every A_i, alpha_i together with the camera frame ^W T_Se;
//     distal:   a rigid motion H of every B_i, beta_i together with the pattern frame ^M T_P;
//     stiffness: a common scale of every rod's bending stiffness E_i d_i^4.
//   During the stages (StageGauge::kSubspace, the default) each step is restricted to the
//   complement, in half-width units, of the gauge generators whose parameters are all free in the
//   stage, taken at the stage's start: the stage then picks, on the gauge orbit of its optimum,
//   the representative with no gauge component relative to its start (to first order the one
//   closest to it), and the problem it solves is full rank. Measured on the paper's 99
//   configurations: 18 Levenberg-Marquardt iterations for the three stages instead of ~290 with
//   the former weak prior (StageGauge::kPrior, kept as an option), same final cost to 7 digits:
//   the prior's curvature along the gauge (weight^2 ~ 1e-6 per half-width^2 against ~1e8 for
//   the data) left LM crawling along near-gauge valleys. Holding limb 0 at its nominal values
//   during the stages is not an option: a rotation of up to 5 mrad about limb 0's clamp moves the
//   other clamps by up to 0.5 mm, outside their +-0.16 mm boxes.
//   Bounds and gauge: a truth inside the box may have, in the gauge a stage starts in, a
//   representative outside it (the gauge components of its deviations are not those of the
//   start), which a stage restricted to the complement of the gauge cannot reach: it stalls on
//   the bounds. So each stage first moves the values along the gauge orbit (no prediction
//   changes) to the representative deepest inside the box, and runs in rounds: a round that ends
//   with parameters at a bound (held there by an active set) is followed by another from the
//   recentred values with every parameter free, while the rounds lower the cost by 1%.
//   After the last stage the gauge is fixed exactly, without changing any prediction: limb 0
//   defines the frames, so A_0, alpha_0 (and, distally, B_0, beta_0) and d_0 get back their nominal
//   (measured) values, the others and the extrinsics follow. The standard deviations are computed
//   in that gauge (those parameters held), so every reported value and deviation is relative to
//   limb 0's measured clamps. Gauge directions are detected (rank of the scaled Jacobian at the
//   solution) and named in the report.
// - Uncertainty: the pseudo-inverse of J^T J (Eigen's SVD of the Jacobian scaled by the
//   half-widths) on the free parameters with the gauge references held, scaled by the residual
//   variance (sum of squares / (m - rank)). Computed only from a Jacobian that evaluated and is
//   finite: Ceres' own covariance crashes after a failed evaluation.
// - Rows: every configuration is first solved on the nominal geometry (each on its own, on the
//   branch connected to home, as everywhere in the calibration). One it cannot reach whose joints
//   lie within their stroke may lie past a fold of the design that the robot does not have: it is
//   set aside with a warning, and joins a second run of the last stage when the identified
//   geometry reaches it (the stage reports say which rows each used). One outside the stroke (a
//   typo, a wrong unit, another robot's row) is an InputError naming the row, or, with
//   drop_unreachable, left out and listed; a joint value outside its stroke is a warning.
// - Platform load: a stage that frees "load" identifies a constant force and moment on the
//   platform (air-bearing drag, a cable) with the geometry, which would otherwise absorb it (at
//   200 uN, l_2 ends 24 sigma off with the validation at the floor). Unbounded; its scale is the
//   load that moves the platform over the rows as far as a clamp tolerance does. It is known
//   relative to the bending stiffness (the stiffness gauge scales it by the fourth power). Under a
//   force a distal translation is no longer a gauge (the moment's arm turns with the platform):
//   the stages keep it; at the end, the translation perpendicular to the force, a gauge to second
//   order in the platform angle, is held by one coordinate of B_0 (both while the data do not see
//   the force) and the other free parameters are refitted with the references held.

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pcr/calib/calibration_sample.hpp"
#include "pcr/calib/calibration_stages.hpp"
#include "pcr/calib/configuration_errors.hpp"
#include "pcr/calib/cost.hpp"
#include "pcr/calib/gauge.hpp"
#include "pcr/input_error.hpp"
#include "pcr/robot_description.hpp"

namespace pcr {

/// How a stage treats the gauge directions (see the header comment).
enum class StageGauge {
  /// Steps restricted to the complement of the gauge generators present in the stage (taken at
  /// the stage's start, in half-width units): the gauge is fixed exactly and the problem stays
  /// well conditioned. The default.
  kSubspace,
  /// A weak prior towards the nominal values (gauge_prior_weight); all free parameters move.
  kPrior,
};

/// FK settings of the calibration's cost: every solve runs to the Newton tolerance
/// (chord_output_share = 0), so that the residuals are smooth in the parameters; the default
/// share leaves ~0.02 nm steps between neighbouring solves, noise that costs Levenberg-Marquardt
/// iterations near the noise floor.
inline SolverOptions calibration_solver_options() {
  SolverOptions options;
  options.chord_output_share = 0.0;
  return options;
}

struct CalibrationOptions {
  std::vector<CalibrationStage> stages = default_stages();
  double orientation_weight = kDefaultOrientationWeight;  ///< w of Eq. 6 (m/rad)
  double residual_scale = kDefaultResidualScale;          ///< whitening of the residuals (m)
  DerivativeMode derivatives = DerivativeMode::kImplicit;
  SolverOptions fk = calibration_solver_options();
  int max_iterations = 100;  ///< per stage
  bool fix_gauge = true;     ///< move the result to the limb-0 gauge (see above)
  /// Weight of the weak prior towards the nominal values during the stages (whitened residual
  /// per half-width of deviation). It fixes the gauge directions smoothly; 0 disables it.
  double gauge_prior_weight = 1e-3;
  StageGauge stage_gauge = StageGauge::kSubspace;
  /// A stage stops when an iteration lowers the cost by less than this fraction. The whitened
  /// cost is ~ m / 2 at the noise floor, so 1e-6 is a decrease far below one noise unit.
  double function_tolerance = 1e-6;
  /// The same for the stages before the last: they only bring the values into the last stage's
  /// basin, which refits every parameter they fit.
  double intermediate_function_tolerance = 1e-2;
  bool compute_covariance = true;
  /// Huber loss on each configuration's whitened residual norm beyond this many declared noise
  /// units (residual_scale): a row that far off pulls like one at the scale, not with its whole
  /// error. Clean data is unaffected (a 3-dof chi-square exceeds 5^2 once in 60,000 rows). 0:
  /// plain least squares.
  double robust_scale = 5.0;
  /// Rows with joints outside their stroke and without an FK solution on the nominal geometry are
  /// left out (and listed in CalibrationResult::dropped) instead of being an InputError. (Rows
  /// within the stroke that the nominal geometry does not reach are always set aside, see above.)
  bool drop_unreachable = false;
  /// Progress lines (stage, iteration, cost); empty: silent.
  std::function<void(const std::string&)> progress;

  static constexpr OptionRange kOrientationWeight{"orientation_weight", 0, 10, "m/rad"};
  static constexpr OptionRange kResidualScale{"residual_scale", 1e-15, 1, "m"};
  static constexpr OptionRange kMaxIterations{"max_iterations", 1, 100000};
  static constexpr OptionRange kGaugePriorWeight{"gauge_prior_weight", 0, 1e6};
  static constexpr OptionRange kFunctionTolerance{"function_tolerance", 0, 1};
  static constexpr OptionRange kIntermediateFunctionTolerance{"intermediate_function_tolerance", 0,
                                                              1};
  static constexpr OptionRange kRobustScale{"robust_scale", 0, 1e6};  ///< 0: no robust loss
  /// As SolverOptions::is_valid, for these fields and fk (the stages are checked by calibrate,
  /// against the robot).
  bool is_valid(std::string* error = nullptr) const {
    return kOrientationWeight.check(orientation_weight, error) &&
           kResidualScale.check(residual_scale, error) &&
           kMaxIterations.check(max_iterations, error) &&
           kGaugePriorWeight.check(gauge_prior_weight, error) &&
           kFunctionTolerance.check(function_tolerance, error) &&
           kIntermediateFunctionTolerance.check(intermediate_function_tolerance, error) &&
           kRobustScale.check(robust_scale, error) && fk.is_valid(error);
  }
};

struct StageReport {
  std::string name;
  std::vector<std::string> free_parameters;
  double initial_cost = 0;  ///< 1/2 sum F^T F (Eq. 7 / 2), in m^2
  double final_cost = 0;    ///< m^2
  int iterations = 0;
  double time_s = 0;
  std::string termination;  ///< Ceres' brief report
  bool usable = false;      ///< Ceres' IsSolutionUsable()
  // Where the time goes (all solves of the stage, active-set passes included).
  int residual_evaluations = 0;  ///< Ceres residual-only evaluations of the whole problem
  int jacobian_evaluations = 0;  ///< Ceres residual + Jacobian evaluations
  double residual_time_s = 0;    ///< Ceres' residual evaluation time
  double jacobian_time_s = 0;    ///< Ceres' Jacobian evaluation time
  double linear_solver_time_s = 0;
  int fk_solves = 0;               ///< double FK solves (all configurations)
  int fk_warm_start_failures = 0;  ///< warm solves that failed (continued in the parameters)
  int fk_newton_iterations = 0;    ///< FK Newton iterations, all solves
};

struct ParameterEstimate {
  std::string name;  ///< "l[1]", "camera_x" ...
  ParameterKind kind = ParameterKind::kLength;
  double nominal = 0;
  double value = 0;    ///< identified, in the final gauge
  double std_dev = 0;  ///< 0 when not free or gauge reference; NaN when not identifiable or failed
  double half_width = 0;
  bool free = false;             ///< free in the last stage
  bool gauge_reference = false;  ///< held by the gauge fix
  /// Where the bounds apply: (value - nominal) / (bounds_scale half-width) at the end of the
  /// last stage, before the gauge fix moves the values to the limb-0 frame (a bounded free
  /// parameter; NaN otherwise). +-1: at a bound. The limb-0 frame is no frame of the box: there a
  /// clamp may lie up to two half-widths from its nominal position inside a valid fit.
  double box_deviation = std::numeric_limits<double>::quiet_NaN();
  bool at_bound = false;  ///< |box_deviation| within 1e-6 of 1
  /// False when it has a share (>= 0.1) in a direction the data cannot identify (see
  /// CalibrationResult::unidentifiable); its std_dev is then NaN.
  bool identifiable = true;
};

struct GaugeDirection {
  std::string name;          ///< e.g. "proximal clamps + camera: rotation"
  std::string combination;   ///< the parameters it moves, e.g. "A_x[*] + camera_x"
  double relative_gain = 0;  ///< |J g| / (sigma_max |g|), scaled units: ~0 means a gauge
  bool free = false;         ///< every parameter it moves is free in the last stage
  /// Free and a gauge: it changes no prediction (under a free platform load, a distal
  /// translation is free but changes the predictions where the force is seen), fixed by limb 0.
  bool present = false;
};

struct CalibrationResult {
  RobotParams<double> identified;       ///< final parameters (gauge fixed)
  RobotParams<double> extrinsics_only;  ///< nominal robot with identified extrinsics
  std::vector<StageReport> stages;
  /// Every flat parameter, in flat order, then the load's three (load_f_x, load_f_y in N,
  /// load_m_z in N m) when a stage frees "load".
  std::vector<ParameterEstimate> parameters;
  /// The identified constant platform load (in W, the moment about the platform origin), zero
  /// unless a stage frees "load". `identified` predicts the measurements under it: Table 3 and
  /// configuration_errors use it, and `pcr fk` takes it (--force fx,fy --moment mz).
  PlatformLoad<double> load;
  bool load_identified = false;
  std::vector<GaugeDirection> gauge;
  int free_count = 0;                   ///< free parameters of the last stage
  int jacobian_rank = 0;                ///< numerical rank of the scaled Jacobian on them
  std::vector<double> singular_values;  ///< of the scaled Jacobian, relative to the largest
  /// Of the whitened residuals: ~1 at the noise floor; NaN when the model could not be
  /// evaluated at the result.
  double residual_variance = 0;
  /// The residual test: residual_variance lies more than 5 standard deviations of its chi-square
  /// estimate (3 rows - rank degrees of freedom, outliers left out) above 1, so the model or the
  /// declared noise does not explain the data: an unmodelled effect, outliers, wrong extrinsics
  /// or more noise than declared (one of `warnings` says so).
  bool residuals_exceed_noise = false;
  /// The standard deviations and the covariance were computed (a Jacobian that evaluated, a
  /// finite residual variance, compute_covariance). True even when some directions are not
  /// identifiable: those parameters' entries are NaN (see covariance).
  bool covariance_ok = false;
  /// Covariance of the identified values, in `parameters` order (the flat parameters, then the
  /// load's three when identified), SI units (m, rad, Pa, N, N m): the pseudo-inverse of J^T J
  /// from the same SVD as the standard deviations (scaled Jacobian on the free parameters less the
  /// gauge references), times the residual variance, the half-widths scaled back. Its diagonal is
  /// std_dev^2: zero rows and columns for the parameters that are not free and the gauge
  /// references (held exactly in the limb-0 gauge); NaN rows and columns for the parameters that
  /// are not identifiable (a share >= 0.1 in a direction below the rank threshold) and, when the
  /// covariance could not be computed (covariance_ok false), for every estimated parameter, except
  /// at the held parameters (zero: a held value has no covariance with any). The other entries
  /// leave out the unidentifiable directions (pseudo-inverse). Empty without compute_covariance.
  Eigen::MatrixXd covariance;
  /// Rows left out: origin, joints and FK status; those outside the stroke (drop_unreachable) and
  /// those set aside that the identified geometry does not reach either.
  std::vector<std::string> dropped;
  /// Rows whose whitened residual norm at the result exceeds robust_scale: origin and norm. The
  /// rank, residual variance and standard deviations are the other rows'.
  std::vector<std::string> outliers;
  /// The whitened residual norm beyond which a row is an outlier (robust_scale, or more while
  /// the rows' median is above the noise); 0 without a robust loss.
  double outlier_threshold = 0;
  /// The parameter combinations the data cannot identify beyond the gauge, in words, in
  /// half-width units ("+ 0.71 l[1] - 0.70 A_x[1]"): right singular vectors of the scaled
  /// Jacobian (gauge references held) below the rank threshold.
  std::vector<std::string> unidentifiable;
  /// What makes the result doubtful, in words (joints outside the stroke, a failed evaluation).
  std::vector<std::string> warnings;
};

/// A singular value of the scaled Jacobian below this fraction of the largest is a direction the
/// data do not identify (rounding in the exact Jacobian is ~1e-12 of it).
inline constexpr double kRankThreshold = 1e-7;

/// The whitened residual Jacobian of one configuration at `robot`, as the stages see it (Eq. 6
/// divided by residual_scale): 3 x num_parameters, rows (w theta, x, y) / residual_scale, columns
/// in flat order, extrinsics included; exact (DerivativeMode::kImplicit, FK from home). Returns
/// false when FK does not converge at q.
bool measurement_jacobian(const RobotParams<double>& robot, const JointVector& q,
                          double orientation_weight, double residual_scale,
                          Eigen::MatrixXd* jacobian, const SolverOptions& fk = SolverOptions());

/// Identifies `nominal` from `data`. Throws InputError when the description has no uncertainty
/// section, the data does not match the limb count, or a stage is invalid.
CalibrationResult calibrate(const RobotDescription& nominal,
                            const std::vector<CalibrationSample>& data,
                            const CalibrationOptions& options = CalibrationOptions());

/// `robot` (a virtual robot's truth, say) moved along the gauge directions `result` fixed, to the
/// same references (`nominal`'s limb-0 values the calibration held: its gauge_reference
/// parameters): its predictions (with no load) are unchanged, and its parameters compare one by
/// one with result.parameters. Throws std::invalid_argument when the limb counts differ.
RobotParams<double> in_calibration_gauge(const CalibrationResult& result,
                                         const RobotParams<double>& nominal,
                                         const RobotParams<double>& robot);

}  // namespace pcr
