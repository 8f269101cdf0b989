// Trajectories and ISO 9283 accuracy (the paper's Section 6): path geometry against closed forms,
// the ISO 9283 formulas against a hand-computed example, AP ~ 0 when the model is the truth,
// errors naming the pose, and the repeatability against the known camera noise.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "pcr/calib/accuracy.hpp"
#include "scratch_directory.hpp"

namespace pcr {
namespace {

double distance(const Pose2<double>& a, const Pose2<double>& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

/// Writes `text` to `name` in the test's scratch directory; returns the path.
std::string write_file(const test::ScratchDirectory& scratch, const std::string& name,
                       const std::string& text) {
  const std::string path = scratch.file(name);
  std::ofstream(path) << text;
  return path;
}

TEST(Trajectory, SquareHasTheRequestedSideCornersAndClosure) {
  SquarePath spec;  // the paper's: side 2 mm, theta 0, centred on home
  const std::vector<Pose2<double>> square = square_path(spec);
  ASSERT_EQ(square.size(), 40u);
  // Corners every 10 poses, counter-clockwise from (-1, -1) mm.
  const double h = 1e-3;
  const double corners[4][2] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
  for (int c = 0; c < 4; ++c) {
    EXPECT_NEAR(square[10 * c].x, corners[c][0], 1e-15);
    EXPECT_NEAR(square[10 * c].y, corners[c][1], 1e-15);
  }
  // Evenly spaced along the 8 mm perimeter, closed (the last pose steps back to the first).
  for (std::size_t k = 0; k < square.size(); ++k) {
    const Pose2<double>& next = square[(k + 1) % square.size()];
    EXPECT_NEAR(distance(square[k], next), 8e-3 / 40, 1e-15) << k;
    EXPECT_EQ(square[k].theta, 0.0);
    EXPECT_LE(std::max(std::abs(square[k].x), std::abs(square[k].y)), h + 1e-15);
  }
  EXPECT_NEAR(distance(spec.at(1.0), square[0]), 0.0, 1e-15);

  // Size, centre, rotation and orientation are honoured.
  SquarePath moved;
  moved.side = 1e-3;
  moved.centre = Vector2<double>(2e-3, -1e-3);
  moved.rotation = M_PI / 2;
  moved.theta = 0.05;
  moved.num_poses = 8;
  const Pose2<double> first = moved.pose(0);  // corner (-0.5, -0.5) mm rotated by 90 degrees
  EXPECT_NEAR(first.x, 2e-3 + 0.5e-3, 1e-15);
  EXPECT_NEAR(first.y, -1e-3 - 0.5e-3, 1e-15);
  EXPECT_EQ(first.theta, 0.05);
  EXPECT_NEAR(distance(moved.pose(0), moved.pose(2)), 1e-3, 1e-15);
  EXPECT_NEAR(distance(moved.pose(0), moved.pose(4)), std::sqrt(2.0) * 1e-3, 1e-15);
}

TEST(Trajectory, CircleHasTheRequestedDiameterAndClosure) {
  CirclePath spec;  // diameter 3 mm
  const std::vector<Pose2<double>> circle = circle_path(spec);
  ASSERT_EQ(circle.size(), 36u);
  const Pose2<double> centre{0, 0, 0};
  for (std::size_t k = 0; k < circle.size(); ++k) {
    EXPECT_NEAR(distance(circle[k], centre), 1.5e-3, 1e-15);
    EXPECT_NEAR(distance(circle[k], circle[(k + 1) % 36]), 3e-3 * std::sin(M_PI / 36), 1e-15);
    EXPECT_NEAR(distance(circle[k], circle[(k + 18) % 36]), 3e-3, 1e-15);  // opposite: diameter
  }
  EXPECT_NEAR(distance(spec.at(1.0), circle[0]), 0.0, 1e-15);
  EXPECT_NEAR(distance(spec.at(0.25), Pose2<double>{0, 1.5e-3, 0}), 0.0, 1e-15);

  // The no-heap path: a caller's buffer, truncated to its capacity.
  Pose2<double> buffer[5];
  EXPECT_EQ(fill_path(spec, buffer, 5), 5);
  EXPECT_NEAR(distance(buffer[4], circle[4]), 0.0, 0.0);
  CirclePath empty;
  empty.num_poses = 0;
  EXPECT_THROW(circle_path(empty), InputError);
}

TEST(Trajectory, PathFromCsv) {
  const test::ScratchDirectory scratch("accuracy");
  const std::string path =
      write_file(scratch, "path.csv", "x,y,theta\n0,0,0\n# comment\n1e-3,2e-3,0.01\n");
  const std::vector<Pose2<double>> poses = load_path_csv(path);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].y, 2e-3);
  EXPECT_EQ(poses[1].theta, 0.01);
  const std::string bad = write_file(scratch, "bad_path.csv", "x,y,theta\n0,0,0\n1e-3,oops,0\n");
  try {
    load_path_csv(bad);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad_path.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3"), std::string::npos) << e.what();
  }
}

TEST(Iso9283, FormulasMatchAHandComputedExample) {
  // Pose 0: commanded at the origin; five attained poses with barycentre (2, 1) um, 2 mrad.
  const double u = 1e-6;
  std::vector<Pose2<double>> commanded = {{0, 0, 0}, {1e-3, 0, -0.01}};
  std::vector<std::vector<Pose2<double>>> attained(2);
  attained[0] = {{1 * u, 0, 0.001},
                 {3 * u, 0, 0.003},
                 {1 * u, 2 * u, 0.002},
                 {3 * u, 2 * u, 0.002},
                 {2 * u, 1 * u, 0.002}};
  // Pose 1: two identical attained poses, 3 um / 4 um off, 2 mrad under the command.
  attained[1] = {{1e-3 + 3 * u, 4 * u, -0.012}, {1e-3 + 3 * u, 4 * u, -0.012}};
  const Iso9283Result r = iso9283(commanded, attained);
  ASSERT_EQ(r.poses.size(), 2u);
  const Iso9283Pose& p = r.poses[0];
  EXPECT_NEAR(p.barycentre.x, 2 * u, 1e-18);
  EXPECT_NEAR(p.barycentre.y, 1 * u, 1e-18);
  EXPECT_NEAR(p.ap_p, std::sqrt(5.0) * u, 1e-18);  // Eq. 10
  EXPECT_NEAR(p.ap_theta, 0.002, 1e-15);           // Eq. 11
  // l_j = sqrt(2), sqrt(2), sqrt(2), sqrt(2), 0 um: l_bar = 4 sqrt(2) / 5, S_l^2 = 1.6 / 4 um^2.
  EXPECT_NEAR(p.l_bar, 4 * std::sqrt(2.0) / 5 * u, 1e-18);
  EXPECT_NEAR(p.s_l, std::sqrt(0.4) * u, 1e-18);
  EXPECT_NEAR(p.rp_l, (4 * std::sqrt(2.0) / 5 + 3 * std::sqrt(0.4)) * u, 1e-18);
  // theta deviations -1, 1, 0, 0, 0 mrad: S_theta^2 = 2e-6 / 4.
  EXPECT_NEAR(p.s_theta, std::sqrt(5e-7), 1e-15);
  EXPECT_NEAR(p.rp_theta, 3 * std::sqrt(5e-7), 1e-15);
  const Iso9283Pose& q = r.poses[1];
  EXPECT_NEAR(q.ap_p, 5 * u, 1e-18);
  EXPECT_NEAR(q.ap_theta, -0.002, 1e-15);
  EXPECT_NEAR(q.rp_l, 0.0, 1e-18);
  // Table 4 summary.
  EXPECT_NEAR(r.ap_p.max, 5 * u, 1e-18);
  EXPECT_NEAR(r.ap_p.min, std::sqrt(5.0) * u, 1e-18);
  EXPECT_NEAR(r.ap_p.mean, (5 + std::sqrt(5.0)) / 2 * u, 1e-18);
  EXPECT_NEAR(r.ap_theta_abs.max, 0.002, 1e-15);
  EXPECT_NEAR(r.ap_theta_abs.min, 0.002, 1e-15);
}

TEST(Iso9283, AnglesAveragedAcrossPlusMinusPi) {
  const std::vector<Pose2<double>> commanded = {{0, 0, M_PI - 0.001}};
  const std::vector<std::vector<Pose2<double>>> attained = {
      {{0, 0, -M_PI + 0.001}, {0, 0, M_PI - 0.001 + 0.002}}};  // both 2 mrad past the command
  const Iso9283Result r = iso9283(commanded, attained);
  EXPECT_NEAR(r.poses[0].ap_theta, 0.002, 1e-12);
  EXPECT_NEAR(r.poses[0].s_theta, 0.0, 1e-12);
}

TEST(Iso9283, RejectsInconsistentInput) {
  const std::vector<Pose2<double>> commanded = {{0, 0, 0}};
  EXPECT_THROW(iso9283(commanded, {}), InputError);
  EXPECT_THROW(iso9283(commanded, {{{0, 0, 0}}}), InputError);  // one attained pose
  EXPECT_THROW(iso9283(commanded, {{{0, 0, 0}, {NAN, 0, 0}}}), InputError);
}

TEST(Iso9283, MeasuredCsvRoundTripAndErrors) {
  const test::ScratchDirectory scratch("accuracy");
  const std::vector<Pose2<double>> commanded = {{0, 0, 0}, {1e-3, -1e-3, 0.01}};
  const std::vector<std::vector<Pose2<double>>> attained = {
      {{1e-8, 0, 0}, {0, 2e-8, 1e-6}}, {{1e-3, -1e-3, 0.01}, {1.1e-3, -1e-3, 0.0101}}};
  const std::string path =
      write_file(scratch, "measured.csv", measured_to_csv(commanded, attained));
  const MeasuredPath m = load_measured_csv(path);
  ASSERT_EQ(m.commanded.size(), 2u);
  ASSERT_EQ(m.attained[1].size(), 2u);
  EXPECT_EQ(m.commanded[1].theta, 0.01);
  EXPECT_EQ(m.attained[1][1].x, 1.1e-3);

  const std::string gap = write_file(
      scratch, "gap.csv", "pose,x_c,y_c,theta_c,x,y,theta\n0,0,0,0,0,0,0\n2,0,0,0,0,0,0\n");
  try {
    load_measured_csv(gap);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pose index 1"), std::string::npos) << e.what();
  }
  const std::string clash = write_file(
      scratch, "clash.csv", "pose,x_c,y_c,theta_c,x,y,theta\n0,0,0,0,0,0,0\n0,1e-3,0,0,0,0,0\n");
  try {
    load_measured_csv(clash);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("clash.csv:3"), std::string::npos) << e.what();
  }
}

