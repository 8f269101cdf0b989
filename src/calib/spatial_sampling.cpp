#include "pcr/calib/spatial_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "configuration_sets.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"  // spatial_default_noise_position
#include "pcr/csv_io.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace pcr {
namespace {

JointBox spatial_sampling_box(int n, const SpatialSamplingOptions& options) {
  JointBox box;
  box.lo = Eigen::VectorXd::Constant(n, kSpatialDefaultJointMin);
  box.hi = Eigen::VectorXd::Constant(n, kSpatialDefaultJointMax);
  if (options.box_min.size() != 0 || options.box_max.size() != 0) {
    if (options.box_min.size() != n || options.box_max.size() != n) {
      throw InputError("spatial sampling box: expected " + std::to_string(n) +
                       " lower and upper bounds, got " + std::to_string(options.box_min.size()) +
                       " and " + std::to_string(options.box_max.size()));
    }
    box.lo = options.box_min;
    box.hi = options.box_max;
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(box.lo(i)) || !std::isfinite(box.hi(i)) || !(box.lo(i) < box.hi(i))) {
      std::ostringstream msg;
      msg << "spatial sampling box: joint q" << i + 1 << " range [" << box.lo(i) << ", "
          << box.hi(i) << "] is empty or not finite";
      throw InputError(msg.str());
    }
  }
  return box;
}

SolverOptions with_stability(SolverOptions solver) {
  solver.check_stability = true;
  return solver;
}

enum class Verdict { kAdmissible, kNoFk, kStrain, kUnstable };

Verdict verdict_of(const SpatialForwardSolution& fk, double strain_limit) {
  if (!fk.summary.converged()) return Verdict::kNoFk;
  if (!(fk.summary.max_strain <= strain_limit)) return Verdict::kStrain;
  if (fk.summary.stability != Stability::kStable) return Verdict::kUnstable;
  return Verdict::kAdmissible;
}

/// The admission test of the spatial sampler (see the header): warm from the point drawn around.
class SpatialAdmission {
 public:
  SpatialAdmission(const SpatialRobotParams<double>& robot, const SpatialSamplingOptions& options)
      : robot_(robot), options_(options), solver_(with_stability(options.solver)) {}

  bool operator()(const Eigen::VectorXd& q, int from, AdmissionCounts* counts) {
    if (from < 0) solutions_.clear();  // a new run
    const SpatialJointVector joints = q;
    SpatialForwardSolution fk =
        from < 0 ? spatial_forward_kinematics(robot_, joints, solver_)
                 : spatial_forward_kinematics(robot_, joints,
                                              solutions_[static_cast<std::size_t>(from)], solver_);
    ++counts->candidates;
    switch (verdict_of(fk, options_.strain_limit)) {
      case Verdict::kNoFk:
        ++counts->rejected_fk;
        return false;
      case Verdict::kStrain:
        ++counts->rejected_strain;
        return false;
      case Verdict::kUnstable:
        ++counts->rejected_unstable;
        return false;
      case Verdict::kAdmissible:
        break;
    }
    solutions_.push_back(std::move(fk));
    return true;
  }

 private:
  const SpatialRobotParams<double>& robot_;
  const SpatialSamplingOptions& options_;
  SolverOptions solver_;
  std::vector<SpatialForwardSolution> solutions_;  // warm starts, in the run's order of acceptance
};

}  // namespace

bool spatial_admissible_configuration(const SpatialRobotParams<double>& robot,
                                      const SpatialJointVector& q, double strain_limit,
                                      const SolverOptions& solver,
                                      SpatialForwardSolution* solution) {
  std::string error;
  if (!kStrainLimitRange.check(strain_limit, &error) || !solver.is_valid(&error)) {
    throw InputError("spatial_admissible_configuration: " + error);
  }
  const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q, with_stability(solver));
  if (solution) *solution = fk;
  return verdict_of(fk, strain_limit) == Verdict::kAdmissible;
}

