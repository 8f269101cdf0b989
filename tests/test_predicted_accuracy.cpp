// Predicted accuracy of a calibrated robot (pcr/calib/predicted_accuracy.hpp), against
// independent references:
// - d pose / d parameters at a given solution against central differences of FK;
// - the pose covariance against the sample covariance of FK over Monte Carlo draws of the
//   parameters from a known, correlated covariance (load and extrinsics included), for ^W T_P
//   and for the camera's measurement of it;
// - the worst case against FK at random draws inside the intervals (never above it) and at the
//   corner that attains it (within a few %), and against every corner of a 12-parameter box;
// - the parameter covariance a calibration returns: its diagonal against the reported standard
//   deviations, written into the report and read back equal; bad covariance blocks give errors
//   naming the file, the field and the value.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "pcr/calib/calibration_report.hpp"
#include "pcr/calib/cost.hpp"
#include "pcr/calib/predicted_accuracy.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace pcr {
namespace {

std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "pcr_predicted_accuracy_" + name;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// The default robot with only the rod lengths and the extrinsics uncertain.
RobotDescription lengths_and_extrinsics_uncertain() {
  RobotDescription nominal = default_robot();
  RobotUncertainty u;
  u.global.rod.length = 126e-6;
  u.global.rod.young_modulus = 5e9;
  u.global.rod.diameter = 2e-6;
  u.limbs.assign(3, u.global);
  u.camera = nominal.uncertainty->camera;
  u.pattern = nominal.uncertainty->pattern;
  nominal.uncertainty = u;
  return nominal;
}

/// A small identification on a virtual robot: the 26 configurations of the sensitivity grid
/// (2 mm), the extrinsics, then the lengths with them and the moduli and diameters. d[0] holds
/// the common stiffness scale (gauge reference); the data see only the ratios of the E_i d_i^4,
/// so E_i and d_i are not identifiable: NaN rows in the covariance.
CalibrationResult small_calibration() {
  const RobotDescription nominal = lengths_and_extrinsics_uncertain();
  VirtualRobotOptions vo;
  vo.seed = 3;
  VirtualRobot robot(nominal, vo);
  std::vector<CalibrationSample> data;
  for (const JointVector& q : sensitivity_configurations(nominal.params, 2e-3)) {
    data.push_back({q, robot.measure_or_throw(q)});
  }
  CalibrationOptions options;
  options.stages = {{"extrinsics", {"extrinsics"}, 1.0},
                    {"lengths", {"l", "E", "d", "extrinsics"}, 1.0}};
  return calibrate(nominal, data, options);
}

const CalibrationResult& calibration() {
  static const CalibrationResult result = small_calibration();
  return result;
}

JointVector joints(double a, double b, double c) {
  JointVector q(3);
  q << a, b, c;
  return q;
}

/// FK converged to rounding: no chord steps left in the output (the default share leaves
/// ~0.02 nm between neighbouring solves, as large as a finite difference's signal).
SolverOptions tight() {
  SolverOptions options;
  options.tolerance = 1e-14;
  options.chord_output_share = 0.0;
  return options;
}

Eigen::Vector3d pose_difference(const Pose2<double>& a, const Pose2<double>& b) {
  return Eigen::Vector3d(a.x - b.x, a.y - b.y, a.theta - b.theta);
}

/// The flat parameters (then the load's three) of a 3-limb robot as a vector, and back.
Eigen::VectorXd flat_values(const RobotParams<double>& robot, const PlatformLoad<double>& load) {
  Eigen::VectorXd v(num_parameters(3) + kLoadParameters);
  get_parameters(robot, v.data());
  v.tail<3>() << load.force.x(), load.force.y(), load.moment;
  return v;
}
RobotParams<double> robot_of(const RobotParams<double>& base, const Eigen::VectorXd& v) {
  return with_parameters(base, v.data());
}
PlatformLoad<double> load_of(const Eigen::VectorXd& v) {
  const int count = num_parameters(3);
  return PlatformLoad<double>{Vector2<double>(v(count), v(count + 1)), v(count + 2)};
}

TEST(PoseParameterJacobian, AtTheGivenSolutionMatchesCentralDifferences) {
  const RobotParams<double> robot = femto_3pf();
  const PlatformLoad<double> load{Vector2<double>(2e-3, -1e-3), 5e-6};
  // The solution reached along a path of warm starts, not from home.
  ForwardSolution solution = forward_kinematics(robot, joints(0, 0, 0), tight(), load);
  for (const JointVector& q : {joints(2e-3, 0, 0), joints(2e-3, -3e-3, 1e-3)}) {
    solution = forward_kinematics(robot, q, solution, tight(), load);
  }
  ASSERT_TRUE(solution.summary.converged());
  PoseParameterJacobian J;
  ASSERT_TRUE(pose_parameter_jacobian(robot, solution, &J, load, tight()));
  ASSERT_EQ(J.cols(), num_parameters(3) + kLoadParameters);
  const Eigen::VectorXd p0 = flat_values(robot, load);
  const double length = robot.limb(0).rod.length;
  for (Eigen::Index k = 0; k < p0.size(); ++k) {
    const ParameterId id = parameter_id(static_cast<int>(k), 3);
    // Steps: 1e-4 relative on E and d, 1e-4 rad, 1e-6 m, 1e-5 N, 1e-6 N m (the truncation and
    // FK's rounding both below the tolerance).
    double h = 1e-6;
    if (id.kind == ParameterKind::kYoungModulus || id.kind == ParameterKind::kDiameter) {
      h = 1e-4 * p0(k);
    } else if (id.kind == ParameterKind::kAlpha || id.kind == ParameterKind::kBeta ||
               id.kind == ParameterKind::kGamma) {
      h = 1e-4;
    } else if (id.kind == ParameterKind::kLoadForceX || id.kind == ParameterKind::kLoadForceY) {
      h = 1e-5;
    } else if (id.kind == ParameterKind::kLoadMoment) {
      h = 1e-6;
    }
    Eigen::VectorXd plus = p0, minus = p0;
    plus(k) += h;
    minus(k) -= h;
    const ForwardSolution fp =
        forward_kinematics(robot_of(robot, plus), solution.q, solution, tight(), load_of(plus));
    const ForwardSolution fm =
        forward_kinematics(robot_of(robot, minus), solution.q, solution, tight(), load_of(minus));
    ASSERT_TRUE(fp.summary.converged() && fm.summary.converged()) << parameter_name(id);
    const Eigen::Vector3d fd = pose_difference(fp.pose, fm.pose) / (2 * h);
    const Eigen::Vector3d exact = J.col(k);
    if (id.limb < 0 && id.kind <= ParameterKind::kPatternTheta) {
      EXPECT_TRUE(exact.isZero(0.0)) << parameter_name(id);  // the extrinsics
    }
    // Relative 1e-6 of the column (theta as an arc length over one rod length), plus the finite
    // differences' own rounding floor.
    const Eigen::Vector3d arc(1, 1, length);
    const double tol = 1e-6 * exact.cwiseProduct(arc).cwiseAbs().maxCoeff() + 1e-14 / h;
    EXPECT_LE((exact - fd).cwiseProduct(arc).cwiseAbs().maxCoeff(), tol)
        << parameter_name(id) << ": " << exact.transpose() << " against " << fd.transpose();
  }
}

/// A covariance on a few limb parameters, the load and the extrinsics, correlated, with the default
/// robot's names.
ParameterCovariance known_covariance() {
  const int size = num_parameters(3) + kLoadParameters;
  ParameterCovariance c;
  for (int k = 0; k < size; ++k) c.names.push_back(parameter_name(parameter_id(k, 3)));
  c.matrix = Eigen::MatrixXd::Zero(size, size);
  struct Entry {
    ParameterKind kind;
    int limb;
    double sigma;
  };
  const Entry entries[] = {
      {ParameterKind::kLength, 0, 3e-6},       {ParameterKind::kAx, 1, 2e-6},
      {ParameterKind::kAy, 2, 2e-6},           {ParameterKind::kAlpha, 0, 1e-3},
      {ParameterKind::kBx, 1, 2e-6},           {ParameterKind::kDiameter, 2, 1e-6},
      {ParameterKind::kGamma, 1, 1e-3},        {ParameterKind::kLoadForceX, -1, 2e-4},
      {ParameterKind::kLoadMoment, -1, 2e-6},  {ParameterKind::kCameraX, -1, 3e-6},
      {ParameterKind::kCameraTheta, -1, 5e-4}, {ParameterKind::kPatternY, -1, 2e-6},
  };
  const auto index = [](const Entry& e) {
    if (e.limb >= 0 || e.kind <= ParameterKind::kPatternTheta) {
      return parameter_index(ParameterId{e.kind, e.limb}, 3);
    }
    return num_parameters(3) + static_cast<int>(e.kind) -
           static_cast<int>(ParameterKind::kLoadForceX);
  };
  for (const Entry& e : entries) c.matrix(index(e), index(e)) = e.sigma * e.sigma;
  const auto correlate = [&](int a, int b, double rho) {
    const int i = index(entries[a]), j = index(entries[b]);
    c.matrix(i, j) = c.matrix(j, i) = rho * entries[a].sigma * entries[b].sigma;
  };
  correlate(0, 1, 0.6);   // l[0], A_x[1]
  correlate(2, 4, -0.5);  // A_y[2], B_x[1]
  correlate(0, 3, 0.3);   // l[0], alpha[0]
  correlate(7, 8, -0.4);  // load f_x, m_z
  correlate(1, 9, 0.4);   // A_x[1], camera_x
  correlate(3, 10, 0.2);  // alpha[0], camera_theta
  return c;
}

TEST(PredictedAccuracy, PoseCovarianceMatchesMonteCarlo) {
  const RobotParams<double> robot = femto_3pf();
  const PlatformLoad<double> load{Vector2<double>(1e-3, 0.0), 0.0};
  const ParameterCovariance covariance = known_covariance();
  ASSERT_NO_THROW(validate_parameter_covariance(covariance, "known_covariance", 3));
  ASSERT_TRUE(covariance.has_load());
  // Draws p = p0 + L z, z standard normal, L L^T = the covariance (on its nonzero block).
  std::vector<int> active;
  for (int k = 0; k < covariance.matrix.rows(); ++k) {
    if (covariance.matrix(k, k) > 0) active.push_back(k);
  }
  const Eigen::Index m = static_cast<Eigen::Index>(active.size());
  Eigen::MatrixXd block(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) {
      block(a, b) = covariance.matrix(active[static_cast<std::size_t>(a)],
                                      active[static_cast<std::size_t>(b)]);
    }
  }
  const Eigen::MatrixXd L = block.llt().matrixL();
  // 4000 draws: a sample variance is then within ~2.2 % (1 sigma) of the true one, and the
  // eigenvalues of the whitened sample covariance within ~5 % of 1; 15 % cannot be reached by
  // chance (fixed seed besides), while a factor of 2 on the covariance, or Jacobian columns of
  // the wrong parameters, move them to 2, 0.5 or far beyond.
  constexpr int kDraws = 4000;
  std::mt19937_64 rng(20210);
  std::normal_distribution<double> normal;
  std::vector<Eigen::VectorXd> draws(kDraws);
  const Eigen::VectorXd p0 = flat_values(robot, load);
  for (Eigen::VectorXd& p : draws) {
    Eigen::VectorXd z(m);
    for (Eigen::Index a = 0; a < m; ++a) z(a) = normal(rng);
    const Eigen::VectorXd dp = L * z;
    p = p0;
    for (Eigen::Index a = 0; a < m; ++a) p(active[static_cast<std::size_t>(a)]) += dp(a);
  }
  PredictedAccuracyOptions options;
  options.load = load;
  struct Case {
    JointVector q;
    PoseFrame frame;
  };
  for (const Case& c : {Case{joints(0, 0, 0), PoseFrame::kPlatform},
                        Case{joints(3e-3, -2e-3, 1e-3), PoseFrame::kPlatform},
                        Case{joints(-4e-3, 2e-3, 5e-3), PoseFrame::kPlatform},
                        Case{joints(6e-3, 5e-3, -3e-3), PoseFrame::kPlatform},
                        Case{joints(3e-3, -2e-3, 1e-3), PoseFrame::kMeasurement},
                        Case{joints(6e-3, 5e-3, -3e-3), PoseFrame::kMeasurement}}) {
    const JointVector& q = c.q;
    const bool measured = c.frame == PoseFrame::kMeasurement;
    const ForwardSolution solution = forward_kinematics(robot, q, tight(), load);
    ASSERT_TRUE(solution.summary.converged());
    options.frame = c.frame;
    const PredictedAccuracy predicted = predicted_accuracy(robot, solution, covariance, options);
    ASSERT_TRUE(predicted.ok()) << to_string(predicted.status);
    // The pose the prediction is of: ^W T_P, or the camera's measurement of it (Eq. 5) with the
    // drawn extrinsics.
    const auto pose_of = [&](const RobotParams<double>& r, const Pose2<double>& platform) {
      return measured ? r.extrinsics.measurement_from_platform(platform) : platform;
    };
    const Pose2<double> reference = pose_of(robot, solution.pose);

    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> errors;
    for (const Eigen::VectorXd& p : draws) {
      const RobotParams<double> drawn = robot_of(robot, p);
      const ForwardSolution s = forward_kinematics(drawn, q, solution, tight(), load_of(p));
      ASSERT_TRUE(s.summary.converged());
      errors.push_back(pose_difference(pose_of(drawn, s.pose), reference));
      mean += errors.back() / kDraws;
    }
    Eigen::Matrix3d sample = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& e : errors) sample += (e - mean) * (e - mean).transpose();
    sample /= kDraws - 1;

