// Identification over many virtual robots:
// - from anywhere in the uncertainty intervals: truths drawn uniformly inside them and truths
//   with every parameter at +-0.9 half-widths (where the bounds and the gauge meet) all reach the
//   noise floor on validation configurations they were not identified from (the reference is the
//   truth itself: its noise-free predictions are what the validation errors measure against).
//   Seeded, the first seeds of each kind; a larger sweep is bench_calibration's;
// - the reported standard deviations against the spread of the identified values over 50 draws
//   of the measurement noise (the reference is the empirical spread);
// - a row millimetres off among clean ones;
// - a constant load on the platform, identified with the geometry: both against the truth, within
//   the reported standard deviations, and the validation set at the floor;
// - model selection: an unknown load drawn at random is found by the residual test, the load
//   model is kept by the validation test and reaches the floor; clean data keep the stages.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace pcr {
namespace {

struct SweepCase {
  double truth_at_fraction;  ///< 0: uniform inside the intervals
  std::uint64_t seed;
};

class CalibrationSweep : public ::testing::TestWithParam<SweepCase> {};

/// The paper's 99 calibration and 56 validation configurations (Poisson-disc, `seed`) measured on
/// `robot`.
struct Measured {
  std::vector<CalibrationSample> calibration, validation;
};
Measured measure_paper_sets(const RobotDescription& nominal, VirtualRobot& robot,
                            std::uint64_t seed) {
  constexpr int kCalibration = 99, kValidation = 56;
  SamplingOptions so;
  so.count = kCalibration + kValidation;
  so.seed = seed;
  const SamplingResult sampled = poisson_disc_sample(nominal.params, so);
  EXPECT_TRUE(sampled.complete);
  if (sampled.configurations.size() < static_cast<std::size_t>(kCalibration + kValidation))
    return {};
  const auto measure = [&](std::size_t from, std::size_t to) {  // each set from home
    const std::vector<JointVector> rows(sampled.configurations.begin() + from,
                                        sampled.configurations.begin() + to);
    const std::vector<VirtualMeasurement> measured = robot.measure_dataset(rows);
    std::vector<CalibrationSample> out;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      EXPECT_TRUE(measured[k].ok) << "configuration " << from + k + 1;
      out.push_back({rows[k], measured[k].measured});
    }
    return out;
  };
  Measured out;
  out.calibration = measure(0, kCalibration);
  out.validation = measure(kCalibration, sampled.configurations.size());
  return out;
}

TEST_P(CalibrationSweep, ReachesTheNoiseFloor) {
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = GetParam().seed;
  vo.truth_at_fraction = GetParam().truth_at_fraction;
  VirtualRobot robot(nominal, vo);
  const auto [calibration, validation] = measure_paper_sets(nominal, robot, GetParam().seed);
  CalibrationOptions options;
  options.compute_covariance = false;
  const CalibrationResult result = calibrate(nominal, calibration, options);
  for (const StageReport& stage : result.stages) EXPECT_TRUE(stage.usable) << stage.termination;
  const PoseErrorStats before = pose_errors(result.extrinsics_only, validation);
  const PoseErrorStats after = pose_errors(result.identified, validation);
  std::printf("truth at %.1f half-widths, seed %d: validation e_p mean %.4f um (nominal %.2f um)\n",
              GetParam().truth_at_fraction, static_cast<int>(GetParam().seed), after.mean_p * 1e6,
              before.mean_p * 1e6);
  EXPECT_EQ(after.failed, 0);
  EXPECT_GT(before.mean_p, 1e-6);  // the nominal model is micrometres off
  // The noise floor: the truth itself scores about 0.012 um with the paper's noise.
  EXPECT_LE(after.mean_p, 0.05e-6);
}

INSTANTIATE_TEST_SUITE_P(TruthsInsideTheIntervals, CalibrationSweep,
                         ::testing::Values(SweepCase{0.9, 1}, SweepCase{0.9, 2}, SweepCase{0.9, 3},
                                           SweepCase{0.0, 1}, SweepCase{0.0, 2}, SweepCase{0.0, 3}),
                         [](const ::testing::TestParamInfo<SweepCase>& info) {
                           return std::string(info.param.truth_at_fraction > 0 ? "corners"
                                                                               : "uniform") +
                                  "_seed" + std::to_string(info.param.seed);
                         });

