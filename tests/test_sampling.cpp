// Poisson-disc sampling of joint configurations: spacing, box, FK convergence from home, strain
// limit (checked with independent cold-start FK), reproducibility. D-optimal design: a larger
// log det of the scaled information on the identifiable subspace than Poisson-disc sampling,
// computed here from the stacked Jacobian, not from the greedy choice's running value.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/robot_io.hpp"
#include "sanitized_build.hpp"

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

struct Information {
  double log_det = 0;
  int rank = 0;
  int dimension = 0;
};

/// The scaled information of `configurations` on the identifiable subspace, built here from the
/// gauge: rows whitened by the paper's noise, columns scaled by the half-widths (the parameters
/// with a nonzero one), projected on the orthonormal complement of the gauge generators; log det
/// and rank from the SVD of the stacked rows.
Information identifiable_information(const RobotDescription& robot,
                                     const std::vector<JointVector>& configurations) {
  const std::vector<double> h = parameter_half_widths(*robot.uncertainty, robot.params.num_limbs);
  std::vector<int> free;
  for (std::size_t k = 0; k < h.size(); ++k) {
    if (h[k] > 0) free.push_back(static_cast<int>(k));
  }
  const Eigen::Index f = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd gauge(f, 0);
  for (const GaugeGenerator& g : gauge_generators(robot.params)) {
    Eigen::VectorXd scaled = Eigen::VectorXd::Zero(f);
    double outside = 0;
    for (std::size_t k = 0; k < h.size(); ++k) {
      const auto at = std::find(free.begin(), free.end(), static_cast<int>(k));
      if (at == free.end()) {
        outside += std::abs(g.direction[k]);
      } else {
        scaled(at - free.begin()) = g.direction[k] / h[k];
      }
    }
    if (outside == 0 && scaled.norm() > 0) {
      gauge.conservativeResize(f, gauge.cols() + 1);
      gauge.col(gauge.cols() - 1) = scaled;
    }
  }
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(gauge).householderQ();
  const Eigen::MatrixXd complement = q.rightCols(f - gauge.cols());
  Eigen::MatrixXd stacked(3 * static_cast<Eigen::Index>(configurations.size()), f);
  for (std::size_t j = 0; j < configurations.size(); ++j) {
    Eigen::MatrixXd J;
    EXPECT_TRUE(measurement_jacobian(robot.params, configurations[j],
                                     kDefaultNoisePosition / kDefaultNoiseAngle,
                                     kDefaultNoisePosition, &J));
    for (Eigen::Index c = 0; c < f; ++c) {
      const std::size_t k = static_cast<std::size_t>(free[static_cast<std::size_t>(c)]);
      stacked.block(3 * static_cast<Eigen::Index>(j), c, 3, 1) =
          J.col(static_cast<Eigen::Index>(k)) * h[k];
    }
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(stacked * complement);
  const Eigen::VectorXd sv = svd.singularValues();
  Information out;
  out.dimension = static_cast<int>(complement.cols());
  for (Eigen::Index k = 0; k < sv.size(); ++k) {
    out.log_det += 2 * std::log(sv(k));
    if (sv(k) > 1e-7 * sv(0)) ++out.rank;
  }
  return out;
}

TEST(Sampling, DesignNames) {
  EXPECT_EQ(parse_sampling_design("poisson-disc"), SamplingDesign::kPoissonDisc);
  EXPECT_EQ(parse_sampling_design("d-optimal"), SamplingDesign::kDOptimal);
  EXPECT_EQ(sampling_design_name(SamplingDesign::kDOptimal), "d-optimal");
  try {
    parse_sampling_design("D-optimal");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'D-optimal'"), std::string::npos) << e.what();
  }
}

TEST(Sampling, DOptimalBeatsPoissonDiscOnTheIdentifiableSubspace) {
  // 300 candidates' identification Jacobians: 8 s in Release, over 3 min under the sanitizers,
  // where DOptimalIsDeterministicAndChecksItsInputs runs the same code on 60.
  if (pcr::test::kSanitized) GTEST_SKIP() << "Release build only (slow under the sanitizers)";
  const RobotDescription robot = default_robot();
  SamplingOptions options;
  options.count = 30;
  options.seed = 4;
  const ConfigurationSets spread = sample_configurations(robot, options, 10);
  options.design = SamplingDesign::kDOptimal;
  const ConfigurationSets designed = sample_configurations(robot, options, 10);
  ASSERT_EQ(spread.calibration.size(), 30u);
  ASSERT_EQ(designed.calibration.size(), 30u);

  // The same Poisson-disc validation set, disjoint from the chosen configurations.
  ASSERT_EQ(designed.validation.size(), 10u);
  for (std::size_t k = 0; k < 10; ++k) EXPECT_EQ(designed.validation[k], spread.validation[k]);
  for (const JointVector& a : designed.calibration) {
    for (const JointVector& b : designed.validation) {
      EXPECT_GE((a - b).norm(), designed.candidates.min_distance);
    }
  }
  // Of the 10 x 30 candidates, those near the validation set are left out.
  EXPECT_LE(designed.candidates.configurations.size(),
            static_cast<std::size_t>(kDesignCandidateFactor * 30));
  EXPECT_GT(designed.candidates.configurations.size(), 200u);
  ASSERT_EQ(designed.design.selected.size(), 30u);
  for (std::size_t k = 0; k < 30; ++k) {
    EXPECT_EQ(
        designed.calibration[k],
        designed.candidates.configurations[static_cast<std::size_t>(designed.design.selected[k])]);
  }
  for (std::size_t a = 0; a < designed.calibration.size(); ++a) {
    for (std::size_t b = a + 1; b < designed.calibration.size(); ++b)
      EXPECT_NE(designed.calibration[a], designed.calibration[b]);
  }

  const Information poisson = identifiable_information(robot, spread.calibration);
  const Information optimal = identifiable_information(robot, designed.calibration);
  // femto-3pf: 33 parameters with a half-width (E has none), minus the 7 gauge directions.
  EXPECT_EQ(designed.design.parameters, 33);
  EXPECT_EQ(optimal.dimension, 26);
  EXPECT_EQ(designed.design.dimension, 26);
  EXPECT_EQ(optimal.rank, 26);
  EXPECT_EQ(designed.design.rank, 26);
  EXPECT_GT(optimal.log_det, poisson.log_det);
  // The reported value is the same quantity (any orthonormal basis of the same subspace).
  EXPECT_NEAR(designed.design.log_det, optimal.log_det, 1e-6 * std::abs(optimal.log_det));
  std::printf("log det on the identifiable subspace, N = 30: poisson-disc %.2f, d-optimal %.2f\n",
              poisson.log_det, optimal.log_det);
}

TEST(Sampling, DOptimalIsDeterministicAndChecksItsInputs) {
  const RobotDescription robot = default_robot();
  SamplingOptions options = centre_box(12, 7);
  options.design = SamplingDesign::kDOptimal;
  options.candidates = 60;
  const ConfigurationSets a = sample_configurations(robot, options);
  const ConfigurationSets b = sample_configurations(robot, options);
  EXPECT_TRUE(a.spread.configurations.empty());  // no validation: no spread draw
  ASSERT_EQ(a.calibration.size(), 12u);
  EXPECT_EQ(a.calibration, b.calibration);
  EXPECT_EQ(a.design.selected, b.design.selected);

  const std::vector<JointVector> few(a.calibration.begin(), a.calibration.begin() + 3);
  EXPECT_THROW(d_optimal_design(robot, few, 4), InputError);
  RobotDescription bare = robot;
  bare.uncertainty.reset();
  EXPECT_THROW(d_optimal_design(bare, few, 2), InputError);
}

}  // namespace
}  // namespace pcr
