// Virtual robot (truth drawn in the uncertainty intervals, Eq. 5 measurements, noise) and the
// dataset CSV format.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "pcr/calib/dataset.hpp"
#include "pcr/calib/virtual_robot.hpp"
#include "pcr/robot_io.hpp"

namespace pcr {
namespace {

JointVector joints(double a, double b, double c) {
  JointVector q(3);
  q << a, b, c;
  return q;
}

/// Homogeneous 3x3 matrix of a pose: an independent reference for the Pose2 algebra.
Eigen::Matrix3d matrix(const Pose2<double>& p) {
  Eigen::Matrix3d m;
  m << std::cos(p.theta), -std::sin(p.theta), p.x, std::sin(p.theta), std::cos(p.theta), p.y, 0, 0,
      1;
  return m;
}

VirtualRobotOptions noiseless(std::uint64_t seed) {
  VirtualRobotOptions options;
  options.seed = seed;
  options.noise_position = 0.0;
  options.noise_angle = 0.0;
  return options;
}

TEST(VirtualRobot, NoiselessMeasurementIsEquation5OfTheTrueRobot) {
  VirtualRobot robot(default_robot(), noiseless(7));
  const RobotParams<double>& truth = robot.truth().params;
  for (const JointVector& q :
       {joints(0, 0, 0), joints(3e-3, -2e-3, 1e-3), joints(-4e-3, 4e-3, 2e-3)}) {
    const VirtualMeasurement m = robot.measure(q);
    ASSERT_TRUE(m.ok) << to_string(m.summary.status);
    // FK of the true robot from a cold start, independent of the virtual robot's warm start.
    const ForwardSolution fk = forward_kinematics(truth, q);
    ASSERT_TRUE(fk.summary.converged());
    // ^Se T_M = (^W T_Se)^-1 ^W T_P (^M T_P)^-1 with matrices.
    const Eigen::Matrix3d expected = matrix(truth.extrinsics.camera).inverse() * matrix(fk.pose) *
                                     matrix(truth.extrinsics.pattern).inverse();
    const Eigen::Matrix3d measured = matrix(m.measured);
    EXPECT_LT((expected - measured).cwiseAbs().maxCoeff(), 1e-12);
    // And back: Eq. 5 with the true extrinsics gives FK of the true robot.
    const Pose2<double> platform = truth.extrinsics.platform_from_measurement(m.measured);
    EXPECT_NEAR(platform.x, fk.pose.x, 1e-12);
    EXPECT_NEAR(platform.y, fk.pose.y, 1e-12);
    EXPECT_NEAR(platform.theta, fk.pose.theta, 1e-12);
  }
}

TEST(VirtualRobot, TruthLiesInsideTheUncertaintyIntervals) {
  const RobotDescription nominal = default_robot();
  const RobotUncertainty& u = *nominal.uncertainty;
  const int n = nominal.params.num_limbs;
  double max_rel_length = 0;  // the draws must also use the intervals, not stay at the nominal
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    VirtualRobot robot(nominal, noiseless(seed));
    const RobotParams<double>& t = robot.truth().params;
    for (int i = 0; i < n; ++i) {
      const LimbParams<double>& a = t.limb(i);
      const LimbParams<double>& b = nominal.params.limb(i);
      const LimbUncertainty& h = u.limbs[static_cast<std::size_t>(i)];
      EXPECT_LE(std::abs(a.rod.length - b.rod.length), h.rod.length);
      EXPECT_LE(std::abs(a.A.x() - b.A.x()), h.A.x());
      EXPECT_LE(std::abs(a.A.y() - b.A.y()), h.A.y());
      EXPECT_LE(std::abs(a.B.x() - b.B.x()), h.B.x());
      EXPECT_LE(std::abs(a.B.y() - b.B.y()), h.B.y());
      EXPECT_LE(std::abs(a.alpha - b.alpha), h.alpha);
      EXPECT_LE(std::abs(a.beta - b.beta), h.beta);
      EXPECT_LE(std::abs(a.gamma - b.gamma), h.gamma);
      EXPECT_LE(std::abs(a.rod.diameter - b.rod.diameter), u.global.rod.diameter);
      EXPECT_EQ(a.rod.young_modulus, b.rod.young_modulus);  // the default E half-width is 0
      // One wire: every limb has the same diameter offset.
      EXPECT_NEAR(a.rod.diameter - b.rod.diameter,
                  t.limb(0).rod.diameter - nominal.params.limb(0).rod.diameter, 1e-18);
      max_rel_length =
          std::max(max_rel_length, std::abs(a.rod.length - b.rod.length) / h.rod.length);
    }
    const Pose2<double>& c = t.extrinsics.camera;
    const Pose2<double>& c0 = nominal.params.extrinsics.camera;
    const Pose2<double>& p = t.extrinsics.pattern;
    const Pose2<double>& p0 = nominal.params.extrinsics.pattern;
    EXPECT_LE(std::abs(c.x - c0.x), u.camera.x());
    EXPECT_LE(std::abs(c.y - c0.y), u.camera.y());
    EXPECT_LE(std::abs(c.theta - c0.theta), u.camera.z());
    EXPECT_LE(std::abs(p.x - p0.x), u.pattern.x());
    EXPECT_LE(std::abs(p.y - p0.y), u.pattern.y());
    EXPECT_LE(std::abs(p.theta - p0.theta), u.pattern.z());
  }
  EXPECT_GT(max_rel_length, 0.5);
}

TEST(VirtualRobot, SameSeedSameRobotAndData) {
  VirtualRobotOptions options;
  options.seed = 42;
  VirtualRobot a(default_robot(), options), b(default_robot(), options);
  options.seed = 43;
  VirtualRobot c(default_robot(), options);
  EXPECT_EQ(robot_to_json(a.truth()), robot_to_json(b.truth()));
  EXPECT_NE(robot_to_json(a.truth()), robot_to_json(c.truth()));
  for (const JointVector& q : {joints(1e-3, 2e-3, -1e-3), joints(-2e-3, 0, 3e-3)}) {
    const Pose2<double> pa = a.measure_or_throw(q), pb = b.measure_or_throw(q);
    EXPECT_EQ(pa.x, pb.x);
    EXPECT_EQ(pa.y, pb.y);
    EXPECT_EQ(pa.theta, pb.theta);
  }
}

TEST(VirtualRobot, NoiseHasTheRequestedStandardDeviation) {
  VirtualRobotOptions options;  // the paper's repeatability by default
  VirtualRobotOptions exact = noiseless(options.seed);
  VirtualRobot robot(default_robot(), options), reference(default_robot(), exact);
  const JointVector q = joints(2e-3, -1e-3, 1e-3);
  const Pose2<double> truth = reference.measure_or_throw(q);
  const int count = 3000;
  Eigen::ArrayXd dx(count), dy(count), dt(count);
  for (int k = 0; k < count; ++k) {
    const Pose2<double> m = robot.measure_or_throw(q);
    dx(k) = m.x - truth.x;
    dy(k) = m.y - truth.y;
    dt(k) = m.theta - truth.theta;
  }
  auto stddev = [](const Eigen::ArrayXd& v) {
    return std::sqrt((v - v.mean()).square().sum() / (v.size() - 1));
  };
  EXPECT_NEAR(stddev(dx), kDefaultNoisePosition, 0.1 * kDefaultNoisePosition);
  EXPECT_NEAR(stddev(dy), kDefaultNoisePosition, 0.1 * kDefaultNoisePosition);
  EXPECT_NEAR(stddev(dt), kDefaultNoiseAngle, 0.1 * kDefaultNoiseAngle);
  // Zero mean: within 4 standard errors.
  EXPECT_LT(std::abs(dx.mean()), 4 * kDefaultNoisePosition / std::sqrt(count));
  EXPECT_LT(std::abs(dt.mean()), 4 * kDefaultNoiseAngle / std::sqrt(count));
  // x and y independent.
  const double corr =
      ((dx - dx.mean()) * (dy - dy.mean())).sum() / ((count - 1) * stddev(dx) * stddev(dy));
  EXPECT_LT(std::abs(corr), 0.1);
}

TEST(VirtualRobot, UnmodelledEffectsAreSwitchedOnOneAtATime) {
  const RobotDescription nominal = default_robot();
  const int n = nominal.params.num_limbs;
  VirtualRobot base(nominal, noiseless(5));

  VirtualRobotOptions options = noiseless(5);
  options.effects.misalignments = true;
  options.effects.misalignment_half_width = 1e-2;
  VirtualRobot misaligned(nominal, options);
  double max_extra = 0;
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& a = misaligned.truth().params.limb(i);
    const LimbParams<double>& b = base.truth().params.limb(i);
    EXPECT_LE(std::abs(a.beta - b.beta), 1e-2);
    EXPECT_LE(std::abs(a.gamma - b.gamma), 1e-2);
    max_extra = std::max({max_extra, std::abs(a.beta - b.beta), std::abs(a.gamma - b.gamma)});
    EXPECT_EQ(a.rod.length, b.rod.length);  // everything else is the base truth
    EXPECT_EQ(a.rod.diameter, b.rod.diameter);
  }
  EXPECT_GT(max_extra, 1e-3);

