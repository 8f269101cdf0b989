// The spatial configurations (pcr/calib/spatial_sampling.hpp): the Poisson-disc set's spacing, its
// points admissible by an independent cold solve (strain, stability), the D-optimal choice against
// random subsets of the same candidates on a log det computed here, and the refusal of bad options.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "pcr/calib/spatial_sampling.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"

namespace pcr {
namespace {

TEST(SpatialSampling, PoissonDiscSetIsSpacedAdmissibleAndReproducible) {
  const SpatialRobotDescription robot = continuum_stewart_gough_description();
  SpatialSamplingOptions options;
  options.count = 12;
  options.seed = 7;
  options.strain_limit =
      2.5e-3;  // the reference robot bends by 2.1e-3 to 2.8e-3 here: some refused
  const SpatialSamplingResult result = spatial_poisson_disc_sample(robot.params, options);
  ASSERT_TRUE(result.complete);
  ASSERT_EQ(result.configurations.size(), 12u);
  std::printf(
      "radius %.4g mm; %d FK solves in the run kept: %d without solution, %d over the "
      "strain limit, %d unstable\n",
      result.min_distance * 1e3, result.counts.candidates, result.counts.rejected_fk,
      result.counts.rejected_strain, result.counts.rejected_unstable);
  double closest = std::numeric_limits<double>::infinity(), worst_strain = 0;
  for (std::size_t a = 0; a < result.configurations.size(); ++a) {
    const SpatialJointVector& q = result.configurations[a];
    for (int i = 0; i < 6; ++i) {
      EXPECT_GE(q(i), kSpatialDefaultJointMin);
      EXPECT_LE(q(i), kSpatialDefaultJointMax);
    }
    for (std::size_t b = 0; b < a; ++b) {
      closest = std::min(closest, (q - result.configurations[b]).norm());
    }
    // Independently: cold FK from straight rods with its own stability check.
    SolverOptions cold;
    cold.check_stability = true;
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot.params, q, cold);
    ASSERT_TRUE(fk.summary.converged());
    EXPECT_EQ(fk.summary.stability, Stability::kStable);
    EXPECT_LE(fk.summary.max_strain, options.strain_limit);
    worst_strain = std::max(worst_strain, fk.summary.max_strain);
    EXPECT_TRUE(spatial_admissible_configuration(robot.params, q, options.strain_limit));
  }
  std::printf("closest pair %.4g mm (radius %.4g mm), largest strain %.4g (limit %.4g)\n",
              closest * 1e3, result.min_distance * 1e3, worst_strain, options.strain_limit);
  EXPECT_GE(closest, result.min_distance);
  EXPECT_GT(result.counts.rejected_strain, 0);

  const SpatialSamplingResult again = spatial_poisson_disc_sample(robot.params, options);
  ASSERT_EQ(again.configurations.size(), result.configurations.size());
  for (std::size_t k = 0; k < again.configurations.size(); ++k) {
    EXPECT_EQ(again.configurations[k], result.configurations[k]);
  }
  // visiting_order is the planar one's, on spatial joints: a permutation from nearest home.
  const std::vector<std::size_t> order = visiting_order(result.configurations);
  std::vector<std::size_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 0; k < sorted.size(); ++k) EXPECT_EQ(sorted[k], k);
  for (const SpatialJointVector& q : result.configurations) {
    EXPECT_LE(result.configurations[order[0]].norm(), q.norm());
  }
}

/// log det of the information of `subset` (6 rows each) on the span of all the rows' right
/// singular vectors above 1e-7 of the largest, by the eigenvalues of V^T F V.
double log_det_on_subspace(const Eigen::MatrixXd& stacked, const std::vector<int>& subset) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(stacked, Eigen::ComputeThinV);
  Eigen::Index r = 0;
  while (r < svd.singularValues().size() &&
         svd.singularValues()(r) > 1e-7 * svd.singularValues()(0)) {
    ++r;
  }
  const Eigen::MatrixXd V = svd.matrixV().leftCols(r);
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(r, r);
  for (int j : subset) {
    const Eigen::MatrixXd rows = stacked.middleRows(6 * j, 6) * V;
    F += rows.transpose() * rows;
  }
  const Eigen::VectorXd eigen = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(F).eigenvalues();
  return eigen.array().log().sum();
}

