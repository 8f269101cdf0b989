#pragma once
// Joint configurations by Poisson-disc sampling (Bridson 2007) in the n-dimensional joint box,
// restricted to the reachable, safe part of it (the calibration's configurations):
// - FK converges on the home branch: the first point is solved from home (q = 0), every later one
//   by continuation from the accepted point that spawned it (a chain of straight paths from home);
// - the maximal bending strain over the rods stays below a limit (default 1 %).
// Every returned point is at least `radius` away (Euclidean, in m) from every other one.
//
// Exactly `count` points are returned: Bridson's algorithm yields a maximal set for a radius; the
// radius (when not given) starts from the box volume and is corrected with the measured count
// (N ~ r^-n, usually 2 or 3 runs) until the maximal set holds `count` to 1.6 `count` points; a
// seeded shuffle then keeps `count` of them (a subset of a Poisson-disc set is still one).
// Calibration and validation sets are made disjoint by drawing them together (count = 99 + 56)
// and splitting the shuffled set (split_configurations).
//
// D-optimal design (SamplingDesign::kDOptimal): the calibration configurations are chosen for
// identifiability instead of spread. From a Poisson-disc candidate set (kDesignCandidateFactor x
// count points, radius chosen from that count), the greedy choice maximises
//   log det(F_S + eps F_C)   on the identifiable subspace,
// F_S = sum over the chosen configurations of J_j^T J_j, J_j the identification Jacobian of
// configuration j at the nominal robot: the calibrator's whitened residual (measurement_jacobian:
// rows divided by the position noise, the angle row by the angle noise), columns scaled by the
// parameter's uncertainty half-width (the sensitivity analysis' units), restricted to the
// parameters with a nonzero half-width (those the default last stage frees); the greedy choice,
// its identifiable subspace (the seven gauge directions drop out) and its regularisation are
// greedy_d_optimal's (pcr/calib/experiment_design.hpp, shared with the spatial sampler). The log
// det reported is the chosen set's, computed afresh. Ties go to the lower candidate index, so the
// choice is deterministic for a seed. With a validation set, that set is
// the Poisson-disc one (the same as for kPoissonDisc with the same seed: it measures accuracy
// over the workspace) and candidates closer to it than the candidates' own radius are left out.

#include <cstdint>
#include <string>
#include <vector>

#include "pcr/calib/experiment_design.hpp"
#include "pcr/calib/virtual_robot.hpp"
#include "pcr/input_error.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/robot_description.hpp"
#include "pcr/trajectory.hpp"

namespace pcr {

inline constexpr int kDefaultCalibrationCount = 99;  ///< the paper's calibration set
inline constexpr int kDefaultValidationCount = 56;   ///< the paper's validation set

/// Solver settings for the admissibility test: a smaller budget than the defaults, because the
/// candidates that fail (outside the reachable set, where the rods would have to stretch) cost the
/// whole continuation budget. Candidates needing a longer continuation are treated as unreachable.
/// The test needs convergence and the strain, not nanometres: a fixed 24 RK4 steps per rod puts the
/// strain within 6e-6 (of the 1e-2 limit) and the pose within 0.6 um of the exact model on the
/// default robot, and costs a third of the adaptive count, which refines towards the folds where
/// the rejected candidates end.
inline SolverOptions sampling_solver_options() {
  SolverOptions options;
  options.rod_steps = 24;
  options.max_iterations = 10;
  options.max_line_search = 8;
  options.max_continuation_steps = 32;
  options.min_continuation_step = 1.0 / 256.0;
  return options;
}

/// How the calibration configurations are chosen (see above).
enum class SamplingDesign {
  kPoissonDisc,  ///< spread: a Poisson-disc sample of the reachable joint box
  kDOptimal,     ///< identifiability: greedy D-optimal choice among Poisson-disc candidates
};

/// "poisson-disc" or "d-optimal".
std::string sampling_design_name(SamplingDesign design);
/// Throws InputError naming the value and the accepted names.
SamplingDesign parse_sampling_design(const std::string& name);

/// D-optimal: candidates per chosen configuration.
inline constexpr int kDesignCandidateFactor = 10;

struct SamplingOptions {
  int count = kDefaultCalibrationCount;
  std::uint64_t seed = 1;
  /// Poisson-disc radius (m). <= 0: chosen from the count (see above).
  double min_distance = 0.0;
  /// Sub-box of the joint space (m). Empty: the strokes [q_min, q_max] of each limb.
  JointVector box_min, box_max;
  double strain_limit = kDefaultStrainLimit;  ///< max bending strain |kappa| d / 2
  int attempts = 30;                          ///< Bridson's k: candidates per active point
  SolverOptions solver = sampling_solver_options();
  PlatformLoad<double> load;
  /// Calibration configurations: spread or D-optimal (sample_configurations).
  SamplingDesign design = SamplingDesign::kPoissonDisc;
  /// D-optimal: size of the candidate set; <= 0: kDesignCandidateFactor x count.
  int candidates = 0;
  /// D-optimal: measurement noise (standard deviations) that weighs the rows.
  double noise_position = kDefaultNoisePosition;  ///< m
  double noise_angle = kDefaultNoiseAngle;        ///< rad

