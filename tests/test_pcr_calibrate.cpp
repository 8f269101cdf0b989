// pcr_calibrate end to end (the paper's Section 5): a simulated dataset in, an identified pcr-robot
// file out, checked with the core's FK against the noise-free measurements of the truth.
// Kept fast: the nominal description is uncertain only in the rod lengths and the extrinsics.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
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
    u.global.rod.length = 126e-6;
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
    const pcr::CsvRow row = predicted.rows[j];
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
    EXPECT_NEAR(identified.params.limb(i).rod.length, truth_.params.limb(i).rod.length, 2e-6) << i;
  }
}

// A constant load on the platform (1.8 mN, 10 uN m): with --identify-load the report gives it,
// within 4 of its standard deviations of the truth's (no gauge moves it here: neither the clamps
// nor the diameters are free), and FK under it reproduces the truth's noise-free measurements.
TEST_F(PcrCalibrate, IdentifyLoadReportsThePlatformLoad) {
  VirtualRobotOptions vo;
  vo.seed = 5;
  vo.effects.external_load = true;
  vo.effects.load = PlatformLoad<double>{Vector2<double>(1.5e-3, -1e-3), 1e-5};
  VirtualRobot robot(nominal_, vo);
  SamplingOptions so;
  so.count = 40;
  so.seed = 6;
  const std::vector<JointVector> q = poisson_disc_sample(nominal_.params, so).configurations;
  ASSERT_EQ(q.size(), 40u);
  Dataset calibration;
  std::vector<Pose2<double>> exact;
  for (std::size_t j = 0; j < q.size(); ++j) {
    const VirtualMeasurement m = robot.measure(q[j]);
    ASSERT_TRUE(m.ok);
    if (j < 30) calibration.add(q[j], m.measured);
    if (j >= 30) exact.push_back(m.exact);
  }
  write_dataset(calibration, path("loaded.csv"));
  std::ofstream(path("stages.json")) << R"([{"name": "extrinsics", "free": ["extrinsics"]},
             {"name": "lengths", "free": ["l", "camera", "pattern"]}])";
  const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                              path("loaded.csv") + " --stages " + path("stages.json") +
                              " --identify-load --output " + path("identified.json") +
                              " --quiet > " + path("out.txt") + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << slurp(path("out.txt"));
  const std::string out = slurp(path("out.txt"));
  PlatformLoad<double> load;
  const std::size_t at = out.find("f = (");
  ASSERT_NE(at, std::string::npos) << out;
  ASSERT_EQ(std::sscanf(out.c_str() + at, "f = (%lf, %lf) N, m = %lf N m", &load.force.x(),
                        &load.force.y(), &load.moment),
            3)
      << out;
  const auto std_of = [&](const std::string& name) {
    const std::size_t line = out.find("  " + name + " ");
    const std::size_t std_at = out.find("std ", line);
    return line == std::string::npos || std_at == std::string::npos
               ? std::numeric_limits<double>::quiet_NaN()
               : std::atof(out.c_str() + std_at + 4);
  };
  const PlatformLoad<double>& truth = robot.load();
  EXPECT_NEAR(load.force.x(), truth.force.x(), 4 * std_of("load_f_x")) << out;
  EXPECT_NEAR(load.force.y(), truth.force.y(), 4 * std_of("load_f_y")) << out;
  EXPECT_NEAR(load.moment, truth.moment, 4 * std_of("load_m_z")) << out;

  const RobotDescription identified = load_robot(path("identified.json"));
  double mean = 0;
  for (std::size_t j = 0; j < exact.size(); ++j) {
    const ForwardSolution s =
        forward_kinematics(identified.params, q[30 + j], SolverOptions(), load);
    ASSERT_TRUE(s.summary.converged());
    const Pose2<double> p = identified.params.extrinsics.measurement_from_platform(s.pose);
    mean += std::hypot(p.x - exact[j].x, p.y - exact[j].y) / static_cast<double>(exact.size());
  }
  EXPECT_LT(mean, 0.05e-6);
}