    // Whitened by the prediction: the identity, up to sampling.
    const Eigen::Matrix3d Lp = predicted.covariance.llt().matrixL();
    const Eigen::Matrix3d W = Lp.triangularView<Eigen::Lower>().solve(
        Lp.triangularView<Eigen::Lower>().solve(sample).transpose());
    const Eigen::Vector3d eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(W).eigenvalues();
    std::printf(
        "%s, q = (%g, %g, %g) mm: 1 sigma %.4f um, %.4f urad; whitened sample covariance's "
        "eigenvalues %.4f %.4f %.4f\n",
        measured ? "measurement" : "platform", q(0) * 1e3, q(1) * 1e3, q(2) * 1e3,
        predicted.position_1sigma * 1e6, predicted.orientation_1sigma * 1e6, eigenvalues(0),
        eigenvalues(1), eigenvalues(2));
    EXPECT_GT(eigenvalues(0), 0.85);
    EXPECT_LT(eigenvalues(2), 1.15);
    // The summaries, against the sample's own.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> position(sample.topLeftCorner<2, 2>());
    EXPECT_NEAR(predicted.position_1sigma, std::sqrt(position.eigenvalues()(1)),
                0.08 * predicted.position_1sigma);
    EXPECT_NEAR(predicted.orientation_1sigma, std::sqrt(sample(2, 2)),
                0.08 * predicted.orientation_1sigma);
    EXPECT_DOUBLE_EQ(predicted.position_3sigma, 3 * predicted.position_1sigma);
    EXPECT_DOUBLE_EQ(predicted.orientation_3sigma, 3 * predicted.orientation_1sigma);
    // The mean error is second order: far below the spread.
    EXPECT_LT(mean.head<2>().norm(), 0.1 * predicted.position_1sigma);
  }
}

