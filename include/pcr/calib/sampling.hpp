#pragma once
// Joint configurations by Poisson-disc sampling (Bridson 2007) in the n-dimensional joint box,
// restricted to the reachable, safe part of it (issue 3, section 2):
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

#include <cstdint>
#include <vector>

#include "pcr/kinematics.hpp"

namespace pcr {

inline constexpr int kDefaultCalibrationCount = 99;  ///< the paper's calibration set
inline constexpr int kDefaultValidationCount = 56;   ///< the paper's validation set

/// Solver settings for the admissibility test: a smaller budget than the defaults, because the
/// candidates that fail (outside the reachable set, where the rods would have to stretch) cost the
/// whole continuation budget. Candidates needing a longer continuation are treated as unreachable.
inline SolverOptions sampling_solver_options() {
  SolverOptions options;
  options.max_iterations = 10;
  options.max_line_search = 8;
  options.max_continuation_steps = 32;
  options.min_continuation_step = 1.0 / 256.0;
  return options;
}

struct SamplingOptions {
  int count = kDefaultCalibrationCount;
  std::uint64_t seed = 1;
  /// Poisson-disc radius (m). <= 0: chosen from the count (see above).
  double min_distance = 0.0;
  /// Sub-box of the joint space (m). Empty: the strokes [q_min, q_max] of each limb.
  JointVector box_min, box_max;
  double strain_limit = 0.01;  ///< max bending strain |kappa| d / 2
  int attempts = 30;           ///< Bridson's k: candidates per active point
  SolverOptions solver = sampling_solver_options();
  PlatformLoad<double> load;
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

/// First `first_count` configurations and the rest (the sampler's order is already shuffled).
void split_configurations(const std::vector<JointVector>& all, int first_count,
                          std::vector<JointVector>* first, std::vector<JointVector>* rest);

}  // namespace pcr
