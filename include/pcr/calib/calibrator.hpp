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

#include "pcr/calib/cost.hpp"
#include "pcr/input_error.hpp"
#include "pcr/robot_description.hpp"

namespace pcr {

/// One measured configuration: joints (m) and measured pattern pose ^Se T_M (m, m, rad).
struct CalibrationSample {
  JointVector q;
  Pose2<double> measured;
  std::string origin;  ///< where the row came from ("data.csv:17"); empty: "configuration j"
  int line = 0;        ///< 1-based line in its file (0: not from a file)
};

struct CalibrationStage {
  std::string name;
  /// Kinds: a per-limb kind of kParameterKinds ("E", "d", "l", "A_x", "A_y", "alpha", "B_x",
  /// "B_y", "beta", "gamma", "precurvature"), "A", "B", "camera", "pattern", "extrinsics", "all"
  /// (the geometry and extrinsics), "load" (the constant platform load, kLoadParameters values;
  /// not in "all").
  std::vector<std::string> free;
  double bounds_scale = 1.0;
};

/// The paper's three stages.
std::vector<CalibrationStage> default_stages();

/// Whether a stage frees "load" (the calibration then identifies a constant platform load).
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

/// Table 3 of the paper for one model and one set: e_p (Eq. 8, m) and e_theta (Eq. 9, rad),
/// comparing FK with the platform pose computed from the measurement by Eq. 5.
struct PoseErrorStats {
  double max_p = 0, mean_p = 0, min_p = 0;
  double max_theta = 0, mean_theta = 0, min_theta = 0;
  int count = 0;   ///< configurations evaluated
  int failed = 0;  ///< configurations whose FK did not converge (not in the statistics)
  /// Configurations measured on another equilibrium than the model's (ConfigurationErrors::
  /// branch_mismatch; not in the statistics).
  int branch_mismatches = 0;
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

/// A tangent vector of the gauge orbit (see the header comment): moving the parameters along it
/// changes no prediction when the platform carries no load.
struct GaugeGenerator {
  std::string name;               ///< e.g. "proximal clamps + camera: rotation"
  std::string combination;        ///< the parameters it moves, in words
  std::vector<double> direction;  ///< flat (parameters.hpp order), unscaled
};

/// The seven generators at `robot`: proximal translation x, y and rotation, distal translation
/// x, y and rotation, common scale of the bending stiffness.
std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot);

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

/// Per-configuration errors of one model on one set (the paper's Figures 8 and 9): e_p (Eq. 8,
/// m) and e_theta (Eq. 9, rad), NaN where FK failed. The rows are solved as `order` says: by
/// default the path the experiment followed, from home in the rows' order (a dataset's row order
/// is its measurement order, each dataset an experiment from home: see docs/calibration.md, "Row
/// order is measurement order"), as the robot moved; SequenceMode::kIndependent solves each from
/// home, as the calibration's residuals do.
///
/// A row whose error is kMismatchFactor times the set's median or more, and whose measurement
/// lies kMismatchFactor times nearer another equilibrium of the model at the same joints, is a
/// branch mismatch: the robot held another equilibrium than the one the model predicts there.
/// The other equilibria looked at: the rows' solutions in the other readings of the set (each
/// from home, as a path, as a path through folds: a robot that snapped through one), and
/// buckled variants of the predicted one (each rod bent one or two turns further either way).
struct ConfigurationErrors {
  std::vector<double> e_p, e_theta;
  std::vector<bool> branch_mismatch;
  /// Where branch_mismatch: the platform pose of the equilibrium the measurement lies next to.
  std::vector<Pose2<double>> other_pose;
};
inline constexpr double kMismatchFactor = 10.0;
/// Two equilibria at the same joints are distinct beyond this (m, with angles at the orientation
/// weight): far above the solver's accuracy.
inline constexpr double kDistinctEquilibrium = 1e-7;
ConfigurationErrors configuration_errors(const RobotParams<double>& robot,
                                         const std::vector<CalibrationSample>& data,
                                         const SolverOptions& fk = SolverOptions(),
                                         const PlatformLoad<double>& load = PlatformLoad<double>(),
                                         SequenceMode order = SequenceMode::kPath);

/// Table 3 statistics (max, mean, min) of per-configuration errors; failures are counted apart.
PoseErrorStats error_statistics(const ConfigurationErrors& errors);

/// Table 3 statistics of `robot` (with its extrinsics) on `data` (configuration_errors).
PoseErrorStats pose_errors(const RobotParams<double>& robot,
                           const std::vector<CalibrationSample>& data,
                           const SolverOptions& fk = SolverOptions(),
                           const PlatformLoad<double>& load = PlatformLoad<double>(),
                           SequenceMode order = SequenceMode::kPath);

/// The flat half-widths of `uncertainty` for a robot with `num_limbs` limbs.
std::vector<double> parameter_half_widths(const RobotUncertainty& uncertainty, int num_limbs);

/// Moves `params` along the gauge orbit (predictions with no load are unchanged): the proximal
/// clamps and the camera frame by the rigid motion G (A -> G A, alpha -> alpha + G.theta,
/// camera -> G camera), the distal clamps and the pattern frame by H (B -> H B,
/// beta -> beta + H.theta, pattern -> pattern H^-1), every diameter times stiffness_scale.
RobotParams<double> move_along_gauge(const RobotParams<double>& params, const Pose2<double>& G,
                                     const Pose2<double>& H, double stiffness_scale);

/// The constant platform load (pcr/calib/cost.hpp, kLoadParameters) that keeps the predictions
/// of move_along_gauge(params, G, H, stiffness_scale) under `load`: the force turns with G (the
/// world moves), force and moment scale with the bending stiffness (stiffness_scale^4), and the
/// moment, taken about the platform origin that H moves, gains the force's arm. That arm turns
/// with each configuration's platform angle; it is taken at theta = 0. So with a force on the
/// platform a distal translation is no longer a gauge (the spread of the platform angles over the
/// data sees it, weakly), and the predictions are kept exactly only when H does not translate.
PlatformLoad<double> move_load_along_gauge(const PlatformLoad<double>& load, const Pose2<double>& G,
                                           const Pose2<double>& H, double stiffness_scale);

/// The equilibrium `solution` of a robot moved along the gauge orbit by (G, H, stiffness_scale):
/// the same rods turned by G, the platform pose G P H^-1, the proximal forces turned by G and every
/// wrench scaled with the bending stiffness (stiffness_scale^4). The model's symmetry makes it the
/// equilibrium of move_along_gauge(...) exactly under move_load_along_gauge(...) when H does not
/// translate; otherwise a start one Newton step away. Its chord matrix is dropped.
ForwardSolution move_equilibrium_along_gauge(const ForwardSolution& solution,
                                             const Pose2<double>& G, const Pose2<double>& H,
                                             double stiffness_scale);

/// The seven generators at `robot` under a constant platform load, with the load's components
/// (move_load_along_gauge to first order, the distal translations' at platform angle 0) after
/// the flat ones: directions of num_parameters(n) + kLoadParameters values.
std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot,
                                             const PlatformLoad<double>& load);

