// A model's errors on a dataset per configuration (Eqs. 8 and 9) and as Table 3's statistics.

#include "pcr/calib/configuration_errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr {

using calib_internal::equilibria_measured_instead;
using calib_internal::kNaN;
using calib_internal::solve_rows;

ConfigurationErrors configuration_errors(const RobotParams<double>& robot,
                                         const std::vector<CalibrationSample>& data,
                                         const SolverOptions& fk, const PlatformLoad<double>& load,
                                         SequenceMode order) {
  ConfigurationErrors errors;
  errors.branch_mismatch.assign(data.size(), false);
  errors.other_pose.assign(data.size(), Pose2<double>{kNaN, kNaN, kNaN});
  const std::vector<ForwardSolution> solutions = solve_rows(robot, data, fk, order, load);
  for (std::size_t j = 0; j < data.size(); ++j) {
    const ForwardSolution& s = solutions[j];
    if (!is_equilibrium(s.summary)) {
      errors.e_p.push_back(kNaN);
      errors.e_theta.push_back(kNaN);
      continue;
    }
    const Pose2<double> measured = robot.extrinsics.platform_from_measurement(data[j].measured);
    errors.e_p.push_back(std::hypot(s.pose.x - measured.x, s.pose.y - measured.y));
    errors.e_theta.push_back(std::abs(wrap_angle(s.pose.theta - measured.theta)));
  }
  std::vector<const ForwardSolution*> predicted;
  for (const ForwardSolution& s : solutions) predicted.push_back(&s);
  const std::vector<std::optional<ForwardSolution>> other =
      equilibria_measured_instead(robot, data, predicted, fk, load, order);
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (!other[j]) continue;
    errors.branch_mismatch[j] = true;
    errors.other_pose[j] = other[j]->pose;
  }
  return errors;
}

PoseErrorStats pose_errors(const RobotParams<double>& robot,
                           const std::vector<CalibrationSample>& data, const SolverOptions& fk,
                           const PlatformLoad<double>& load, SequenceMode order) {
  return error_statistics(configuration_errors(robot, data, fk, load, order));
}

PoseErrorStats error_statistics(const ConfigurationErrors& errors) {
  PoseErrorStats stats;
  stats.min_p = stats.min_theta = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < errors.e_p.size(); ++j) {
    const double e_p = errors.e_p[j], e_t = errors.e_theta[j];
    if (std::isnan(e_p)) {
      ++stats.failed;
      continue;
    }
    if (j < errors.branch_mismatch.size() && errors.branch_mismatch[j]) {
      ++stats.branch_mismatches;
      continue;
    }
    stats.max_p = std::max(stats.max_p, e_p);
    stats.min_p = std::min(stats.min_p, e_p);
    stats.mean_p += e_p;
    stats.max_theta = std::max(stats.max_theta, e_t);
    stats.min_theta = std::min(stats.min_theta, e_t);
    stats.mean_theta += e_t;
    ++stats.count;
  }
  if (stats.count > 0) {
    stats.mean_p /= stats.count;
    stats.mean_theta /= stats.count;
  } else {
    stats.min_p = stats.min_theta = kNaN;
    stats.max_p = stats.max_theta = stats.mean_p = stats.mean_theta = kNaN;
  }
  return stats;
}

}  // namespace pcr
