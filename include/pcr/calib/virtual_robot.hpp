#pragma once
// A simulated stand-in for the real robot (pcr simulate, the demo, the studies): a "true" robot
// drawn from a nominal description inside its uncertainty intervals, true extrinsics, and a camera
// that measures the pattern pose ^Se T_M = (^W T_Se)^-1 . ^W T_P(q) . (^M T_P)^-1 (Eq. 5) with
// Gaussian noise.
//
// How the truth is drawn (seeded, std::mt19937_64, reproducible across runs of the same build):
// - every limb parameter and every extrinsic parameter = nominal + U(-h, h), h its half-width in
//   the nominal description's RobotUncertainty (a missing uncertainty means h = 0); or, with
//   VirtualRobotOptions::truth_at_fraction f > 0, nominal +- f h with the sign drawn (a truth in
//   the corners of the intervals, where a bounded identification is hardest);
// - E and d are drawn once for all limbs (one material, one wire): per-limb differences are an
//   unmodelled effect, switched on by UnmodelledEffects::unequal_diameters.
// Unmodelled effects, each independent of the others:
// - misalignments: beta_i and gamma_i get an extra U(-h_m, h_m) on top of their nominal draw, for
//   a nominal model that treats them as known (the paper neglects beta and gamma);
// - unequal_diameters: each d_i gets an extra, independent U(-h_d, h_d);
// - external_load: a constant force and moment applied on the platform (in W, at P's origin).

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/robot_description.hpp"

namespace pcr {

/// The paper's repeatability (standard deviations): 9.13 nm in position, 1.2 urad in orientation.
inline constexpr double kDefaultNoisePosition = 9.13e-9;  ///< m
inline constexpr double kDefaultNoiseAngle = 1.2e-6;      ///< rad

struct UnmodelledEffects {
  bool misalignments = false;
  double misalignment_half_width =
      5e-3;  ///< rad, on beta_i and gamma_i (paper Section 4.3: 5 mrad)
  bool unequal_diameters = false;
  double diameter_half_width = 2e-6;  ///< m, independent on each d_i
  bool external_load = false;
  /// N, N m (in W, at P). The default robot is stiff: 5 mN along x moves the platform ~1 um.
  PlatformLoad<double> load{Vector2<double>(5e-3, 0.0), 0.0};

  bool any() const { return misalignments || unequal_diameters || external_load; }

  static constexpr OptionRange kMisalignmentHalfWidth{"misalignment_half_width", 0, 0.1, "rad"};
  static constexpr OptionRange kDiameterHalfWidth{"diameter_half_width", 0, 1e-3, "m"};
  /// As SolverOptions::is_valid, for these fields and the load's.
  bool is_valid(std::string* error = nullptr) const {
    return kMisalignmentHalfWidth.check(misalignment_half_width, error, "effects.") &&
           kDiameterHalfWidth.check(diameter_half_width, error, "effects.") &&
           load.is_valid(error, "effects.load.");
  }
};

struct VirtualRobotOptions {
  std::uint64_t seed = 1;
  /// 0: the truth is drawn uniformly inside the intervals; f in (0, 1]: every parameter at
  /// nominal +- f half-widths, the sign drawn.
  double truth_at_fraction = 0.0;
  double noise_position = kDefaultNoisePosition;  ///< m, std of x and of y (independent)
  double noise_angle = kDefaultNoiseAngle;        ///< rad, std of theta
  UnmodelledEffects effects;
  SolverOptions solver;

  static constexpr OptionRange kTruthAtFraction{"truth_at_fraction", 0, 1};
  static constexpr OptionRange kNoisePosition{"noise_position", 0, 0.01, "m"};
  static constexpr OptionRange kNoiseAngle{"noise_angle", 0, 0.1, "rad"};
  /// As SolverOptions::is_valid, for these fields, the effects' and the solver's.
  bool is_valid(std::string* error = nullptr) const {
    return kTruthAtFraction.check(truth_at_fraction, error) &&
           kNoisePosition.check(noise_position, error) && kNoiseAngle.check(noise_angle, error) &&
           effects.is_valid(error) && solver.is_valid(error);
  }
};

/// One simulated measurement.
struct VirtualMeasurement {
  /// false: FK of the true robot has no solution at q, or only an unstable one (summary.status
  /// kUnstable: the robot would snap off it, and is homed again)
  bool ok = false;
  Pose2<double> measured;  ///< ^Se T_M with noise: what the camera reports
  Pose2<double> exact;     ///< ^Se T_M without noise
  Pose2<double> platform;  ///< ^W T_P of the true robot
  SolverSummary summary;   ///< of the true robot's FK
};

class VirtualRobot {
 public:
  /// Draws the truth from `nominal` (throws InputError on an invalid robot or negative option).
  VirtualRobot(const RobotDescription& nominal, const VirtualRobotOptions& options = {});

  const RobotDescription& nominal() const { return nominal_; }
  /// The true description (same uncertainty block as the nominal one). Never needed by
  /// calibration, only by tests and `pcr simulate --truth`.
  const RobotDescription& truth() const { return truth_; }
  /// The load actually applied (zero unless effects.external_load).
  const PlatformLoad<double>& load() const { return load_; }
  const VirtualRobotOptions& options() const { return options_; }

  /// Moves to q and measures: FK of the truth along the path from the last configuration, as the
  /// robot moves (a pcr::ForwardSequence in SequenceMode::kPath: on the branch of the last
  /// successful call, a cold retry from home where it ends; through folds with
  /// solver.through_folds); the noise stream advances only on success. An unstable equilibrium
  /// (solver.check_stability) is not measured: a real robot would snap off it to one no model
  /// says; the robot is homed again.
  VirtualMeasurement measure(const JointVector& q);

  /// measure(q), throwing std::runtime_error (naming q and the solver status) on failure.
  Pose2<double> measure_or_throw(const JointVector& q);

  /// The robot goes back home: the next measurement starts there.
  void return_home() { sequence_.reset(); }

  /// A dataset's experiment: the robot goes home, then moves to each row of `rows` in their
  /// order and measures it (the rows of a dataset file are its measurement order, which the
  /// calibration and configuration_errors follow). One measurement per row, ok false where the
  /// truth has no equilibrium.
  std::vector<VirtualMeasurement> measure_dataset(const std::vector<JointVector>& rows);

 private:
  RobotDescription nominal_;
  RobotDescription truth_;
  PlatformLoad<double> load_;
  VirtualRobotOptions options_;
  std::mt19937_64 noise_rng_;
  ForwardSequence sequence_{RobotParams<double>()};  ///< on the truth, set by the constructor
};

}  // namespace pcr
