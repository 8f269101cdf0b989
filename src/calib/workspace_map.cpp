// Workspace maps: IK over a grid of positions at a fixed orientation (pcr/calib/workspace_map.hpp).
#include "pcr/calib/workspace_map.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>

#include "pcr/csv_io.hpp"
#include "pcr/input_error.hpp"

namespace pcr {
namespace {

/// IK at a pose from up to two warm starts (null or not usable: skipped), from home when there is
/// none. Returns a usable solution when one of them gives it, else an equilibrium (IK's
/// kUnstable), else the last failure.
InverseSolution solve_from_neighbours(const RobotParams<double>& robot, const Pose2<double>& pose,
                                      const InverseSolution* first, const InverseSolution* second,
                                      const SolverOptions& options,
                                      const PlatformLoad<double>& load) {
  InverseSolution best;
  bool tried = false, have_equilibrium = false;
  for (const InverseSolution* warm : {first, second}) {
    if (warm == nullptr || !usable_as_warm_start(warm->summary)) continue;
    tried = true;
    InverseSolution s = inverse_kinematics(robot, pose, *warm, options, load);
    if (usable_as_warm_start(s.summary)) return s;
    if (!have_equilibrium) {
      have_equilibrium = is_equilibrium(s.summary);
      best = std::move(s);
    }
  }
  if (!tried) return inverse_kinematics(robot, pose, options, load);
  return best;
}

}  // namespace

std::array<double, 4> stroke_pose_box(const RobotParams<double>& robot, int levels,
                                      const SolverOptions& options,
                                      const PlatformLoad<double>& load) {
  const int n = robot.num_limbs;
  if (n < 2 || n > kMaxLimbs || levels < 2) {
    throw std::invalid_argument("stroke_pose_box: needs 2 to " + std::to_string(kMaxLimbs) +
                                " limbs and at least 2 levels");
  }
  std::array<double, 4> box{HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL};
  ForwardSequence sequence(robot, options, load);
  std::vector<int> index(static_cast<std::size_t>(n), 0);
  JointVector q(n);
  for (;;) {
    for (int i = 0; i < n; ++i) {
      const LimbParams<double>& limb = robot.limb(i);
      q(i) = limb.q_min +
             (limb.q_max - limb.q_min) * index[static_cast<std::size_t>(i)] / (levels - 1);
    }
    const ForwardSolution& fk = sequence.solve(q);
    if (is_equilibrium(fk.summary)) {
      box[0] = std::min(box[0], fk.pose.x);
      box[1] = std::max(box[1], fk.pose.x);
      box[2] = std::min(box[2], fk.pose.y);
      box[3] = std::max(box[3], fk.pose.y);
    }
    int i = 0;  // the next index vector, odometer order
    while (i < n && ++index[static_cast<std::size_t>(i)] == levels) {
      index[static_cast<std::size_t>(i)] = 0;
      ++i;
    }
    if (i == n) break;
  }
  if (!(box[0] <= box[1])) {
    throw std::runtime_error("stroke_pose_box: no configuration of the stroke box was solved");
  }
  return box;
}

std::function<void(const InverseSolution&, WorkspaceMapPoint&)> predicted_accuracy_of_points(
    const RobotParams<double>& robot, ParameterCovariance covariance,
    PredictedAccuracyOptions options) {
  return [robot, covariance = std::move(covariance), options = std::move(options)](
             const InverseSolution& solution, WorkspaceMapPoint& point) {
    const PredictedAccuracy a =
        predicted_accuracy(robot, as_forward_solution(solution), covariance, options);
    if (!covariance.names.empty()) {
      point.position_3sigma = a.position_3sigma;
      point.orientation_3sigma = a.orientation_3sigma;
    }
    point.worst_position = a.worst_position;
    point.worst_orientation = a.worst_orientation;
  };
}

WorkspaceMap workspace_map(const RobotParams<double>& robot, const WorkspaceMapOptions& options) {
  const int n = robot.num_limbs;
  if (n < 2 || n > 3) {
    throw std::invalid_argument(
        "workspace_map: inverse kinematics needs 2 or 3 limbs, the robot "
        "has " +
        std::to_string(n));
  }
  require_valid(options, "workspace_map");
  std::array<double, 4> range;
  if (options.range) {
    range = *options.range;
  } else {
    range = stroke_pose_box(robot, 7, options.solver, options.load);
    const double mx = 0.1 * (range[1] - range[0]), my = 0.1 * (range[3] - range[2]);
    range = {range[0] - mx, range[1] + mx, range[2] - my, range[3] + my};
  }
  for (double v : range) {
    if (!std::isfinite(v)) throw std::invalid_argument("workspace_map: the range is not finite");
  }
  if (!(range[0] < range[1] && range[2] < range[3])) {
    throw std::invalid_argument("workspace_map: empty range (x_min < x_max and y_min < y_max)");
  }
  WorkspaceMap map;
  map.theta = options.theta;
  map.nx = map.ny = options.grid;
  map.x_min = range[0];
  map.x_max = range[1];
  map.y_min = range[2];
  map.y_max = range[3];
  map.points.resize(static_cast<std::size_t>(map.nx) * static_cast<std::size_t>(map.ny));

  const auto start = std::chrono::steady_clock::now();
  std::vector<InverseSolution> previous_row(static_cast<std::size_t>(map.nx));
  std::vector<InverseSolution> row(static_cast<std::size_t>(map.nx));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int j = 0; j < map.ny; ++j) {
    const double y = map.y_min + (map.y_max - map.y_min) * j / (map.ny - 1);
    const InverseSolution* neighbour = nullptr;
    for (int k = 0; k < map.nx; ++k) {
      const int i = j % 2 == 0 ? k : map.nx - 1 - k;  // serpentine
      const auto ui = static_cast<std::size_t>(i);
      const double x = map.x_min + (map.x_max - map.x_min) * i / (map.nx - 1);
      const InverseSolution* above = j > 0 ? &previous_row[ui] : nullptr;
      row[ui] = solve_from_neighbours(robot, Pose2<double>{x, y, options.theta}, neighbour, above,
                                      options.solver, options.load);
      const InverseSolution& s = row[ui];
      neighbour = &s;
      WorkspaceMapPoint& p =
          map.points[static_cast<std::size_t>(j) * static_cast<std::size_t>(map.nx) + ui];
      p.x = x;
      p.y = y;
      p.status = s.summary.status;
      const bool equilibrium = is_equilibrium(s.summary);
      p.q = equilibrium ? s.q : JointVector::Constant(n, nan);
      p.reachable = equilibrium && within_stroke(robot, s.q);
      p.stable = equilibrium && s.summary.stability == Stability::kStable;
      if (equilibrium) {
        p.max_strain = s.summary.max_strain;
        p.stability_margin = s.summary.stability_margin;
        p.singularity = s.summary.singularity;
        if (options.accuracy) options.accuracy(s, p);
      }
      if (p.reachable) map.reachable_area += 1;
      if (p.reachable && p.stable) map.stable_area += 1;
    }
    std::swap(previous_row, row);
  }
  map.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  map.reachable_area *= map.cell_area();
  map.stable_area *= map.cell_area();
  return map;
}