TEST(SpatialSampling, DOptimalBeatsRandomSubsetsOfTheCandidates) {
  const SpatialRobotDescription robot = continuum_stewart_gough_description();
  SpatialSamplingOptions options;
  options.count = 100;
  options.seed = 3;
  const std::vector<SpatialJointVector> candidates =
      spatial_poisson_disc_sample(robot.params, options).configurations;
  const int count = 24;
  const DesignResult design = spatial_d_optimal_design(robot, candidates, count, options);
  ASSERT_EQ(design.selected.size(), static_cast<std::size_t>(count));
  EXPECT_EQ(design.failed, 0);
  EXPECT_EQ(design.parameters, num_spatial_parameters(6));  // every half-width is nonzero
  EXPECT_EQ(design.rank, design.dimension);

  // The rows again, whitened and scaled here.
  const double sp = spatial_default_noise_position(robot.params), sa = kDefaultNoiseAngle;
  const int p = num_spatial_parameters(6);
  Eigen::MatrixXd stacked(6 * static_cast<Eigen::Index>(candidates.size()), p);
  for (std::size_t j = 0; j < candidates.size(); ++j) {
    Eigen::MatrixXd J;
    ASSERT_TRUE(spatial_pose_parameter_jacobian(robot, candidates[j],
                                                SpatialSensitivityPose::kMeasured, &J));
    for (int k = 0; k < p; ++k) {
      const double h = spatial_half_width(*robot.uncertainty, spatial_parameter_id(k, 6));
      stacked.block(6 * static_cast<Eigen::Index>(j), k, 3, 1) = J.block(0, k, 3, 1) * h / sp;
      stacked.block(6 * static_cast<Eigen::Index>(j) + 3, k, 3, 1) = J.block(3, k, 3, 1) * h / sa;
    }
  }
  const double chosen = log_det_on_subspace(stacked, design.selected);
  EXPECT_NEAR(chosen, design.log_det, 1e-6 * std::abs(chosen));
  std::mt19937_64 rng(11);
  std::vector<int> all(candidates.size());
  for (std::size_t j = 0; j < all.size(); ++j) all[j] = static_cast<int>(j);
  double best_random = -std::numeric_limits<double>::infinity();
  for (int draw = 0; draw < 20; ++draw) {
    std::shuffle(all.begin(), all.end(), rng);
    const std::vector<int> subset(all.begin(), all.begin() + count);
    const double random = log_det_on_subspace(stacked, subset);
    best_random = std::max(best_random, random);
    EXPECT_GE(chosen, random) << "random draw " << draw;
  }
  std::printf("identifiable dimension %d of %d; log det: d-optimal %.2f, best of 20 random %.2f\n",
              design.dimension, design.parameters, chosen, best_random);
}

TEST(SpatialSampling, BadOptionsAreRefusedByName) {
  const SpatialRobotDescription robot = continuum_stewart_gough_description();
  const auto refused = [&](const SpatialSamplingOptions& options, const std::string& field) {
    try {
      spatial_sample_configurations(robot, options);
      ADD_FAILURE() << "accepted; expected a refusal naming " << field;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  SpatialSamplingOptions options;
  options.count = 0;
  refused(options, "count");
  options = SpatialSamplingOptions();
  options.strain_limit = 0.5;
  refused(options, "strain_limit");
  options = SpatialSamplingOptions();
  options.min_distance = std::nan("");
  refused(options, "min_distance");
  options = SpatialSamplingOptions();
  options.noise_angle = 0;
  refused(options, "noise_angle");
  options = SpatialSamplingOptions();
  options.box_min = SpatialJointVector::Constant(3, 0.0);
  options.box_max = SpatialJointVector::Constant(3, 1e-3);
  refused(options, "box");
  options.box_min = SpatialJointVector::Constant(6, 2e-3);
  options.box_max = SpatialJointVector::Constant(6, 1e-3);
  refused(options, "box");
  options.box_max = SpatialJointVector::Constant(6, 5.0);  // mm typed as m
  refused(options, "box_max");
  options = SpatialSamplingOptions();
  options.solver.max_iterations = 0;
  refused(options, "max_iterations");
  SpatialRobotDescription bare = robot;
  bare.uncertainty.reset();
  EXPECT_THROW(spatial_d_optimal_design(bare, {SpatialJointVector::Constant(6, 1e-3)}, 1),
               InputError);
}

}  // namespace
}  // namespace pcr