TEST(PredictedAccuracy, MeasurementCovarianceAndStatus) {
  const RobotParams<double> robot = femto_3pf();
  const ForwardSolution solution = forward_kinematics(robot, joints(1e-3, 2e-3, -1e-3));
  ParameterCovariance covariance = known_covariance();
  PredictedAccuracyOptions options;
  const PredictedAccuracy model = predicted_accuracy(robot, solution, covariance, options);
  options.measurement_covariance = Eigen::Vector3d(1e-16, 1e-16, 1e-12).asDiagonal();
  const PredictedAccuracy measured = predicted_accuracy(robot, solution, covariance, options);
  EXPECT_TRUE(
      (measured.covariance - options.measurement_covariance).isApprox(model.covariance, 1e-12));
  // A parameter that moves the platform with a NaN variance: the others' covariance, flagged.
  const int l1 = parameter_index(ParameterId{ParameterKind::kLength, 1}, 3);
  covariance.matrix.row(l1).setConstant(std::numeric_limits<double>::quiet_NaN());
  covariance.matrix.col(l1).setConstant(std::numeric_limits<double>::quiet_NaN());
  const PredictedAccuracy partial = predicted_accuracy(robot, solution, covariance, {});
  EXPECT_EQ(partial.status, PredictionStatus::kNotIdentifiable);
  EXPECT_TRUE(partial.covariance.isApprox(model.covariance, 1e-12));
  // No covariance: the worst case only; an unconverged solution: nothing.
  const PredictedAccuracy none = predicted_accuracy(robot, solution, ParameterCovariance(), {});
  EXPECT_EQ(none.status, PredictionStatus::kNoCovariance);
  ForwardSolution failed = solution;
  failed.summary.status = SolveStatus::kMaxIterations;
  const PredictedAccuracy nothing = predicted_accuracy(robot, failed, known_covariance(), {});
  EXPECT_EQ(nothing.status, PredictionStatus::kNoJacobian);
  EXPECT_TRUE(std::isnan(nothing.position_1sigma));
  // Misuse: another robot's covariance, half-widths of the wrong size.
  ParameterCovariance two_limbs;
  for (int k = 0; k < num_parameters(2); ++k)
    two_limbs.names.push_back(parameter_name(parameter_id(k, 2)));
  two_limbs.matrix = Eigen::MatrixXd::Zero(num_parameters(2), num_parameters(2));
  EXPECT_THROW(predicted_accuracy(robot, solution, two_limbs, {}), InputError);
  PredictedAccuracyOptions bad;
  bad.half_widths.assign(5, 1e-6);
  EXPECT_THROW(predicted_accuracy(robot, solution, ParameterCovariance(), bad), InputError);
}

