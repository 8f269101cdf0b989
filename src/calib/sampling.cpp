#include "pcr/calib/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "configuration_sets.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/robot_io.hpp"

namespace pcr {
namespace {

JointBox sampling_box(const RobotParams<double>& robot, const SamplingOptions& options) {
  const int n = robot.num_limbs;
  JointBox box;
  box.lo.resize(n);
  box.hi.resize(n);
  for (int i = 0; i < n; ++i) {
    box.lo(i) = robot.limb(i).q_min;
    box.hi(i) = robot.limb(i).q_max;
  }
  if (options.box_min.size() != 0 || options.box_max.size() != 0) {
    if (options.box_min.size() != n || options.box_max.size() != n) {
      throw InputError("sampling box: expected " + std::to_string(n) +
                       " lower and upper bounds, got " + std::to_string(options.box_min.size()) +
                       " and " + std::to_string(options.box_max.size()));
    }
    box.lo = options.box_min;
    box.hi = options.box_max;
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(box.lo(i)) || !std::isfinite(box.hi(i)) || !(box.lo(i) < box.hi(i))) {
      std::ostringstream msg;
      msg << "sampling box: joint q" << i + 1 << " range [" << box.lo(i) << ", " << box.hi(i)
          << "] is empty or not finite";
      throw InputError(msg.str());
    }
    const LimbParams<double>& limb = robot.limb(i);
    if (!limb.within_stroke(box.lo(i)) || !limb.within_stroke(box.hi(i))) {
      std::ostringstream msg;
      msg << "sampling box: joint q" << i + 1 << " range [" << box.lo(i) << ", " << box.hi(i)
          << "] m is not a sub-interval of its stroke q_range [" << limb.q_min << ", " << limb.q_max
          << "] m";
      throw InputError(msg.str());
    }
  }
  return box;
}

/// The planar admission test: FK on the home branch (the first point from home, every later one by
/// a straight continuation from the accepted point it was drawn around, itself reached from home),
/// and the strain limit.
class PlanarAdmission {
 public:
  PlanarAdmission(const RobotParams<double>& robot, const SamplingOptions& options)
      : robot_(robot), options_(options) {}

  bool operator()(const Eigen::VectorXd& q, int from, AdmissionCounts* counts) {
    if (from < 0) solutions_.clear();  // a new run
    const JointVector joints = q;
    ForwardSolution fk =
        from < 0 ? forward_kinematics(robot_, joints, options_.solver, options_.load)
                 : forward_kinematics(robot_, joints, solutions_[static_cast<std::size_t>(from)],
                                      options_.solver, options_.load);
    ++counts->candidates;
    if (!fk.summary.converged()) {
      ++counts->rejected_fk;
      return false;
    }
    if (!(fk.summary.max_strain <= options_.strain_limit)) {
      ++counts->rejected_strain;
      return false;
    }
    solutions_.push_back(fk);
    return true;
  }

 private:
  const RobotParams<double>& robot_;
  const SamplingOptions& options_;
  std::vector<ForwardSolution> solutions_;  // warm starts, in the run's order of acceptance
};

}  // namespace

bool admissible_configuration(const RobotParams<double>& robot, const JointVector& q,
                              double strain_limit, const SolverOptions& solver,
                              const PlatformLoad<double>& load, ForwardSolution* solution) {
  std::string error;
  if (!kStrainLimitRange.check(strain_limit, &error) || !solver.is_valid(&error)) {
    throw InputError("admissible_configuration: " + error);
  }
  ForwardSolution fk = forward_kinematics(robot, q, solver, load);
  const bool ok = fk.summary.converged() && fk.summary.max_strain <= strain_limit;
  if (solution) *solution = fk;
  return ok;
}

SamplingResult poisson_disc_sample(const RobotParams<double>& robot,
                                   const SamplingOptions& options) {
  if (robot.num_limbs < 1 || robot.num_limbs > kMaxLimbs) {
    throw InputError("poisson_disc_sample: invalid number of limbs " +
                     std::to_string(robot.num_limbs));
  }
  require_valid(options, "poisson_disc_sample");
  const JointBox box = sampling_box(robot, options);
  SamplingResult result;
  result.box_min = box.lo;
  result.box_max = box.hi;
  PlanarAdmission admission(robot, options);
  const PoissonDiscDraw draw =
      poisson_disc_draw(box, options.count, options.min_distance, options.seed, options.attempts,
                        std::ref(admission));
  if (options.min_distance <= 0 && draw.points.empty()) {
    throw InputError("poisson_disc_sample: could not find " + std::to_string(options.count) +
                     " admissible configurations (FK converged, strain <= " +
                     std::to_string(options.strain_limit) + ") in the box");
  }
  result.min_distance = draw.radius;
  result.candidates = draw.counts.candidates;
  result.rejected_fk = draw.counts.rejected_fk;
  result.rejected_strain = draw.counts.rejected_strain;
  std::vector<JointVector> points(draw.points.begin(), draw.points.end());
  result.complete = static_cast<int>(points.size()) >= options.count;
  if (result.complete) points.resize(static_cast<std::size_t>(options.count));
  result.configurations = std::move(points);
  return result;
}