/// A motion along the gauge orbit (move_along_gauge's arguments).
struct GaugeMotion {
  Pose2<double> G{0, 0, 0};  ///< of the proximal clamps and the camera frame
  Pose2<double> H{0, 0, 0};  ///< of the distal clamps, about the platform origin
  double stiffness_scale = 1;
};

/// The motion that puts limb 0's clamps and d_0 at `reference`'s values: A_0 (with
/// `proximal_translation`) and alpha_0 (with `proximal_rotation` too), B_0 and beta_0 alike (a
/// distal rotation alone turns about the platform origin and sets beta_0), d_0 (`stiffness`).
GaugeMotion gauge_fix_motion(const RobotParams<double>& params,
                             const RobotParams<double>& reference, bool proximal_translation,
                             bool proximal_rotation, bool distal_translation, bool distal_rotation,
                             bool stiffness);

/// The distal translation that fixes the gauge of `params` under a constant platform `load`
/// (after gauge_fix_motion's rotations). Without a force: B_0 takes `reference`'s value, both
/// coordinates `held`. With one, a distal translation changes the predictions, by the force's arm
/// that turns with the platform, to first order in the platform angle unless it is perpendicular
/// to the force: the motion is along that perpendicular, until the coordinate of B_0 with the
/// larger share in it takes `reference`'s value (held[0]: x, held[1]: y). Move the load with it
/// (move_load_along_gauge).
GaugeMotion gauge_fix_motion(const RobotParams<double>& params, const PlatformLoad<double>& load,
                             const RobotParams<double>& reference, bool held[2]);

/// move_along_gauge by gauge_fix_motion: predictions (with no load) are unchanged.
RobotParams<double> fix_gauge(const RobotParams<double>& params,
                              const RobotParams<double>& reference, bool proximal_translation,
                              bool proximal_rotation, bool distal_translation, bool distal_rotation,
                              bool stiffness);

}  // namespace pcr