/// The default robot's half-widths, scaled by `factor`.
std::vector<double> half_widths(double factor) {
  std::vector<double> h = parameter_half_widths(*default_robot().uncertainty, 3);
  for (double& v : h) v *= factor;
  return h;
}

TEST(PredictedAccuracy, WorstCaseBoundsRandomDrawsAndIsAttainedAtItsCorner) {
  const RobotParams<double> robot = femto_3pf();
  const JointVector q = joints(2e-3, -1e-3, 3e-3);
  const ForwardSolution solution = forward_kinematics(robot, q, tight());
  PredictedAccuracyOptions options;
  options.half_widths = half_widths(0.1);  // small intervals: the linear regime
  const PredictedAccuracy worst =
      predicted_accuracy(robot, solution, ParameterCovariance(), options);
  ASSERT_EQ(worst.status, PredictionStatus::kNoCovariance);
  ASSERT_TRUE(std::isfinite(worst.worst_position));
  const Eigen::Vector3d& w = worst.worst_components;
  EXPECT_EQ(worst.worst_orientation, w(2));
  EXPECT_LE(worst.worst_position, std::hypot(w(0), w(1)) * (1 + 1e-12));
  EXPECT_GE(worst.worst_position, std::max(w(0), w(1)) * (1 - 1e-12));
  std::printf(
      "worst case at 0.1 half-widths: |dx| %.3f um, |dy| %.3f um, |d(x, y)| %.3f um, "
      "|dtheta| %.3f urad\n",
      w(0) * 1e6, w(1) * 1e6, worst.worst_position * 1e6, w(2) * 1e6);

  const std::vector<double>& h = options.half_widths;
  const int count = num_parameters(3);
  Eigen::VectorXd p0(count);
  get_parameters(robot, p0.data());
  const auto error_at = [&](const Eigen::VectorXd& dp) {
    const Eigen::VectorXd p = p0 + dp;
    const ForwardSolution s =
        forward_kinematics(with_parameters(robot, p.data()), q, solution, tight());
    EXPECT_TRUE(s.summary.converged());
    return pose_difference(s.pose, solution.pose);
  };
  // Random draws inside the intervals: never beyond the worst case.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double largest_position = 0, largest_theta = 0;
  for (int draw = 0; draw < 300; ++draw) {
    Eigen::VectorXd dp(count);
    for (int k = 0; k < count; ++k) dp(k) = unit(rng) * h[static_cast<std::size_t>(k)];
    const Eigen::Vector3d e = error_at(dp);
    largest_position = std::max(largest_position, e.head<2>().norm());
    largest_theta = std::max(largest_theta, std::abs(e(2)));
  }
  std::printf("largest of 300 random draws: |d(x, y)| %.3f um, |dtheta| %.3f urad\n",
              largest_position * 1e6, largest_theta * 1e6);
  EXPECT_LE(largest_position, worst.worst_position);
  EXPECT_LE(largest_theta, worst.worst_orientation);
  // The corners that attain it, by FK: the signs of the first-order error's components.
  PoseParameterJacobian J;
  ASSERT_TRUE(pose_parameter_jacobian(robot, solution, &J));
  const auto corner = [&](const Eigen::Vector3d& direction) {
    Eigen::VectorXd dp(count);
    for (int k = 0; k < count; ++k) {
      const double side = direction.dot(J.col(k));
      dp(k) = (side > 0 ? 1 : side < 0 ? -1 : 0) * h[static_cast<std::size_t>(k)];
    }
    return error_at(dp);
  };
  const Eigen::Vector2d& u = worst.worst_position_direction;
  const Eigen::Vector3d at_position = corner(Eigen::Vector3d(u(0), u(1), 0));
  const Eigen::Vector3d at_x = corner(Eigen::Vector3d::UnitX());
  const Eigen::Vector3d at_y = corner(Eigen::Vector3d::UnitY());
  const Eigen::Vector3d at_theta = corner(Eigen::Vector3d::UnitZ());
  std::printf(
      "FK at the corners / worst case: |d(x, y)| %.4f, |dx| %.4f, |dy| %.4f, |dtheta| "
      "%.4f\n",
      at_position.head<2>().norm() / worst.worst_position, std::abs(at_x(0)) / w(0),
      std::abs(at_y(1)) / w(1), std::abs(at_theta(2)) / w(2));
  EXPECT_NEAR(at_position.head<2>().norm(), worst.worst_position, 0.03 * worst.worst_position);
  EXPECT_NEAR(std::abs(at_x(0)), w(0), 0.03 * w(0));
  EXPECT_NEAR(std::abs(at_y(1)), w(1), 0.03 * w(1));
  EXPECT_NEAR(std::abs(at_theta(2)), w(2), 0.03 * w(2));
}

