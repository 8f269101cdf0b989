// The spatial calibration (pcr/calib/spatial_calibrator.hpp): its exact derivatives (the platform
// load's included) against central differences of FK solved again, and identification of hidden
// virtual spatial robots to the noise floor, scored on validation rows against the noise and
// against the virtual truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"
#include "spatial_calibration_support.hpp"

namespace {

using pcr::SpatialDataset;
using pcr::SpatialJointVector;

using pcr::testing::measured;
using pcr::testing::random_joints;

TEST(SpatialCalibration, DerivativesMatchCentralDifferences) {
  // The flat deviations, then the platform load's six (force in N, moment in N m).
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  const int flat = pcr::num_spatial_parameters(6);
  const int count = flat + pcr::kSpatialLoadParameters;
  const auto size_of = [&](int k) {
    if (k >= flat) return k < flat + 3 ? 0.5 : 0.02;  // a payload of ~50 g, its moment at 4 cm
    return pcr::spatial_half_width(*nominal.uncertainty, pcr::spatial_parameter_id(k, 6));
  };
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<double> d(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) d[static_cast<std::size_t>(k)] = 0.5 * unit(rng) * size_of(k);
  pcr::SolverOptions fk;
  fk.rod_steps = 64;  // one discrete model for every solve: its derivative is what is exact
  fk.tolerance = 1e-13;
  fk.chord_output_share = 0;
  const SpatialJointVector q = random_joints(rng, 1, 0.0, 0.01)[0];
  pcr::SpatialPose<double> measured;
  measured.position = Eigen::Vector3d(0.01, -0.02, 0.4);
  const double weight = 0.1, scale = 1e-7;
  Eigen::Matrix<double, 6, 1> r;
  Eigen::MatrixXd J;
  ASSERT_TRUE(
      pcr::spatial_measurement_jacobian(nominal, d, q, measured, weight, scale, &r, &J, fk));
  double worst = 0;
  for (int k = 0; k < count; ++k) {
    const double h = 1e-3 * std::max(1e-9, size_of(k));
    Eigen::Matrix<double, 6, 1> sides[2];
    for (int s = 0; s < 2; ++s) {
      std::vector<double> moved = d;
      moved[static_cast<std::size_t>(k)] += s == 0 ? h : -h;
      Eigen::MatrixXd unused;
      ASSERT_TRUE(pcr::spatial_measurement_jacobian(nominal, moved, q, measured, weight, scale,
                                                    &sides[s], &unused, fk));
    }
    const Eigen::Matrix<double, 6, 1> difference = (sides[0] - sides[1]) / (2 * h);
    // Relative to the column's size, and to the residual's sensitivity at this step (rounding).
    const double error =
        (difference - J.col(k)).norm() / (J.col(k).norm() + 1e-6 * (r.norm() + 1.0) / h);
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-5) << pcr::spatial_parameter_name(pcr::spatial_parameter_id(k, 6))
                           << "\n  exact " << J.col(k).transpose() << "\n  differences "
                           << difference.transpose();
  }
  std::printf("worst relative derivative error: %.3g\n", worst);
}

