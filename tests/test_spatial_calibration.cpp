// The spatial calibration (pcr/calib/spatial_calibrator.hpp): its exact derivatives (the platform
// load's included) against central differences of FK solved again, and identification of hidden
// virtual spatial robots to the noise floor, scored on validation rows against the noise and
// against the virtual truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "pcr/calib/model_selection.hpp"
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

// Three of 60 rows measured 1 mm off (hundreds of noise units: a mislabelled row, another
// equilibrium): each stage leaves them out (gross outliers), the result names exactly them, and
// the identified model is scored against the virtual truth as on clean data; least squares is not.
TEST(SpatialCalibration, GrossOutliersAreNamedAndLeftOut) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  pcr::SpatialVirtualRobotOptions options;
  options.seed = 7;
  pcr::SpatialVirtualRobot robot(nominal, options);
  std::mt19937_64 rng(options.seed);
  SpatialDataset calibration = measured(robot, random_joints(rng, 60, 0.0, 0.01));
  const std::vector<SpatialJointVector> validation_q = random_joints(rng, 20, 0.0, 0.01);
  ASSERT_GE(calibration.size(), 50u);
  const std::size_t corrupted[] = {5, 23, 41};
  for (const std::size_t j : corrupted)
    calibration.poses[j].position += Eigen::Vector3d(0, 1e-3, 0);

  const pcr::SpatialCalibrationResult result = pcr::calibrate_spatial(nominal, calibration);
  for (const std::string& w : result.warnings) std::printf("  warning: %s\n", w.c_str());
  ASSERT_EQ(result.outliers.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {  // "row 6 (432 x the noise)": 1-based rows
    const std::string name = "row " + std::to_string(corrupted[k] + 1) + " (";
    EXPECT_EQ(result.outliers[k].rfind(name, 0), 0u) << result.outliers[k];
  }
  EXPECT_GT(result.outlier_threshold, 0.0);
  EXPECT_FALSE(result.residuals_exceed_noise);  // the other rows are at the noise
  EXPECT_LT(result.residual_variance, 1.5);

  robot.return_home();
  const SpatialDataset exact = measured(robot, validation_q, true);
  const pcr::SpatialPredictionErrors truth_score =
      pcr::spatial_prediction_errors(result.identified, exact);
  const double floor_p = std::sqrt(3.0) * robot.noise_position();
  const double floor_a = std::sqrt(3.0) * options.noise_angle;
  std::printf(
      "3 rows 1 mm off: outlier threshold %.3g, variance %.3f; against the truth %.3g m "
      "%.3g rad (floor %.3g m %.3g rad)\n",
      result.outlier_threshold, result.residual_variance, truth_score.rms_position,
      truth_score.rms_angle, floor_p, floor_a);
  EXPECT_LT(truth_score.rms_position, floor_p);
  EXPECT_LT(truth_score.rms_angle, floor_a);

  // Plain least squares (robust_scale 0) on the same rows: no outlier is named, and the three
  // rows pull the model off the truth.
  pcr::SpatialCalibrationOptions plain;
  plain.robust_scale = 0;
  const pcr::SpatialCalibrationResult least_squares =
      pcr::calibrate_spatial(nominal, calibration, plain);
  const pcr::SpatialPredictionErrors plain_score =
      pcr::spatial_prediction_errors(least_squares.identified, exact);
  std::printf("least squares: variance %.3g; against the truth %.3g m %.3g rad\n",
              least_squares.residual_variance, plain_score.rms_position, plain_score.rms_angle);
  EXPECT_TRUE(least_squares.outliers.empty());
  EXPECT_EQ(least_squares.outlier_threshold, 0.0);
  EXPECT_TRUE(least_squares.residuals_exceed_noise);
  EXPECT_GT(plain_score.rms_position, 10 * truth_score.rms_position);
}

// Model selection on a spatial robot (pcr::calibrate_selecting_model): a 100 g payload the
// nominal robot does not know leaves residuals beyond the noise, and the load model (the platform
// wrench's six values in the last stage) predicts the validation rows better: chosen. Without
// the payload the residuals are at the noise: the stages' model, the load model not even fitted.
TEST(SpatialCalibration, SelectionKeepsTheLoadModelOnlyForAnUnmodelledPayload) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  for (const double payload : {0.1, 0.0}) {
    pcr::SpatialVirtualRobotOptions options;
    options.seed = 11;
    options.effects.payload = payload;
    pcr::SpatialVirtualRobot robot(nominal, options);
    std::mt19937_64 rng(options.seed);
    const SpatialDataset calibration = measured(robot, random_joints(rng, 40, 0.0, 0.01));
    const SpatialDataset validation = measured(robot, random_joints(rng, 20, 0.0, 0.01));
    ASSERT_GE(calibration.size(), 35u);
    ASSERT_GE(validation.size(), 15u);
    const pcr::SpatialModelSelection selection =
        pcr::calibrate_selecting_model(nominal, calibration, validation);
    std::printf("payload %.2f kg: stages' variance %.3g; %s\n", payload,
                selection.stages.residual_variance, selection.decision.c_str());
    EXPECT_EQ(selection.stages.residuals_exceed_noise, payload > 0);
    EXPECT_EQ(selection.tried_load, payload > 0);
    EXPECT_EQ(selection.load_chosen, payload > 0);
    EXPECT_EQ(selection.chosen().load_identified, payload > 0);
    if (payload > 0) {
      const double weight = payload * nominal.params.gravity.z();
      const pcr::SpatialParameterEstimate& f_z =
          selection.load.parameters[static_cast<std::size_t>(pcr::num_spatial_parameters(6) + 2)];
      std::printf("  f_z %.4f N +- %.4f (m g %.4f N)\n", f_z.deviation, f_z.std_dev, weight);
      EXPECT_NEAR(f_z.deviation, weight, 4 * f_z.std_dev);
      EXPECT_GT(selection.t, pcr::kModelSelectionT);
      EXPECT_LT(selection.load_table.identified_validation.rms_position,
                selection.stages_table.identified_validation.rms_position);
    }
  }
}

}  // namespace
