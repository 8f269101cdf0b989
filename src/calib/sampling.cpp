#include "pcr/calib/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

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
  if (options.count < 1) {
    throw InputError("poisson_disc_sample: count must be >= 1, got " +
                     std::to_string(options.count));
  }
  if (options.attempts < 1) {
    throw InputError("poisson_disc_sample: attempts must be >= 1, got " +
                     std::to_string(options.attempts));
  }
  if (!std::isfinite(options.min_distance) || !(options.strain_limit > 0)) {
    throw InputError("poisson_disc_sample: min_distance must be finite and strain_limit > 0");
  }
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
