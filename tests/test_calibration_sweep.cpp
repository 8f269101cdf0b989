// Identification over many virtual robots:
// - from anywhere in the uncertainty intervals: truths drawn uniformly inside them and truths
//   with every parameter at +-0.9 half-widths (where the bounds and the gauge meet) all reach the
//   noise floor on validation configurations they were not identified from (the reference is the
//   truth itself: its noise-free predictions are what the validation errors measure against).
//   Seeded, the first seeds of each kind; a larger sweep is bench_calibration's;
// - the reported standard deviations against the spread of the identified values over 50 draws
//   of the measurement noise (the reference is the empirical spread).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace pcr {
namespace {

struct SweepCase {
  double truth_at_fraction;  ///< 0: uniform inside the intervals
  std::uint64_t seed;
};

class CalibrationSweep : public ::testing::TestWithParam<SweepCase> {};

TEST_P(CalibrationSweep, ReachesTheNoiseFloor) {
  constexpr int kCalibration = 99, kValidation = 56;  // the paper's
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = GetParam().seed;
  vo.truth_at_fraction = GetParam().truth_at_fraction;
  VirtualRobot robot(nominal, vo);
  SamplingOptions so;
  so.count = kCalibration + kValidation;
  so.seed = GetParam().seed;
  const SamplingResult sampled = poisson_disc_sample(nominal.params, so);
  ASSERT_TRUE(sampled.complete);
  std::vector<CalibrationSample> calibration, validation;
  for (std::size_t j = 0; j < sampled.configurations.size(); ++j) {
    const JointVector& q = sampled.configurations[j];
    (static_cast<int>(j) < kCalibration ? calibration : validation)
        .push_back({q, robot.measure_or_throw(q)});
  }
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

}  // namespace
}  // namespace pcr
