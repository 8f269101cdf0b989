// Sequences of inputs in the order users have them (shuffled rows across the whole stroke box, long
// jumps), on random robots drawn inside the paper's intervals (3 to 5 limbs, one of each size
// loaded): independent rows give the cold solve's equilibrium row by row, and a path stays on the
// branch of its warm start, checked against the same path walked in steps too short to leave it.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "pcr/kinematics.hpp"
#include "random_robots.hpp"

namespace pcr {
namespace {

struct Case {
  int limbs;
  bool loaded;
  unsigned seed;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (int n = 3; n <= 5; ++n) {
    for (bool loaded : {false, true}) out.push_back({n, loaded, 100u * n + (loaded ? 7u : 0u)});
  }
  return out;
}

std::string name(const Case& c) {
  return std::to_string(c.limbs) + "limbs" + (c.loaded ? "_loaded" : "") + "_seed" +
         std::to_string(c.seed);
}

PlatformLoad<double> load_of(const Case& c) {
  PlatformLoad<double> load;
  if (c.loaded) {
    load.force = Vector2<double>(3e-3, -2e-3);  // N: a few times EI / L^2
    load.moment = 2e-5;                         // N m
  }
  return load;
}

/// The box the rows are drawn in (m) and their count: robots with four or more limbs are
/// pre-stressed, and most of a wider box lies past their folds, where every cold solve tries the
/// bowed variants (a fraction of a second each).
double half_box(const Case& c) { return c.limbs == 3 ? 6e-3 : 4e-3; }
int row_count(const Case& c) { return c.limbs == 3 ? 30 : 15; }

/// Joints drawn uniformly in a box of half-width `half` (m) inside the stroke, in random order.
std::vector<JointVector> scattered_joints(const RobotParams<double>& robot, double half, int count,
                                          std::mt19937_64& rng) {
  std::vector<JointVector> out;
  for (int k = 0; k < count; ++k) {
    JointVector q(robot.num_limbs);
    for (int i = 0; i < robot.num_limbs; ++i) {
      const LimbParams<double>& limb = robot.limb(i);
      std::uniform_real_distribution<double> u(std::max(limb.q_min, -half),
                                               std::min(limb.q_max, half));
      q(i) = u(rng);
    }
    out.push_back(q);
  }
  return out;
}

double pose_distance(const Pose2<double>& a, const Pose2<double>& b) {
  return std::max(std::hypot(a.x - b.x, a.y - b.y), 1e-2 * std::abs(a.theta - b.theta));
}

class Sequences : public ::testing::TestWithParam<Case> {};

TEST_P(Sequences, IndependentRowsAreTheColdSolves) {
  const Case c = GetParam();
  std::mt19937_64 rng(c.seed);
  const RobotParams<double> robot = testing::perturbed(testing::regular_robot(c.limbs), rng);
  const PlatformLoad<double> load = load_of(c);
  const std::vector<JointVector> rows = scattered_joints(robot, half_box(c), row_count(c), rng);
  ForwardSequence sequence(robot, SolverOptions(), load);
  int converged = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const ForwardSolution& row = sequence.solve(rows[r]);
    const ForwardSolution cold = forward_kinematics(robot, rows[r], SolverOptions(), load);
    ASSERT_EQ(row.summary.status, cold.summary.status) << "row " << r;
    if (!cold.summary.converged()) continue;
    ++converged;
    EXPECT_EQ(row.pose.x, cold.pose.x) << "row " << r;
    EXPECT_EQ(row.pose.y, cold.pose.y) << "row " << r;
    EXPECT_EQ(row.pose.theta, cold.pose.theta) << "row " << r;
  }
  EXPECT_GE(converged, 5) << "too few rows reach an equilibrium to test anything";