// One truth drawn inside the intervals, in detail: every stage usable, the noise floor on both
// sets, residual variance ~1, the seven gauge directions detected, and every estimated parameter
// within 3 reported standard deviations of the truth in the same gauge.
TEST(CalibrationSweep, OneTruthInDetail) {
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = 11;
  VirtualRobot robot(nominal, vo);
  const auto [calibration, validation] = measure_paper_sets(nominal, robot, 11);
  CalibrationOptions options;
  const CalibrationResult result = calibrate(nominal, calibration, options);
  ASSERT_EQ(result.stages.size(), 3u);
  for (const StageReport& stage : result.stages) {
    EXPECT_TRUE(stage.usable) << stage.termination;
    std::printf("stage %s: %zu free, cost %.3e -> %.3e m^2, %d iterations, %.2f s\n  %s\n",
                stage.name.c_str(), stage.free_parameters.size(), stage.initial_cost,
                stage.final_cost, stage.iterations, stage.time_s, stage.termination.c_str());
  }

  const PoseErrorStats nominal_val = pose_errors(result.extrinsics_only, validation);
  const PoseErrorStats identified_cal = pose_errors(result.identified, calibration);
  const PoseErrorStats identified_val = pose_errors(result.identified, validation);
  // Where the bounds apply (the stages' frame), every bounded free value lies inside its box.
  for (std::size_t k = 0; k < result.parameters.size(); ++k) {
    const ParameterEstimate& p = result.parameters[k];
    const bool bounded = p.free && parameter_id(static_cast<int>(k), 3).limb >= 0;
    EXPECT_EQ(std::isfinite(p.box_deviation), bounded) << p.name;
    if (bounded) EXPECT_LE(std::abs(p.box_deviation), 1 + 1e-9) << p.name;
    EXPECT_EQ(p.at_bound, bounded && std::abs(std::abs(p.box_deviation) - 1) <= 1e-6) << p.name;
  }
  std::printf("nominal (extrinsics only) validation: mean e_p %.3g m, mean e_theta %.3g rad\n",
              nominal_val.mean_p, nominal_val.mean_theta);
  std::printf(
      "identified calibration: mean e_p %.3g m, e_theta %.3g rad; validation %.3g m, %.3g rad\n",
      identified_cal.mean_p, identified_cal.mean_theta, identified_val.mean_p,
      identified_val.mean_theta);
  EXPECT_EQ(identified_val.failed, 0);
  EXPECT_GT(nominal_val.mean_p, 10e-6);  // tens of micrometres before identification
  EXPECT_LE(identified_cal.mean_p, 0.05e-6);
  EXPECT_LE(identified_val.mean_p, 0.05e-6);  // the noise floor
  EXPECT_LE(identified_val.mean_theta, 5e-6);
  EXPECT_NEAR(result.residual_variance, 1.0, 0.3);  // whitened residuals: noise only

  // The six rigid-motion directions and the stiffness scale are gauges, detected as such.
  ASSERT_EQ(result.gauge.size(), 7u);
  for (const GaugeDirection& g : result.gauge) {
    EXPECT_TRUE(g.present) << g.name;
    EXPECT_LT(g.relative_gain, 1e-6) << g.name;
  }
  EXPECT_EQ(result.jacobian_rank, result.free_count - 7);

  // Identifiable parameters within 3 standard deviations of the truth, in the same gauge.
  ASSERT_TRUE(result.covariance_ok);
  std::vector<double> truth(static_cast<std::size_t>(num_parameters(3)));
  get_parameters(fix_gauge(robot.truth().params, nominal.params, true, true, true, true, true),
                 truth.data());
  int compared = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const ParameterEstimate& p = result.parameters[k];
    if (!p.free || p.gauge_reference) continue;
    ASSERT_TRUE(std::isfinite(p.std_dev) && p.std_dev > 0) << p.name;
    EXPECT_LE(std::abs(p.value - truth[k]), 3 * p.std_dev)
        << p.name << " value " << p.value << " truth " << truth[k] << " std " << p.std_dev;
    ++compared;
  }
  EXPECT_GE(compared, 20);
}

