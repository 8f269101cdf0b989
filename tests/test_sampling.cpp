// Poisson-disc sampling of joint configurations: spacing, box, FK convergence from home, strain
// limit (checked with independent cold-start FK), reproducibility.
#include <gtest/gtest.h>

#include <cmath>

#include "pcr/calib/sampling.hpp"
#include "pcr/robot_io.hpp"

namespace pcr {
namespace {

double min_pairwise_distance(const std::vector<JointVector>& points) {
  double d = INFINITY;
  for (std::size_t a = 0; a < points.size(); ++a) {
    for (std::size_t b = a + 1; b < points.size(); ++b)
      d = std::min(d, (points[a] - points[b]).norm());
  }
  return d;
}

/// Every point inside the box, FK from home converges (cold start) under the strain limit.
void expect_admissible(const RobotParams<double>& robot, const SamplingResult& result,
                       double strain_limit) {
  for (const JointVector& q : result.configurations) {
    for (int i = 0; i < q.size(); ++i) {
      EXPECT_GE(q(i), result.box_min(i));
      EXPECT_LE(q(i), result.box_max(i));
    }
    const ForwardSolution fk = forward_kinematics(robot, q);
    EXPECT_TRUE(fk.summary.converged()) << to_string(fk.summary.status);
    EXPECT_LE(fk.summary.max_strain, strain_limit);
  }
}

/// A sub-box of the strokes that the default robot reaches everywhere (keeps the test fast: the
/// unreachable corners of the full strokes cost a whole continuation each).
SamplingOptions centre_box(int count, std::uint64_t seed) {
  SamplingOptions options;
  options.count = count;
  options.seed = seed;
  options.box_min = JointVector::Constant(3, -5e-3);
  options.box_max = JointVector::Constant(3, 5e-3);
  return options;
}

TEST(Sampling, RadiusChosenFromTheCount) {
  const RobotParams<double> robot = default_robot().params;
  const SamplingOptions options = centre_box(30, 3);
  const SamplingResult result = poisson_disc_sample(robot, options);
  ASSERT_TRUE(result.complete);
  ASSERT_EQ(result.configurations.size(), 30u);
  // 30 to 48 points in a 10 mm cube: a maximal set with r ~ 2.5 mm.
  EXPECT_GT(result.min_distance, 1.5e-3);
  EXPECT_LT(result.min_distance, 5e-3);
  EXPECT_GE(min_pairwise_distance(result.configurations), result.min_distance);
  expect_admissible(robot, result, options.strain_limit);
  // Spread over the box: each coordinate spans most of it.
  for (int i = 0; i < 3; ++i) {
    double lo = INFINITY, hi = -INFINITY;
    for (const JointVector& q : result.configurations) {
      lo = std::min(lo, q(i));
      hi = std::max(hi, q(i));
    }
    EXPECT_GT(hi - lo, 6e-3);
  }
}

TEST(Sampling, WholeStrokesReproducibleWithTheSeed) {
  const RobotParams<double> robot = default_robot().params;
  SamplingOptions options;
  options.count = 8;
  options.min_distance = 6e-3;
  options.seed = 5;
  const SamplingResult a = poisson_disc_sample(robot, options);
  ASSERT_TRUE(a.complete);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.box_min(i), robot.limb(i).q_min);
    EXPECT_EQ(a.box_max(i), robot.limb(i).q_max);
  }
  EXPECT_GE(min_pairwise_distance(a.configurations), 6e-3);
  expect_admissible(robot, a, options.strain_limit);
  const SamplingResult b = poisson_disc_sample(robot, options);
  ASSERT_EQ(a.configurations.size(), b.configurations.size());
  for (std::size_t k = 0; k < a.configurations.size(); ++k) {
    EXPECT_EQ(a.configurations[k], b.configurations[k]);
  }
  options.seed = 6;
  const SamplingResult c = poisson_disc_sample(robot, options);
  EXPECT_NE(a.configurations[0], c.configurations[0]);
}

TEST(Sampling, SubBoxGivenRadiusAndStrainLimit) {
  const RobotParams<double> robot = default_robot().params;
  SamplingOptions options;
  options.count = 15;
  options.seed = 11;
  options.min_distance = 3e-3;
  options.strain_limit = 0.003;  // tighter than what the box corners reach
  options.box_min = JointVector::Constant(3, -7e-3);
  options.box_max = JointVector::Constant(3, 7e-3);
  const SamplingResult result = poisson_disc_sample(robot, options);
  ASSERT_TRUE(result.complete);
  EXPECT_EQ(result.min_distance, 3e-3);
  EXPECT_GE(min_pairwise_distance(result.configurations), 3e-3);
  expect_admissible(robot, result, 0.003);
  EXPECT_GT(result.rejected_strain, 0);  // the limit was active
}

TEST(Sampling, SplitGivesDisjointSets) {
  const RobotParams<double> robot = default_robot().params;
  SamplingOptions options = centre_box(20, 9);
  options.min_distance = 2e-3;
  const SamplingResult all = poisson_disc_sample(robot, options);
  std::vector<JointVector> calibration, validation;
  split_configurations(all.configurations, 12, &calibration, &validation);
  EXPECT_EQ(calibration.size(), 12u);
  EXPECT_EQ(validation.size(), 8u);
  for (const JointVector& a : calibration) {
    for (const JointVector& b : validation) EXPECT_GE((a - b).norm(), 2e-3);
  }
  EXPECT_THROW(split_configurations(all.configurations, 21, &calibration, &validation), InputError);
}

TEST(Sampling, RejectsBadOptions) {
  const RobotParams<double> robot = default_robot().params;
  SamplingOptions options;
  options.count = 0;
  EXPECT_THROW(poisson_disc_sample(robot, options), InputError);
  options = SamplingOptions();
  options.box_min = JointVector::Constant(3, 1e-3);
  options.box_max = JointVector::Constant(3, -1e-3);
  EXPECT_THROW(poisson_disc_sample(robot, options), InputError);
  options.box_max = JointVector::Constant(2, 1e-3);
  EXPECT_THROW(poisson_disc_sample(robot, options), InputError);
}

}  // namespace
}  // namespace pcr
