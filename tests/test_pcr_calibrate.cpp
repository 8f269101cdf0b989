// pcr_calibrate end to end (issue 3, section 5): a simulated dataset in, an identified pcr-robot
// file out, checked with the core's FK against the noise-free measurements of the truth.
// Kept fast: the nominal description is uncertain only in the rod lengths and the extrinsics.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "pcr/calib/dataset.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/virtual_robot.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/robot_io.hpp"
#include "scratch_directory.hpp"

namespace pcr {
namespace {

namespace fs = std::filesystem;

const std::string kTool = std::string(PCR_BINARY_DIR) + "/apps/pcr_calibrate";
const std::string kCli = std::string(PCR_BINARY_DIR) + "/apps/pcr";

int run(const std::string& args) {
  const std::string command = kTool + " " + args + " > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class PcrCalibrate : public ::testing::Test {
 protected:
  void SetUp() override {
    nominal_ = default_robot();
    RobotUncertainty u;  // only l and the extrinsics are uncertain: a fast, complete problem
    u.global.length = 126e-6;
    u.limbs.assign(3, u.global);
    u.camera = Eigen::Vector3d(1e-3, 1e-3, 50e-3);
    u.pattern = Eigen::Vector3d(1e-3, 1e-3, 50e-3);
    nominal_.uncertainty = u;
    save_robot(nominal_, path("nominal.json"));

    VirtualRobotOptions vo;
    vo.seed = 5;
    VirtualRobot robot(nominal_, vo);
    truth_ = robot.truth();
    SamplingOptions so;
    so.count = 40;
    so.seed = 5;
    const SamplingResult sampled = poisson_disc_sample(nominal_.params, so);
    Dataset calibration, validation;
    for (std::size_t j = 0; j < sampled.configurations.size(); ++j) {
      const VirtualMeasurement m = robot.measure(sampled.configurations[j]);
      ASSERT_TRUE(m.ok);
      if (j < 30) {
        calibration.add(sampled.configurations[j], m.measured);
      } else {
        validation.add(sampled.configurations[j], m.measured);
        exact_.push_back(m.exact);
      }
    }
    validation_q_ = validation.q;
    write_dataset(calibration, path("calibration.csv"));
    write_dataset(validation, path("validation.csv"));
  }

  std::string path(const std::string& name) const { return scratch_.file(name); }

  pcr::test::ScratchDirectory scratch_{"pcr_calibrate"};
  RobotDescription nominal_, truth_;
  std::vector<JointVector> validation_q_;
  std::vector<Pose2<double>> exact_;
};

TEST_F(PcrCalibrate, IdentifiedFileReproducesTheTruthsMeasurements) {
  std::ofstream(path("stages.json"))
      << R"({"stages": [{"name": "extrinsics", "free": ["extrinsics"]},
                        {"name": "lengths", "free": ["l", "camera", "pattern"], "bounds_scale": 1}]})";
  ASSERT_EQ(
      run("--robot " + path("nominal.json") + " --data " + path("calibration.csv") +
          " --validation " + path("validation.csv") + " --stages " + path("stages.json") +
          " --output " + path("identified.json") + " --report " + path("report.json") + " --quiet"),
      0);
  const RobotDescription identified = load_robot(path("identified.json"));
  ASSERT_TRUE(identified.uncertainty.has_value());
  EXPECT_NE(slurp(path("report.json")).find("identified_model_validation_set"), std::string::npos);

  // The identified file, used as is by `pcr fk`, predicts what the truth's camera sees (noise
  // free); the nominal model is far off.
  write_configurations(validation_q_, path("validation-q.csv"));
  const std::string fk = kCli + " fk --robot " + path("identified.json") + " --input " +
                         path("validation-q.csv") + " --output " + path("fk.csv") + " 2> /dev/null";
  ASSERT_EQ(std::system(fk.c_str()), 0);
  CsvReadOptions columns;
  columns.columns = {"x", "y", "theta", "converged"};
  columns.ignore_other_columns = true;
  const CsvTable predicted = read_csv(path("fk.csv"), columns);
  ASSERT_EQ(predicted.rows.size(), validation_q_.size());
  double nominal_mean = 0, identified_mean = 0;
  for (std::size_t j = 0; j < validation_q_.size(); ++j) {
    const std::vector<double>& row = predicted.rows[j];
    ASSERT_EQ(row[3], 1.0) << "pcr fk did not converge on row " << j;
    const ForwardSolution b = forward_kinematics(nominal_.params, validation_q_[j]);
    ASSERT_TRUE(b.summary.converged());
    const Pose2<double> pa = identified.params.extrinsics.measurement_from_platform(
        Pose2<double>{row[0], row[1], row[2]});
    const Pose2<double> pb = nominal_.params.extrinsics.measurement_from_platform(b.pose);
    identified_mean += std::hypot(pa.x - exact_[j].x, pa.y - exact_[j].y) / exact_.size();
    nominal_mean += std::hypot(pb.x - exact_[j].x, pb.y - exact_[j].y) / exact_.size();
    EXPECT_NEAR(pa.theta, exact_[j].theta, 5e-6);
  }
  EXPECT_GT(nominal_mean, 1e-5);
  EXPECT_LT(identified_mean, 0.05e-6);
  // The identified lengths are the truth's (gauge-free parameters), to well below their interval.
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(identified.params.limb(i).length, truth_.params.limb(i).length, 2e-6) << i;
  }
}

TEST_F(PcrCalibrate, RefusesToOverwriteAnInput) {
  const std::string before = slurp(path("nominal.json"));
  EXPECT_NE(run("--robot " + path("nominal.json") + " --data " + path("calibration.csv") +
                " --output " + path("nominal.json") + " --quiet"),
            0);
  EXPECT_EQ(slurp(path("nominal.json")), before);
}

TEST_F(PcrCalibrate, BadStagesFileIsAnErrorNamingTheKind) {
  std::ofstream(path("stages.json")) << R"([{"name": "x", "free": ["lenght"]}])";
  const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                              path("calibration.csv") + " --stages " + path("stages.json") +
                              " --output " + path("out.json") + " --quiet 2> " + path("err.txt");
  EXPECT_NE(std::system(command.c_str()), 0);
  EXPECT_NE(slurp(path("err.txt")).find("lenght"), std::string::npos);
  EXPECT_FALSE(fs::exists(path("out.json")));
}

}  // namespace
}  // namespace pcr