SpatialSamplingResult spatial_poisson_disc_sample(const SpatialRobotParams<double>& robot,
                                                  const SpatialSamplingOptions& options) {
  if (robot.num_rods < 1 || robot.num_rods > kMaxSpatialRods) {
    throw InputError("spatial_poisson_disc_sample: invalid number of rods " +
                     std::to_string(robot.num_rods));
  }
  require_valid(options, "spatial_poisson_disc_sample");
  const JointBox box = spatial_sampling_box(robot.num_rods, options);
  SpatialSamplingResult result;
  result.box_min = box.lo;
  result.box_max = box.hi;
  SpatialAdmission admission(robot, options);
  const PoissonDiscDraw draw =
      poisson_disc_draw(box, options.count, options.min_distance, options.seed, options.attempts,
                        std::ref(admission));
  if (options.min_distance <= 0 && draw.points.empty()) {
    throw InputError("spatial_poisson_disc_sample: could not find " +
                     std::to_string(options.count) +
                     " admissible configurations (FK converged, strain <= " +
                     format_double(options.strain_limit) + ", stable) in the box");
  }
  result.min_distance = draw.radius;
  result.counts = draw.counts;
  result.configurations.assign(draw.points.begin(), draw.points.end());
  result.complete = static_cast<int>(result.configurations.size()) >= options.count;
  if (result.complete) result.configurations.resize(static_cast<std::size_t>(options.count));
  return result;
}

DesignResult spatial_d_optimal_design(const SpatialRobotDescription& robot,
                                      const std::vector<SpatialJointVector>& candidates, int count,
                                      const SpatialSamplingOptions& options) {
  if (!robot.uncertainty) {
    throw InputError("spatial d-optimal design: robot '" + robot.name +
                     "' has no uncertainty section (the half-widths scale the parameters)");
  }
  require_valid(options, "spatial d-optimal design");
  const int n = robot.params.num_rods;
  const double noise_position = std::isnan(options.noise_position)
                                    ? spatial_default_noise_position(robot.params)
                                    : options.noise_position;
  std::vector<int> free;
  std::vector<double> h;
  for (int k = 0; k < num_spatial_parameters(n); ++k) {
    const double w = spatial_half_width(*robot.uncertainty, spatial_parameter_id(k, n));
    if (w > 0) {
      free.push_back(k);
      h.push_back(w);
    }
  }
  const Eigen::Index f = static_cast<Eigen::Index>(free.size());
  DesignResult result;
  result.parameters = static_cast<int>(f);

  // Whitened rows in half-width units of every candidate FK reaches on the nominal robot.
  SolverOptions fk = options.solver;
  fk.check_stability = false;  // the derivatives do not need it
  std::vector<int> usable;
  Eigen::MatrixXd stacked(6 * static_cast<Eigen::Index>(candidates.size()), f);
  Eigen::MatrixXd J;
  for (std::size_t j = 0; j < candidates.size(); ++j) {
    if (!spatial_pose_parameter_jacobian(robot, candidates[j], SpatialSensitivityPose::kMeasured,
                                         &J, fk)) {
      ++result.failed;
      continue;
    }
    const Eigen::Index row = 6 * static_cast<Eigen::Index>(usable.size());
    for (Eigen::Index c = 0; c < f; ++c) {
      const Eigen::Index k = free[static_cast<std::size_t>(c)];
      const double scale = h[static_cast<std::size_t>(c)];
      stacked.block(row, c, 3, 1) = J.block(0, k, 3, 1) * (scale / noise_position);
      stacked.block(row + 3, c, 3, 1) = J.block(3, k, 3, 1) * (scale / options.noise_angle);
    }
    usable.push_back(static_cast<int>(j));
  }
  stacked.conservativeResize(6 * static_cast<Eigen::Index>(usable.size()), f);
  if (count < 1 || count > static_cast<int>(usable.size())) {
    throw InputError("spatial d-optimal design: cannot choose " + std::to_string(count) + " of " +
                     std::to_string(usable.size()) + " usable candidates (" +
                     std::to_string(result.failed) + " without an FK solution)");
  }
  const GreedyDesign greedy = greedy_d_optimal(stacked, 6, count);
  for (int j : greedy.selected) result.selected.push_back(usable[static_cast<std::size_t>(j)]);
  result.dimension = greedy.dimension;
  result.rank = greedy.rank;
  result.log_det = greedy.log_det;
  return result;
}

SpatialConfigurationSets spatial_sample_configurations(const SpatialRobotDescription& robot,
                                                       const SpatialSamplingOptions& options,
                                                       int validation_count) {
  require_valid(options, "spatial_sample_configurations");
  return internal::sample_configuration_sets<SpatialConfigurationSets>(
      "spatial_sample_configurations", options, validation_count,
      [&](const SpatialSamplingOptions& draw) {
        return spatial_poisson_disc_sample(robot.params, draw);
      },
      [&](const std::vector<SpatialJointVector>& candidates, int count) {
        return spatial_d_optimal_design(robot, candidates, count, options);
      });
}

}  // namespace pcr
