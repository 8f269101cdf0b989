#include "pcr/calib/sampling.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "pcr/calib/calibrator.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/robot_io.hpp"

namespace pcr {
namespace {

struct Box {
  JointVector lo, hi;
  int dim() const { return static_cast<int>(lo.size()); }
  bool contains(const JointVector& q) const {
    for (int i = 0; i < dim(); ++i) {
      if (!(q(i) >= lo(i) && q(i) <= hi(i))) return false;
    }
    return true;
  }
  double volume() const {
    double v = 1.0;
    for (int i = 0; i < dim(); ++i) v *= hi(i) - lo(i);
    return v;
  }
};

Box sampling_box(const RobotParams<double>& robot, const SamplingOptions& options) {
  const int n = robot.num_limbs;
  Box box;
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

class Sampler {
 public:
  Sampler(const RobotParams<double>& robot, const SamplingOptions& options, const Box& box)
      : robot_(robot), options_(options), box_(box) {}

  /// One run of Bridson's algorithm with radius r: a maximal set of admissible points.
  std::vector<JointVector> run(double r, std::uint64_t seed, SamplingResult* stats) {
    std::seed_seq seq{seed, std::uint64_t{0x706f6973736f6e}};
    std::mt19937_64 rng(seq);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const int n = box_.dim();
    stats->candidates = stats->rejected_fk = stats->rejected_strain = 0;

    std::vector<JointVector> points;
    std::vector<ForwardSolution> solutions;  // warm starts: FK continues from the spawning point
    std::vector<std::size_t> active;
    // Seed point: uniform in the box until one is admissible.
    const int max_seed_tries = 1000;
    for (int t = 0; t < max_seed_tries && points.empty(); ++t) {
      JointVector q(n);
      for (int i = 0; i < n; ++i) q(i) = box_.lo(i) + (box_.hi(i) - box_.lo(i)) * unit(rng);
      ForwardSolution fk = forward_kinematics(robot_, q, options_.solver, options_.load);
      if (accept(fk, stats)) {
        points.push_back(q);
        solutions.push_back(fk);
        active.push_back(0);
      }
    }
    const double shell = std::pow(2.0, n) - 1.0;
    while (!active.empty()) {
      const std::size_t pick = static_cast<std::size_t>(unit(rng) * active.size()) % active.size();
      const JointVector centre = points[active[pick]];
      const ForwardSolution from = solutions[active[pick]];
      bool found = false;
      for (int k = 0; k < options_.attempts; ++k) {
        // Uniform in the spherical shell r <= |d| <= 2r.
        JointVector d(n);
        for (int i = 0; i < n; ++i) d(i) = gauss(rng);
        const double norm = d.norm();
        if (!(norm > 0)) continue;
        const double radius = r * std::pow(1.0 + shell * unit(rng), 1.0 / n);
        const JointVector q = centre + d * (radius / norm);
        if (!box_.contains(q)) continue;
        bool far = true;
        for (const JointVector& p : points) {
          if ((p - q).squaredNorm() < r * r) {
            far = false;
            break;
          }
        }
        if (!far) continue;
        // A straight continuation from an accepted point, itself reached from home: the path
        // q = 0 -> ... -> centre -> q stays on the home branch.
        ForwardSolution fk = forward_kinematics(robot_, q, from, options_.solver, options_.load);
        if (!accept(fk, stats)) continue;
        points.push_back(q);
        solutions.push_back(fk);
        active.push_back(points.size() - 1);
        found = true;
        break;
      }
      if (!found) {
        active[pick] = active.back();
        active.pop_back();
      }
    }
    // Seeded shuffle, so any prefix is spread over the whole region.
    std::shuffle(points.begin(), points.end(), rng);
    return points;
  }

 private:
  bool accept(const ForwardSolution& fk, SamplingResult* stats) const {
    ++stats->candidates;
    if (!fk.summary.converged()) {
      ++stats->rejected_fk;
      return false;
    }
    if (!(fk.summary.max_strain <= options_.strain_limit)) {
      ++stats->rejected_strain;
      return false;
    }
    return true;
  }

  const RobotParams<double>& robot_;
  const SamplingOptions& options_;
  Box box_;
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
  const Box box = sampling_box(robot, options);
  const int n = box.dim();
  Sampler sampler(robot, options, box);
  SamplingResult result;
  result.box_min = box.lo;
  result.box_max = box.hi;

  std::vector<JointVector> points;
  if (options.min_distance > 0) {
    result.min_distance = options.min_distance;
    points = sampler.run(options.min_distance, options.seed, &result);
  } else {
    // Radius from the count: a maximal Poisson-disc set of radius r holds about 0.7 V / r^n points
    // in 3-D (random sequential packing); the unreachable part of the box makes it fewer, so each
    // run corrects r with the measured count (N ~ r^-n). Each run costs thousands of FK solves:
    // accept the first set holding `count` to 1.6 `count` points.
    const double target = options.count * 1.2 + 1.0;
    double r = std::pow(0.5 * box.volume() / target, 1.0 / n);
    double best_r = 0.0;
    std::vector<JointVector> best;
    SamplingResult best_stats;
    for (int iteration = 0; iteration < 8; ++iteration) {
      SamplingResult stats;
      std::vector<JointVector> set = sampler.run(r, options.seed, &stats);
      const double count = static_cast<double>(set.size());
      if (static_cast<int>(set.size()) >= options.count && r > best_r) {
        best_r = r;
        best = std::move(set);
        best_stats = stats;
        if (count <= 1.6 * options.count) break;
      }
      const double ratio = std::max(count, 1.0) / target;
      r *= std::clamp(std::pow(ratio, 1.0 / n), 0.5, 2.0);
    }
    if (best.empty()) {
      throw InputError("poisson_disc_sample: could not find " + std::to_string(options.count) +
                       " admissible configurations (FK converged, strain <= " +
                       std::to_string(options.strain_limit) + ") in the box");
    }
    result.min_distance = best_r;
    result.candidates = best_stats.candidates;
    result.rejected_fk = best_stats.rejected_fk;
    result.rejected_strain = best_stats.rejected_strain;
    points = std::move(best);
  }
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

  // Identifiable subspace, in coordinates where the candidates' information is the identity:
  // T = V_r S_r^-1, rows U_j = J_j T.
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(stacked, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const double smax = sv.size() > 0 ? sv(0) : 0.0;
  Eigen::Index r = 0;
  while (r < sv.size() && smax > 0 && sv(r) > kRankThreshold * smax) ++r;
  result.dimension = static_cast<int>(r);
  const Eigen::MatrixXd basis = svd.matrixV().leftCols(r);
  const Eigen::MatrixXd U = stacked * basis * sv.head(r).cwiseInverse().asDiagonal();

  // Greedy choice: A = eps I + sum of the chosen U_j^T U_j, A^-1 kept up to date.
  Eigen::MatrixXd A_inv = Eigen::MatrixXd::Identity(r, r) / kDesignRegularisation;
  std::vector<bool> chosen(usable.size(), false);
  for (int step = 0; step < count; ++step) {
    double best_gain = -INFINITY;
    std::size_t best = usable.size();
    for (std::size_t j = 0; j < usable.size(); ++j) {
      if (chosen[j]) continue;
      const auto Uj = U.middleRows(3 * static_cast<Eigen::Index>(j), 3);
      const Eigen::Matrix3d G = Eigen::Matrix3d::Identity() + Uj * A_inv * Uj.transpose();
      const Eigen::LLT<Eigen::Matrix3d> llt(G);
      if (llt.info() != Eigen::Success) continue;
      const double gain = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
      if (gain > best_gain) {
        best_gain = gain;
        best = j;
      }
    }
    if (best == usable.size()) break;  // no candidate left with a finite gain
    chosen[best] = true;
    result.selected.push_back(usable[best]);
    const auto Ub = U.middleRows(3 * static_cast<Eigen::Index>(best), 3);
    const Eigen::MatrixXd W = Ub * A_inv;  // 3 x r
    const Eigen::Matrix3d G = Eigen::Matrix3d::Identity() + W * Ub.transpose();
    A_inv -= W.transpose() * G.ldlt().solve(W);
    A_inv = 0.5 * (A_inv + A_inv.transpose()).eval();
  }

  // The chosen set's criterion afresh, in an orthonormal basis of the subspace.
  Eigen::MatrixXd rows(3 * static_cast<Eigen::Index>(result.selected.size()), r);
  for (std::size_t j = 0, k = 0; j < usable.size(); ++j) {
    if (!chosen[j]) continue;
    rows.middleRows(3 * static_cast<Eigen::Index>(k++), 3) =
        stacked.middleRows(3 * static_cast<Eigen::Index>(j), 3) * basis;
  }
  const Eigen::VectorXd chosen_sv = Eigen::BDCSVD<Eigen::MatrixXd>(rows).singularValues();
  result.rank = 0;
  result.log_det = 0;
  for (Eigen::Index k = 0; k < r; ++k) {
    const double s = k < chosen_sv.size() ? chosen_sv(k) : 0.0;
    if (chosen_sv.size() > 0 && s > kRankThreshold * chosen_sv(0)) ++result.rank;
    result.log_det += 2.0 * std::log(s);
  }
  return result;
}

ConfigurationSets sample_configurations(const RobotDescription& robot,
                                        const SamplingOptions& options, int validation_count) {
  if (validation_count < 0) {
    throw InputError("sample_configurations: validation count must be >= 0, got " +
                     std::to_string(validation_count));
  }
  require_valid(options, "sample_configurations");
  const bool designed = options.design == SamplingDesign::kDOptimal;
  ConfigurationSets sets;
  if (!designed || validation_count > 0) {
    // D-optimal too draws count + validation_count, so that its validation set is the one the
    // Poisson-disc design gets with the same seed (a paired comparison of the designs).
    SamplingOptions spread = options;
    spread.count = options.count + validation_count;
    sets.spread = poisson_disc_sample(robot.params, spread);
    if (!sets.spread.complete) {
      throw std::runtime_error("only " + std::to_string(sets.spread.configurations.size()) +
                               " admissible configurations are " +
                               format_double(sets.spread.min_distance) + " m apart; asked for " +
                               std::to_string(spread.count) +
                               " (lower min_distance: pcr sample --min-distance)");
    }
    split_configurations(sets.spread.configurations, spread.count - validation_count,
                         &sets.calibration, &sets.validation);
  }
  if (!designed) return sets;

  SamplingOptions pool = options;
  pool.count = options.candidates > 0 ? options.candidates : kDesignCandidateFactor * options.count;
  pool.min_distance = 0.0;  // from the candidate count
  sets.candidates = poisson_disc_sample(robot.params, pool);
  // Disjoint from the validation set, and the union still a Poisson-disc set of the candidates'
  // radius.
  std::vector<JointVector> candidates;
  const double r2 = sets.candidates.min_distance * sets.candidates.min_distance;
  for (const JointVector& q : sets.candidates.configurations) {
    bool far = true;
    for (const JointVector& v : sets.validation) far = far && (q - v).squaredNorm() >= r2;
    if (far) candidates.push_back(q);
  }
  if (static_cast<int>(candidates.size()) < options.count) {
    throw std::runtime_error("d-optimal design: only " + std::to_string(candidates.size()) +
                             " candidates away from the validation set; asked for " +
                             std::to_string(options.count));
  }
  sets.candidates.configurations = std::move(candidates);
  sets.design = d_optimal_design(robot, sets.candidates.configurations, options.count, options);
  sets.calibration.clear();
  for (int j : sets.design.selected) {
    sets.calibration.push_back(sets.candidates.configurations[static_cast<std::size_t>(j)]);
  }
  return sets;
}

std::vector<std::size_t> visiting_order(const std::vector<JointVector>& configurations) {
  std::vector<std::size_t> left(configurations.size()), order;
  for (std::size_t k = 0; k < left.size(); ++k) left[k] = k;
  const auto take_nearest = [&](const JointVector& from) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < left.size(); ++k) {
      if ((configurations[left[k]] - from).squaredNorm() <
          (configurations[left[best]] - from).squaredNorm()) {
        best = k;
      }
    }
    order.push_back(left[best]);
    left.erase(left.begin() + static_cast<std::ptrdiff_t>(best));
  };
  if (!left.empty()) take_nearest(JointVector::Zero(configurations[left[0]].size()));
  while (!left.empty()) take_nearest(configurations[order.back()]);
  return order;
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
