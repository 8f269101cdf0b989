#pragma once
// A simulated stand-in for a real spatial robot (pcr/calib/virtual_robot.hpp's counterpart): a
// "true" robot drawn from a nominal spatial description inside its uncertainty intervals
// (SpatialUncertainty, pcr/spatial/parameters.hpp), and a measuring system that reports the marker
// pose ^S T_M = (^W T_S)^-1 ^W T_P(q) (^M T_P)^-1 with Gaussian noise.
//
// How the truth is drawn (seeded, std::mt19937_64, reproducible across runs of the same build):
// every flat deviation U(-h, h), h its half-width (0 without an uncertainty section); or, with
// truth_at_fraction f > 0, +- f h with the sign drawn (a truth in the corners of the intervals,
// where a bounded identification is hardest). E, G and d are drawn once for all rods from the
// first rod's intervals (one material, one wire), as the planar virtual robot does.
//
// The noise model: each position coordinate gets N(0, noise_position^2), and the orientation a
// turn exp([noise_angle xi]x) composed on the right (in the marker frame), xi ~ N(0, I3). The
// default scales the paper's repeatability (9.13 nm, 1.2 urad, on a robot of 30 mm rods) to the
// robot: positions by its mean rod length over 30 mm (a tracker's error grows with the volume it
// sees), angles unchanged.
//
// Unmodelled effects, each independent of the others: a payload (a mass the nominal model does
// not know, at P's origin), misaligned holes (an extra U(-h_m, h_m) on every base turn component,
// beyond the intervals), unequal rods (an extra, independent U(-h_d, h_d) on each rod's d, beyond
// the one wire's draw), and rods whose weight the model leaves out (the truth's density).
// pcr/calib/named_effects.hpp names them as pcr demo --effects does.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/spatial/sequence.hpp"

namespace pcr {

/// The length of the paper's rods, the scale its repeatability was measured at.
inline constexpr double kPaperRodLength = 30e-3;  ///< m

/// The paper's position repeatability scaled to `robot`: 9.13 nm times its mean rod length at
/// q = 0 over 30 mm (122 nm for the reference continuum Stewart-Gough robot).
double spatial_default_noise_position(const SpatialRobotParams<double>& robot);

struct SpatialUnmodelledEffects {
  double payload = 0.0;  ///< kg added at P's origin
  /// rad: each base turn component gets an extra U(-h, h) (0: none)
  double misalignment_half_width = 0.0;
  /// m: each rod's d gets an extra, independent U(-h, h) (0: none, one wire)
  double diameter_half_width = 0.0;
  /// kg/m^3: the truth's rod density (< 0: as described). A model that leaves the rods' weight
  /// out has density 0, and its truth this.
  double rod_density = -1.0;

  static constexpr OptionRange kPayload{"payload", 0, 1e3, "kg"};
  static constexpr OptionRange kMisalignmentHalfWidth{"misalignment_half_width", 0, 0.1, "rad"};
  static constexpr OptionRange kDiameterHalfWidth{"diameter_half_width", 0, 1e-3, "m"};
  static constexpr OptionRange kRodDensity{"rod_density", -1, 1e5, "kg/m^3"};
  bool is_valid(std::string* error = nullptr) const {
    return kPayload.check(payload, error, "effects.") &&
           kMisalignmentHalfWidth.check(misalignment_half_width, error, "effects.") &&
           kDiameterHalfWidth.check(diameter_half_width, error, "effects.") &&
           kRodDensity.check(rod_density, error, "effects.");
  }
};

struct SpatialVirtualRobotOptions {
  std::uint64_t seed = 1;
  /// 0: the truth is drawn uniformly inside the intervals; f in (0, 1]: at +- f half-widths.
  double truth_at_fraction = 0.0;
  /// m, std of each position coordinate; NaN: spatial_default_noise_position of the robot.
  double noise_position = std::numeric_limits<double>::quiet_NaN();
  double noise_angle = 1.2e-6;  ///< rad, std of each turn component
  SpatialUnmodelledEffects effects;
  SolverOptions solver;

  static constexpr OptionRange kTruthAtFraction{"truth_at_fraction", 0, 1};
  static constexpr OptionRange kNoisePosition{"noise_position", 0, 0.01, "m"};
  static constexpr OptionRange kNoiseAngle{"noise_angle", 0, 0.1, "rad"};
  bool is_valid(std::string* error = nullptr) const {
    return kTruthAtFraction.check(truth_at_fraction, error) &&
           (std::isnan(noise_position) || kNoisePosition.check(noise_position, error)) &&
           kNoiseAngle.check(noise_angle, error) && effects.is_valid(error) &&
           solver.is_valid(error);
  }
};

/// One simulated measurement.
struct SpatialVirtualMeasurement {
  /// false: FK of the true robot has no solution at q, or only an unstable one (summary.status
  /// kUnstable: a real robot snaps off it, and is homed again)
  bool ok = false;
  SpatialPose<double> measured;  ///< ^S T_M with noise: what the measuring system reports
  SpatialPose<double> exact;     ///< ^S T_M without noise
  SpatialPose<double> platform;  ///< ^W T_P of the true robot
  SolverSummary summary;         ///< of the true robot's FK
};

class SpatialVirtualRobot {
 public:
  /// Draws the truth from `nominal` (throws InputError on invalid options or a robot it cannot
  /// draw: no rods, or a diameter or modulus drawn <= 0).
  SpatialVirtualRobot(const SpatialRobotDescription& nominal,
                      const SpatialVirtualRobotOptions& options = {});

  const SpatialRobotDescription& nominal() const { return nominal_; }
  /// The true description (with the nominal intervals); for tests and studies, never for the
  /// calibration.
  const SpatialRobotDescription& truth() const { return truth_; }
  const SpatialVirtualRobotOptions& options() const { return options_; }
  double noise_position() const { return noise_position_; }  ///< m, resolved

  /// Moves to q and measures: FK of the truth along the path from the last configuration (a
  /// SpatialForwardSequence in SequenceMode::kPath: continued from the last success, retried cold
  /// where that fails); the noise stream advances only on success. An unstable equilibrium is
  /// not measured; the robot is homed again.
  SpatialVirtualMeasurement measure(const SpatialJointVector& q);

  /// The robot goes back home: the next measurement starts there.
  void return_home() { sequence_.reset(); }

  /// An experiment: home, then each row in its order, one measurement per row.
  std::vector<SpatialVirtualMeasurement> measure_dataset(
      const std::vector<SpatialJointVector>& rows);

 private:
  SpatialRobotDescription nominal_;
  SpatialRobotDescription truth_;
  SpatialVirtualRobotOptions options_;
  double noise_position_ = 0.0;
  std::mt19937_64 noise_rng_;
  SpatialForwardSequence sequence_{SpatialRobotParams<double>()};
};

}  // namespace pcr