TEST(PredictedAccuracy, WorstPositionIsTheFarthestCorner) {
  // Twelve parameters with an interval, the others held: every one of the 4096 corners, mapped by
  // the Jacobian, against the zonotope's farthest vertex.
  const RobotParams<double> robot = femto_3pf();
  const ForwardSolution solution = forward_kinematics(robot, joints(-3e-3, 4e-3, 1e-3));
  PoseParameterJacobian J;
  ASSERT_TRUE(pose_parameter_jacobian(robot, solution, &J));
  PredictedAccuracyOptions options;
  options.half_widths.assign(static_cast<std::size_t>(num_parameters(3)), 0.0);
  const std::vector<double> full = half_widths(1.0);
  std::vector<int> chosen;
  for (const ParameterKind kind :
       {ParameterKind::kLength, ParameterKind::kAx, ParameterKind::kBy, ParameterKind::kAlpha}) {
    for (int limb = 0; limb < 3; ++limb) {
      const int k = parameter_index(ParameterId{kind, limb}, 3);
      chosen.push_back(k);
      options.half_widths[static_cast<std::size_t>(k)] = full[static_cast<std::size_t>(k)];
    }
  }
  const PredictedAccuracy worst =
      predicted_accuracy(robot, solution, ParameterCovariance(), options);
  double farthest = 0;
  for (int mask = 0; mask < (1 << chosen.size()); ++mask) {
    Eigen::Vector2d v = Eigen::Vector2d::Zero();
    for (std::size_t c = 0; c < chosen.size(); ++c) {
      const int k = chosen[c];
      v += J.block<2, 1>(0, k) * ((mask >> c) & 1 ? 1.0 : -1.0) *
           options.half_widths[static_cast<std::size_t>(k)];
    }
    farthest = std::max(farthest, v.norm());
  }
  EXPECT_NEAR(worst.worst_position, farthest, 1e-12 * farthest);
}

