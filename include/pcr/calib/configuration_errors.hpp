#pragma once
// A model's errors on a dataset, per configuration and as Table 3's statistics (Eqs. 8 and 9).

#include <vector>

#include "pcr/calib/calibration_sample.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/robot.hpp"
#include "pcr/se2.hpp"
#include "pcr/shooting.hpp"
#include "pcr/solver.hpp"

namespace pcr {

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

}  // namespace pcr
