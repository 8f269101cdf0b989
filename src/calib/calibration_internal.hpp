#pragma once
// Declarations shared by the calibration's source files (src/calib), not part of the API.

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pcr/calib/calibrator.hpp"

namespace pcr::calib_internal {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// calibration_text.cpp: how the messages name rows and list items.

std::string format_number(double v);
std::string origin_of(const std::vector<CalibrationSample>& data, std::size_t j);
std::string joints_text(const JointVector& q);
/// "a, b, c and 4 more" of the first `shown` items.
std::string listing(const std::vector<std::string>& items, std::size_t shown = 5);

// calibration_rows.cpp

/// The rows the nominal geometry reaches. Ceres cannot start from a failed evaluation. A row whose
/// joints lie within their stroke and that the nominal geometry does not reach may lie past a fold
/// of the design that the robot itself does not have: it is set aside (`set_aside`), to be brought
/// back when the identified geometry reaches it. One with joints outside the stroke is a typo, a
/// wrong unit or another robot's: an InputError, or with drop_unreachable left out and listed in
/// result->dropped; joints outside their stroke are warned of. `used`: the reachable rows' places
/// in `data`.
std::vector<CalibrationSample> reachable_rows(const RobotParams<double>& nominal,
                                              const std::vector<CalibrationSample>& data,
                                              const CalibrationOptions& options,
                                              const std::string& source, CalibrationResult* result,
                                              std::vector<Pose2<double>>* poses,
                                              std::vector<std::size_t>* used,
                                              std::vector<std::size_t>* set_aside);

// equilibrium_branches.cpp

/// The ways a robot may have reached the equilibria of a dataset's rows at their joints (its
/// readings): each row on its own from home, the rows as a path in their order from home, and as
/// a path through folds (a robot that snapped through one).
std::vector<std::pair<SolverOptions, SequenceMode>> dataset_readings(const SolverOptions& fk);

/// The rows' equilibria in one reading.
std::vector<ForwardSolution> solve_rows(const RobotParams<double>& robot,
                                        const std::vector<CalibrationSample>& data,
                                        const SolverOptions& options, SequenceMode mode,
                                        const PlatformLoad<double>& load);

/// The branch-mismatch rule: a row whose equilibrium `predicted[j]` misses its measurement by
/// kMismatchFactor times the rows' median position error or more, and whose measurement lies
/// kMismatchFactor times nearer another equilibrium at the same joints (nearest_other_equilibrium,
/// with the rows' readings, solved once a row needs them), was measured on that one: the robot
/// came to it another way than the one predicted. Per row, that equilibrium or none (also for a
/// row without a converged prediction, or a null one). `predicted_reading`: the mode in which
/// `predicted` is itself the reading of `fk` (that reading is not solved again: it gives each row
/// its prediction, which is not another equilibrium), or none.
std::vector<std::optional<ForwardSolution>> equilibria_measured_instead(
    const RobotParams<double>& robot, const std::vector<CalibrationSample>& data,
    const std::vector<const ForwardSolution*>& predicted, const SolverOptions& fk,
    const PlatformLoad<double>& load, std::optional<SequenceMode> predicted_reading);

// calibration_stages.cpp

/// Free flat indices of a stage: its kinds, restricted to non-zero half-widths (an index past
/// `half_widths`, the load's when its scales are not known yet, counts as free).
std::vector<int> stage_free_indices(const CalibrationStage& stage,
                                    const std::vector<double>& half_widths, int n);

/// Throws InputError naming `source` on no stage, a kind `known` refuses (the message ends with
/// `unknown_hint`) or a non-positive bounds scale: the one check of the planar and spatial stages.
void validate_stage_list(const std::vector<CalibrationStage>& stages, const std::string& source,
                         bool (*known)(const std::string&), const std::string& unknown_hint);

// registration.cpp

/// The extrinsics of Eq. 5, P_j = C M_j Pm, from the platform poses P_j of the nominal geometry
/// and the measurements M_j, whatever the guess: a 2D registration. C's rotation (c, s) and
/// translation solve a linear least-squares problem, p_j = t_C + R_C (t_Mj + R_Mj t_Pm), with Pm's
/// translation held at its guess (the platform turns by milliradians, so the data hardly tell it
/// from C's translation: the stages do); Pm's rotation is the mean of theta_Pj - theta_Mj -
/// theta_C. Too few distinct measurements to fix the rotation: the guess.
Extrinsics<double> registered_extrinsics(const std::vector<Pose2<double>>& platform,
                                         const std::vector<CalibrationSample>& rows,
                                         const Extrinsics<double>& guess);

/// A dataset written in a left-handed frame (an image's, y down) is mirrored: no rigid extrinsics
/// map it onto the model, and the stages end far from the noise, naming the extrinsics. When the
/// measurements register ten times better onto the nominal model's poses with y and theta
/// negated, the warning says so. `registered`: registered_extrinsics of the rows as given.
void warn_of_mirror(const std::vector<Pose2<double>>& platform,
                    const std::vector<CalibrationSample>& rows,
                    const Extrinsics<double>& registered, const Extrinsics<double>& guess,
                    CalibrationResult* result);

// gauge.cpp

/// gauge_generators' order.
enum GaugeIndex {
  kProximalX,
  kProximalY,
  kProximalRotation,
  kDistalX,
  kDistalY,
  kDistalRotation,
  kStiffness,
};

/// Generators whose every moved parameter is in `is_free` (and that move at least one).
std::vector<bool> present_generators(const std::vector<GaugeGenerator>& generators,
                                     const std::vector<bool>& is_free);

// calibration_diagnostics.cpp: what calibrate() says of its result.

class Identification;

/// Outliers: rows whose whitened residual norm exceeds robust_scale. The Huber loss bounded
/// their pull in the stages; the rank, the variance and the covariance are the other rows'. `J`
/// and `r` (at the result, on id.evaluated_rows(), when `evaluated`) keep the other rows' blocks.
void leave_out_outliers(Identification& id, const std::vector<CalibrationSample>& rows,
                        bool evaluated, Eigen::MatrixXd& J, Eigen::VectorXd& r,
                        CalibrationResult& result);

/// The rank of the Jacobian `J` (columns scaled by the half-widths) on the `free` parameters, its
/// singular values, the gauge directions with their gain (`present`: the gauges; `movable`: the
/// generators whose parameters are all free), and the residual variance of `r`.
void rank_and_gauge_directions(const Identification& id, const std::vector<int>& free,
                               const std::vector<bool>& present, const std::vector<bool>& movable,
                               const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                               CalibrationResult& result);

/// Standard deviations in the limb-0 gauge: the pseudo-inverse of J^T J on the free parameters
/// that are not gauge references (`held`), in half-width units, scaled back and by the residual
/// variance; with compute_covariance, the covariance too. Directions below the rank threshold are
/// what the data cannot identify: named in words, and every parameter with a share in one is "not
/// identifiable" (std NaN), not 0.
void standard_deviations(const Identification& id, const CalibrationOptions& options, int block,
                         const std::vector<int>& free, const std::vector<int>& held, bool evaluated,
                         const Eigen::MatrixXd& J, CalibrationResult& result);

/// What makes `result` doubtful, in words: extrinsics outside their declared interval, residuals
/// inconsistent with the declared noise, parameters held at a bound.
void add_warnings(const Identification& id, CalibrationResult* result);

}  // namespace pcr::calib_internal