  options = noiseless(5);
  options.effects.unequal_diameters = true;
  VirtualRobot unequal(nominal, options);
  double spread = 0;
  for (int i = 0; i < n; ++i) {
    const double d = unequal.truth().params.limb(i).rod.diameter;
    EXPECT_LE(std::abs(d - base.truth().params.limb(i).rod.diameter),
              options.effects.diameter_half_width);
    spread = std::max(spread, std::abs(d - unequal.truth().params.limb(0).rod.diameter));
    EXPECT_EQ(unequal.truth().params.limb(i).alpha, base.truth().params.limb(i).alpha);
  }
  EXPECT_GT(spread, 1e-8);

  options = noiseless(5);
  options.effects.external_load = true;
  options.effects.load = PlatformLoad<double>{Vector2<double>(5e-3, 0), 0};
  VirtualRobot loaded(nominal, options);
  EXPECT_EQ(robot_to_json(loaded.truth()), robot_to_json(base.truth()));
  const JointVector q = joints(1e-3, 1e-3, 1e-3);
  const Pose2<double> free_pose = base.measure_or_throw(q),
                      loaded_pose = loaded.measure_or_throw(q);
  // The platform moves with the load, and FK of the loaded truth predicts it.
  EXPECT_GT(std::hypot(free_pose.x - loaded_pose.x, free_pose.y - loaded_pose.y), 3e-7);
  const ForwardSolution fk =
      forward_kinematics(base.truth().params, q, SolverOptions(), options.effects.load);
  const Pose2<double> expected = base.truth().params.extrinsics.measurement_from_platform(fk.pose);
  EXPECT_NEAR(loaded_pose.x, expected.x, 1e-12);
  EXPECT_NEAR(loaded_pose.y, expected.y, 1e-12);
}

