// Sensitivity analysis (Table 2): exact implicit derivatives against central differences of FK,
// the zero rows (E, all diameters together), and the ranking for the default robot.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "pcr/calib/cost.hpp"
#include "pcr/calib/sensitivity.hpp"

namespace pcr {
namespace {

JointVector joints(double a, double b, double c) {
  JointVector q(3);
  q << a, b, c;
  return q;
}

/// Central differences of cold-start FK, relative step per kind.
Eigen::Vector3d central_difference(const RobotParams<double>& robot, const JointVector& q,
                                   const ParameterId& id, double h,
                                   const PlatformLoad<double>& load) {
  SolverOptions tight;
  tight.tolerance = 1e-14;
  RobotParams<double> plus = robot, minus = robot;
  parameter_ref(plus, id) += h;
  parameter_ref(minus, id) -= h;
  const ForwardSolution fp = forward_kinematics(plus, q, tight, load);
  const ForwardSolution fm = forward_kinematics(minus, q, tight, load);
  EXPECT_TRUE(fp.summary.converged() && fm.summary.converged());
  return Eigen::Vector3d(fp.pose.x - fm.pose.x, fp.pose.y - fm.pose.y,
                         fp.pose.theta - fm.pose.theta) /
         (2 * h);
}

/// Central-difference step: large enough that FK's rounding (~1e-15 m) stays below the relative
/// tolerance, small enough that the O(h^2) truncation does too.
double step_for(const RobotParams<double>& robot, const ParameterId& id) {
  switch (id.kind) {
    case ParameterKind::kYoungModulus:
      return 1e-4 * robot.limb(id.limb).rod.young_modulus;
    case ParameterKind::kDiameter:
      return 1e-4 * robot.limb(id.limb).rod.diameter;
    case ParameterKind::kAlpha:
    case ParameterKind::kBeta:
    case ParameterKind::kGamma:
      return 1e-4;  // rad
    case ParameterKind::kPrecurvature:
      return 1e-3;  // 1/m
    default:
      return 1e-6;  // m
  }
}

void cross_check(const PlatformLoad<double>& load) {
  const RobotParams<double> robot = femto_3pf();
  const double length = robot.limb(0).rod.length;
  const JointVector q = joints(2e-3, -1e-3, 3e-3);
  Eigen::MatrixXd J;
  ASSERT_TRUE(platform_parameter_jacobian(robot, q, &J, load));
  ASSERT_EQ(J.rows(), 3);
  ASSERT_EQ(J.cols(), 3 * kLimbParameters);
  for (int limb = 0; limb < 3; ++limb) {
    for (int k = 0; k < kLimbParameters; ++k) {
      const ParameterId id{static_cast<ParameterKind>(k), limb};
      const double h = step_for(robot, id);
      const Eigen::Vector3d fd = central_difference(robot, q, id, h, load);
      const Eigen::Vector3d exact = J.col(limb * kLimbParameters + k);
      // Relative 1e-6 of the column (theta as an arc length over one rod length), plus the
      // finite differences' own rounding floor, 1e-14 m / h.
      const double scale =
          std::max({std::abs(exact(0)), std::abs(exact(1)), length * std::abs(exact(2))});
      const double tol = 1e-6 * scale + 1e-14 / h;
      EXPECT_NEAR(exact(0), fd(0), tol) << parameter_name(id);
      EXPECT_NEAR(exact(1), fd(1), tol) << parameter_name(id);
      EXPECT_NEAR(exact(2), fd(2), tol / length) << parameter_name(id);
    }
  }
}

TEST(Sensitivity, ImplicitDerivativesMatchCentralDifferences) {
  cross_check(PlatformLoad<double>());
}

TEST(Sensitivity, ImplicitDerivativesMatchCentralDifferencesUnderLoad) {
  cross_check(PlatformLoad<double>{Vector2<double>(5e-3, -2e-3), 1e-5});
}

TEST(Sensitivity, GridIs26ConfigurationsAroundTheCentre) {
  const RobotParams<double> robot = femto_3pf();
  const std::vector<JointVector> grid = sensitivity_configurations(robot, 1e-3);
  ASSERT_EQ(grid.size(), 26u);
  for (std::size_t a = 0; a < grid.size(); ++a) {
    EXPECT_GT(grid[a].norm(), 0.5e-3);  // the centre (0, 0, 0) is left out
    EXPECT_LE(grid[a].cwiseAbs().maxCoeff(), 1e-3 + 1e-15);
    for (std::size_t b = a + 1; b < grid.size(); ++b) EXPECT_GT((grid[a] - grid[b]).norm(), 0.5e-3);
  }
  EXPECT_THROW(sensitivity_configurations(robot, 0.0), InputError);
}

const SensitivityRow& row(const SensitivityReport& report, const std::string& kind) {
  for (const SensitivityRow& r : report.rows) {
    if (r.kind == kind) return r;
  }
  ADD_FAILURE() << "no row " << kind;
  return report.rows.front();
}

TEST(Sensitivity, TableOfTheDefaultRobot) {
  const RobotDescription robot = default_robot();
  const SensitivityReport report = sensitivity_analysis(robot);
  ASSERT_EQ(report.configurations.size(), 26u);
  ASSERT_EQ(report.rows.size(), 11u);
  // Table 2, first two rows: E, and all diameters together, have no effect without a load (the
  // equilibrium only depends on EI ratios). Per-Pa and per-metre derivatives against the
  // length-scale ones.
  const SensitivityRow& e = row(report, "E");
  EXPECT_LT(std::max({e.dx, e.dy}) * 69e9, 1e-9);
  EXPECT_LT(e.dtheta * 69e9, 1e-7);
  const SensitivityRow& d_all = row(report, "D");
  const SensitivityRow& d = row(report, "d");
  EXPECT_LT(std::max(d_all.dx, d_all.dy), 1e-7 * std::max(d.dx, d.dy));
  EXPECT_LT(d_all.dtheta, 1e-7 * d.dtheta);
  EXPECT_GT(d.dx, 0.0);  // one diameter alone does matter
  // The orders of magnitude of the paper's Table 2 (its robot differs from ours in details).
  EXPECT_GT(row(report, "l").dx, 0.3);
  EXPECT_LT(row(report, "l").dx, 5.0);
  EXPECT_GT(row(report, "A_x").dx, 0.3);
  EXPECT_LT(row(report, "alpha").dx, 1e-2);
  // Ranking: l, A and B ahead of beta and gamma.
  auto rank = [&](const std::string& kind) {
    for (std::size_t k = 0; k < report.ranking.size(); ++k) {
      if (report.rows[static_cast<std::size_t>(report.ranking[k])].kind == kind)
        return static_cast<int>(k);
    }
    return -1;
  };
  for (const char* strong : {"l", "A_x", "A_y", "B_x", "B_y"}) {
    for (const char* weak : {"beta", "gamma"})
      EXPECT_LT(rank(strong), rank(weak)) << strong << " vs " << weak;
  }
  // The ranking's errors are sensitivity x half-width.
  const SensitivityRow& l = row(report, "l");
  EXPECT_NEAR(l.half_width, 126e-6, 1e-18);
  EXPECT_LE(l.position_error, std::hypot(l.dx, l.dy) * l.half_width * (1 + 1e-12));
  EXPECT_GE(l.position_error, std::max(l.dx, l.dy) * l.half_width * (1 - 1e-12));
  EXPECT_FALSE(sensitivity_table_text(report).empty());
}

// A kind the paper's table does not have is a row when the robot declares it uncertain: the
// precurvature of rods shape-set to arcs, its error the sensitivity times its half-width. A rod's
// u0 acts on the pose as a platform moment EI u0 would (docs/kinematics.md, "Pre-curved rods"):
// its column is EI times the load moment's, two derivations that share nothing but the solution.
TEST(Sensitivity, PrecurvatureIsARowWhenDeclaredUncertain) {
  RobotDescription robot = default_robot();
  for (int i = 0; i < 3; ++i) robot.params.limb(i).rod.precurvature = 10.0 * (i - 1);
  for (LimbUncertainty& limb : robot.uncertainty->limbs) limb.rod.precurvature = 2.0;
  const SensitivityReport report = sensitivity_analysis(robot);
  ASSERT_EQ(report.rows.size(), 12u);
  const SensitivityRow& u0 = row(report, "precurvature");
  EXPECT_EQ(u0.half_width, 2.0);
  EXPECT_GT(u0.dx, 0.0);
  EXPECT_LE(u0.position_error, std::hypot(u0.dx, u0.dy) * 2.0 * (1 + 1e-12));
  EXPECT_NE(sensitivity_table_text(report).find("precurvature"), std::string::npos);

  const RobotParams<double>& params = robot.params;
  const ForwardSolution fk = forward_kinematics(params, joints(2e-3, -1e-3, 3e-3));
  ASSERT_TRUE(fk.summary.converged());
  const int count = num_parameters(3);
  std::vector<double> J(static_cast<std::size_t>(3 * count));
  double by_load[9];
  ASSERT_TRUE(platform_pose_jacobian(params, PlatformLoad<double>(), fk, SolverOptions(), J.data(),
                                     by_load));
  for (int i = 0; i < 3; ++i) {
    const int k = parameter_index(ParameterId{ParameterKind::kPrecurvature, i}, 3);
    const double ei = params.limb(i).rod.bending_stiffness();
    for (int r = 0; r < 3; ++r) {
      const double moment = by_load[3 * r + 2];
      EXPECT_NEAR(J[static_cast<std::size_t>(r * count + k)], ei * moment,
                  1e-9 * std::abs(ei * moment))
          << "limb " << i << " row " << r;
    }
  }
  robot.uncertainty->limbs.assign(3, robot.uncertainty->global);  // not declared: no row
  EXPECT_EQ(sensitivity_analysis(robot).rows.size(), 11u);
}

TEST(Sensitivity, DiametersMatterUnderAnExternalLoad) {
  SensitivityOptions options;
  options.load = PlatformLoad<double>{Vector2<double>(5e-3, 0), 0};
  const SensitivityReport report = sensitivity_analysis(default_robot(), options);
  // A load on the platform is resisted by EI: scaling all diameters now moves the platform.
  EXPECT_GT(std::max(row(report, "D").dx, row(report, "D").dy), 1e-3);
  EXPECT_GT(row(report, "E").dx * 69e9, 1e-7);
}

}  // namespace
}  // namespace pcr
