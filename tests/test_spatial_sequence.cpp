// Sequences of spatial FK and IK inputs (pcr/spatial/sequence.hpp): independent inputs give the
// cold solve's result whatever the order, to the bit; a path gives the same equilibria, warm; IK
// of FK's poses gives back the joints; a long jump stays on its start's branch.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "pcr/spatial/sequence.hpp"

namespace {

using namespace pcr;

bool same_bits(const SpatialPose<double>& a, const SpatialPose<double>& b) {
  return std::memcmp(a.position.data(), b.position.data(), 3 * sizeof(double)) == 0 &&
         std::memcmp(a.orientation.data(), b.orientation.data(), 4 * sizeof(double)) == 0;
}
bool same_bits(const SpatialJointVector& a, const SpatialJointVector& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
}

/// Joints of the reference robot about 5 mm out, up to 10 mm apart (as test_spatial_kinematics).
std::vector<SpatialJointVector> random_joints(int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<SpatialJointVector> rows;
  for (int r = 0; r < count; ++r) {
    SpatialJointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = 0.005 + 0.01 * u(rng);
    rows.push_back(q);
  }
  return rows;
}

TEST(SpatialSequence, IndependentInputsDoNotDependOnTheirOrder) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const std::vector<SpatialJointVector> rows = random_joints(5, 5);
  const std::vector<std::size_t> orders[] = {{0, 1, 2, 3, 4}, {4, 2, 0, 3, 1}, {3, 4, 1, 0, 2}};

  // FK: each row the cold solve's, to the bit, in every order.
  std::vector<SpatialForwardSolution> first(rows.size());
  for (const auto& order : orders) {
    SpatialForwardSequence sequence(robot);
    for (const std::size_t r : order) {
      const SpatialForwardSolution& s = sequence.solve(rows[r]);
      ASSERT_TRUE(s.summary.converged()) << "row " << r << " " << to_string(s.summary.status);
      if (&order == &orders[0]) {
        first[r] = s;
        EXPECT_TRUE(same_bits(s.pose, spatial_forward_kinematics(robot, rows[r]).pose));
      } else {
        EXPECT_TRUE(same_bits(s.pose, first[r].pose)) << "row " << r;
        EXPECT_EQ(s.summary.iterations, first[r].summary.iterations) << "row " << r;
      }
    }
  }

  // IK of those poses: from the home solution, the same bits in every order; the joints back.
  std::vector<SpatialJointVector> joints(rows.size());
  double worst = 0;
  for (const auto& order : orders) {
    SpatialInverseSequence sequence(robot);
    for (const std::size_t r : order) {
      const SpatialInverseSolution& s = sequence.solve(first[r].pose);
      ASSERT_TRUE(s.summary.converged()) << "row " << r << " " << to_string(s.summary.status);
      if (&order == &orders[0]) {
        joints[r] = s.q;
        worst = std::max(worst, (s.q - rows[r]).lpNorm<Eigen::Infinity>());
        EXPECT_TRUE(same_bits(s.q, spatial_inverse_kinematics(robot, first[r].pose).q));
      } else {
        EXPECT_TRUE(same_bits(s.q, joints[r])) << "row " << r;
      }
    }
  }
  std::printf("IK of FK over %zu independent rows: joints within %.2e m\n", rows.size(), worst);
  EXPECT_LT(worst, 1e-9);
}

