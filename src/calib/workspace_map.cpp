// Workspace maps: IK over a grid of positions at a fixed orientation (pcr/calib/workspace_map.hpp).
#include "pcr/calib/workspace_map.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <ostream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
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

/// Runs task(k) for k in [0, count) on up to `threads` threads, the caller's among them, each
/// taking the next k when it is done with one (a failed solve costs a hundred converged ones).
/// Rethrows the first exception a task threw, once every thread has stopped.
template <class Task>
void parallel_for(std::size_t count, int threads, const Task& task) {
  const auto workers = std::min(count, static_cast<std::size_t>(std::max(threads, 1)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto work = [&] {
    for (std::size_t k = next++; k < count; k = next++) {
      try {
        task(k);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = count;
      }
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < workers; ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads to be had: the ones running take the rest
    }
  }
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

/// Threads to run on: `threads`, or one per core when 0.
int thread_count(int threads) {
  return threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

/// The solves of workspace_map: waves of points, each wave the unvisited neighbours of the points
/// the wave before solved, warm-started from them.
class MapFlood {
 public:
  MapFlood(const RobotParams<double>& robot, const WorkspaceMapOptions& options, WorkspaceMap& map)
      : robot_(robot),
        options_(options),
        map_(map),
        threads_(thread_count(options.threads)),
        slot_(map.points.size(), -1) {
    // The map follows its branch: where it turns unstable the point says so (stable false), and
    // the flood goes on along it, as rotation_range does.
    cold_options_ = options.solver;
    cold_options_.stable_inverse = false;
    // A neighbour lies a cell away: its warm start converges in a few iterations unless a fold
    // lies between, where Newton crawls. There the solve stops early (a point one neighbour does
    // not reach is left to the others): the budget that makes the border cost a few converged
    // solves per point instead of a hundred.
    neighbour_options_ = cold_options_;
    SolverOptions& o = neighbour_options_;
    o.max_iterations = std::min(o.max_iterations, 8);
    o.max_line_search = std::min(o.max_line_search, 4);
    o.max_continuation_steps = std::min(o.max_continuation_steps, 16);
    o.min_continuation_step = std::max(o.min_continuation_step, 1.0 / 16);
  }

  void run() {
    const ForwardSolution home = home_solution(robot_, cold_options_, options_.load);
    if (usable_as_warm_start(home.summary)) flood(solve_cold({nearest_point(home.pose)}));
    std::vector<std::size_t> lattice;
    const int levels_x = std::min(kSeedLattice, map_.nx),
              levels_y = std::min(kSeedLattice, map_.ny);
    for (int b = 0; b < levels_y; ++b) {
      for (int a = 0; a < levels_x; ++a) {
        const std::size_t k =
            index(static_cast<int>(std::lround(1.0 * a * (map_.nx - 1) / (levels_x - 1))),
                  static_cast<int>(std::lround(1.0 * b * (map_.ny - 1) / (levels_y - 1))));
        if (!map_.points[k].visited) lattice.push_back(k);
      }
    }
    flood(solve_cold(lattice));
  }

 private:
  /// The solved points of a wave and their solutions.
  struct Wave {
    std::vector<std::size_t> points;
    std::vector<InverseSolution> solutions;
  };

  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(map_.nx) +
           static_cast<std::size_t>(i);
  }
  Pose2<double> pose(std::size_t k) const {
    return Pose2<double>{map_.points[k].x, map_.points[k].y, options_.theta};
  }
  std::size_t nearest_point(const Pose2<double>& at) const {
    const auto nearest = [](double v, double lo, double hi, int count) {
      return static_cast<int>(std::clamp(std::lround((v - lo) / (hi - lo) * (count - 1)), 0L,
                                         static_cast<long>(count - 1)));
    };
    return index(nearest(at.x, map_.x_min, map_.x_max, map_.nx),
                 nearest(at.y, map_.y_min, map_.y_max, map_.ny));
  }
  /// The four neighbours of point k in a fixed order (left, right, below, above; the grid's size
  /// where there is none), so that the warm start a point gets does not depend on the threads.
  std::array<std::size_t, 4> neighbours(std::size_t k) const {
    const auto nx = static_cast<std::size_t>(map_.nx), size = map_.points.size();
    const std::size_t i = k % nx;
    return {i > 0 ? k - 1 : size, i + 1 < nx ? k + 1 : size, k >= nx ? k - nx : size,
            k + nx < size ? k + nx : size};
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

  /// Marks the points visited, solves them with `solve(k, point)` in parallel, and returns the
  /// wave of those that can warm-start their neighbours.
  template <class Solve>
  Wave solve_wave(std::vector<std::size_t> points, const Solve& solve) {
    for (std::size_t k : points) map_.points[k].visited = true;
    std::vector<InverseSolution> solutions(points.size());
    parallel_for(points.size(), threads_, [&](std::size_t w) {
      solutions[w] = solve(points[w]);
      record(points[w], solutions[w]);
    });
    Wave wave;
    for (std::size_t w = 0; w < points.size(); ++w) {
      if (!usable_as_warm_start(solutions[w].summary)) continue;
      wave.points.push_back(points[w]);
      wave.solutions.push_back(std::move(solutions[w]));
    }
    return wave;
  }

  Wave solve_cold(std::vector<std::size_t> points) {
    return solve_wave(std::move(points), [&](std::size_t k) {
      return inverse_kinematics(robot_, pose(k), cold_options_, options_.load);
    });
  }

  void flood(Wave wave) {
    const std::size_t none = map_.points.size();
    while (!wave.points.empty()) {
      std::vector<std::size_t> next;
      for (std::size_t w = 0; w < wave.points.size(); ++w) {
        slot_[wave.points[w]] = static_cast<std::ptrdiff_t>(w);
        for (std::size_t k : neighbours(wave.points[w])) {
          if (k != none && !map_.points[k].visited) {
            map_.points[k].visited = true;
            next.push_back(k);
          }
        }
      }
      Wave solved = solve_wave(std::move(next), [&](std::size_t k) {
        std::array<const InverseSolution*, 2> warm{nullptr, nullptr};
        std::size_t found = 0;
        for (std::size_t m : neighbours(k)) {
          if (m != none && slot_[m] >= 0 && found < warm.size()) {
            warm[found++] = &wave.solutions[static_cast<std::size_t>(slot_[m])];
          }
        }
        return solve_from_neighbours(robot_, pose(k), warm[0], warm[1], neighbour_options_,
                                     options_.load);
      });
      for (std::size_t k : wave.points) slot_[k] = -1;
      wave = std::move(solved);
    }
  }

  const RobotParams<double>& robot_;
  const WorkspaceMapOptions& options_;
  WorkspaceMap& map_;
  int threads_;
  SolverOptions cold_options_, neighbour_options_;
  std::vector<std::ptrdiff_t> slot_;  ///< a point's place in the current wave, -1 if not in it
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
  const int workers = std::max(1, std::min(thread_count(threads), static_cast<int>(count)));
  std::vector<std::array<double, 4>> boxes(static_cast<std::size_t>(workers),
                                           {HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL});
  parallel_for(boxes.size(), workers, [&](std::size_t w) {
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
  MapFlood(robot, options, map).run();
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