TEST(VirtualRobot, ReportsConfigurationsWithoutSolution) {
  VirtualRobot robot(default_robot(), noiseless(1));
  const JointVector q = joints(0.2, -0.2, 0.2);  // far beyond any reachable pose
  const VirtualMeasurement m = robot.measure(q);
  EXPECT_FALSE(m.ok);
  EXPECT_FALSE(m.summary.converged());
  EXPECT_THROW(robot.measure_or_throw(q), std::runtime_error);
  // And it recovers on the next reachable configuration.
  EXPECT_TRUE(robot.measure(joints(1e-3, 0, 0)).ok);
}

// A real robot does not hold an unstable equilibrium. The default robot, moved from home to
// (3.57, 1.46, -10.18) mm and then to (6.01, 1.53, -1.56) mm, follows its branch past the point
// where it stops being stable (no fold: the path goes on, the energy-Hessian margin ends at -162,
// found by a search over random two-row tours). The virtual robot does not measure that row
// (status unstable) and, homed again, measures the next row from home, as a cold solve. With
// the stability check off it holds the path's equilibrium, millimetres from the cold solve's.
TEST(VirtualRobot, DoesNotMeasureAnUnstableEquilibrium) {
  RobotDescription nominal = default_robot();
  nominal.uncertainty.reset();  // the truth is the nominal robot
  const std::vector<JointVector> rows = {
      joints(3.566415114507882e-3, 1.4601330688085983e-3, -10.177504610230644e-3),
      joints(6.008575294285489e-3, 1.5303280691677766e-3, -1.5550781356242563e-3),
      joints(1e-3, -2e-3, 0.5e-3)};
  VirtualRobot robot(nominal, noiseless(1));
  const std::vector<VirtualMeasurement> measured = robot.measure_dataset(rows);
  ASSERT_TRUE(measured[0].ok);
  EXPECT_FALSE(measured[1].ok);
  EXPECT_EQ(measured[1].summary.status, SolveStatus::kUnstable);
  ASSERT_TRUE(measured[2].ok);
  const ForwardSolution cold = forward_kinematics(nominal.params, rows[2]);
  ASSERT_TRUE(cold.summary.converged());
  EXPECT_NEAR(measured[2].platform.x, cold.pose.x, 1e-12);
  EXPECT_NEAR(measured[2].platform.y, cold.pose.y, 1e-12);

  VirtualRobotOptions unchecked = noiseless(1);
  unchecked.solver.check_stability = false;
  VirtualRobot held(nominal, unchecked);
  const std::vector<VirtualMeasurement> on_path = held.measure_dataset(rows);
  ASSERT_TRUE(on_path[1].ok);
  const ForwardSolution cold_1 = forward_kinematics(nominal.params, rows[1]);
  ASSERT_TRUE(cold_1.summary.converged());
  EXPECT_GT(
      std::hypot(on_path[1].platform.x - cold_1.pose.x, on_path[1].platform.y - cold_1.pose.y),
      1e-3);
}

