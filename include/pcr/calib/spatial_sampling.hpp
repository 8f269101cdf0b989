#pragma once
// Calibration configurations of a spatial robot (Mauze et al. 2021, Section 5.1, in 3-D): the
// spatial counterpart of pcr/calib/sampling.hpp, on its robot-free parts
// (pcr/calib/experiment_design.hpp).
//
// - Box: the joint box given, else [kSpatialDefaultJointMin, kSpatialDefaultJointMax] (0 to 10 mm)
//   per rod: a spatial description has no strokes.
// - Admissible: FK converges (the first point of a run cold, from straight rods; every later one
//   warm from the accepted point it was drawn around, the sampler's chain of short paths), the
//   largest bending strain is within strain_limit (SolverSummary::max_strain) and the equilibrium
//   is stable (the spatial stability check, always on here: SolverOptions::check_stability).
// - Poisson-disc (SamplingDesign::kPoissonDisc): exactly `count` points at least the radius apart,
//   the radius given or chosen from the count (poisson_disc_draw).
// - D-optimal (SamplingDesign::kDOptimal): greedy_d_optimal among a Poisson-disc candidate set
//   (`candidates`, default kDesignCandidateFactor x count), on the whitened rows of each
//   candidate's measured-pose Jacobian (spatial_pose_parameter_jacobian, kMeasured: six rows,
//   the position divided by noise_position and the rotation vector by noise_angle), columns the
//   parameters with a nonzero half-width, in half-width units (as the spatial calibration's
//   unknowns). The Jacobians come from cold FK at the nominal robot: candidates without a
//   solution there are never chosen (DesignResult::failed).
// - Validation (validation_count > 0): drawn with the calibration set as one Poisson-disc set and
//   split (disjoint, spaced alike); with D-optimal, the candidates closer to the validation set
//   than their own radius are left out.

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "pcr/calib/experiment_design.hpp"
#include "pcr/calib/sampling.hpp"  // SamplingDesign, DesignResult, the planar defaults
#include "pcr/calib/spatial_sensitivity.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace pcr {

struct SpatialSamplingOptions {
  int count = kDefaultCalibrationCount;
  std::uint64_t seed = 1;
  /// Poisson-disc radius (m). <= 0: chosen from the count.
  double min_distance = 0.0;
  /// Joint box (m). Empty: kSpatialDefaultJointMin to kSpatialDefaultJointMax per rod.
  SpatialJointVector box_min, box_max;
  double strain_limit = kDefaultStrainLimit;  ///< max bending strain |kappa| d / 2
  int attempts = 30;                          ///< Bridson's k: candidates per active point
  /// FK of the admission test (check_stability is forced on) and of the D-optimal Jacobians.
  SolverOptions solver;
  SamplingDesign design = SamplingDesign::kPoissonDisc;
  /// D-optimal: size of the candidate set; <= 0: kDesignCandidateFactor x count.
  int candidates = 0;
  /// D-optimal: measurement noise weighing the rows. NaN: spatial_default_noise_position of the
  /// robot (the paper's repeatability scaled to its rod length).
  double noise_position = std::numeric_limits<double>::quiet_NaN();  ///< m
  double noise_angle = kDefaultNoiseAngle;                           ///< rad

  /// As SamplingOptions::is_valid (the same ranges; a NaN noise_position is the default).
  bool is_valid(std::string* error = nullptr) const {
    return SamplingOptions::kCount.check(count, error) &&
           SamplingOptions::kMinDistance.check(min_distance, error) &&
           kStrainLimitRange.check(strain_limit, error) &&
           SamplingOptions::kAttempts.check(attempts, error) &&
           SamplingOptions::kCandidates.check(candidates, error) &&
           (std::isnan(noise_position) ||
            SamplingOptions::kNoisePosition.check(noise_position, error)) &&
           SamplingOptions::kNoiseAngle.check(noise_angle, error) &&
           box_is_valid(box_min, "box_min", error) && box_is_valid(box_max, "box_max", error) &&
           solver.is_valid(error);
  }
  static bool box_is_valid(const SpatialJointVector& box, const char* field, std::string* error) {
    const OptionRange& b = SamplingOptions::kBox;
    const OptionRange range{field, b.lo, b.hi, b.unit};
    for (Eigen::Index i = 0; i < box.size(); ++i) {
      if (!range.check(box(i), error)) return false;
    }
    return true;
  }
};

struct SpatialSamplingResult {
  std::vector<SpatialJointVector> configurations;  ///< `count` points (fewer: see `complete`)
  double min_distance = 0.0;                       ///< the radius used (m)
  SpatialJointVector box_min, box_max;             ///< the box used (m)
  AdmissionCounts counts;                          ///< of the run kept
  bool complete = false;  ///< false: fewer than `count` admissible points for the given radius
};

/// True when cold FK converges at q, its max strain is <= strain_limit and its equilibrium is
/// stable (solver.check_stability forced on). The admission test, for an independent check.
bool spatial_admissible_configuration(const SpatialRobotParams<double>& robot,
                                      const SpatialJointVector& q, double strain_limit,
                                      const SolverOptions& solver = SolverOptions(),
                                      SpatialForwardSolution* solution = nullptr);

/// Throws InputError on bad options, a bad box, or no admissible set of `count` (radius chosen).
SpatialSamplingResult spatial_poisson_disc_sample(const SpatialRobotParams<double>& robot,
                                                  const SpatialSamplingOptions& options);

/// Chooses `count` of `candidates` (see above). Throws InputError when the description has no
/// uncertainty section, or count exceeds the usable candidates.
DesignResult spatial_d_optimal_design(const SpatialRobotDescription& robot,
                                      const std::vector<SpatialJointVector>& candidates, int count,
                                      const SpatialSamplingOptions& options = {});

struct SpatialConfigurationSets {
  std::vector<SpatialJointVector> calibration;  ///< options.count configurations
  std::vector<SpatialJointVector> validation;   ///< validation_count configurations
  SpatialSamplingResult spread;      ///< the Poisson-disc draw (not drawn: D-optimal alone)
  SpatialSamplingResult candidates;  ///< D-optimal: the candidates chosen from
  DesignResult design;               ///< D-optimal: the choice (indices into candidates)
};

/// Calibration configurations by options.design and, with validation_count > 0, a disjoint
/// Poisson-disc validation set. Throws InputError on bad options and std::runtime_error when the
/// box does not hold enough admissible configurations.
SpatialConfigurationSets spatial_sample_configurations(const SpatialRobotDescription& robot,
                                                       const SpatialSamplingOptions& options,
                                                       int validation_count = 0);

}  // namespace pcr
