// The method as one call (pcr::run_method): the stages in order, the configurations visited in
// the order of a greedy nearest-neighbour tour, and a calibration that finds the virtual robot's
// truth (the independent reference) within its standard deviations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "pcr/calib/method.hpp"
#include "pcr/parameters.hpp"

namespace pcr {
namespace {

// Drawn at random inside a stroke box, in shuffled order: the tour starts at the row nearest
// home and always goes on to the nearest row left, and visits each row once.
TEST(VisitingOrder, IsAGreedyTourFromTheRowNearestHome) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  for (int n : {0, 1, 2, 37}) {
    std::vector<JointVector> rows;
    for (int k = 0; k < n; ++k)
      rows.push_back(JointVector(Eigen::Vector3d(u(rng), u(rng), u(rng))));
    const std::vector<std::size_t> order = visiting_order(rows);
    ASSERT_EQ(order.size(), rows.size());
    std::vector<std::size_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t k = 0; k < sorted.size(); ++k) EXPECT_EQ(sorted[k], k);
    std::vector<bool> visited(rows.size(), false);
    for (std::size_t k = 0; k < order.size(); ++k) {
      const JointVector from = k == 0 ? JointVector(JointVector::Zero(3)) : rows[order[k - 1]];
      for (std::size_t j = 0; j < rows.size(); ++j) {
        if (!visited[j]) {
          EXPECT_LE((rows[order[k]] - from).squaredNorm(), (rows[j] - from).squaredNorm());
        }
      }
      visited[order[k]] = true;
    }
  }
}

TEST(RunMethod, RunsItsStagesInOrderAndFindsTheTruth) {
  const RobotDescription nominal = default_robot();
  VirtualRobotOptions vo;
  vo.seed = 7;
  VirtualRobot robot(nominal, vo);

  MethodOptions options;
  options.sensitivity = false;
  options.sampling.count = 40;
  options.sampling.seed = 7;
  options.validation_count = 12;
  options.model = CalibratedModel::kStages;
  options.accuracy.repeat = 3;
  options.square.num_poses = options.circle.num_poses = 8;
  options.map.grid = 12;
  std::vector<std::string> events;
  options.on_stage_begin = [&](MethodStage s) {
    events.push_back(std::string("+") + to_string(s));
  };
  options.on_stage_end = [&](MethodStage s, const MethodResult&) {
    events.push_back(std::string("-") + to_string(s));
  };
  const MethodResult r = run_method(nominal, robot, options);

  const std::vector<std::string> expected = {
      "+sampling",   "-sampling",   "+measurement", "-measurement", "+calibration", "-calibration",
      "+validation", "-validation", "+accuracy",    "-accuracy",    "+maps",        "-maps"};
  EXPECT_EQ(events, expected);
  EXPECT_EQ(r.seconds[static_cast<int>(MethodStage::kSensitivity)], 0.0);  // not run
  EXPECT_GT(r.seconds[static_cast<int>(MethodStage::kCalibration)], 0.0);
  EXPECT_FALSE(r.sensitivity);
  EXPECT_FALSE(r.selection);

  // Every sampled configuration measured or counted, the sets visited as a tour.
  EXPECT_EQ(r.calibration_data.size() + r.validation_data.size() + r.unmeasured, 52u);
  const std::vector<std::size_t> tour = visiting_order(r.configurations.calibration);
  for (std::size_t k = 0; k < r.calibration_data.size(); ++k) {
    EXPECT_TRUE(std::find(r.configurations.calibration.begin(), r.configurations.calibration.end(),
                          r.calibration_data.q[k]) != r.configurations.calibration.end());
  }
  // This truth holds a stable equilibrium at every sampled row, so the order is checkable.
  ASSERT_EQ(r.unmeasured, 0);
  for (std::size_t k = 0; k < tour.size(); ++k) {
    EXPECT_EQ(r.calibration_data.q[k], r.configurations.calibration[tour[k]]) << k;
  }

  // The truth, moved to the calibration's gauge, within 5 standard deviations of every
  // identified parameter that has one.
  const int n = nominal.params.num_limbs;
  std::vector<double> truth(static_cast<std::size_t>(num_parameters(n)));
  get_parameters(r.truth_in_gauge, truth.data());
  int compared = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const ParameterEstimate& p = r.calibration.parameters[k];
    if (!(p.std_dev > 0)) continue;
    ++compared;
    EXPECT_LT(std::abs(p.value - truth[k]), 5 * p.std_dev) << p.name;
  }
  EXPECT_GT(compared, 20);

  // Table 3 at the camera's noise floor (9 nm) for the identified model, and far above it for
  // the nominal; both paths commanded with both models, the identified closer.
  EXPECT_LT(r.table.identified_validation.mean_p, 0.05e-6);
  EXPECT_GT(r.table.nominal_validation.mean_p, 1e-6);
  ASSERT_EQ(r.accuracy.size(), 4u);
  for (const char* path : {"square", "circle"}) {
    EXPECT_LT(r.accuracy_of(path, "identified").iso.ap_p.max,
              0.1 * r.accuracy_of(path, "nominal").iso.ap_p.max)
        << path;
  }
  EXPECT_THROW(r.accuracy_of("figure-eight", "identified"), std::out_of_range);
  ASSERT_TRUE(r.map);
  EXPECT_EQ(r.map->nx, 12);
  EXPECT_GT(r.map->stable_area, 0.0);
  std::printf(
      "[ method ] %zu + %zu rows, identified validation mean e_p %.3e m, %d parameters "
      "compared with the truth\n",
      r.calibration_data.size(), r.validation_data.size(), r.table.identified_validation.mean_p,
      compared);
}

TEST(RunMethod, RefusesInvalidOptionsNamingTheField) {
  const RobotDescription nominal = default_robot();
  VirtualRobot robot(nominal);
  MethodOptions options;
  options.accuracy.repeat = 1;
  try {
    run_method(nominal, robot, options);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("repeat"), std::string::npos) << e.what();
  }
  EXPECT_EQ(parse_calibrated_model("load"), CalibratedModel::kLoad);
  EXPECT_THROW(parse_calibrated_model("loads"), InputError);
}

}  // namespace
}  // namespace pcr