TEST(VirtualRobot, RejectsBadOptions) {
  VirtualRobotOptions options;
  options.noise_position = -1;
  EXPECT_THROW(VirtualRobot(default_robot(), options), InputError);
  options = VirtualRobotOptions();
  options.noise_angle = std::nan("");
  EXPECT_THROW(VirtualRobot(default_robot(), options), InputError);
}

// ---- dataset CSV ----------------------------------------------------------------------------

std::string error_of(const std::string& text, int num_joints = -1) {
  std::istringstream in(text);
  try {
    parse_dataset(in, "data.csv", num_joints);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Dataset, RoundTripIsExact) {
  Dataset data;
  data.add(joints(1e-3, -2.5e-3, 1.0 / 3.0 * 1e-3), Pose2<double>{1.23456789012345e-2, -1e-9, 0.1});
  data.add(joints(0, 0, 0), Pose2<double>{M_PI * 1e-3, 2.0 / 3.0, -M_PI / 7});
  const std::string path = std::string(PCR_BINARY_DIR) + "/test_dataset_roundtrip.csv";
  write_dataset(data, path);
  const Dataset back = read_dataset(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.num_joints, 3);
  for (std::size_t r = 0; r < 2; ++r) {
    for (int i = 0; i < 3; ++i) EXPECT_EQ(back.q[r](i), data.q[r](i));
    EXPECT_EQ(back.poses[r].x, data.poses[r].x);
    EXPECT_EQ(back.poses[r].y, data.poses[r].y);
    EXPECT_EQ(back.poses[r].theta, data.poses[r].theta);
  }
  EXPECT_EQ(back.line_numbers[0], 2);
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "q1,q2,q3,x,y,theta");
  std::remove(path.c_str());
}

TEST(Dataset, CommentColumnsAndLinesAreIgnored) {
  std::istringstream in(
      "# a comment line\nq1,#label,q2,x,y,theta,#note\n0.001,abc,0.002,1,2,3,free text\n");
  const Dataset data = parse_dataset(in, "data.csv");
  ASSERT_EQ(data.size(), 1u);
  EXPECT_EQ(data.num_joints, 2);
  EXPECT_EQ(data.q[0](1), 0.002);
  EXPECT_EQ(data.poses[0].theta, 3.0);
  EXPECT_EQ(data.line_numbers[0], 3);
}