  static constexpr OptionRange kCount{"count", 1, 1e7};
  static constexpr OptionRange kMinDistance{"min_distance", 0, 0.1, "m"};  ///< 0: from the count
  static constexpr OptionRange kAttempts{"attempts", 1, 10000};
  static constexpr OptionRange kCandidates{"candidates", 0, 1e7};  ///< 0: from the count
  /// The D-optimal design weighs the rows by the noise: it may not be zero.
  static constexpr OptionRange kNoisePosition{"noise_position", 1e-12, 0.01, "m"};
  static constexpr OptionRange kNoiseAngle{"noise_angle", 1e-12, 0.1, "rad"};
  /// Each bound of box_min and box_max: beyond a metre, a unit typo (mm typed as m).
  static constexpr OptionRange kBox{"box", -1, 1, "m"};
  /// As SolverOptions::is_valid, for these fields, the solver's and the load's (the box is also
  /// checked against the robot's strokes by the sampler).
  bool is_valid(std::string* error = nullptr) const {
    return kCount.check(count, error) && kMinDistance.check(min_distance, error) &&
           kStrainLimitRange.check(strain_limit, error) && kAttempts.check(attempts, error) &&
           kCandidates.check(candidates, error) && kNoisePosition.check(noise_position, error) &&
           kNoiseAngle.check(noise_angle, error) && box_is_valid(box_min, "box_min", error) &&
           box_is_valid(box_max, "box_max", error) && solver.is_valid(error) &&
           load.is_valid(error);
  }
  /// Whether every bound of `box` lies in kBox; the message names `field` ("box_max").
  static bool box_is_valid(const JointVector& box, const char* field, std::string* error) {
    const OptionRange range{field, kBox.lo, kBox.hi, kBox.unit};
    for (Eigen::Index i = 0; i < box.size(); ++i) {
      if (!range.check(box(i), error)) return false;
    }
    return true;
  }
};

struct SamplingResult {
  std::vector<JointVector> configurations;  ///< exactly `count` points (or fewer, see `complete`)
  double min_distance = 0.0;                ///< the radius used (m)
  JointVector box_min, box_max;             ///< the box used (m)
  int candidates = 0;                       ///< FK evaluations of the final run
  int rejected_fk = 0;                      ///< of which FK failed
  int rejected_strain = 0;                  ///< of which the strain limit was exceeded
  bool complete = false;  ///< false: fewer than `count` admissible points for the given radius
};

/// True when FK from home converges at q and the max strain is <= strain_limit.
bool admissible_configuration(const RobotParams<double>& robot, const JointVector& q,
                              double strain_limit, const SolverOptions& solver = SolverOptions(),
                              const PlatformLoad<double>& load = PlatformLoad<double>(),
                              ForwardSolution* solution = nullptr);

/// Throws InputError on a bad box, count or radius.
SamplingResult poisson_disc_sample(const RobotParams<double>& robot,
                                   const SamplingOptions& options);

/// The D-optimal choice among candidates (see above).
struct DesignResult {
  std::vector<int> selected;  ///< indices into the candidates, in the order chosen
  int parameters = 0;         ///< parameters with a nonzero half-width
  int dimension = 0;          ///< of the identifiable subspace (rank of all the candidates)
  int rank = 0;               ///< of the chosen set on that subspace (= dimension: all identified)
  /// log det of the chosen set's scaled information on the identifiable subspace (orthonormal
  /// basis), computed afresh from the chosen rows (not the running value of the greedy choice).
  double log_det = 0;
  int failed = 0;  ///< candidates without an FK solution on the nominal robot (never chosen)
};

/// Chooses `count` of `candidates` for options.noise_position and noise_angle. Throws InputError
/// when the description has no uncertainty section, or count exceeds the usable candidates.
DesignResult d_optimal_design(const RobotDescription& robot,
                              const std::vector<JointVector>& candidates, int count,
                              const SamplingOptions& options = SamplingOptions());

/// Calibration configurations by options.design and, with validation_count > 0, a disjoint
/// Poisson-disc validation set.
struct ConfigurationSets {
  std::vector<JointVector> calibration;  ///< options.count configurations
  std::vector<JointVector> validation;   ///< validation_count configurations
  /// The Poisson-disc draw of count + validation_count (D-optimal: of validation_count; not
  /// drawn when D-optimal without validation).
  SamplingResult spread;
  /// D-optimal: the candidate draw, less the candidates near the validation set (the
  /// configurations the design chose from: design.selected indexes them).
  SamplingResult candidates;
  DesignResult design;  ///< D-optimal: the choice
};

/// Throws InputError on bad options and std::runtime_error when the box does not hold enough
/// admissible configurations.
ConfigurationSets sample_configurations(const RobotDescription& robot,
                                        const SamplingOptions& options, int validation_count = 0);

/// First `first_count` configurations and the rest (the sampler's order is already shuffled).
void split_configurations(const std::vector<JointVector>& all, int first_count,
                          std::vector<JointVector>* first, std::vector<JointVector>* rest);

}  // namespace pcr
