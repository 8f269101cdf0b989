// Workspace maps (pcr/calib/workspace_map.hpp) against brute force and symmetry: the reachable
// region of a map at theta = 0 against an FK scan of the stroke box, the rotation range at the
// default robot's centre against FK of equal joints.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <vector>

#include "pcr/calib/workspace_map.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/robot_io.hpp"
#include "random_robots.hpp"
#include "sanitized_build.hpp"

namespace pcr {
namespace {

using test::kSanitized;  // sanitized_build.hpp

// The map's reachable points against a brute-force FK scan of the stroke box: the scan's poses
// whose orientation lies within delta of the map's mark the grid cells they fall in. Each such cell
// is reachable on the map or next to a reachable cell (a pose at |theta| <= delta lies up to the
// platform's radius times delta, ~0.1 mm here, from the theta = 0 slice), and each reachable cell
// is next to a scanned one, away from the scan's own sampling gaps at the border.
void expect_map_matches_a_scan(const RobotParams<double>& robot, bool every_point_stable,
                               int levels = 61) {
  WorkspaceMapOptions options;
  options.grid = 48;
  const WorkspaceMap map = workspace_map(robot, options);
  ASSERT_EQ(map.points.size(), 48u * 48u);
  const double dx = (map.x_max - map.x_min) / (map.nx - 1);
  const double dy = (map.y_max - map.y_min) / (map.ny - 1);

  std::vector<int> scanned(map.points.size(), 0);
  // The scan fills the joint grid outwards from home, each configuration solved by plain Newton
  // from a solved neighbour (0.35 mm away): what FK reaches from home within the stroke box.
  const double delta = 0.003;
  SolverOptions scan_options;
  scan_options.continuation = false;
  scan_options.check_stability = false;
  const auto flat = [&](int a, int b, int c) { return (a * levels + b) * levels + c; };
  std::vector<char> visited(static_cast<std::size_t>(levels * levels * levels), 0);
  std::vector<std::pair<int, ForwardSolution>> queue;  // (grid index, solved neighbour)
  const int centre = (levels - 1) / 2;                 // q = 0: the stroke is symmetric
  queue.emplace_back(flat(centre, centre, centre), home_solution(robot, scan_options));
  visited[static_cast<std::size_t>(queue.back().first)] = 1;
  int in_slice = 0;
  for (std::size_t next = 0; next < queue.size(); ++next) {
    const int index = queue[next].first;
    const int ijk[3] = {index / (levels * levels), index / levels % levels, index % levels};
    JointVector q(3);
    for (int i = 0; i < 3; ++i) {
      const LimbParams<double>& limb = robot.limb(i);
      q(i) = limb.q_min + (limb.q_max - limb.q_min) * ijk[i] / (levels - 1);
    }
    const ForwardSolution fk = forward_kinematics(robot, q, queue[next].second, scan_options);
    if (!fk.summary.converged()) continue;
    for (int axis = 0; axis < 3; ++axis) {
      for (int step : {-1, 1}) {
        int n[3] = {ijk[0], ijk[1], ijk[2]};
        n[axis] += step;
        if (n[axis] < 0 || n[axis] >= levels) continue;
        const int neighbour = flat(n[0], n[1], n[2]);
        if (visited[static_cast<std::size_t>(neighbour)]) continue;
        visited[static_cast<std::size_t>(neighbour)] = 1;
        queue.emplace_back(neighbour, fk);
      }
    }
    queue[next].second = ForwardSolution();  // keep the memory bounded
    if (std::abs(fk.pose.theta - map.theta) > delta) continue;
    ++in_slice;
    const long i = std::lround((fk.pose.x - map.x_min) / dx);
    const long j = std::lround((fk.pose.y - map.y_min) / dy);
    ASSERT_TRUE(i >= 0 && i < map.nx && j >= 0 && j < map.ny)
        << "an FK pose outside the map's range: " << fk.pose.x << " " << fk.pose.y;
    scanned[static_cast<std::size_t>(j * map.nx + i)] = 1;
  }
  ASSERT_GT(in_slice, 1000);
  const auto near = [&](const auto& marked, long i, long j) {
    for (long v = std::max(0L, j - 1); v <= std::min<long>(map.ny - 1, j + 1); ++v) {
      for (long u = std::max(0L, i - 1); u <= std::min<long>(map.nx - 1, i + 1); ++u) {
        if (marked(u, v)) return true;
      }
    }
    return false;
  };
  const auto reachable = [&](long i, long j) {
    return map.points[static_cast<std::size_t>(j * map.nx + i)].reachable;
  };
  const auto was_scanned = [&](long i, long j) {
    return scanned[static_cast<std::size_t>(j * map.nx + i)] == 1;
  };
  int scanned_cells = 0, reachable_cells = 0, reachable_far = 0;
  for (long j = 0; j < map.ny; ++j) {
    for (long i = 0; i < map.nx; ++i) {
      if (was_scanned(i, j)) {
        ++scanned_cells;
        EXPECT_TRUE(near(reachable, i, j)) << "scanned cell " << i << " " << j;
      }
      if (reachable(i, j)) {
        ++reachable_cells;
        if (!near(was_scanned, i, j)) ++reachable_far;
      }
    }
  }
  EXPECT_LE(reachable_far, reachable_cells / 50) << reachable_cells;
  EXPECT_NEAR(scanned_cells, reachable_cells, 0.1 * reachable_cells);
  EXPECT_NEAR(map.reachable_area, reachable_cells * map.cell_area(), 1e-15);
  if (every_point_stable) EXPECT_NEAR(map.stable_area, map.reachable_area, 1e-15);
  EXPECT_GT(map.stable_area, 0.5 * map.reachable_area);
}

// 100,000 FK solves per robot: ~6 s in Release, far longer under the sanitizers, where the map's
// code runs in the other tests.
TEST(WorkspaceMap, ReachableRegionMatchesAnFkScanOfTheStrokeBox) {
  if (kSanitized) GTEST_SKIP() << "Release build only (slow under the sanitizers)";
  // The default robot's stroke box at theta = 0: every reachable point is stable.
  expect_map_matches_a_scan(femto_3pf(), true);
}

// The same with rods shape-set to arcs (0.45 rad over their length, alternately left and right),
// the distal clamps where the stress-free rods end, so that home is still (0, 0, 0).
TEST(WorkspaceMap, ReachableRegionOfPrecurvedRodsMatchesAnFkScan) {
  if (kSanitized) GTEST_SKIP() << "Release build only (slow under the sanitizers)";
  RobotParams<double> robot = testing::regular_robot(3);
  for (int i = 0; i < 3; ++i) {
    LimbParams<double>& limb = robot.limb(i);
    limb.rod.precurvature = (i % 2 ? -15.0 : 15.0);
    const RodState<double> free_tip =
        integrate_rod(proximal_rod_state(limb, 0.0, Wrench<double>{}), limb.rod, 4096);
    limb.B = Vector2<double>(free_tip.x, free_tip.y);
    limb.beta = free_tip.theta;
  }
  expect_map_matches_a_scan(robot, false);
}

// The default robot with a stroke of +-60 mm, six times its own
// (robots/femto-3pf-long-stroke.json): at theta = 0 more than half of the map lies beyond the
// branch's folds, where the flood leaves points unvisited, and a region of it is reached only by
// unstable equilibria.
RobotParams<double> long_stroke_robot() {
  const RobotParams<double> robot =
      load_robot(std::string(PCR_SOURCE_DIR) + "/robots/femto-3pf-long-stroke.json").params;
  for (int i = 0; i < robot.num_limbs; ++i) EXPECT_EQ(robot.limb(i).q_max, 0.06);
  return robot;
}

// Random points of the long-stroke map against IK from home with the solver's whole budget (the
// branch followed, as the map does): where that finds an equilibrium within the stroke, the map
// has one at the point or a neighbour (the border is located to about a cell).
TEST(WorkspaceMap, LongStrokeMapAgreesWithColdIkAtRandomPoints) {
  const RobotParams<double> robot = long_stroke_robot();
  WorkspaceMapOptions options;
  options.grid = kSanitized ? 10 : 40;
  const WorkspaceMap map = workspace_map(robot, options);
  SolverOptions on_branch;
  on_branch.stable_inverse = false;
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> column(0, map.nx - 1), row(0, map.ny - 1);
  const auto at = [&](int i, int j) -> const WorkspaceMapPoint& {
    return map.points[static_cast<std::size_t>(j * map.nx + i)];
  };
  int cold_reachable = 0;
  for (int trial = 0; trial < (kSanitized ? 4 : 60); ++trial) {
    const int i = column(rng), j = row(rng);
    const WorkspaceMapPoint& p = at(i, j);
    const InverseSolution cold =
        inverse_kinematics(robot, Pose2<double>{p.x, p.y, map.theta}, on_branch);
    if (cold.summary.converged()) {
      ++cold_reachable;
      bool near = false;
      for (int v = std::max(0, j - 1); v <= std::min(map.ny - 1, j + 1); ++v) {
        for (int u = std::max(0, i - 1); u <= std::min(map.nx - 1, i + 1); ++u) {
          near = near || at(u, v).reachable;
        }
      }
      EXPECT_TRUE(near) << "IK from home reaches (" << p.x << ", " << p.y << ")";
    }
  }
  if (!kSanitized) EXPECT_GT(cold_reachable, 10);
}

bool same_value(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// Random robots (the paper's intervals around the default design, strokes of 10 to 60 mm each way,
// orientations within 0.1 rad): the map on 1, 2 and 3 threads is the same to the last bit.
TEST(WorkspaceMap, IsTheSameWhateverTheNumberOfThreads) {
  std::mt19937_64 rng(20261128);
  std::uniform_real_distribution<double> stroke(0.01, 0.06), theta(-0.1, 0.1);
  for (int trial = 0; trial < (kSanitized ? 1 : 3); ++trial) {
    RobotParams<double> robot = testing::perturbed(femto_3pf(), rng);
    for (int i = 0; i < robot.num_limbs; ++i) {
      const double s = stroke(rng);
      robot.limb(i).q_min = -s;
      robot.limb(i).q_max = s;
    }
    WorkspaceMapOptions options;
    options.grid = kSanitized ? 8 : 16;
    options.theta = theta(rng);
    options.threads = 1;
    const WorkspaceMap one = workspace_map(robot, options);
    for (int threads : {2, 3}) {
      options.threads = threads;
      const WorkspaceMap many = workspace_map(robot, options);
      ASSERT_EQ(many.points.size(), one.points.size());
      for (std::size_t k = 0; k < one.points.size(); ++k) {
        const WorkspaceMapPoint &a = one.points[k], &b = many.points[k];
        EXPECT_TRUE(a.visited == b.visited && a.reachable == b.reachable && a.stable == b.stable &&
                    a.status == b.status && same_value(a.max_strain, b.max_strain) &&
                    same_value(a.stability_margin, b.stability_margin))
            << "trial " << trial << ", " << threads << " threads, point " << k;
        for (int i = 0; i < robot.num_limbs; ++i) EXPECT_TRUE(same_value(a.q(i), b.q(i)));
      }
      EXPECT_EQ(many.reachable_area, one.reachable_area);
    }
  }
}

// Points the flood never visited lie beyond the branch's border: IK from home with the solver's
// whole budget (continuation down to 1/1024 of the path, the branch followed as the map does)
// finds no equilibrium at any of them.
TEST(WorkspaceMap, NoEquilibriumAtUnvisitedPoints) {
  const RobotParams<double> robot = long_stroke_robot();
  WorkspaceMapOptions options;
  options.grid = kSanitized ? 10 : 40;
  const WorkspaceMap map = workspace_map(robot, options);
  std::vector<std::size_t> unvisited;
  for (std::size_t k = 0; k < map.points.size(); ++k) {
    if (!map.points[k].visited) unvisited.push_back(k);
  }
  // More than a quarter of the map at 40 x 40; at the sanitizers' 10 x 10 the 9 x 9 lattice of
  // seeds, solved cold, visits most points.
  ASSERT_GT(unvisited.size(), kSanitized ? 0 : map.points.size() / 4);
  std::mt19937_64 rng(7);
  std::shuffle(unvisited.begin(), unvisited.end(), rng);
  unvisited.resize(std::min<std::size_t>(unvisited.size(), kSanitized ? 3 : 60));
  SolverOptions on_branch;
  on_branch.stable_inverse = false;
  for (std::size_t k : unvisited) {
    const WorkspaceMapPoint& p = map.points[k];
    EXPECT_FALSE(p.reachable || p.stable || std::isfinite(p.q(0)));
    const InverseSolution cold =
        inverse_kinematics(robot, Pose2<double>{p.x, p.y, map.theta}, on_branch);
    EXPECT_FALSE(is_equilibrium(cold.summary))
        << "an equilibrium at unvisited (" << p.x << ", " << p.y << "): q " << cold.q.transpose();
  }
  std::ostringstream out;
  write_workspace_map_csv(map, 3, out);
  EXPECT_NE(out.str().find(",unvisited,"), std::string::npos);
}

// By the default robot's 120 degree symmetry, equal joints turn the platform about its centre:
// pushed to q_max on every joint it turns to one end of the rotation range at (0, 0).
TEST(WorkspaceMap, RotationRangeAtTheCentreIsThatOfEqualJoints) {
  const RobotParams<double> robot = femto_3pf();
  const RotationRange range = rotation_range(robot, 0.0, 0.0);
  ASSERT_TRUE(range.reachable);
  const double hi = robot.limb(0).q_max;
  const ForwardSolution at_max = forward_kinematics(robot, JointVector::Constant(3, hi));
  ASSERT_TRUE(at_max.summary.converged());
  EXPECT_NEAR(at_max.pose.x, 0.0, 1e-12);
  EXPECT_NEAR(at_max.pose.y, 0.0, 1e-12);
  const double end = at_max.pose.theta;
  EXPECT_NEAR(end > 0 ? range.theta_max : range.theta_min, end, 2e-5);
  // The other end lies where equal pulls meet the forward problem's singularity: IK walked from
  // theta = 0 in 0.1 mrad steps, on its branch, meets it near -0.32 rad. The range holds short of
  // it, and past where FK from home along equal joints stops (about -0.275 rad).
  const double other = end > 0 ? range.theta_min : range.theta_max;
  SolverOptions on_branch;
  on_branch.stable_inverse = false;
  InverseSolution walked = inverse_kinematics(robot, Pose2<double>{0, 0, 0}, on_branch);
  double walk_end = 0;
  for (int k = 1; k <= 5000; ++k) {
    const double theta = std::copysign(k * 1e-4, other);
    const InverseSolution s = inverse_kinematics(robot, {0, 0, theta}, walked, on_branch);
    // Close to the singularity IK's error estimate outgrows the targets (kInaccurate): still an
    // equilibrium within the stroke, as the range counts it.
    const bool equilibrium = s.summary.converged() || s.summary.status == SolveStatus::kInaccurate;
    if (!equilibrium || s.summary.stability != Stability::kStable) break;
    walked = s;
    walk_end = theta;
  }
  EXPECT_GT(std::abs(walk_end), 0.3);
  EXPECT_LE(std::abs(other), std::abs(walk_end) + 1e-4);
  EXPECT_GT(std::abs(other), 0.275);
  EXPECT_LT(other * end, 0);
}

TEST(WorkspaceMap, WritesOneRowPerPointAndRefusesBadInput) {
  const RobotParams<double> robot = femto_3pf();
  WorkspaceMapOptions options;
  options.grid = 5;
  options.range = std::array<double, 4>{-0.002, 0.002, -0.001, 0.001};
  const WorkspaceMap map = workspace_map(robot, options);
  std::ostringstream out;
  write_workspace_map_csv(map, 3, out);
  const std::string text = out.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 26);  // a header and 25 rows
  EXPECT_EQ(text.rfind("x,y,theta,reachable,stable,status,q1,q2,q3,max_strain,", 0), 0u);
  for (const WorkspaceMapPoint& p : map.points) EXPECT_TRUE(p.reachable && p.stable);
  // Each point stands for the cell around it.
  EXPECT_NEAR(map.reachable_area, 25 * (0.004 / 4) * (0.002 / 4), 1e-15);

  options.grid = 1;
  EXPECT_THROW(workspace_map(robot, options), std::invalid_argument);
  options.grid = 5;
  options.range = std::array<double, 4>{0.002, -0.002, -0.001, 0.001};
  EXPECT_THROW(workspace_map(robot, options), std::invalid_argument);
  RobotParams<double> four = robot;
  four.num_limbs = 4;
  four.limb(3) = robot.limb(0);
  EXPECT_THROW(workspace_map(four, WorkspaceMapOptions()), std::invalid_argument);
}

}  // namespace
}  // namespace pcr