TEST(CommandPath, PoseOutsideTheWorkspaceIsNamed) {
  const RobotParams<double> robot = femto_3pf();
  const std::vector<Pose2<double>> path = {{0, 0, 0}, {0.5e-3, 0, 0}, {25e-3, 0, 0}};
  try {
    command_path(robot, path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pose 2 "), std::string::npos) << e.what();
  }
  // The strain limit is checked too (home is stress-free, the next pose is not).
  PathCommandOptions tight;
  tight.step.strain_limit = 1e-6;
  try {
    command_path(robot, path, tight);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pose 1 "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("strain"), std::string::npos) << e.what();
  }
  // A narrower stroke puts a reachable pose out of range.
  RobotParams<double> short_stroke = robot;
  for (int i = 0; i < 3; ++i) short_stroke.limb(i).q_min = short_stroke.limb(i).q_max = 0.0;
  EXPECT_THROW(command_path(short_stroke, {{0.5e-3, 0, 0}}), InputError);
}

TEST(CommandPath, CommandedJointsReproduceThePosesByForwardKinematics) {
  const RobotParams<double> robot = femto_3pf();
  const std::vector<Pose2<double>> square = square_path();
  const PathCommand command = command_path(robot, square);
  ASSERT_EQ(command.q.size(), square.size());
  ForwardSolution fk = home_solution(robot);
  for (std::size_t k = 0; k < square.size(); ++k) {
    fk = forward_kinematics(robot, command.q[k], fk);
    ASSERT_TRUE(fk.summary.converged()) << k;
    // IK and FK each pick their RK4 step count for the default accuracy (1 nm, 1 urad).
    EXPECT_LT(distance(fk.pose, square[k]), 1e-9) << k;
    EXPECT_NEAR(fk.pose.theta, 0.0, 1e-6) << k;
    EXPECT_LE(command.max_strain[k], kDefaultStrainLimit);
  }
}

TEST(Accuracy, TrueModelOnANoiselessVirtualRobotIsExact) {
  VirtualRobotOptions vr_options;
  vr_options.seed = 7;
  vr_options.noise_position = 0;
  vr_options.noise_angle = 0;
  VirtualRobot robot(default_robot(), vr_options);
  SquarePath spec;
  spec.num_poses = 12;
  AccuracyOptions options;
  options.repeat = 3;
  const AccuracyEvaluation truth =
      evaluate_on_virtual_robot(robot.truth().params, robot, square_path(spec), options);
  ASSERT_EQ(truth.attained.size(), 12u);
  ASSERT_EQ(truth.attained[0].size(), 3u);
  EXPECT_LT(truth.iso.ap_p.max, 1e-9);
  EXPECT_LT(truth.iso.ap_theta_abs.max, 1e-6);  // the default accuracy of IK and FK
  EXPECT_LT(truth.iso.rp_l.max, 1e-12);

  // Mapped with the true extrinsics (here the model's too): the same.
  options.frame = AttainedFrame::kTrueExtrinsics;
  const AccuracyEvaluation mapped =
      evaluate_on_virtual_robot(robot.truth().params, robot, square_path(spec), options);
  EXPECT_LT(mapped.iso.ap_p.max, 1e-9);

  // The nominal model misses by far more than the noise floor (the check can fail).
  options.frame = AttainedFrame::kTrueExtrinsics;
  const AccuracyEvaluation nominal =
      evaluate_on_virtual_robot(robot.nominal().params, robot, square_path(spec), options);
  EXPECT_GT(nominal.iso.ap_p.max, 1e-6);
}

/// The truth in other frames: W moved by G (A_i, alpha_i, camera) and P by H (B_i, beta_i,
/// pattern). Every camera measurement is unchanged, so calibration cannot tell them apart.
RobotParams<double> regauged(const RobotParams<double>& truth, const Pose2<double>& G,
                             const Pose2<double>& H) {
  RobotParams<double> out = truth;
  const Pose2<double> H_inv = H.inverse();
  for (int i = 0; i < truth.num_limbs; ++i) {
    LimbParams<double>& limb = out.limb(i);
    limb.A = G.transform(truth.limb(i).A);
    limb.alpha = truth.limb(i).alpha + G.theta;
    limb.B = H_inv.transform(truth.limb(i).B);
    limb.beta = truth.limb(i).beta - H.theta;
  }
  out.extrinsics.camera = G * truth.extrinsics.camera;    // ^Wnew T_Se = ^Wnew T_W ^W T_Se
  out.extrinsics.pattern = truth.extrinsics.pattern * H;  // ^M T_Pnew = ^M T_P ^P T_Pnew
  return out;
}

TEST(Accuracy, ModelFramesMakeTheEvaluationGaugeInvariant) {
  VirtualRobotOptions vr_options;
  vr_options.seed = 11;
  vr_options.noise_position = 0;
  vr_options.noise_angle = 0;
  VirtualRobot robot(default_robot(), vr_options);
  // An identified model may sit in other frames, here 300 um / 4 mrad and 200 um / 3 mrad away.
  const RobotParams<double> model = regauged(robot.truth().params, Pose2<double>{3e-4, -1e-4, 4e-3},
                                             Pose2<double>{-2e-4, 1e-4, -3e-3});
  CirclePath spec;
  spec.num_poses = 8;
  AccuracyOptions options;
  options.repeat = 2;
  const AccuracyEvaluation in_model =
      evaluate_on_virtual_robot(model, robot, circle_path(spec), options);
  EXPECT_LT(in_model.iso.ap_p.max, 1e-9);
  EXPECT_LT(in_model.iso.ap_theta_abs.max, 1e-6);
  // Compared in the truth's frames, the same model looks hundreds of micrometres off.
  options.frame = AttainedFrame::kTrueExtrinsics;
  const AccuracyEvaluation in_truth =
      evaluate_on_virtual_robot(model, robot, circle_path(spec), options);
  EXPECT_GT(in_truth.iso.ap_p.min, 50e-6);
}

TEST(Accuracy, RepeatabilityMatchesTheCameraNoise) {
  VirtualRobotOptions vr_options;
  vr_options.seed = 3;  // noise: the paper's 9.13 nm and 1.2 urad
  VirtualRobot robot(default_robot(), vr_options);
  CirclePath spec;
  spec.num_poses = 12;
  AccuracyOptions options;  // 30 cycles
  const AccuracyEvaluation e =
      evaluate_on_virtual_robot(robot.truth().params, robot, circle_path(spec), options);
  const double sigma = vr_options.noise_position, sigma_theta = vr_options.noise_angle;
  // Isotropic Gaussian (x, y): l is Rayleigh, E[l] = sigma sqrt(pi/2), sd(l) = sigma
  // sqrt((4 - pi)/2), so RP_l -> 3.2187 sigma (x sqrt(29/30) for the estimated barycentre).
  const double rayleigh =
      (std::sqrt(M_PI / 2) + 3 * std::sqrt((4 - M_PI) / 2)) * std::sqrt(29.0 / 30.0);
  // Over 12 poses the mean RP_l has a standard error of about 0.08 sigma.
  EXPECT_NEAR(e.iso.rp_l.mean / sigma, rayleigh, 0.35);
  EXPECT_NEAR(e.iso.rp_theta.mean / sigma_theta, 3.0, 0.4);
  // AP of the true model is the barycentre's noise: sigma / sqrt(30) per axis.
  EXPECT_LT(e.iso.ap_p.max, sigma);
  EXPECT_LT(e.iso.ap_theta_abs.max, sigma_theta);
}

#ifdef PCR_CLI_PATH
/// Runs `pcr <arguments>`, stdout to `out`, stderr to the scratch directory's stderr.txt.
int run_cli(const test::ScratchDirectory& scratch, const std::string& arguments,
            const std::string& out) {
  const std::string command = std::string(PCR_CLI_PATH) + " " + arguments + " > '" + out +
                              "' 2> '" + scratch.file("stderr.txt") + "'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(AccuracyCli, TableFromMeasuredPoses) {
  const test::ScratchDirectory scratch("accuracy");
  // Pose 0: attained 3 um / 4 um off in x / y on average (AP_p = 5 um), 1 mrad in theta.
  const std::string measured = write_file(scratch, "cli_measured.csv",
                                          "pose,x_c,y_c,theta_c,x,y,theta\n"
                                          "0,0,0,0,2e-6,4e-6,0.001\n"
                                          "0,0,0,0,4e-6,4e-6,0.001\n"
                                          "1,1e-3,0,0,1e-3,1e-6,0\n"
                                          "1,1e-3,0,0,1e-3,1e-6,0\n");
  const std::string out = scratch.file("out.csv");
  ASSERT_EQ(run_cli(scratch, "accuracy --measured " + measured + " --format csv", out), 0)
      << read_text(scratch.file("stderr.txt"));
  std::ifstream in(out);
  std::string header, row0, row1;
  std::getline(in, header);
  std::getline(in, row0);
  std::getline(in, row1);
  EXPECT_EQ(header.rfind("pose,x_c,y_c,theta_c,x_bar,y_bar,theta_bar,cycles,ap_x,ap_y,ap_p,", 0),
            0u);
  // ap_p is the 11th column.
  const auto field = [](const std::string& line, int index) {
    std::stringstream s(line);
    std::string f;
    for (int i = 0; i <= index; ++i) std::getline(s, f, ',');
    return std::stod(f);
  };
  EXPECT_NEAR(field(row0, 10), 5e-6, 1e-18);
  EXPECT_NEAR(field(row0, 11), 0.001, 1e-15);
  EXPECT_NEAR(field(row1, 10), 1e-6, 1e-18);
}

TEST(AccuracyCli, PoseOutOfReachIsAnErrorNamingThePose) {
  const test::ScratchDirectory scratch("accuracy");
  const std::string out = scratch.file("table.md");
  EXPECT_EQ(run_cli(scratch, "accuracy --path circle --size 0.04 --repeat 2", out), 2);
  const std::string err = read_text(scratch.file("stderr.txt"));
  EXPECT_NE(err.find("pose 0 "), std::string::npos) << err;
  // The paper's square on the nominal model: a table with one row, AP_p in micrometres.
  ASSERT_EQ(run_cli(scratch, "accuracy --path square --count 8 --repeat 2", out), 0)
      << read_text(scratch.file("stderr.txt"));
  EXPECT_NE(read_text(out).find("| square | "), std::string::npos);
}
#endif

}  // namespace
}  // namespace pcr