RotationRange rotation_range(const RobotParams<double>& robot, double x, double y, double theta,
                             const SolverOptions& options, const PlatformLoad<double>& load,
                             double step, double tolerance) {
  const auto holds = [&](const InverseSolution& s) {
    return usable_as_warm_start(s.summary) && within_stroke(robot, s.q) &&
           s.summary.stability == Stability::kStable;
  };
  // The range of the branch reached at theta: the search for a stable equilibrium at a pose where
  // the branch turns unstable would carry on along another one.
  SolverOptions on_branch = options;
  on_branch.stable_inverse = false;
  RotationRange range;
  const InverseSolution start =
      inverse_kinematics(robot, Pose2<double>{x, y, theta}, options, load);
  if (!holds(start)) return range;
  range.reachable = true;
  for (double direction : {1.0, -1.0}) {
    InverseSolution good = start;
    double good_theta = theta, bad_theta = NAN;
    while (std::abs(good_theta - theta) < M_PI) {
      const double next = good_theta + direction * step;
      InverseSolution s =
          inverse_kinematics(robot, Pose2<double>{x, y, next}, good, on_branch, load);
      if (!holds(s)) {
        bad_theta = next;
        break;
      }
      good = std::move(s);
      good_theta = next;
    }
    while (std::isfinite(bad_theta) && std::abs(bad_theta - good_theta) > tolerance) {
      const double mid = 0.5 * (good_theta + bad_theta);
      InverseSolution s =
          inverse_kinematics(robot, Pose2<double>{x, y, mid}, good, on_branch, load);
      if (holds(s)) {
        good = std::move(s);
        good_theta = mid;
      } else {
        bad_theta = mid;
      }
    }
    (direction > 0 ? range.theta_max : range.theta_min) = good_theta;
  }
  return range;
}

void write_workspace_map_csv(const WorkspaceMap& map, int num_limbs, std::ostream& out) {
  CsvWriter csv(out);
  for (const char* c : {"x", "y", "theta", "reachable", "stable", "status"}) csv.add(c);
  for (int i = 0; i < num_limbs; ++i) csv.add("q" + std::to_string(i + 1));
  for (const char* c : {"max_strain", "stability_margin", "singularity", "position_3sigma",
                        "orientation_3sigma", "worst_position", "worst_orientation"}) {
    csv.add(c);
  }
  csv.end_row();
  for (const WorkspaceMapPoint& p : map.points) {
    csv.add(p.x);
    csv.add(p.y);
    csv.add(map.theta);
    csv.add(p.reachable ? 1 : 0);
    csv.add(p.stable ? 1 : 0);
    csv.add(to_string(p.status));
    for (int i = 0; i < num_limbs; ++i) csv.add(p.q(i));
    csv.add(p.max_strain);
    csv.add(p.stability_margin);
    csv.add(p.singularity);
    csv.add(p.position_3sigma);
    csv.add(p.orientation_3sigma);
    csv.add(p.worst_position);
    csv.add(p.worst_orientation);
    csv.end_row();
  }
  csv.flush();
}

}  // namespace pcr