TEST(SpatialCalibration, HiddenRobotsAreIdentifiedToTheNoiseFloor) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  // A truth drawn uniformly inside the intervals, and one in their corners (+-0.9 half-widths).
  const std::pair<std::uint64_t, double> truths[] = {{7, 0.0}, {23, 0.9}};
  for (const auto& [seed, fraction] : truths) {
    pcr::SpatialVirtualRobotOptions options;
    options.seed = seed;
    options.truth_at_fraction = fraction;
    pcr::SpatialVirtualRobot robot(nominal, options);
    std::mt19937_64 rng(options.seed);
    const SpatialDataset calibration = measured(robot, random_joints(rng, 60, 0.0, 0.01));
    const std::vector<SpatialJointVector> validation_q = random_joints(rng, 20, 0.0, 0.01);
    const SpatialDataset validation = measured(robot, validation_q);
    ASSERT_GE(calibration.size(), 50u);
    ASSERT_GE(validation.size(), 15u);

    const pcr::SpatialCalibrationResult result = pcr::calibrate_spatial(nominal, calibration);
    for (const pcr::SpatialStageReport& s : result.stages) {
      std::printf("  stage %-10s free %3zu unseen %d cost %.4g -> %.4g in %d iterations, %.2f s\n",
                  s.name.c_str(), s.free_parameters.size(), s.unseen_directions, s.initial_cost,
                  s.final_cost, s.iterations, s.time_s);
    }
    for (const std::string& w : result.warnings) std::printf("  warning: %s\n", w.c_str());
    for (const std::string& u : result.unidentifiable)
      std::printf("  unidentifiable: %s\n", u.c_str());

    // The noise floor: a perfect model's rms position (angle) error is sqrt(3) sigma.
    const double sigma_p = robot.noise_position(), sigma_a = options.noise_angle;
    const pcr::SpatialPredictionErrors nominal_errors =
        pcr::spatial_prediction_errors(nominal.params, validation);
    const pcr::SpatialPredictionErrors identified =
        pcr::spatial_prediction_errors(result.identified, validation);
    // Scored against the virtual truth: the identified model against noise-free measurements.
    robot.return_home();
    const SpatialDataset exact = measured(robot, validation_q, true);
    const pcr::SpatialPredictionErrors truth_score =
        pcr::spatial_prediction_errors(result.identified, exact);
    std::printf(
        "truth at %.1f: %zu rows, %.2f s, rank %d of %d, variance %.3f; validation rms %.3g m "
        "%.3g rad (noise floor %.3g m %.3g rad; nominal %.3g m %.3g rad); against the truth "
        "%.3g m %.3g rad\n",
        fraction, calibration.size(), result.time_s, result.jacobian_rank, result.free_count,
        result.residual_variance, identified.rms_position, identified.rms_angle,
        std::sqrt(3.0) * sigma_p, std::sqrt(3.0) * sigma_a, nominal_errors.rms_position,
        nominal_errors.rms_angle, truth_score.rms_position, truth_score.rms_angle);
    EXPECT_EQ(identified.failures, 0);
    EXPECT_GT(nominal_errors.rms_position, 100 * sigma_p);  // there was something to identify
    EXPECT_LT(identified.rms_position, 1.3 * std::sqrt(3.0) * sigma_p);
    EXPECT_LT(identified.rms_angle, 1.3 * std::sqrt(3.0) * sigma_a);
    // The identified model's own error, against noise-free measurements: below the floor.
    EXPECT_LT(truth_score.rms_position, std::sqrt(3.0) * sigma_p);
    EXPECT_LT(truth_score.rms_angle, std::sqrt(3.0) * sigma_a);
    EXPECT_LT(result.residual_variance, 1.5);

    // The nominal model of Tables 3 and 4: the nominal geometry, the extrinsics fitted to it.
    std::vector<double> moved(static_cast<std::size_t>(pcr::num_spatial_parameters(6)));
    pcr::spatial_deviations(nominal.params, result.extrinsics_only, moved.data());
    for (int k = 0; k < pcr::num_spatial_parameters(6); ++k) {
      const bool extrinsic = k >= pcr::kSpatialRodParameters * 6;
      if (!extrinsic) EXPECT_EQ(moved[static_cast<std::size_t>(k)], 0.0) << k;
    }
    const double fitted =
        pcr::spatial_prediction_errors(result.extrinsics_only, calibration).rms_position;
    const double as_described =
        pcr::spatial_prediction_errors(nominal.params, calibration).rms_position;
    std::printf("  nominal model on the calibration set: %.3g m (as described %.3g m)\n", fitted,
                as_described);
    EXPECT_LT(fitted, as_described);
  }
}

}  // namespace