// Each draw of the noise gives another identification; their spread is what the reported standard
// deviations claim. 50 draws estimate a spread to about 10 %: the ratio must lie in [0.7, 1.4] for
// every identifiable parameter. The truth sits at the nominal values (far from the bounds, which
// would clip the spread); 30 configurations keep the spread well above the solver's tolerance.
TEST(CalibrationStatistics, ReportedStandardDeviationsMatchTheSpreadOverNoiseDraws) {
  constexpr int kDraws = 50, kConfigurations = 30;
  const RobotDescription nominal = default_robot();
  SamplingOptions so;
  so.count = kConfigurations;
  so.seed = 5;
  const std::vector<JointVector> q = poisson_disc_sample(nominal.params, so).configurations;
  ASSERT_EQ(static_cast<int>(q.size()), kConfigurations);
  CalibrationOptions options;
  std::vector<std::vector<double>> values;  // per draw, every flat parameter (limb-0 gauge)
  std::vector<double> reported;  // mean square of the reported standard deviations over the draws
  std::vector<bool> compared;    // identifiable in every draw
  for (int draw = 0; draw < kDraws; ++draw) {
    VirtualRobotOptions vo;
    vo.seed = static_cast<std::uint64_t>(draw + 1);  // the noise stream; the truth is the nominal
    vo.truth_at_fraction = 1e-12;
    VirtualRobot robot(nominal, vo);
    std::vector<CalibrationSample> data;
    for (const JointVector& qj : q) data.push_back({qj, robot.measure_or_throw(qj)});
    const CalibrationResult result = calibrate(nominal, data, options);
    ASSERT_TRUE(result.covariance_ok) << "draw " << draw;
    std::vector<double> v;
    for (const ParameterEstimate& p : result.parameters) v.push_back(p.value);
    values.push_back(v);
    reported.resize(v.size(), 0.0);
    compared.resize(v.size(), true);
    for (std::size_t k = 0; k < v.size(); ++k) {
      const ParameterEstimate& p = result.parameters[k];
      reported[k] += p.std_dev * p.std_dev / kDraws;
      compared[k] = compared[k] && p.free && !p.gauge_reference && p.identifiable && !p.at_bound &&
                    std::isfinite(p.std_dev) && p.std_dev > 0;
    }
  }
  int checked = 0;
  double lowest = 1e300, highest = 0;
  for (std::size_t k = 0; k < reported.size(); ++k) {
    if (!compared[k]) continue;
    double mean = 0, square = 0;
    for (const std::vector<double>& v : values) mean += v[k] / kDraws;
    for (const std::vector<double>& v : values) square += (v[k] - mean) * (v[k] - mean);
    const double ratio = std::sqrt(square / (kDraws - 1) / reported[k]);
    lowest = std::min(lowest, ratio);
    highest = std::max(highest, ratio);
    EXPECT_GE(ratio, 0.7) << "parameter " << k;
    EXPECT_LE(ratio, 1.4) << "parameter " << k;
    ++checked;
  }
  std::printf("%d parameters: spread / reported std in [%.3f, %.3f]\n", checked, lowest, highest);
  EXPECT_GE(checked, 20);
}

// A row measured 10 mm off (another equilibrium branch, a typo) is named as an outlier and the
// other rows reach the floor. Its Huber cost, linear in the residual, outweighs all the others':
// kept in the stages, it blunted Ceres' relative convergence test (0.073 um for this truth).
TEST(CalibrationOutliers, ARowMillimetresOffIsNamedAndTheOthersReachTheFloor) {
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = 4;
  VirtualRobot robot(nominal, vo);
  auto [calibration, validation] = measure_paper_sets(nominal, robot, 4);
  calibration[50].measured.x += 0.01;
  const CalibrationResult result = calibrate(nominal, calibration, CalibrationOptions());
  const PoseErrorStats after = pose_errors(result.identified, validation);
  std::printf("validation e_p mean %.4f um, residual variance %.3f\n", after.mean_p * 1e6,
              result.residual_variance);
  ASSERT_EQ(result.outliers.size(), 1u);
  EXPECT_EQ(result.outliers[0].rfind("configuration 51 ", 0), 0u) << result.outliers[0];
  EXPECT_LE(after.mean_p, 0.05e-6);
  EXPECT_LT(result.residual_variance, 1.5);
}

// A constant force and moment on the platform (air-bearing drag, a cable), 2 mN and 200 uN:
// without the load parameters the geometry absorbs it, biased by many standard deviations; with
// them (the last stage frees "load") every identified value, the load's included, lies within 4
// reported standard deviations of the truth in the same gauge, and the validation set is at the
// floor. At 2 mN the data see the force, and one coordinate of B_0 holds the distal translation
// perpendicular to it; at 200 uN they do not, and B_0 is held whole.
class CalibrationLoad : public ::testing::TestWithParam<double> {};