TEST(Dataset, BadInputNamesFileAndLine) {
  const std::string header = "q1,q2,q3,x,y,theta\n";
  std::string e = error_of(header + "0,0,0,1,2,3\n0,0,0,1,2\n");
  EXPECT_NE(e.find("data.csv:3"), std::string::npos) << e;
  e = error_of(header + "0,0,0,1,2,3\n0,0,zero,1,2,3\n");
  EXPECT_NE(e.find("data.csv:3"), std::string::npos) << e;
  EXPECT_NE(e.find("zero"), std::string::npos) << e;
  e = error_of(header + "0,0,0,nan,2,3\n");
  EXPECT_NE(e.find("data.csv:2"), std::string::npos) << e;
  e = error_of("q1,q2,q3,x,y,z\n0,0,0,1,2,3\n");  // wrong column name
  EXPECT_NE(e.find("data.csv:1"), std::string::npos) << e;
  e = error_of(header + "0,0,0,1,2,3\n", 2);  // expected 2 joints
  EXPECT_FALSE(e.empty());
  e = error_of("x,y,theta\n1,2,3\n");  // no joints
  EXPECT_FALSE(e.empty());
  EXPECT_THROW(read_dataset("/nonexistent/data.csv"), InputError);
}

TEST(Dataset, ConfigurationsRoundTrip) {
  const std::vector<JointVector> configs = {joints(1e-3, 2e-3, 3e-3), joints(-1e-3, 0, 0.1 / 3)};
  std::istringstream in(configurations_to_csv(configs));
  const std::vector<JointVector> back = parse_configurations(in, "configs.csv");
  ASSERT_EQ(back.size(), 2u);
  for (std::size_t r = 0; r < 2; ++r) EXPECT_EQ(back[r], configs[r]);
  std::istringstream bad("q1,q2,q3\n0,0\n");
  EXPECT_THROW(parse_configurations(bad, "configs.csv"), InputError);
}

#ifdef PCR_CLI_PATH
// ---- pcr sample | pcr simulate | pcr sensitivity, end to end --------------------------------

int run(const std::string& args) {
  const std::string command = std::string(PCR_CLI_PATH) + " " + args + " 2>/dev/null";
  return std::system(command.c_str());
}