TEST(ParameterCovariance, DiagonalIsTheStandardDeviationsSquared) {
  const CalibrationResult& result = calibration();
  ASSERT_TRUE(result.covariance_ok);
  const Eigen::Index size = static_cast<Eigen::Index>(result.parameters.size());
  ASSERT_EQ(size, num_parameters(3));
  ASSERT_EQ(result.covariance.rows(), size);
  ASSERT_EQ(result.covariance.cols(), size);
  int unknown = 0, estimated = 0;
  for (Eigen::Index k = 0; k < size; ++k) {
    const ParameterEstimate& p = result.parameters[static_cast<std::size_t>(k)];
    const double variance = result.covariance(k, k);
    if (!p.free || p.gauge_reference) {
      EXPECT_EQ(p.std_dev, 0.0) << p.name;
      EXPECT_TRUE((result.covariance.row(k).array() == 0).all()) << p.name;
      EXPECT_TRUE((result.covariance.col(k).array() == 0).all()) << p.name;
    } else if (std::isnan(p.std_dev)) {
      ++unknown;
      EXPECT_FALSE(p.identifiable) << p.name;
      for (Eigen::Index j = 0; j < size; ++j) {
        const ParameterEstimate& other = result.parameters[static_cast<std::size_t>(j)];
        if (!other.free || other.gauge_reference) {
          EXPECT_EQ(result.covariance(k, j), 0.0) << p.name << ", " << other.name;
          EXPECT_EQ(result.covariance(j, k), 0.0) << p.name << ", " << other.name;
        } else {
          EXPECT_TRUE(std::isnan(result.covariance(k, j))) << p.name << ", " << other.name;
          EXPECT_TRUE(std::isnan(result.covariance(j, k))) << p.name << ", " << other.name;
        }
      }
    } else {
      ++estimated;
      EXPECT_NEAR(std::sqrt(variance), p.std_dev, 1e-12 * p.std_dev) << p.name;
    }
  }
  EXPECT_EQ(estimated, 9);  // l[0..2] and the extrinsics
  EXPECT_EQ(unknown, 5);    // E[0..2], d[1], d[2]: the data see only the ratios of E_i d_i^4
  for (const char* name : {"E[0]", "E[2]", "d[1]", "d[2]"}) {
    const auto it = std::find_if(result.parameters.begin(), result.parameters.end(),
                                 [&](const ParameterEstimate& p) { return p.name == name; });
    ASSERT_NE(it, result.parameters.end());
    EXPECT_FALSE(it->identifiable) << name;
  }
  EXPECT_NO_THROW(validate_parameter_covariance(parameter_covariance(result), "result", 3));
}