TEST_P(CalibrationLoad, AConstantPlatformLoadIsIdentifiedWithTheGeometry) {
  const double newton = GetParam();  // the force's magnitude
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = 4;
  vo.effects.external_load = true;
  vo.effects.load = PlatformLoad<double>{Vector2<double>(0.8, -0.6) * newton, 1e-2 * newton};
  VirtualRobot robot(nominal, vo);
  const auto [calibration, validation] = measure_paper_sets(nominal, robot, 4);

  // The worst |value - truth| / std over the estimated parameters, the truth moved to the
  // result's gauge: limb 0's clamps and d_0 at their nominal values, under a free load B_0 as
  // the calibration holds it (whole, or the coordinate gauge_fix_motion picks).
  const int b0 = parameter_index({ParameterKind::kBx, 0}, nominal.params.num_limbs);
  const auto holds_b0 = [&](const CalibrationResult& result, int axis) {
    return result.parameters[static_cast<std::size_t>(b0 + axis)].gauge_reference;
  };
  const auto worst_deviation = [&](const CalibrationResult& result) {
    const GaugeMotion m = gauge_fix_motion(robot.truth().params, nominal.params, true, true,
                                           !result.load_identified, true, true);
    RobotParams<double> fixed = move_along_gauge(robot.truth().params, m.G, m.H, m.stiffness_scale);
    PlatformLoad<double> load = move_load_along_gauge(robot.load(), m.G, m.H, m.stiffness_scale);
    if (result.load_identified) {
      const bool whole = holds_b0(result, 0) && holds_b0(result, 1);
      bool held[2];
      const GaugeMotion t =
          gauge_fix_motion(fixed, whole ? PlatformLoad<double>() : load, nominal.params, held);
      fixed = move_along_gauge(fixed, t.G, t.H, t.stiffness_scale);
      load = move_load_along_gauge(load, t.G, t.H, t.stiffness_scale);
      EXPECT_EQ(holds_b0(result, 0), held[0]);
      EXPECT_EQ(holds_b0(result, 1), held[1]);
    }
    std::vector<double> truth(static_cast<std::size_t>(num_parameters(fixed.num_limbs)));
    get_parameters(fixed, truth.data());
    truth.insert(truth.end(), {load.force.x(), load.force.y(), load.moment});
    double worst = 0;
    int compared = 0;
    for (std::size_t k = 0; k < result.parameters.size(); ++k) {
      const ParameterEstimate& p = result.parameters[k];
      if (!p.free || p.gauge_reference) continue;
      EXPECT_TRUE(p.identifiable && std::isfinite(p.std_dev) && p.std_dev > 0) << p.name;
      const double deviation = std::abs(p.value - truth[k]) / p.std_dev;
      if (deviation > worst)
        std::printf("  %s: %.1f std from the truth\n", p.name.c_str(), deviation);
      worst = std::max(worst, deviation);
      ++compared;
    }
    EXPECT_GE(compared, 25);
    return worst;
  };

  CalibrationOptions options;
  const CalibrationResult absorbed = calibrate(nominal, calibration, options);
  const double absorbed_worst = worst_deviation(absorbed);
  options.stages.back().free.push_back("load");
  const CalibrationResult result = calibrate(nominal, calibration, options);
  for (const StageReport& stage : result.stages) EXPECT_TRUE(stage.usable) << stage.termination;
  const double worst = worst_deviation(result);
  const PoseErrorStats absorbed_validation = pose_errors(absorbed.identified, validation);
  const PoseErrorStats validation_errors =
      pose_errors(result.identified, validation, SolverOptions(), result.load);
  std::printf(
      "without the load parameters: worst %.1f std, validation e_p mean %.4f um\n"
      "with them: worst %.1f std, validation e_p mean %.4f um, load (%.4g, %.4g) N, %.4g N m\n",
      absorbed_worst, absorbed_validation.mean_p * 1e6, worst, validation_errors.mean_p * 1e6,
      result.load.force.x(), result.load.force.y(), result.load.moment);
  EXPECT_GT(absorbed_worst, 5.0);  // the effect this test is about is visible without the load
  EXPECT_TRUE(result.load_identified);
  EXPECT_EQ(holds_b0(result, 0) && holds_b0(result, 1), newton < 1e-3);  // the force seen or not
  EXPECT_LE(worst, 4.0);
  EXPECT_EQ(validation_errors.failed, 0);
  EXPECT_LE(validation_errors.mean_p, 0.05e-6);
}