std::string sampling_design_name(SamplingDesign design) {
  return design == SamplingDesign::kDOptimal ? "d-optimal" : "poisson-disc";
}

SamplingDesign parse_sampling_design(const std::string& name) {
  for (SamplingDesign design : {SamplingDesign::kPoissonDisc, SamplingDesign::kDOptimal}) {
    if (name == sampling_design_name(design)) return design;
  }
  throw InputError("sampling design: expected poisson-disc or d-optimal, got '" +
                   name.substr(0, 60) + "'");
}

DesignResult d_optimal_design(const RobotDescription& robot,
                              const std::vector<JointVector>& candidates, int count,
                              const SamplingOptions& options) {
  if (!robot.uncertainty) {
    throw InputError("d-optimal design: robot '" + robot.name +
                     "' has no uncertainty section (the half-widths scale the parameters)");
  }
  require_valid(options, "d-optimal design");
  const RobotParams<double>& nominal = robot.params;
  const std::vector<double> h = parameter_half_widths(*robot.uncertainty, nominal.num_limbs);
  std::vector<int> free;
  for (std::size_t k = 0; k < h.size(); ++k) {
    if (h[k] > 0) free.push_back(static_cast<int>(k));
  }
  const Eigen::Index f = static_cast<Eigen::Index>(free.size());
  DesignResult result;
  result.parameters = static_cast<int>(f);

  // Scaled, whitened rows of every candidate FK reaches on the nominal robot.
  std::vector<int> usable;
  Eigen::MatrixXd stacked(3 * static_cast<Eigen::Index>(candidates.size()), f);
  Eigen::MatrixXd J;
  for (std::size_t j = 0; j < candidates.size(); ++j) {
    if (!measurement_jacobian(nominal, candidates[j], options.noise_position / options.noise_angle,
                              options.noise_position, &J) ||
        !J.allFinite()) {
      ++result.failed;
      continue;
    }
    const Eigen::Index row = 3 * static_cast<Eigen::Index>(usable.size());
    for (Eigen::Index c = 0; c < f; ++c) {
      const int k = free[static_cast<std::size_t>(c)];
      stacked.block(row, c, 3, 1) = J.col(k) * h[static_cast<std::size_t>(k)];
    }
    usable.push_back(static_cast<int>(j));
  }
  stacked.conservativeResize(3 * static_cast<Eigen::Index>(usable.size()), f);
  if (count < 1 || count > static_cast<int>(usable.size())) {
    throw InputError("d-optimal design: cannot choose " + std::to_string(count) + " of " +
                     std::to_string(usable.size()) + " usable candidates (" +
                     std::to_string(result.failed) + " without an FK solution)");
  }

  const GreedyDesign greedy = greedy_d_optimal(stacked, 3, count);
  for (int j : greedy.selected) result.selected.push_back(usable[static_cast<std::size_t>(j)]);
  result.dimension = greedy.dimension;
  result.rank = greedy.rank;
  result.log_det = greedy.log_det;
  return result;
}

ConfigurationSets sample_configurations(const RobotDescription& robot,
                                        const SamplingOptions& options, int validation_count) {
  require_valid(options, "sample_configurations");
  return internal::sample_configuration_sets<ConfigurationSets>(
      "sample_configurations", options, validation_count,
      [&](const SamplingOptions& draw) { return poisson_disc_sample(robot.params, draw); },
      [&](const std::vector<JointVector>& candidates, int count) {
        return d_optimal_design(robot, candidates, count, options);
      });
}

void split_configurations(const std::vector<JointVector>& all, int first_count,
                          std::vector<JointVector>* first, std::vector<JointVector>* rest) {
  if (first_count < 0 || first_count > static_cast<int>(all.size())) {
    throw InputError("split_configurations: cannot take " + std::to_string(first_count) + " of " +
                     std::to_string(all.size()) + " configurations");
  }
  if (first) first->assign(all.begin(), all.begin() + first_count);
  if (rest) rest->assign(all.begin() + first_count, all.end());
}

}  // namespace pcr