TEST(ParameterCovariance, ReportRoundTrip) {
  const CalibrationResult& result = calibration();
  const std::string path = temp_path("report.json");
  write_text(path, calibration_report_json(result, CalibrationTable()));
  const ParameterCovariance read = read_parameter_covariance(path, 3);
  ASSERT_EQ(read.names.size(), result.parameters.size());
  for (std::size_t k = 0; k < read.names.size(); ++k) {
    EXPECT_EQ(read.names[k], result.parameters[k].name);
  }
  EXPECT_EQ(read.num_limbs(), 3);
  EXPECT_FALSE(read.has_load());
  ASSERT_EQ(read.matrix.rows(), result.covariance.rows());
  ASSERT_EQ(read.matrix.cols(), result.covariance.cols());
  for (Eigen::Index r = 0; r < read.matrix.rows(); ++r) {
    for (Eigen::Index c = 0; c < read.matrix.cols(); ++c) {
      const double a = read.matrix(r, c), b = result.covariance(r, c);
      if (std::isnan(b)) {
        EXPECT_TRUE(std::isnan(a)) << r << ", " << c;
      } else {
        EXPECT_EQ(a, b) << r << ", " << c;  // full precision: the same double
      }
    }
  }
  // The existing fields are still there.
  std::ifstream in(path);
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_TRUE(report.contains("parameters") && report.contains("covariance_ok"));
  EXPECT_EQ(report["covariance"]["units"], "SI, flat order");
}

/// A valid block for a 3-limb robot: diagonal variances, one correlation.
nlohmann::json valid_block() {
  nlohmann::json names = nlohmann::json::array();
  for (int k = 0; k < num_parameters(3); ++k) names.push_back(parameter_name(parameter_id(k, 3)));
  const int size = num_parameters(3);
  nlohmann::json matrix = nlohmann::json::array();
  for (int r = 0; r < size; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < size; ++c) row.push_back(r == c ? 1e-12 : 0.0);
    matrix.push_back(row);
  }
  matrix[2][12] = 0.5e-12;
  matrix[12][2] = 0.5e-12;
  return {{"parameters", names}, {"units", "SI, flat order"}, {"matrix", matrix}};
}

/// Writes `report` and expects read_parameter_covariance to throw InputError whose message holds
/// the file's name and every one of `parts`.
void expect_error(const std::string& name, const nlohmann::json& report,
                  const std::vector<std::string>& parts, int num_limbs = 0) {
  const std::string path = temp_path(name);
  write_text(path, report.dump());
  try {
    read_parameter_covariance(path, num_limbs);
    ADD_FAILURE() << name << ": no error";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    }
  }
}