  if (c.limbs != 3) return;  // IK is square for 3 limbs
  // Poses of reachable configurations, shuffled, with some beyond the workspace.
  std::vector<Pose2<double>> poses;
  for (const JointVector& q : rows) {
    const ForwardSolution fk = forward_kinematics(robot, q, SolverOptions(), load);
    if (fk.summary.converged()) poses.push_back(fk.pose);
  }
  poses.push_back(Pose2<double>{0.02, 0.0, 0.0});
  std::shuffle(poses.begin(), poses.end(), rng);
  InverseSequence inverse(robot, SolverOptions(), load);
  for (std::size_t r = 0; r < poses.size(); ++r) {
    const InverseSolution& row = inverse.solve(poses[r]);
    const InverseSolution cold = inverse_kinematics(robot, poses[r], SolverOptions(), load);
    ASSERT_EQ(row.summary.status, cold.summary.status) << "pose " << r;
    if (!is_equilibrium(cold.summary)) continue;
    for (int i = 0; i < c.limbs; ++i) EXPECT_EQ(row.q(i), cold.q(i)) << "pose " << r;
  }
}

/// The equilibrium reached from `start` by walking the straight input path to `to` in `steps`
/// warm solves, each too short to leave the branch; not converged where the branch ends.
template <class Solution, class Input, class Solve>
Solution walk(const Solution& start, const Input& from, const Input& to, int steps, Solve&& solve) {
  Solution at = start;
  for (int k = 1; k <= steps; ++k) {
    at = solve(from + (to - from) * (double(k) / steps), at);
    if (!usable_as_warm_start(at.summary)) return at;
  }
  return at;
}

TEST_P(Sequences, APathStaysOnTheBranchOfItsWarmStart) {
  const Case c = GetParam();
  std::mt19937_64 rng(c.seed + 1);
  const RobotParams<double> robot = testing::perturbed(testing::regular_robot(c.limbs), rng);
  const PlatformLoad<double> load = load_of(c);
  const std::vector<JointVector> rows = scattered_joints(robot, half_box(c), row_count(c), rng);
  const SolverOptions options;
  const auto solve_fk = [&](const JointVector& q, const ForwardSolution& warm) {
    return forward_kinematics(robot, q, warm, options, load);
  };
  ForwardSequence path(robot, options, load, SequenceMode::kPath);
  ForwardSolution previous = home_solution(robot, options, load);
  ASSERT_TRUE(previous.summary.converged());
  int compared = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const ForwardSolution& row = path.solve(rows[r]);
    // The policy: the warm solve where it converges, else the cold one.
    const ForwardSolution warm = forward_kinematics(robot, rows[r], previous, options, load);
    const ForwardSolution expected =
        warm.summary.converged() ? warm : forward_kinematics(robot, rows[r], options, load);
    ASSERT_EQ(row.summary.status, expected.summary.status) << "row " << r;
    EXPECT_EQ(row.pose.x, expected.pose.x) << "row " << r;
    EXPECT_EQ(row.pose.theta, expected.pose.theta) << "row " << r;
    // And the warm solve's equilibrium is the one the walk in short steps reaches.
    const ForwardSolution reference = walk(previous, previous.q, rows[r], 200, solve_fk);
    if (warm.summary.converged() && reference.summary.converged()) {
      ++compared;
      EXPECT_LT(pose_distance(warm.pose, reference.pose), 2e-9) << "row " << r;
    }
    if (usable_as_warm_start(row.summary)) previous = row;
  }
  if (c.limbs == 3) EXPECT_GE(compared, 5) << "too few rows to test anything";

  if (c.limbs != 3) return;
  std::vector<Pose2<double>> poses;
  for (const JointVector& q : rows) {
    const ForwardSolution fk = forward_kinematics(robot, q, SolverOptions(), load);
    if (fk.summary.converged()) poses.push_back(fk.pose);
  }
  std::shuffle(poses.begin(), poses.end(), rng);
  // Equilibria as they come: the search for a stable one at the same pose would leave the branch.
  SolverOptions ik_options;
  ik_options.stable_inverse = false;
  const auto solve_ik = [&](const Eigen::Vector3d& p, const InverseSolution& warm) {
    return inverse_kinematics(robot, Pose2<double>{p(0), p(1), p(2)}, warm, ik_options, load);
  };
  InverseSequence inverse(robot, ik_options, load, SequenceMode::kPath);
  InverseSolution previous_ik = as_inverse_warm_start(home_solution(robot, options, load));
  int compared_ik = 0;
  for (std::size_t r = 0; r < poses.size(); ++r) {
    const InverseSolution& row = inverse.solve(poses[r]);
    const InverseSolution warm = inverse_kinematics(robot, poses[r], previous_ik, ik_options, load);
    const InverseSolution expected = usable_as_warm_start(warm.summary)
                                         ? warm
                                         : inverse_kinematics(robot, poses[r], ik_options, load);
    ASSERT_EQ(row.summary.status, expected.summary.status) << "pose " << r;
    if (is_equilibrium(expected.summary)) {
      for (int i = 0; i < c.limbs; ++i) EXPECT_EQ(row.q(i), expected.q(i)) << "pose " << r;
    }
    const Eigen::Vector3d from(previous_ik.pose.x, previous_ik.pose.y, previous_ik.pose.theta);
    const Eigen::Vector3d to(poses[r].x, poses[r].y, poses[r].theta);
    const InverseSolution reference = walk(previous_ik, from, to, 200, solve_ik);
    if (usable_as_warm_start(warm.summary) && usable_as_warm_start(reference.summary)) {
      ++compared_ik;
      for (int i = 0; i < c.limbs; ++i)
        EXPECT_NEAR(warm.q(i), reference.q(i), 2e-9) << "pose " << r;
    }
    if (usable_as_warm_start(row.summary)) previous_ik = row;
  }
  EXPECT_GE(compared_ik, 5) << "too few poses to test anything";
}

INSTANTIATE_TEST_SUITE_P(RandomRobots, Sequences, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return name(info.param);
                         });

}  // namespace
}  // namespace pcr
