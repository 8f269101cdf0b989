// pcr_calibrate on a spatial robot end to end: a hidden virtual spatial robot's measurements in
// (seeded), an identified spatial robot file out, scored on validation rows against the noise
// floor sqrt(3) sigma of a perfect model; the report's and the residuals' fields; the model
// selection, unreachable rows and outliers; the refusals.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "scratch_directory.hpp"
#include "spatial_calibration_support.hpp"

namespace pcr {
namespace {

const std::string kTool = std::string(PCR_BINARY_DIR) + "/apps/pcr_calibrate";
/// A joint value (m) at which the nominal robot has no equilibrium: every rod 1 cm long.
constexpr double kUnreachableJoint = -0.39;

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs pcr_calibrate; its exit status, its stderr in `err` and its stdout in `out`.
int run(const std::string& args, const test::ScratchDirectory& dir, std::string* err = nullptr,
        std::string* out = nullptr) {
  const std::string command =
      kTool + " " + args + " > " + dir.file("stdout.txt") + " 2> " + dir.file("stderr.txt");
  const int status = std::system(command.c_str());
  if (err) *err = slurp(dir.file("stderr.txt"));
  if (out) *out = slurp(dir.file("stdout.txt"));
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(PcrCalibrateSpatial, IdentifiesAHiddenRobotToTheNoiseFloor) {
  const test::ScratchDirectory dir("pcr_calibrate_spatial");
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  save_spatial_robot(nominal, dir.file("nominal.json"));
  SpatialVirtualRobotOptions options;
  options.seed = 11;
  SpatialVirtualRobot robot(nominal, options);
  std::mt19937_64 rng(options.seed);
  const SpatialDataset calibration =
      testing::measured(robot, testing::random_joints(rng, 40, 0.0, 0.01));
  const SpatialDataset validation =
      testing::measured(robot, testing::random_joints(rng, 15, 0.0, 0.01));
  ASSERT_GE(calibration.size(), 35u);
  ASSERT_GE(validation.size(), 12u);
  write_spatial_dataset(calibration, dir.file("calibration.csv"));
  write_spatial_dataset(validation, dir.file("validation.csv"));

  const auto start = std::chrono::steady_clock::now();
  std::string err, text;
  ASSERT_EQ(run("--robot " + dir.file("nominal.json") + " --data " + dir.file("calibration.csv") +
                    " --validation " + dir.file("validation.csv") + " --output " +
                    dir.file("identified.json") + " --report " + dir.file("report.json") +
                    " --residuals " + dir.file("residuals.csv") + " --quiet",
                dir, &err, &text),
            0)
      << err;
  std::printf("%s", text.c_str());  // the text report
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The identified file, scored with the library's FK on the validation rows (as read back).
  const SpatialRobotDescription identified = load_spatial_robot(dir.file("identified.json"));
  ASSERT_TRUE(identified.uncertainty.has_value());  // kept from the nominal file
  const SpatialDataset validation_read = read_spatial_dataset(dir.file("validation.csv"), 6);
  const SpatialPredictionErrors nominal_errors =
      spatial_prediction_errors(nominal.params, validation_read);
  const SpatialPredictionErrors errors =
      spatial_prediction_errors(identified.params, validation_read);
  const double floor_p = std::sqrt(3.0) * robot.noise_position();
  const double floor_a = std::sqrt(3.0) * options.noise_angle;
  std::printf(
      "%zu + %zu rows, pcr_calibrate %.1f s; validation rms %.3g m %.3g rad (floor %.3g m %.3g "
      "rad; nominal %.3g m %.3g rad)\n",
      calibration.size(), validation.size(), seconds, errors.rms_position, errors.rms_angle,
      floor_p, floor_a, nominal_errors.rms_position, nominal_errors.rms_angle);
  EXPECT_EQ(errors.failures, 0);
  EXPECT_GT(nominal_errors.rms_position, 100 * floor_p);  // there was something to identify
  EXPECT_LT(errors.rms_position, 2 * floor_p);
  EXPECT_LT(errors.rms_angle, 2 * floor_a);

  // The report: every section, and the validation errors as the file's robot gives them.
  const nlohmann::json report = nlohmann::json::parse(slurp(dir.file("report.json")));
  EXPECT_EQ(report.at("kind"), "spatial");
  for (const char* key :
       {"pose_errors", "stages", "parameters", "parameters_at_bound", "jacobian_rank",
        "free_parameters", "unidentifiable_combinations", "residual_variance", "rms_position_m",
        "rms_angle_rad", "orientation_weight_m_per_rad", "residual_scale_m", "warnings",
        "inputs"}) {
    EXPECT_TRUE(report.contains(key)) << key;
  }
  const nlohmann::json& set = report.at("pose_errors").at("identified_model_validation_set");
  EXPECT_EQ(set.at("configurations"), static_cast<int>(validation.size()));
  EXPECT_NEAR(set.at("rms_position_m").get<double>(), errors.rms_position,
              1e-3 * errors.rms_position);
  ASSERT_FALSE(report.at("stages").empty());
  for (const nlohmann::json& stage : report.at("stages")) {
    for (const char* key : {"name", "free_parameters", "initial_cost", "final_cost", "iterations",
                            "time_s", "termination", "usable"}) {
      EXPECT_TRUE(stage.contains(key)) << key;
    }
  }
  ASSERT_EQ(report.at("parameters").size(), static_cast<std::size_t>(num_spatial_parameters(6)));
  for (const nlohmann::json& p : report.at("parameters")) {
    for (const char* key :
         {"name", "unit", "deviation", "std", "half_width", "free", "at_bound", "identifiable"}) {
      EXPECT_TRUE(p.contains(key)) << key;
    }
  }
  EXPECT_EQ(report.at("parameters").at(0).at("name"),
            spatial_parameter_name(spatial_parameter_id(0, 6)));

  // --weight and --stages reach the library: the extrinsics alone, at w = 0.05 m/rad.
  std::ofstream(dir.file("stages.json")) << R"([{"name": "tracker", "free": ["extrinsics"]}])";
  ASSERT_EQ(run("--robot " + dir.file("nominal.json") + " --data " + dir.file("calibration.csv") +
                    " --stages " + dir.file("stages.json") + " --weight 0.05 --output " +
                    dir.file("extrinsics.json") + " --report " + dir.file("extrinsics.report") +
                    " --quiet",
                dir, &err),
            0)
      << err;
  const nlohmann::json extrinsics = nlohmann::json::parse(slurp(dir.file("extrinsics.report")));
  EXPECT_EQ(extrinsics.at("orientation_weight_m_per_rad").get<double>(), 0.05);
  EXPECT_EQ(extrinsics.at("inputs").at("orientation_weight_m_per_rad").get<double>(), 0.05);
  ASSERT_EQ(extrinsics.at("stages").size(), 1u);
  EXPECT_EQ(extrinsics.at("stages").at(0).at("name"), "tracker");
  EXPECT_EQ(extrinsics.at("free_parameters"), 12);

  // The residuals: one row per calibration row, under the documented header.
  std::istringstream residuals(slurp(dir.file("residuals.csv")));
  std::string line;
  std::getline(residuals, line);
  EXPECT_EQ(line, "row,line,q1,q2,q3,q4,q5,q6,e_p,e_angle,residual_norm,outlier");
  std::size_t rows = 0;
  while (std::getline(residuals, line)) ++rows;
  EXPECT_EQ(rows, calibration.size());
}

// A 100 g payload the nominal robot does not know: a stages file freeing "load" (and
// --identify-load, which adds it to the default stages' last) identifies its weight, which the
// report gives and the identified file carries as its external force.
TEST(PcrCalibrateSpatial, LoadStageIdentifiesAPayload) {
  const test::ScratchDirectory dir("pcr_calibrate_spatial");
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  save_spatial_robot(nominal, dir.file("nominal.json"));
  SpatialVirtualRobotOptions options;
  options.seed = 11;
  options.effects.payload = 0.1;
  SpatialVirtualRobot robot(nominal, options);
  std::mt19937_64 rng(options.seed);
  const SpatialDataset calibration =
      testing::measured(robot, testing::random_joints(rng, 60, 0.0, 0.01));
  ASSERT_GE(calibration.size(), 50u);
  write_spatial_dataset(calibration, dir.file("calibration.csv"));
  std::ofstream(dir.file("stages.json"))
      << R"([{"name": "extrinsics", "free": ["extrinsics"]}, {"free": ["all", "load"]}])";
  const double weight = options.effects.payload * nominal.params.gravity.z();
  for (const std::string how :
       {" --stages " + dir.file("stages.json"), std::string(" --identify-load")}) {
    std::string err;
    ASSERT_EQ(run("--robot " + dir.file("nominal.json") + " --data " + dir.file("calibration.csv") +
                      how + " --output " + dir.file("identified.json") + " --report " +
                      dir.file("report.json") + " --quiet",
                  dir, &err),
              0)
        << err;
    const nlohmann::json report = nlohmann::json::parse(slurp(dir.file("report.json")));
    ASSERT_TRUE(report.at("platform_load").at("identified").get<bool>()) << how;
    const double f_z = report.at("platform_load").at("f_z_N").get<double>();
    const nlohmann::json& parameters = report.at("parameters");
    ASSERT_EQ(parameters.size(), static_cast<std::size_t>(num_spatial_parameters(6) + 6));
    const nlohmann::json& entry = parameters.at(num_spatial_parameters(6) + 2);
    EXPECT_EQ(entry.at("name"), "load_f_z");
    const double sigma = entry.at("std").get<double>();
    std::printf("%s: f_z %.4f N +- %.4f (m g %.4f N)\n", how.c_str(), f_z, sigma, weight);
    EXPECT_NEAR(f_z, weight, 4 * sigma);
    const SpatialRobotDescription identified = load_spatial_robot(dir.file("identified.json"));
    EXPECT_NEAR(identified.params.external_force.z(), f_z, 1e-12 + 1e-9 * std::abs(f_z));
    EXPECT_TRUE(report.contains("covariance"));
  }
}

// --select-load, --drop-unreachable and the outliers on a spatial robot: a row the nominal robot
// cannot reach is refused naming its line, or with --drop-unreachable left out and named; a row
// measured 1 mm off is named an outlier (report and residuals CSV); the other rows' residuals are
// at the noise, so the selection keeps the stages' model without fitting the load model
// (tests/test_spatial_calibration.cpp has the selection of a payload).
TEST(PcrCalibrateSpatial, SelectsTheModelDropsUnreachableRowsAndNamesOutliers) {
  const test::ScratchDirectory dir("pcr_calibrate_spatial");
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  save_spatial_robot(nominal, dir.file("nominal.json"));
  SpatialVirtualRobotOptions options;
  options.seed = 11;
  SpatialVirtualRobot robot(nominal, options);
  std::mt19937_64 rng(options.seed);
  SpatialDataset calibration = testing::measured(robot, testing::random_joints(rng, 40, 0.0, 0.01));
  const SpatialDataset validation =
      testing::measured(robot, testing::random_joints(rng, 15, 0.0, 0.01));
  ASSERT_GE(calibration.size(), 35u);
  constexpr std::size_t kOff = 10;
  calibration.poses[kOff].position.y() += 1e-3;
  SpatialJointVector far(6);  // rods 1 cm long: no equilibrium
  far.setConstant(kUnreachableJoint);
  calibration.add(far, calibration.poses.back());
  write_spatial_dataset(calibration, dir.file("calibration.csv"));
  write_spatial_dataset(validation, dir.file("validation.csv"));
  const SpatialDataset written = read_spatial_dataset(dir.file("calibration.csv"), 6);
  const std::string off_line = "line " + std::to_string(written.line_numbers[kOff]);
  const std::string far_line = "line " + std::to_string(written.line_numbers.back());

  const std::string command =
      "--robot " + dir.file("nominal.json") + " --data " + dir.file("calibration.csv") +
      " --validation " + dir.file("validation.csv") + " --output " + dir.file("identified.json") +
      " --report " + dir.file("report.json") + " --residuals " + dir.file("residuals.csv") +
      " --quiet --select-load";
  std::string err;
  EXPECT_EQ(run(command, dir, &err), 1);
  EXPECT_NE(err.find(far_line + ": the nominal robot has no equilibrium"), std::string::npos)
      << err;
  EXPECT_NE(err.find("--drop-unreachable"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("identified.json")));

  ASSERT_EQ(run(command + " --drop-unreachable", dir, &err), 0) << err;
  EXPECT_NE(err.find("left out (drop_unreachable): " + far_line), std::string::npos) << err;
  const nlohmann::json report = nlohmann::json::parse(slurp(dir.file("report.json")));
  ASSERT_EQ(report.at("dropped_rows").size(), 1u);
  EXPECT_EQ(report.at("dropped_rows").at(0).get<std::string>().rfind(far_line + " (", 0), 0u);
  ASSERT_EQ(report.at("outlier_rows").size(), 1u) << report.at("outlier_rows");
  EXPECT_EQ(report.at("outlier_rows").at(0).get<std::string>().rfind(off_line + " (", 0), 0u);
  EXPECT_GT(report.at("outlier_threshold").get<double>(), 0.0);
  EXPECT_FALSE(report.at("residuals_exceed_noise").get<bool>());
  const nlohmann::json& selection = report.at("model_selection");
  std::printf("selection: %s\n", selection.at("decision").get<std::string>().c_str());
  EXPECT_FALSE(selection.at("load_tried").get<bool>());
  EXPECT_FALSE(selection.at("load_chosen").get<bool>());
  EXPECT_FALSE(report.at("platform_load").at("identified").get<bool>());

  // The residuals CSV flags the row 1 mm off, and it alone.
  std::istringstream residuals(slurp(dir.file("residuals.csv")));
  std::string line;
  std::getline(residuals, line);
  std::vector<std::size_t> flagged;
  for (std::size_t row = 0; std::getline(residuals, line); ++row) {
    if (line.substr(line.rfind(',') + 1) == "1") flagged.push_back(row);
  }
  EXPECT_EQ(flagged, std::vector<std::size_t>{kOff});
}

TEST(PcrCalibrateSpatial, RefusesWrongColumnsAndOverwritingAnInput) {
  const test::ScratchDirectory dir("pcr_calibrate_spatial");
  const std::string robot = dir.file("nominal.json");
  save_spatial_robot(continuum_stewart_gough_description(), robot);
  const std::string robot_text = slurp(robot);
  {
    std::ofstream planar(dir.file("planar.csv"));  // a planar robot's columns: 9, not 12
    planar << "q1,q2,q3,q4,q5,q6,x,y,theta\n0,0,0,0,0,0,0,0,0\n";
  }
  const std::string common =
      "--robot " + robot + " --data " + dir.file("planar.csv") + " --quiet --output ";
  std::string err;
  EXPECT_EQ(run(common + dir.file("out.json"), dir, &err), 1);
  EXPECT_NE(err.find(dir.file("planar.csv")), std::string::npos) << err;
  // Stages files: the spatial kinds (the load's too) are taken (the data is refused next), a
  // planar one is not; so is --identify-load.
  EXPECT_EQ(run(common + dir.file("out.json") + " --identify-load", dir, &err), 1);
  EXPECT_NE(err.find(dir.file("planar.csv")), std::string::npos) << err;
  {
    std::ofstream(dir.file("spatial_stages.json"))
        << R"([{"name": "s", "free": ["tracker", "load"]}])";
    std::ofstream(dir.file("planar_stages.json")) << R"([{"name": "s", "free": ["camera"]}])";
  }
  EXPECT_EQ(run(common + dir.file("out.json") + " --stages " + dir.file("spatial_stages.json"), dir,
                &err),
            1);
  EXPECT_NE(err.find(dir.file("planar.csv")), std::string::npos) << err;
  EXPECT_EQ(
      run(common + dir.file("out.json") + " --stages " + dir.file("planar_stages.json"), dir, &err),
      1);
  EXPECT_NE(err.find(dir.file("planar_stages.json")), std::string::npos) << err;
  EXPECT_NE(err.find("camera"), std::string::npos) << err;
  EXPECT_EQ(run(common + robot, dir, &err), 1);
  EXPECT_NE(err.find("refusing to overwrite the input"), std::string::npos) << err;
  EXPECT_EQ(slurp(robot), robot_text);
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.json")));
}

}  // namespace
}  // namespace pcr