// A report written before rods had a precurvature (ten parameters per limb) held it: it reads as
// the current layout with the precurvatures' rows and columns zero, every other entry in place.
TEST(ParameterCovariance, AReportWithoutPrecurvaturesHeldThem) {
  const nlohmann::json current = valid_block();
  nlohmann::json names = nlohmann::json::array(), matrix = nlohmann::json::array();
  std::vector<int> kept;
  for (int k = 0; k < num_parameters(3); ++k) {
    if (parameter_id(k, 3).kind != ParameterKind::kPrecurvature) kept.push_back(k);
  }
  ASSERT_EQ(kept.size(), 36u);
  for (const int r : kept) {
    names.push_back(current["parameters"][static_cast<std::size_t>(r)]);
    nlohmann::json row = nlohmann::json::array();
    for (const int c : kept) {
      row.push_back(r == c ? 1e-12 * (1 + r) : (r + c == 14 ? 0.5e-12 : 0.0));
    }
    matrix.push_back(row);
  }
  const std::string path = temp_path("ten_per_limb.json");
  write_text(path,
             nlohmann::json{{"covariance", {{"parameters", names}, {"matrix", matrix}}}}.dump());
  const ParameterCovariance c = read_parameter_covariance(path, 3);
  ASSERT_EQ(c.names.size(), 39u);
  for (int k = 0; k < num_parameters(3); ++k) {
    EXPECT_EQ(c.names[static_cast<std::size_t>(k)], parameter_name(parameter_id(k, 3)));
    if (parameter_id(k, 3).kind == ParameterKind::kPrecurvature) {
      EXPECT_EQ(c.matrix.row(k).cwiseAbs().maxCoeff(), 0.0) << k;
      EXPECT_EQ(c.matrix.col(k).cwiseAbs().maxCoeff(), 0.0) << k;
    } else {
      EXPECT_EQ(c.matrix(k, k), 1e-12 * (1 + k)) << k;
    }
  }
  EXPECT_EQ(c.matrix(2, 12), 0.5e-12);
  EXPECT_EQ(c.matrix(12, 2), 0.5e-12);
}

TEST(ParameterCovariance, BadBlocksNameFileFieldAndValue) {
  const nlohmann::json good{{"covariance", valid_block()}};
  {
    const std::string path = temp_path("good.json");
    write_text(path, good.dump());
    const ParameterCovariance c = read_parameter_covariance(path, 3);
    EXPECT_EQ(c.matrix(2, 12), 0.5e-12);
  }
  expect_error("missing.json", nlohmann::json{{"table3", {}}}, {"covariance", "missing"});
  auto with = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json report = good;
    edit(report["covariance"]);
    return report;
  };
  expect_error("short_row.json", with([](nlohmann::json& b) { b["matrix"][4].erase(0); }),
               {"covariance.matrix[4]", "row of 39 numbers", "[0.0,0.0"});
  expect_error("rows.json", with([](nlohmann::json& b) { b["matrix"].erase(35); }),
               {"covariance.matrix", "38 rows for 39 parameters"});
  expect_error("name.json", with([](nlohmann::json& b) { b["parameters"][2] = "length[0]"; }),
               {"covariance.parameters[2]", "\"l[0]\"", "length[0]"});
  expect_error("limbs.json", good, {"covariance.parameters", "3 limbs", "has 4"}, 4);
  expect_error("text.json", with([](nlohmann::json& b) { b["matrix"][3][5] = "abc"; }),
               {"covariance.matrix[3][5]", "\"abc\""});
  expect_error("nan.json", with([](nlohmann::json& b) { b["matrix"][1][2] = nullptr; }),
               {"covariance.matrix[1][2]", "null", "d[0]", "l[0]"});
  expect_error("nan_row.json", with([](nlohmann::json& b) { b["matrix"][7][7] = nullptr; }),
               {"covariance.matrix[0][7]", "B_y[0]", "must be null"});
  expect_error("negative.json", with([](nlohmann::json& b) { b["matrix"][5][5] = -1e-12; }),
               {"covariance.matrix[5][5]", "-1e-12", "alpha[0]", "negative"});
  expect_error("asymmetric.json", with([](nlohmann::json& b) { b["matrix"][12][2] = 0.4e-12; }),
               {"covariance.matrix[2][12]", "5e-13", "4e-13", "not symmetric"});
  // Each pair correlated 0.9, 0.9 and -0.9: (1, -1, 1) has the eigenvalue -0.8.
  expect_error("not_psd.json", with([](nlohmann::json& b) {
                 const int k[3] = {2, 12, 22};  // l[0], l[1], l[2]
                 const double rho[3][3] = {{1, 0.9, -0.9}, {0.9, 1, 0.9}, {-0.9, 0.9, 1}};
                 for (int r = 0; r < 3; ++r) {
                   for (int c = 0; c < 3; ++c) b["matrix"][k[r]][k[c]] = rho[r][c] * 1e-12;
                 }
               }),
               {"covariance.matrix", "not positive semi-definite", "eigenvalue -0.", "l[0]"});
  expect_error("units.json", with([](nlohmann::json& b) { b["units"] = "um"; }),
               {"covariance.units", "\"um\""});
  EXPECT_THROW(read_parameter_covariance(temp_path("does_not_exist.json")), InputError);
}

}  // namespace
}  // namespace pcr