/// Mean position error (m) of a robot file's predictions against the truth's noise-free
/// measurements of the validation set.
double validation_mean(const RobotDescription& robot, const std::vector<JointVector>& q,
                       const std::vector<Pose2<double>>& exact) {
  double mean = 0;
  for (std::size_t j = 0; j < q.size(); ++j) {
    const ForwardSolution s = forward_kinematics(robot.params, q[j]);
    if (!s.summary.converged()) return std::numeric_limits<double>::infinity();
    const Pose2<double> p = robot.params.extrinsics.measurement_from_platform(s.pose);
    mean += std::hypot(p.x - exact[j].x, p.y - exact[j].y) / static_cast<double>(q.size());
  }
  return mean;
}

// The extrinsics start from the registration of the data, not from the guess: a camera turned by
// 0.3 rad and frames 5 mm off (far outside the declared +-50 mrad, +-1 mm) reach the same floor,
// and the report names each guess that was wrong (--strict: exit 3).
TEST_F(PcrCalibrate, AnyExtrinsicsGuessReachesTheFloorAndIsNamed) {
  const std::string common = " --data " + path("calibration.csv") + " --quiet --strict";
  const auto calibrate = [&](const std::string& robot, const std::string& out) {
    const std::string command = kTool + " --robot " + robot + common + " --output " + out +
                                " > /dev/null 2> " + path("err.txt");
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(calibrate(path("nominal.json"), path("good.json")), 0) << slurp(path("err.txt"));
  RobotDescription wrong = nominal_;
  wrong.params.extrinsics.camera = Pose2<double>{5e-3, 0, 0.3};
  wrong.params.extrinsics.pattern = Pose2<double>{0, -5e-3, -0.2};
  save_robot(wrong, path("wrong.json"));
  EXPECT_EQ(calibrate(path("wrong.json"), path("from-wrong.json")), 3);
  const std::string err = slurp(path("err.txt"));
  for (const char* name : {"camera_x", "camera_theta", "pattern_y", "pattern_theta"})
    EXPECT_NE(err.find(std::string("warning: ") + name), std::string::npos) << name << ": " << err;
  const double good = validation_mean(load_robot(path("good.json")), validation_q_, exact_);
  const double from_wrong =
      validation_mean(load_robot(path("from-wrong.json")), validation_q_, exact_);
  EXPECT_LT(good, 0.05e-6);
  EXPECT_LT(from_wrong, 0.05e-6);
  EXPECT_NEAR(from_wrong, good, 1e-10);
}

// A row the nominal geometry cannot reach (here q1 in millimetres) is named by file and line; with
// --drop-unreachable it is left out, listed, and the rest is identified.
TEST_F(PcrCalibrate, UnreachableRowsAreNamedOrDropped) {
  std::istringstream text(slurp(path("calibration.csv")));
  std::ostringstream edited;
  std::string line;
  for (int number = 1; std::getline(text, line); ++number) {
    if (number == 5) line = "12.5" + line.substr(line.find(','));
    edited << line << "\n";
  }
  std::ofstream(path("mm.csv")) << edited.str();
  const std::string base = kTool + " --robot " + path("nominal.json") + " --data " +
                           path("mm.csv") + " --quiet --output " + path("out.json");
  EXPECT_NE(std::system((base + " > /dev/null 2> " + path("err.txt")).c_str()), 0);
  EXPECT_NE(slurp(path("err.txt")).find("mm.csv:5 (q = (12.5,"), std::string::npos)
      << slurp(path("err.txt"));
  EXPECT_FALSE(fs::exists(path("out.json")));
  ASSERT_EQ(
      std::system((base + " --drop-unreachable > " + path("report.txt") + " 2> /dev/null").c_str()),
      0);
  const std::string report = slurp(path("report.txt"));
  EXPECT_NE(report.find("rows left out"), std::string::npos) << report;
  EXPECT_NE(report.find("mm.csv:5"), std::string::npos) << report;
  EXPECT_NE(report.find("q1 = 12.5 m outside"), std::string::npos) << report;
  EXPECT_LT(validation_mean(load_robot(path("out.json")), validation_q_, exact_), 0.05e-6);
}

// Two of 30 rows moved by 50 um (a mistyped digit, a bumped camera): the Huber loss keeps the
// result at the floor, and the report names the two rows; plain least squares does not.
TEST_F(PcrCalibrate, OutliersAreDownWeightedAndNamed) {
  Dataset data = read_dataset(path("calibration.csv"));
  data.poses[7].x += 50e-6;
  data.poses[19].y -= 50e-6;
  write_dataset(data, path("outliers.csv"));
  const auto calibrate = [&](const std::string& extra, const std::string& out) {
    const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                                path("outliers.csv") + " --quiet --output " + out + extra +
                                " > /dev/null 2> " + path("err.txt");
    EXPECT_EQ(std::system(command.c_str()), 0) << slurp(path("err.txt"));
    return validation_mean(load_robot(out), validation_q_, exact_);
  };
  const double robust = calibrate(" --residuals " + path("residuals.csv"), path("robust.json"));
  const std::string err = slurp(path("err.txt"));
  EXPECT_NE(err.find("2 rows are outliers"), std::string::npos) << err;
  EXPECT_NE(err.find("outliers.csv:9 "), std::string::npos) << err;  // line 9: row 8
  EXPECT_NE(err.find("outliers.csv:21 "), std::string::npos) << err;
  EXPECT_LT(robust, 0.05e-6);
  // The residuals file flags exactly those rows, with their lines.
  CsvReadOptions columns;
  columns.columns = {"row", "line", "residual_norm", "outlier"};
  columns.ignore_other_columns = true;
  const CsvTable residuals = read_csv(path("residuals.csv"), columns);
  ASSERT_EQ(residuals.rows.size(), data.size());
  for (const pcr::CsvRow row : residuals.rows) {
    const bool moved = row[0] == 8 || row[0] == 20;
    EXPECT_EQ(row[1], row[0] + 1);  // the header is line 1
    EXPECT_EQ(row[3], moved ? 1.0 : 0.0) << "row " << row[0] << " norm " << row[2];
    if (moved) EXPECT_GT(row[2], 1000);  // 50 um over 9.13 nm
  }
  const double plain = calibrate(" --robust-scale 0", path("plain.json"));
  EXPECT_GT(plain, 2 * robust);
  std::printf("validation mean with 2 outliers: %.4g um (Huber), %.4g um (least squares)\n",
              robust * 1e6, plain * 1e6);
}

// theta in degrees and x, y in millimetres: columns that vary ~57 and ~1000 times more than the
// nominal model's poses are named with their likely unit.
TEST_F(PcrCalibrate, UnitSlipsAreNamed) {
  Dataset data = read_dataset(path("calibration.csv"));
  for (Pose2<double>& pose : data.poses) {
    pose.theta *= 180 / M_PI;
    pose.x *= 1e3;
    pose.y *= 1e3;
  }
  write_dataset(data, path("units.csv"));
  const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                              path("units.csv") + " --quiet --output " + path("out.json") +
                              " > /dev/null 2> " + path("err.txt");
  EXPECT_EQ(std::system(command.c_str()), 0);
  const std::string err = slurp(path("err.txt"));
  EXPECT_NE(err.find("degrees instead of radians?"), std::string::npos) << err;
  EXPECT_NE(err.find("(x) varies"), std::string::npos) << err;
  EXPECT_NE(err.find("millimetres instead of metres?"), std::string::npos) << err;
  EXPECT_NE(err.find("units.csv:"), std::string::npos) << err;
}

// A dataset written in an image's left-handed frame (y down): named as mirrored; the clean one is
// not.
TEST_F(PcrCalibrate, AMirroredDatasetIsNamed) {
  Dataset data = read_dataset(path("calibration.csv"));
  for (Pose2<double>& pose : data.poses) {
    pose.y = -pose.y;
    pose.theta = -pose.theta;
  }
  write_dataset(data, path("mirrored.csv"));
  for (const std::string name : {"mirrored.csv", "calibration.csv"}) {
    const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                                path(name) + " --quiet --output " + path("out.json") +
                                " > /dev/null 2> " + path("err.txt");
    EXPECT_EQ(std::system(command.c_str()), 0);
    const std::string err = slurp(path("err.txt"));
    EXPECT_EQ(err.find("times better mirrored (y and theta negated)") != std::string::npos,
              name == "mirrored.csv")
        << name << ": " << err;
  }
}

// Two rows pasted twice and a validation set of another robot (its poses 0.5 mm off): warnings
// name the copies by line and the validation set by its error, and --strict makes them an exit 3.
TEST_F(PcrCalibrate, CopiedRowsAndAForeignValidationSetAreNamed) {
  Dataset data = read_dataset(path("calibration.csv"));
  const std::size_t rows = data.size();
  data.add(data.q[2], data.poses[2]);
  data.add(data.q[9], data.poses[9]);
  write_dataset(data, path("copies.csv"));
  Dataset foreign = read_dataset(path("validation.csv"));
  for (Pose2<double>& pose : foreign.poses) pose.x += 0.5e-3;
  write_dataset(foreign, path("foreign.csv"));
  const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                              path("copies.csv") + " --validation " + path("foreign.csv") +
                              " --quiet --output " + path("out.json") + " --report " +
                              path("report.json") + " > /dev/null 2> " + path("err.txt");
  ASSERT_EQ(std::system(command.c_str()), 0) << slurp(path("err.txt"));
  const std::string err = slurp(path("err.txt"));
  // Row j is on line j + 1 (the header is line 1).
  const std::string copies = path("copies.csv");
  const std::string first = copies + ":" + std::to_string(rows + 2) + " = " + copies + ":4";
  const std::string second = copies + ":" + std::to_string(rows + 3) + " = " + copies + ":11";
  EXPECT_NE(err.find("2 rows repeat an earlier row"), std::string::npos) << err;
  EXPECT_NE(err.find(first), std::string::npos) << err;
  EXPECT_NE(err.find(second), std::string::npos) << err;
  EXPECT_NE(err.find("mean e_p on the validation set"), std::string::npos) << err;
  EXPECT_NE(slurp(path("report.json")).find("mean e_p on the validation set"), std::string::npos);
  // A clean run has neither warning; --strict turns them into exit status 3.
  const std::string clean = kTool + " --robot " + path("nominal.json") + " --data " +
                            path("calibration.csv") + " --validation " + path("validation.csv") +
                            " --quiet --output " + path("clean.json") + " > /dev/null 2> " +
                            path("clean.txt");
  ASSERT_EQ(std::system(clean.c_str()), 0);
  EXPECT_EQ(slurp(path("clean.txt")).find("repeat an earlier row"), std::string::npos);
  EXPECT_EQ(slurp(path("clean.txt")).find("validation set ("), std::string::npos);
  const int strict = std::system((command + " --strict").c_str());
  ASSERT_TRUE(WIFEXITED(strict));
  EXPECT_EQ(WEXITSTATUS(strict), 3);
}

// 30 measurements of one configuration identify 3 combinations of the 9 free parameters: the
// other 6 are named, and no parameter they involve gets a standard deviation (not 0, not a number).
TEST_F(PcrCalibrate, UnidentifiableCombinationsAreNamed) {
  const Dataset data = read_dataset(path("calibration.csv"));
  Dataset same;
  for (std::size_t j = 0; j < data.size(); ++j) same.add(data.q[0], data.poses[0]);
  write_dataset(same, path("same.csv"));
  const std::string command = kTool + " --robot " + path("nominal.json") + " --data " +
                              path("same.csv") + " --quiet --output " + path("out.json") + " > " +
                              path("report.txt") + " 2> " + path("err.txt");
  ASSERT_EQ(std::system(command.c_str()), 0) << slurp(path("err.txt"));
  const std::string report = slurp(path("report.txt"));
  EXPECT_NE(report.find("combinations of parameters (in half-widths) are not identifiable"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("std not identifiable"), std::string::npos) << report;
  EXPECT_EQ(report.find("std 0.000e+00"), std::string::npos) << report;
  ASSERT_NE(report.find("not identifiable from these data"), std::string::npos) << report;
  std::istringstream lines(report);
  int combinations = 0;
  for (std::string line; std::getline(lines, line);)
    combinations += line.rfind("  + ", 0) == 0 || line.rfind("  - ", 0) == 0;
  EXPECT_EQ(combinations, 6) << report;
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
