// Workspace maps: IK over a grid of positions at a fixed orientation (pcr/calib/workspace_map.hpp).
#include "pcr/calib/workspace_map.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>

#include "map_flood.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/input_error.hpp"

namespace pcr {
namespace {

/// The planar map's points for map_internal::GridFlood: IK at the grid's poses at the map's
/// orientation, from home or from a neighbour, each recorded into its WorkspaceMapPoint.
class PlanarMapPoints {
 public:
  using Solution = InverseSolution;

  PlanarMapPoints(const RobotParams<double>& robot, const WorkspaceMapOptions& options,
                  WorkspaceMap& map)
      : robot_(robot), options_(options), map_(map) {
    // The map follows its branch: where it turns unstable the point says so (stable false), and
    // the flood goes on along it, as rotation_range does.
    cold_options_ = options.solver;
    cold_options_.stable_inverse = false;
    neighbour_options_ = map_internal::neighbour_solver_options(cold_options_);
  }

  /// The grid point nearest home's position, when home is solved.
  std::optional<std::size_t> first_seed() const {
    const ForwardSolution home = home_solution(robot_, cold_options_, options_.load);
    if (!usable_as_warm_start(home.summary)) return std::nullopt;
    using map_internal::nearest_grid_index;
    return static_cast<std::size_t>(
               nearest_grid_index(home.pose.y, map_.y_min, map_.y_max, map_.ny)) *
               static_cast<std::size_t>(map_.nx) +
           static_cast<std::size_t>(
               nearest_grid_index(home.pose.x, map_.x_min, map_.x_max, map_.nx));
  }

  InverseSolution cold(std::size_t k) const {
    return inverse_kinematics(robot_, pose(k), cold_options_, options_.load);
  }
  InverseSolution warm(std::size_t k, const InverseSolution& from) const {
    return inverse_kinematics(robot_, pose(k), from, neighbour_options_, options_.load);
  }

  void record(std::size_t k, const InverseSolution& s) {
    WorkspaceMapPoint& p = map_.points[k];
    p.visited = true;
    p.status = s.summary.status;
    const bool equilibrium = is_equilibrium(s.summary);
    if (!equilibrium) return;
    p.q = s.q;
    p.reachable = within_stroke(robot_, s.q);
    p.stable = s.summary.stability == Stability::kStable;
    p.max_strain = s.summary.max_strain;
    p.stability_margin = s.summary.stability_margin;
    p.singularity = s.summary.singularity;
    if (options_.accuracy) options_.accuracy(s, p);
  }

 private:
  Pose2<double> pose(std::size_t k) const {
    return Pose2<double>{map_.points[k].x, map_.points[k].y, options_.theta};
  }

  const RobotParams<double>& robot_;
  const WorkspaceMapOptions& options_;
  WorkspaceMap& map_;
  SolverOptions cold_options_, neighbour_options_;
};

}  // namespace

std::array<double, 4> stroke_pose_box(const RobotParams<double>& robot, int levels,
                                      const SolverOptions& options,
                                      const PlatformLoad<double>& load, int threads) {
  const int n = robot.num_limbs;
  if (n < 2 || n > kMaxLimbs || levels < 2 || levels > 1000) {
    throw std::invalid_argument("stroke_pose_box: needs 2 to " + std::to_string(kMaxLimbs) +
                                " limbs and 2 to 1000 levels");
  }
  std::size_t count = 1;
  for (int i = 0; i < n; ++i) count *= static_cast<std::size_t>(levels);
  // Each configuration solved as cold (from home, once per thread): the box does not depend on
  // the order, and every thread takes every workers-th configuration so that the corners' long
  // paths spread over them.
  const int workers =
      std::max(1, std::min(map_internal::thread_count(threads), static_cast<int>(count)));
  std::vector<std::array<double, 4>> boxes(static_cast<std::size_t>(workers),
                                           {HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL});
  map_internal::parallel_for(boxes.size(), workers, [&](std::size_t w) {
    ForwardSequence sequence(robot, options, load);
    std::array<double, 4>& box = boxes[w];
    JointVector q(n);
    for (std::size_t c = w; c < count; c += boxes.size()) {
      std::size_t digits = c;  // the configuration's level per joint
      for (int i = 0; i < n; ++i) {
        const LimbParams<double>& limb = robot.limb(i);
        const auto level = static_cast<double>(digits % static_cast<std::size_t>(levels));
        digits /= static_cast<std::size_t>(levels);
        q(i) = limb.q_min + (limb.q_max - limb.q_min) * level / (levels - 1);
      }
      const ForwardSolution& fk = sequence.solve(q);
      if (!is_equilibrium(fk.summary)) continue;
      box[0] = std::min(box[0], fk.pose.x);
      box[1] = std::max(box[1], fk.pose.x);
      box[2] = std::min(box[2], fk.pose.y);
      box[3] = std::max(box[3], fk.pose.y);
    }
  });
  std::array<double, 4> box = boxes[0];
  for (const std::array<double, 4>& b : boxes) {
    box = {std::min(box[0], b[0]), std::max(box[1], b[1]), std::min(box[2], b[2]),
           std::max(box[3], b[3])};
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
    range = stroke_pose_box(robot, 7, options.solver, options.load, options.threads);
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
  for (std::size_t k = 0; k < map.points.size(); ++k) {
    map.points[k].x = map.x(static_cast<int>(k % static_cast<std::size_t>(map.nx)));
    map.points[k].y = map.y(static_cast<int>(k / static_cast<std::size_t>(map.nx)));
    map.points[k].q = JointVector::Constant(n, std::numeric_limits<double>::quiet_NaN());
  }
  const auto start = std::chrono::steady_clock::now();
  PlanarMapPoints points(robot, options, map);
  map_internal::GridFlood<PlanarMapPoints>(points, map.nx, map.ny, options.threads)
      .run(points.first_seed());
  map.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const WorkspaceMapPoint& p : map.points) {
    if (p.reachable) map.reachable_area += 1;
    if (p.reachable && p.stable) map.stable_area += 1;
  }
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
    csv.add(p.visited ? to_string(p.status) : "unvisited");
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