INSTANTIATE_TEST_SUITE_P(Forces, CalibrationLoad, ::testing::Values(2e-3, 2e-4),
                         [](const ::testing::TestParamInfo<double>& info) {
                           return std::to_string(static_cast<int>(info.param * 1e6)) + "uN";
                         });

// An unknown constant load (5 to 10 mN in a random direction, a random moment of up to 100 uN m)
// on a truth drawn inside the intervals: the stages' residuals exceed the noise, the load model
// is fitted, the validation test keeps it, and it predicts the validation set at the noise floor
// (the truth's own noise-free predictions are the reference) where the stages' model does not.
class SelectingTheLoadModel : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(SelectingTheLoadModel, AnUnknownLoadIsFoundAndKept) {
  std::mt19937_64 rng(GetParam());
  const double magnitude = std::uniform_real_distribution<double>(5e-3, 10e-3)(rng);
  const double direction = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
  const double moment = std::uniform_real_distribution<double>(-1e-4, 1e-4)(rng);
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = GetParam();
  vo.effects.external_load = true;
  vo.effects.load = PlatformLoad<double>{
      Vector2<double>(std::cos(direction), std::sin(direction)) * magnitude, moment};
  VirtualRobot robot(nominal, vo);
  const auto [calibration, validation] = measure_paper_sets(nominal, robot, GetParam());
  CalibrationOptions options;
  options.compute_covariance = false;
  const ModelSelection selection =
      calibrate_selecting_model(nominal, calibration, validation, options);
  std::printf("load %.2f mN at %.2f rad, %.3g N m: %s\n", magnitude * 1e3, direction, moment,
              selection.decision.c_str());
  for (const CalibrationResult* fit : {&selection.stages, &selection.load}) {
    for (const StageReport& stage : fit->stages) {
      std::printf("  %s: %d iterations, %.2f s, %d FK solves (%d warm starts failed)\n",
                  stage.name.c_str(), stage.iterations, stage.time_s, stage.fk_solves,
                  stage.fk_warm_start_failures);
    }
  }
  std::printf("the stages' residual variance %.4g\n", selection.stages.residual_variance);
  for (const std::string& w : selection.stages.warnings) std::printf("  warning: %s\n", w.c_str());
  ASSERT_TRUE(selection.tried_load);
  EXPECT_TRUE(selection.load_chosen);
  EXPECT_EQ(&selection.chosen(), &selection.load);
  const PoseErrorStats stages = pose_errors(selection.stages.identified, validation);
  const PoseErrorStats chosen = pose_errors(selection.chosen().identified, validation,
                                            SolverOptions(), selection.chosen().load);
  std::printf("validation e_p mean: stages %.4f um, chosen %.4f um\n", stages.mean_p * 1e6,
              chosen.mean_p * 1e6);
  EXPECT_EQ(chosen.failed, 0);
  EXPECT_LE(chosen.mean_p, 0.05e-6);
  EXPECT_GT(stages.mean_p, 2 * chosen.mean_p);
}

INSTANTIATE_TEST_SUITE_P(RandomLoads, SelectingTheLoadModel, ::testing::Values(21u, 22u));

// Clean data (a truth inside the intervals, the declared noise): the residual test passes and the
// stages' model is kept without fitting the load model.
TEST(SelectingTheLoadModel, CleanDataKeepTheStagesModel) {
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = 23;
  VirtualRobot robot(nominal, vo);
  const auto [calibration, validation] = measure_paper_sets(nominal, robot, 23);
  CalibrationOptions options;
  options.compute_covariance = false;
  const ModelSelection selection =
      calibrate_selecting_model(nominal, calibration, validation, options);
  EXPECT_FALSE(selection.stages.residuals_exceed_noise) << selection.stages.residual_variance;
  EXPECT_FALSE(selection.tried_load);
  EXPECT_FALSE(selection.load_chosen);
  EXPECT_EQ(&selection.chosen(), &selection.stages);
}

}  // namespace
}  // namespace pcr
