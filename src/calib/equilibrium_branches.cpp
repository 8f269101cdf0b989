// The equilibria a dataset's rows may have been measured on, and the branch-mismatch rule.

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr::calib_internal {

std::vector<std::pair<SolverOptions, SequenceMode>> dataset_readings(const SolverOptions& fk) {
  SolverOptions through = fk;
  through.through_folds = true;
  std::vector<std::pair<SolverOptions, SequenceMode>> out{{fk, SequenceMode::kIndependent},
                                                          {fk, SequenceMode::kPath}};
  if (!fk.through_folds) out.emplace_back(through, SequenceMode::kPath);
  return out;
}

std::vector<ForwardSolution> solve_rows(const RobotParams<double>& robot,
                                        const std::vector<CalibrationSample>& data,
                                        const SolverOptions& options, SequenceMode mode,
                                        const PlatformLoad<double>& load) {
  ForwardSequence sequence(robot, options, load, mode);
  std::vector<ForwardSolution> out;
  out.reserve(data.size());
  for (const CalibrationSample& row : data) out.push_back(sequence.solve(row.q));
  return out;
}

namespace {

/// The equilibria of `robot` at the joints of `at` other than `at` itself, found from its buckled
/// seeds (buckled_seed) and `reached` (equilibria at those joints the robot may have
/// come to otherwise, dataset_readings): the one whose platform pose lies nearest `target`, if
/// any.
std::optional<ForwardSolution> nearest_other_equilibrium(
    const RobotParams<double>& robot, const ForwardSolution& at,
    const std::vector<const ForwardSolution*>& reached, const Pose2<double>& target,
    const SolverOptions& fk, const PlatformLoad<double>& load) {
  std::optional<ForwardSolution> best;
  double best_distance = HUGE_VAL;
  const auto consider = [&](const ForwardSolution& s) {
    if (!is_equilibrium(s.summary)) return;
    const double from_at = pose_distance(s.pose, at.pose, kDefaultOrientationWeight);
    if (!(from_at > kDistinctEquilibrium)) return;  // `at` again
    const double distance = std::hypot(s.pose.x - target.x, s.pose.y - target.y);
    if (distance < best_distance) {
      best_distance = distance;
      best = s;
    }
  };
  for (const ForwardSolution* r : reached) consider(*r);
  for (int k = 0; k < kBuckledSeedsPerRod * robot.num_limbs; ++k) {
    consider(forward_kinematics(robot, at.q, buckled_seed(robot, at, k), fk, load));
  }
  return best;
}

}  // namespace

std::vector<std::optional<ForwardSolution>> equilibria_measured_instead(
    const RobotParams<double>& robot, const std::vector<CalibrationSample>& data,
    const std::vector<const ForwardSolution*>& predicted, const SolverOptions& fk,
    const PlatformLoad<double>& load, std::optional<SequenceMode> predicted_reading) {
  std::vector<std::optional<ForwardSolution>> out(data.size());
  std::vector<double> errors(data.size(), kNaN), finite;
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (predicted[j] == nullptr || !is_equilibrium(predicted[j]->summary)) continue;
    const Pose2<double> measured = robot.extrinsics.platform_from_measurement(data[j].measured);
    errors[j] = std::hypot(predicted[j]->pose.x - measured.x, predicted[j]->pose.y - measured.y);
    if (std::isfinite(errors[j])) finite.push_back(errors[j]);
  }
  if (finite.empty()) return out;
  std::nth_element(finite.begin(), finite.begin() + finite.size() / 2, finite.end());
  const double median = finite[finite.size() / 2];
  std::vector<std::vector<ForwardSolution>> readings;
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (!(errors[j] > kMismatchFactor * median)) continue;
    if (readings.empty()) {
      for (const auto& [options, mode] : dataset_readings(fk)) {
        if (mode == predicted_reading && options.through_folds == fk.through_folds) continue;
        readings.push_back(solve_rows(robot, data, options, mode, load));
      }
    }
    std::vector<const ForwardSolution*> reached;
    for (const std::vector<ForwardSolution>& reading : readings) reached.push_back(&reading[j]);
    const Pose2<double> measured = robot.extrinsics.platform_from_measurement(data[j].measured);
    std::optional<ForwardSolution> other =
        nearest_other_equilibrium(robot, *predicted[j], reached, measured, fk, load);
    if (other &&
        kMismatchFactor * std::hypot(other->pose.x - measured.x, other->pose.y - measured.y) <
            errors[j]) {
      out[j] = std::move(other);
    }
  }
  return out;
}

}  // namespace pcr::calib_internal
