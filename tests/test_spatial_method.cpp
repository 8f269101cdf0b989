// The paper's method on a virtual spatial robot as one call (pcr/calib/spatial_method.hpp): its
// stages in order, every configuration measured or counted, Table 3 at the noise floor for the
// identified model, and Table 4's paths attained far closer with it than with the nominal one.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "pcr/calib/spatial_method.hpp"

namespace {

using namespace pcr;

TEST(RunSpatialMethod, RunsItsStagesAndReachesTheNoiseFloor) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  SpatialVirtualRobotOptions vo;
  vo.seed = 5;
  SpatialVirtualRobot robot(nominal, vo);

  SpatialMethodOptions options;
  options.sensitivity = false;
  options.sampling.count = 40;
  options.sampling.seed = 5;
  options.validation_count = 12;
  options.accuracy.repeat = 3;
  options.square.num_poses = options.circle.num_poses = options.helix.num_poses = 8;
  std::vector<std::string> events;
  options.on_stage_begin = [&](MethodStage s) {
    events.push_back(std::string("+") + to_string(s));
  };
  options.on_stage_end = [&](MethodStage s, const SpatialMethodResult&) {
    events.push_back(std::string("-") + to_string(s));
  };
  const SpatialMethodResult r = run_spatial_method(nominal, robot, options);

  const std::vector<std::string> expected = {
      "+sampling",    "-sampling",   "+measurement", "-measurement", "+calibration",
      "-calibration", "+validation", "-validation",  "+accuracy",    "-accuracy"};
  EXPECT_EQ(events, expected);
  EXPECT_FALSE(r.sensitivity);
  EXPECT_EQ(r.calibration_data.size() + r.validation_data.size() + r.unmeasured, 52u);

  // Table 3: the identified model at the floor sqrt(3) sigma on the validation set, which the
  // calibration never saw; the nominal geometry (with its extrinsics fitted) far above it.
  const double floor = std::sqrt(3.0) * robot.noise_position();
  EXPECT_EQ(r.table.identified_validation.failures, 0);
  EXPECT_LT(r.table.identified_validation.rms_position, 2.0 * floor);
  EXPECT_GT(r.table.nominal_validation.rms_position, 30 * floor);

  // Table 4: three paths with both models; the identified one's AP_p near the floor of a mean of
  // 3 cycles, the nominal's its geometry's error.
  ASSERT_EQ(r.accuracy.size(), 6u);
  for (const char* path : {"square", "circle", "helix"}) {
    const double identified = r.accuracy_of(path, "identified").iso.ap_p.max;
    const double guessed = r.accuracy_of(path, "nominal").iso.ap_p.max;
    std::printf("%s: AP_p max %.3g m identified, %.3g m nominal\n", path, identified, guessed);
    EXPECT_LT(identified, 0.1 * guessed) << path;
    EXPECT_LT(identified, 3.0 * floor) << path;
  }
  EXPECT_THROW(r.accuracy_of("figure-eight", "identified"), std::out_of_range);
  std::printf(
      "[ spatial method ] %zu + %zu rows; calibration %.1f s, paths %.1f s; validation rms "
      "%.3g m (floor %.3g m), nominal %.3g m\n",
      r.calibration_data.size(), r.validation_data.size(),
      r.seconds[static_cast<int>(MethodStage::kCalibration)],
      r.seconds[static_cast<int>(MethodStage::kAccuracy)],
      r.table.identified_validation.rms_position, floor, r.table.nominal_validation.rms_position);
}

TEST(RunSpatialMethod, RefusesInvalidOptionsNamingTheField) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  SpatialVirtualRobot robot(nominal);
  SpatialMethodOptions options;
  options.helix.num_poses = 0;
  try {
    run_spatial_method(nominal, robot, options);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("helix.num_poses"), std::string::npos) << e.what();
  }
}

}  // namespace