TEST(SpatialSequence, APathReachesTheSameEquilibriaWarm) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  // A short path: each row 1 mm or less from the last.
  std::vector<SpatialJointVector> rows = random_joints(1, 9);
  std::mt19937_64 rng(10);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int r = 1; r < 6; ++r) {
    SpatialJointVector q = rows.back();
    for (int i = 0; i < 6; ++i) q(i) += 0.001 * u(rng);
    rows.push_back(q);
  }
  SpatialForwardSequence path(robot, SolverOptions(), SequenceMode::kPath);
  SpatialInverseSequence inverse(robot, SolverOptions(), SequenceMode::kPath);
  double worst_pose = 0, worst_joints = 0;
  int path_evaluations = 0, cold_evaluations = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const SpatialForwardSolution& s = path.solve(rows[r]);
    ASSERT_TRUE(s.summary.converged()) << "row " << r;
    const SpatialForwardSolution cold = spatial_forward_kinematics(robot, rows[r]);
    ASSERT_TRUE(cold.summary.converged()) << "row " << r;
    worst_pose = std::max(worst_pose, (s.pose.position - cold.pose.position).norm());
    if (r > 0) {
      path_evaluations += s.summary.residual_evaluations;
      cold_evaluations += cold.summary.residual_evaluations;
    }
    const SpatialInverseSolution& ik = inverse.solve(s.pose);
    ASSERT_TRUE(ik.summary.converged()) << "row " << r;
    worst_joints = std::max(worst_joints, (ik.q - rows[r]).lpNorm<Eigen::Infinity>());
  }
  std::printf(
      "path of %zu rows: poses within %.2e m of the cold solves, %d residual evaluations "
      "against %d cold; IK joints within %.2e m\n",
      rows.size(), worst_pose, path_evaluations, cold_evaluations, worst_joints);
  EXPECT_LT(worst_pose, 1e-9);
  EXPECT_LT(worst_joints, 1e-9);
  EXPECT_LT(path_evaluations, cold_evaluations);
}

/// A warm solve over a long jump of the inputs lands where the robot goes when it moves there:
/// on the branch of its start, as a path of short steps (each 1/50 of the jump) follows it. Pairs
/// drawn anywhere in the joint range, in no order; a pair whose short-step path does not reach its
/// end (a fold on the way: the robot would snap) says nothing and is not counted.
TEST(SpatialSequence, ALongJumpLandsOnItsStartsBranch) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const std::vector<SpatialJointVector> ends = random_joints(40, 21);
  constexpr int kShortSteps = 50;
  int compared = 0;
  double worst_fk = 0, worst_ik = 0;
  for (std::size_t p = 0; p + 1 < ends.size(); p += 2) {
    const SpatialForwardSolution start = spatial_forward_kinematics(robot, ends[p]);
    ASSERT_TRUE(start.summary.converged()) << "pair " << p;
    SpatialForwardSolution fine = start;
    bool reached = true;
    for (int k = 1; k <= kShortSteps && reached; ++k) {
      const double t = static_cast<double>(k) / kShortSteps;
      fine = spatial_forward_kinematics(robot, (1 - t) * ends[p] + t * ends[p + 1], fine);
      reached = fine.summary.converged() && fine.summary.path_fraction == 1.0;
    }
    if (!reached) continue;
    ++compared;
    const SpatialForwardSolution jump = spatial_forward_kinematics(robot, ends[p + 1], start);
    ASSERT_TRUE(jump.summary.converged()) << "pair " << p;
    worst_fk = std::max(worst_fk, (jump.pose.position - fine.pose.position).norm());
    // IK over the same jump of poses, from the start's equilibrium, gives the joints back.
    const SpatialInverseSolution ik = spatial_inverse_kinematics(robot, fine.pose, start);
    ASSERT_TRUE(ik.summary.converged()) << "pair " << p;
    worst_ik = std::max(worst_ik, (ik.q - ends[p + 1]).lpNorm<Eigen::Infinity>());
  }
  std::printf(
      "%d long jumps of %zu: FK within %.2e m of the short-step paths, IK joints within "
      "%.2e m\n",
      compared, ends.size() / 2, worst_fk, worst_ik);
  EXPECT_GE(compared, 15);
  EXPECT_LT(worst_fk, 1e-9);
  EXPECT_LT(worst_ik, 1e-9);
}

TEST(SpatialSequence, IkOfAnotherRodCountIsUnsupported) {
  SpatialRobotParams<double> robot = continuum_stewart_gough();
  robot.num_rods = 4;  // IK is square for 3, 5 and 6 rods
  SpatialInverseSequence sequence(robot);
  EXPECT_EQ(sequence.solve(SpatialPose<double>()).summary.status, SolveStatus::kUnsupported);
}

}  // namespace