TEST(CalibCli, SampleSimulateSensitivity) {
  const std::string dir = std::string(PCR_BINARY_DIR) + "/test_calib_cli_";
  ASSERT_EQ(run("sample --count 5 --validation-count 3 --seed 2 --box -3e-3,3e-3 --output " + dir +
                "cfg.csv --validation-output " + dir + "val.csv"),
            0);
  const std::vector<JointVector> cfg = read_configurations(dir + "cfg.csv", 3);
  const std::vector<JointVector> val = read_configurations(dir + "val.csv", 3);
  ASSERT_EQ(cfg.size(), 5u);
  ASSERT_EQ(val.size(), 3u);
  for (const JointVector& a : cfg) {
    EXPECT_LE(a.cwiseAbs().maxCoeff(), 3e-3);
    for (const JointVector& b : val) EXPECT_GT((a - b).norm(), 0.0);
  }

  ASSERT_EQ(run("simulate --seed 4 --configs " + dir + "cfg.csv --output " + dir +
                "data.csv --truth " + dir + "truth.json"),
            0);
  const Dataset data = read_dataset(dir + "data.csv");
  const RobotDescription truth = load_robot(dir + "truth.json");
  ASSERT_EQ(data.size(), 5u);
  for (std::size_t k = 0; k < data.size(); ++k) {
    EXPECT_EQ(data.q[k], cfg[k]);
    const ForwardSolution fk = forward_kinematics(truth.params, data.q[k]);
    ASSERT_TRUE(fk.summary.converged());
    const Pose2<double> exact = truth.params.extrinsics.measurement_from_platform(fk.pose);
    // Noise of the paper's repeatability: within 6 standard deviations.
    EXPECT_NEAR(data.poses[k].x, exact.x, 6 * kDefaultNoisePosition);
    EXPECT_NEAR(data.poses[k].y, exact.y, 6 * kDefaultNoisePosition);
    EXPECT_NEAR(data.poses[k].theta, exact.theta, 6 * kDefaultNoiseAngle);
  }
  // The truth file is the library's truth for the same seed.
  VirtualRobotOptions options;
  options.seed = 4;
  EXPECT_EQ(robot_to_json(truth), robot_to_json(VirtualRobot(default_robot(), options).truth()));

  // An unreachable configuration fails the run and writes nothing.
  {
    std::ofstream bad(dir + "bad.csv");
    bad << "q1,q2,q3\n0.001,0,0\n0.2,-0.2,0.2\n";
  }
  std::remove((dir + "bad_data.csv").c_str());
  EXPECT_NE(run("simulate --configs " + dir + "bad.csv --output " + dir + "bad_data.csv"), 0);
  EXPECT_FALSE(std::ifstream(dir + "bad_data.csv").good());

  ASSERT_EQ(run("sensitivity --csv " + dir + "sens.csv --json " + dir + "sens.json > /dev/null"),
            0);
  std::ifstream csv_in(dir + "sens.csv");
  std::string line;
  std::getline(csv_in, line);
  EXPECT_EQ(line.rfind("param,dx_dp,dy_dp,dtheta_dp,half_width,", 0), 0u) << line;
  int rows = 0;
  while (std::getline(csv_in, line)) {
    ++rows;
    std::istringstream fields(line);
    std::string field;
    std::getline(fields, field, ',');  // the parameter kind
    int numbers = 0;
    while (std::getline(fields, field, ',')) {
      char* end = nullptr;
      const double value = std::strtod(field.c_str(), &end);
      EXPECT_TRUE(*end == '\0' && std::isfinite(value)) << line;
      ++numbers;
    }
    EXPECT_EQ(numbers, 7) << line;
  }
  EXPECT_EQ(rows, 11);
}

TEST(CalibCli, SampleDesign) {
  const std::string dir = std::string(PCR_BINARY_DIR) + "/test_calib_cli_design_";
  const std::string common = "sample --count 6 --validation-count 3 --seed 2 --box -3e-3,3e-3 ";
  ASSERT_EQ(run(common + "--design poisson-disc --output " + dir + "pd.csv --validation-output " +
                dir + "pd_val.csv"),
            0);
  ASSERT_EQ(run(common + "--design d-optimal --candidates 30 --output " + dir +
                "do.csv --validation-output " + dir + "do_val.csv"),
            0);
  const std::vector<JointVector> cfg = read_configurations(dir + "do.csv", 3);
  const std::vector<JointVector> val = read_configurations(dir + "do_val.csv", 3);
  ASSERT_EQ(cfg.size(), 6u);
  // The validation set is the Poisson-disc one of the same seed, disjoint from the design.
  EXPECT_EQ(val, read_configurations(dir + "pd_val.csv", 3));
  EXPECT_NE(cfg, read_configurations(dir + "pd.csv", 3));
  for (const JointVector& a : cfg) {
    EXPECT_LE(a.cwiseAbs().maxCoeff(), 3e-3);
    for (const JointVector& b : val) EXPECT_GT((a - b).norm(), 0.0);
  }

  // A design CLI11 does not know: bad usage, its name in the message, nothing written.
  std::remove((dir + "bad.csv").c_str());
  const std::string command = std::string(PCR_CLI_PATH) + " sample --design optimal --output " +
                              dir + "bad.csv 2> " + dir + "bad.txt";
  EXPECT_NE(std::system(command.c_str()), 0);
  EXPECT_FALSE(std::ifstream(dir + "bad.csv").good());
  std::ifstream err(dir + "bad.txt");
  const std::string message((std::istreambuf_iterator<char>(err)),
                            std::istreambuf_iterator<char>());
  EXPECT_NE(message.find("--design"), std::string::npos) << message;
  EXPECT_NE(message.find("optimal"), std::string::npos) << message;
}
#endif

}  // namespace
}  // namespace pcr
