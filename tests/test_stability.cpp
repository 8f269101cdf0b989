// The stability check of an equilibrium (pcr/stability.hpp) against independent references:
// Euler's clamped-clamped column, a cantilever's closed-form tip stiffness and its stability under
// any dead tip load, the platform stiffness by finite differences of re-solved rods, and the
// energy-based check (pcr::energy_stability) on both sides of a fold.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/reference.hpp"
#include "pcr/stability.hpp"
#include "random_robots.hpp"

namespace pcr {
namespace {

constexpr double kLength = 0.030;
constexpr double kDiameter = 125e-6;
constexpr double kYoung = 69e9;
const double kEi = bending_stiffness(kYoung, kDiameter);

/// One rod along x from the origin, its tip clamped to the platform's origin: a cantilever whose
/// free end is the platform.
RobotParams<double> one_rod() {
  RobotParams<double> robot;
  robot.num_limbs = 1;
  LimbParams<double>& limb = robot.limb(0);
  limb.rod.length = kLength;
  limb.rod.diameter = kDiameter;
  limb.rod.young_modulus = kYoung;
  return robot;
}

std::array<Wrench<double>, kMaxLimbs> wrench(double nx, double ny, double m) {
  std::array<Wrench<double>, kMaxLimbs> w{};
  w[0] = Wrench<double>{nx, ny, m};
  return w;
}

/// The rod's equilibrium with proximal wrench w, as the platform pose at its tip.
Pose2<double> tip_pose(const Wrench<double>& w, int steps) {
  const RobotParams<double> robot = one_rod();
  const RodState<double> tip =
      integrate_rod(proximal_rod_state(robot.limb(0), 0.0, w), robot.limb(0).rod, steps);
  return Pose2<double>{tip.x, tip.y, tip.theta};
}

// A straight column under an axial compression P, clamped at both ends: its first conjugate point
// lies at 2 pi sqrt(EI / P) (the Jacobi fields of EI dtheta'' + P dtheta = const vanishing at both
// ends with zero mean), inside the rod exactly when P exceeds Euler's 4 pi^2 EI / l^2.
TEST(Stability, ClampedClampedColumnHasItsConjugatePointAtEulersLength) {
  const double critical = 4 * M_PI * M_PI * kEi / (kLength * kLength);
  const int steps = 64;
  for (double ratio : {0.0, 0.5, 0.99, 0.998, 1.002, 1.01, 1.5, 3.0}) {
    const double p = ratio * critical;
    const auto w = wrench(-p, 0.0, 0.0);
    JointVector q = JointVector::Zero(1);
    const EquilibriumStability s =
        equilibrium_stability(one_rod(), q, tip_pose(w[0], steps), w, steps);
    if (ratio < 1) {
      EXPECT_EQ(s.conjugate_limb, -1) << ratio;
    } else {
      ASSERT_EQ(s.conjugate_limb, 0) << ratio;
      EXPECT_FALSE(s.stable) << ratio;
      const double expected = 2 * M_PI * std::sqrt(kEi / p);
      EXPECT_NEAR(s.conjugate_arc_length, expected, 2e-3 * kLength) << ratio;
    }
  }
}

// Unloaded, the cantilever's tip stiffness is the inverse of its closed-form compliance:
// dy = l^3 / (3 EI) F + l^2 / (2 EI) M, dtheta = l^2 / (2 EI) F + l / EI M, dx = l / EA F.
TEST(Stability, UnloadedCantileverHasTheClosedFormTipStiffness) {
  const RobotParams<double> robot = one_rod();
  const double ea = robot.limb(0).rod.axial_stiffness();
  Eigen::Matrix3d compliance;
  compliance << kLength / ea, 0, 0,                                        //
      0, std::pow(kLength, 3) / (3 * kEi), kLength * kLength / (2 * kEi),  //
      0, kLength * kLength / (2 * kEi), kLength / kEi;
  const ShootingScale scale = shooting_scale(robot);
  // Scaled: pose (x / L, y / L, theta), wrench (n / F, m / (F L)).
  const Eigen::Vector3d pose_scale(1 / scale.length, 1 / scale.length, 1);
  const Eigen::Vector3d wrench_scale(scale.force, scale.force, scale.moment());
  const Eigen::Matrix3d expected =
      (pose_scale.asDiagonal() * compliance * wrench_scale.asDiagonal()).inverse();
  const auto w = wrench(0, 0, 0);
  const EquilibriumStability s =
      equilibrium_stability(robot, JointVector::Zero(1), tip_pose(w[0], 32), w, 32);
  ASSERT_TRUE(s.stable);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(s.stiffness(r, c), expected(r, c), 1e-6 * expected.norm()) << r << " " << c;
    }
  }
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(expected).eigenvalues()(0);
  EXPECT_NEAR(s.margin, smallest, 1e-5 * smallest);
}

// A cantilever loaded from straight by a dead tip force, in steps (each solved by Newton on the
// proximal moment so that the tip carries no moment): every equilibrium on the way is stable, as
// the energy check finds too, however far the rod bends.
TEST(Stability, CantileverUnderADeadTipLoadIsStable) {
  const RobotParams<double> robot = one_rod();
  const int steps = 48;
  const double unit = kEi / (kLength * kLength);
  for (double direction : {-M_PI / 2, -3 * M_PI / 4, 0.9 * M_PI}) {
    double m0 = 0;
    for (double load = 0.25; load <= 8.0; load += 0.25) {
      const double nx = load * unit * std::cos(direction), ny = load * unit * std::sin(direction);
      for (int it = 0; it < 30; ++it) {  // m(l) = 0 by Newton on m(0)
        const RodTip<double> tip = integrate_rod_with_sensitivity(
            proximal_rod_state(robot.limb(0), 0.0, Wrench<double>{nx, ny, m0}), robot.limb(0).rod,
            steps);
        m0 -= tip.state.m / tip.sensitivity(3, 2);
        if (std::abs(tip.state.m) < 1e-14 * unit * kLength) break;
      }
      const auto w = wrench(nx, ny, m0);
      const Pose2<double> pose = tip_pose(w[0], steps);
      const EquilibriumStability s =
          equilibrium_stability(robot, JointVector::Zero(1), pose, w, steps);
      EXPECT_TRUE(s.stable) << direction << " " << load << " margin " << s.margin;
      EXPECT_GT(s.margin, 0) << direction << " " << load;
      if (std::fmod(load, 2.0) == 0) {
        EnergyProblem problem;
        problem.rods.push_back({Vector2<double>(0, 0), 0, Vector2<double>(0, 0), 0, kLength, kEi});
        problem.load.force = Vector2<double>(nx, ny);  // the platform's equilibrium: n(l) = load
        JointVector q = JointVector::Zero(1);
        const EnergyStability e = energy_stability(problem, energy_start(robot, q, pose, w, 100));
        ASSERT_TRUE(e.converged) << direction << " " << load;
        EXPECT_LT(std::hypot(e.state.pose.x - pose.x, e.state.pose.y - pose.y), 1e-4 * kLength);
        EXPECT_GT(e.min_eigenvalue, 0) << direction << " " << load;
      }
    }
  }
}

// Pushed straight along its axis, the cantilever stays straight, and loses its stability at the
// free-standing column's Euler load pi^2 EI / (4 l^2): the platform's stiffness, not a conjugate
// point (that of the clamped-clamped column comes at 16 times the load).
TEST(Stability, StraightCantileverBucklesAtTheFreeColumnsEulerLoad) {
  const RobotParams<double> robot = one_rod();
  const double critical = M_PI * M_PI * kEi / (4 * kLength * kLength);
  double previous = HUGE_VAL;
  for (double ratio : {0.0, 0.5, 0.99, 0.999, 1.001, 1.01, 2.0, 8.0}) {
    const auto w = wrench(-ratio * critical, 0, 0);
    const EquilibriumStability s =
        equilibrium_stability(robot, JointVector::Zero(1), tip_pose(w[0], 64), w, 64);
    EXPECT_EQ(s.stable, ratio < 1) << ratio << " margin " << s.margin;
    EXPECT_EQ(s.conjugate_limb, -1) << ratio;
    if (ratio > 0 && ratio < 1) {
      EXPECT_LT(s.margin, previous) << ratio;  // compression softens it
    }
    previous = s.margin;
  }
}

/// The platform's scaled stiffness by central differences: move the pose, re-solve every rod's
/// proximal wrench so that it meets its clamp again (Newton on its 3 closure equations), and
/// difference the equilibrium residual. The inextensible model: equal to the check's stiffness
/// up to the rods' axial compliance, O((d / l)^2) for bent rods.
Eigen::Matrix3d stiffness_by_differences(const RobotParams<double>& robot,
                                         const ShootingPoint<double>& solved, int steps) {
  const ShootingScale scale = shooting_scale(robot);
  const int n = robot.num_limbs;
  const auto equilibrium_at = [&](const Pose2<double>& pose) {
    ShootingPoint<double> p = solved;
    p.pose = pose;
    ResidualVector<double> r;
    ShootingMatrix partials;
    for (int it = 0; it < 20; ++it) {
      shooting_residual(robot, p, PlatformLoad<double>(), scale, steps, r, &partials);
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d dw =
            partials.block<3, 3>(3 * i, 3 * i).lu().solve(-r.segment<3>(3 * i));
        p.wrenches[i].nx += dw(0) * scale.force;
        p.wrenches[i].ny += dw(1) * scale.force;
        p.wrenches[i].m += dw(2) * scale.moment();
      }
    }
    shooting_residual(robot, p, PlatformLoad<double>(), scale, steps, r);
    return Eigen::Vector3d(r.tail<3>());
  };
  // Nearly straight inextensible rods make the stiffness a steep function of the pose: a small
  // step (the residual's rounding is ~1e-14 of its differences then).
  const double h = 1e-7;
  Eigen::Matrix3d k;
  for (int j = 0; j < 3; ++j) {
    Pose2<double> plus = solved.pose, minus = solved.pose;
    const double step = j < 2 ? h * scale.length : h;
    double* plus_c[3] = {&plus.x, &plus.y, &plus.theta};
    double* minus_c[3] = {&minus.x, &minus.y, &minus.theta};
    *plus_c[j] += step;
    *minus_c[j] -= step;
    k.col(j) = (equilibrium_at(plus) - equilibrium_at(minus)) / (2 * h);
  }
  return k;
}

// Random robots in the paper's intervals, 2 to 5 limbs, at random joints: the check's stiffness
// matches the re-solved rods' finite differences, is symmetric (as the Hessian of an energy must
// be: nothing in its construction makes it so), and its verdict matches the energy check's.
TEST(Stability, RandomRobotsAgreeWithDifferencesAndTheEnergy) {
  std::mt19937_64 rng(20261126);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0, differenced = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const int n = 2 + trial % 4;
    const RobotParams<double> robot = testing::perturbed(testing::regular_robot(n), rng);
    JointVector q(n);
    // The redundant robots are pre-stressed: their stroke's corners are past 1 % strain.
    const double amplitude = n <= 3 ? 0.005 : 0.003;
    for (int i = 0; i < n; ++i) q(i) = amplitude * u(rng);
    const ForwardSolution fk = forward_kinematics(robot, q);
    if (!fk.summary.converged()) {
      ADD_FAILURE() << trial << " " << to_string(fk.summary.status);
      continue;
    }
    ++checked;
    const int steps = fk.summary.rod_steps;
    const EquilibriumStability s = equilibrium_stability(robot, fk.q, fk.pose, fk.wrenches, steps);
    const EquilibriumStability inextensible =
        internal::equilibrium_stability(robot, fk.q, fk.pose, fk.wrenches, steps, false);
    const ShootingPoint<double> point = internal::shooting_point(robot, fk);
    // A straight inextensible rod has no finite stiffness to difference (the re-solve of its
    // wrench is singular): the difference is then compared on the other configurations.
    const Eigen::Matrix3d k = stiffness_by_differences(robot, point, steps);
    if (k.allFinite()) {
      ++differenced;
      const double size = k.norm();
      EXPECT_LT((k - k.transpose()).norm(), 1e-4 * size) << trial;
      EXPECT_LT((inextensible.stiffness - k).norm(), 1e-4 * size) << trial;
      EXPECT_EQ(inextensible.stable, s.stable) << trial;
      // The singularity measure against the forward Jacobian's rcond from its inverse by a
      // pivoted LU of the whole matrix (the check's comes from its 3 x 3 blocks).
      ResidualVector<double> r;
      ShootingMatrix partials;
      shooting_residual(robot, point, PlatformLoad<double>(), shooting_scale(robot), steps, r,
                        &partials);
      const Eigen::MatrixXd forward = partials.leftCols(3 * n + 3);
      const auto norm1 = [](const Eigen::MatrixXd& m) {
        return m.cwiseAbs().colwise().sum().maxCoeff();
      };
      const double rcond =
          1.0 / (norm1(forward) * norm1(Eigen::FullPivLU<Eigen::MatrixXd>(forward).inverse()));
      EXPECT_NEAR(inextensible.singularity, rcond, 1e-6 * rcond) << trial;
    }
    EXPECT_GT(s.singularity, 0) << trial;
    const EnergyStability e = energy_stability(
        energy_problem(robot, fk.q), energy_start(robot, fk.q, fk.pose, fk.wrenches, 100));
    ASSERT_TRUE(e.converged) << trial;
    EXPECT_EQ(s.stable, e.min_eigenvalue > 0)
        << trial << " margin " << s.margin << " energy " << e.min_eigenvalue;
  }
  EXPECT_EQ(checked, 24);
  EXPECT_GE(differenced, 18);
}

// The solvers check a solution at half its RK4 steps (stability_rod_steps): on random robots at
// random joints, the verdict is that of a fine integration (four times the solution's steps), and
// the margin within 1e-4 of it where the platform's softest direction bends the rods (margins
// below 10^3, where stability can be lost), within 10 % where it stretches them (margins of 10^4
// to 10^6, set by the rods' axial stiffness: a difference of nearly equal bending terms).
TEST(Stability, CheckAtHalfTheStepsAgreesWithAFineIntegration) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int soft = 0, stiff = 0;
  for (int trial = 0; trial < 80; ++trial) {
    const int n = 2 + trial % 4;
    const RobotParams<double> robot = testing::perturbed(testing::regular_robot(n), rng);
    JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = 0.004 * u(rng);
    const ForwardSolution fk = forward_kinematics(robot, q);
    if (!fk.summary.converged()) continue;
    const int steps = fk.summary.rod_steps;
    const EquilibriumStability fine =
        equilibrium_stability(robot, fk.q, fk.pose, fk.wrenches, 4 * steps);
    EXPECT_EQ(fk.summary.stability == Stability::kStable, fine.stable) << trial;
    const double margin = std::abs(fine.margin);
    if (margin < 1e3) {
      ++soft;
      EXPECT_NEAR(fk.summary.stability_margin, fine.margin, 1e-4 * margin) << trial;
    } else {
      ++stiff;
      EXPECT_NEAR(fk.summary.stability_margin, fine.margin, 0.1 * margin) << trial;
    }
    EXPECT_NEAR(fk.summary.singularity, fine.singularity, 0.1 * fine.singularity) << trial;
  }
  EXPECT_GE(soft, 20);
  EXPECT_GE(stiff, 20);
}

// The default robot at home: straight rods, stable, and stiff (the rods' axial stiffness holds
// the platform).
TEST(Stability, DefaultRobotIsStableAtHome) {
  const RobotParams<double> robot = femto_3pf();
  const ForwardSolution home = home_solution(robot);
  ASSERT_TRUE(home.summary.converged());
  const EquilibriumStability s =
      equilibrium_stability(robot, home.q, home.pose, home.wrenches, home.summary.rod_steps);
  EXPECT_TRUE(s.stable);
  EXPECT_GT(s.margin, 1e3);
  EXPECT_GT(s.singularity, 0);
}

RobotParams<double> longer_stroke_robot() {
  RobotParams<double> robot = femto_3pf();
  for (int i = 0; i < 3; ++i) {
    robot.limb(i).q_min = -0.030;
    robot.limb(i).q_max = 0.030;
  }
  return robot;
}

double energy_eigenvalue(const RobotParams<double>& robot, const InverseSolution& ik) {
  const EnergyStability e = energy_stability(energy_problem(robot, ik.q),
                                             energy_start(robot, ik.q, ik.pose, ik.wrenches, 100));
  EXPECT_TRUE(e.converged);
  EXPECT_LT(std::hypot(e.state.pose.x - ik.pose.x, e.state.pose.y - ik.pose.y), 1e-5);
  return e.min_eigenvalue;
}

// The default robot with a 60 mm stroke, its platform moved along a line at theta = 0 (75 degrees
// from the x axis) by warm-started IK left on its branch: past about 22.78 mm rod 0, compressed
// along its axis, exceeds its clamped-clamped Euler load. The flag agrees with the energy on both
// sides, and the margin falls to zero as the fold nears.
TEST(Stability, FlagAgreesWithTheEnergyOnBothSidesOfAFold) {
  const RobotParams<double> robot = longer_stroke_robot();
  SolverOptions options;
  options.stable_inverse = false;
  InverseSequence sequence(robot, options, PlatformLoad<double>(), SequenceMode::kPath);
  const double direction = 75 * M_PI / 180;
  double margin_before = HUGE_VAL;
  for (int k = 0; k <= 250; ++k) {
    const double t = k * 1e-4;
    const InverseSolution& ik =
        sequence.solve({t * std::cos(direction), t * std::sin(direction), 0.0});
    ASSERT_TRUE(ik.summary.converged()) << t;
    ASSERT_NE(ik.summary.stability, Stability::kUnchecked);
    if (k == 200 || k == 220 || k == 226) {
      EXPECT_EQ(ik.summary.stability, Stability::kStable) << t;
      EXPECT_LT(ik.summary.stability_margin, margin_before) << t;
      margin_before = ik.summary.stability_margin;
      EXPECT_GT(energy_eigenvalue(robot, ik), 0) << t;
    }
    if (k == 230 || k == 240 || k == 250) {
      EXPECT_EQ(ik.summary.stability, Stability::kUnstable) << t;
      EXPECT_LT(ik.summary.stability_margin, 0) << t;
      EXPECT_LT(energy_eigenvalue(robot, ik), 0) << t;
    }
  }
}

// The same line with the default options: where the branch IK follows turns unstable, IK finds the
// stable equilibrium at the same pose (rod 0 buckled to one side, its joint ~10 mm further on),
// which the energy confirms; cold IK finds it too.
TEST(Stability, InverseKinematicsReturnsAStableEquilibrium) {
  const RobotParams<double> robot = longer_stroke_robot();
  InverseSequence sequence(robot, SolverOptions(), PlatformLoad<double>(), SequenceMode::kPath);
  SolverOptions unchecked;
  unchecked.stable_inverse = false;
  InverseSequence branch(robot, unchecked, PlatformLoad<double>(), SequenceMode::kPath);
  const double direction = 75 * M_PI / 180;
  for (int k = 0; k <= 250; ++k) {
    const double t = k * 1e-4;
    const Pose2<double> pose{t * std::cos(direction), t * std::sin(direction), 0.0};
    const InverseSolution& ik = sequence.solve(pose);
    const InverseSolution& unstable = branch.solve(pose);
    ASSERT_TRUE(usable_as_warm_start(ik.summary)) << t << " " << to_string(ik.summary.status);
    EXPECT_EQ(ik.summary.stability, Stability::kStable) << t;
    EXPECT_NEAR(ik.pose.x, pose.x, 1e-15);
    EXPECT_NEAR(ik.pose.y, pose.y, 1e-15);
    if (k == 235 || k == 250) {
      EXPECT_GT(energy_eigenvalue(robot, ik), 0) << t;
      ASSERT_EQ(unstable.summary.stability, Stability::kUnstable) << t;
      EXPECT_GT((ik.q - unstable.q).norm(), 1e-3) << t;
    }
  }
  const Pose2<double> far{0.025 * std::cos(direction), 0.025 * std::sin(direction), 0.0};
  const InverseSolution cold = inverse_kinematics(robot, far);
  EXPECT_EQ(cold.summary.stability, Stability::kStable);
  EXPECT_EQ(cold.summary.status, SolveStatus::kOutOfRange);  // q0 = 35 mm: past the stroke
  EXPECT_GT(energy_eigenvalue(robot, cold), 0);
}

// Forward kinematics through the fold above by pseudo-arclength continuation: from a stable
// equilibrium next to the fold, along the joints' direction that leaves the forward problem
// without a solution (the fold's left null vector mapped to the joints), the curve turns back at
// the fold. The flag agrees with the energy check at every point traced, on both sides.
TEST(Stability, FlagAgreesWithTheEnergyThroughAFoldTracedByArclength) {
  const RobotParams<double> robot = longer_stroke_robot();
  SolverOptions options;
  options.stable_inverse = false;
  InverseSequence sequence(robot, options, PlatformLoad<double>(), SequenceMode::kPath);
  const double direction = 75 * M_PI / 180;
  InverseSolution near_fold;
  for (int k = 0; k <= 2276; ++k) {  // 10 um steps to 22.76 mm
    const double t = k * 1e-5;
    near_fold = sequence.solve({t * std::cos(direction), t * std::sin(direction), 0.0});
    ASSERT_TRUE(near_fold.summary.converged()) << t;
  }
  ASSERT_EQ(near_fold.summary.stability, Stability::kStable);
  const ShootingPoint<double> point = internal::shooting_point(robot, near_fold);
  ResidualVector<double> r;
  ShootingMatrix partials;
  shooting_residual(robot, point, PlatformLoad<double>(), shooting_scale(robot),
                    near_fold.summary.rod_steps, r, &partials);
  const Eigen::MatrixXd forward = partials.leftCols(12);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(forward, Eigen::ComputeFullU);
  Eigen::Vector3d across = partials.middleCols(12, 3).transpose() * svd.matrixU().col(11);
  across.normalize();
  const ForwardSolution warm = as_forward_solution(near_fold);
  // The side of the fold with solutions is where FK converges.
  const double h = 2e-4;
  const double side =
      forward_kinematics(robot, JointVector(near_fold.q + h * across), warm).summary.converged()
          ? 1.0
          : -1.0;
  const ForwardSolution start =
      forward_kinematics(robot, JointVector(near_fold.q + side * h * across), warm);
  ASSERT_TRUE(start.summary.converged());
  const JointVector beyond = near_fold.q - side * h * across;
  // The energy check is a reference where it finds the same equilibrium (within 10 um; next to
  // the fold its own discrete fold, O(1 / N^2) away, can make it fail or change branch).
  int stable = 0, unstable = 0, compared_stable = 0, compared_unstable = 0;
  // The singularity measure and the forward Jacobian's own sigma_min / sigma_max (SVD) along the
  // trace: both least at the same point, the one nearest the fold.
  std::vector<double> singularity, singular_value_ratio;
  const ForwardSolution traced = forward_kinematics_through_folds(
      robot, beyond, start, SolverOptions(), PlatformLoad<double>(), [&](const ForwardSolution& p) {
        ASSERT_NE(p.summary.stability, Stability::kUnchecked);
        (p.summary.stability == Stability::kStable ? stable : unstable) += 1;
        ResidualVector<double> rp;
        ShootingMatrix jp;
        shooting_residual(robot, internal::shooting_point(robot, p), PlatformLoad<double>(),
                          shooting_scale(robot), p.summary.rod_steps, rp, &jp);
        const Eigen::VectorXd sv =
            Eigen::JacobiSVD<Eigen::MatrixXd>(jp.leftCols(12)).singularValues();
        singularity.push_back(p.summary.singularity);
        singular_value_ratio.push_back(sv(11) / sv(0));
        const EnergyStability e = energy_stability(
            energy_problem(robot, p.q), energy_start(robot, p.q, p.pose, p.wrenches, 100));
        if (!e.converged ||
            std::hypot(e.state.pose.x - p.pose.x, e.state.pose.y - p.pose.y) > 1e-5) {
          return;
        }
        (p.summary.stability == Stability::kStable ? compared_stable : compared_unstable) += 1;
        EXPECT_EQ(p.summary.stability == Stability::kStable, e.min_eigenvalue > 0)
            << p.summary.path_fraction << " margin " << p.summary.stability_margin << " energy "
            << e.min_eigenvalue;
      });
  EXPECT_GE(traced.summary.folds_passed, 1);
  EXPECT_GT(traced.summary.first_fold, 0.0);
  EXPECT_LT(traced.summary.first_fold, 1.0);
  EXPECT_GE(stable, 2);
  EXPECT_GE(unstable, 1);
  EXPECT_GE(compared_stable, 2);
  EXPECT_GE(compared_unstable, 1);
  const auto least = [](const std::vector<double>& v) {
    return std::min_element(v.begin(), v.end()) - v.begin();
  };
  ASSERT_GE(singularity.size(), 3u);
  EXPECT_EQ(least(singularity), least(singular_value_ratio));
  EXPECT_LT(*std::min_element(singularity.begin(), singularity.end()),
            0.1 * *std::max_element(singularity.begin(), singularity.end()));
}

}  // namespace
}  // namespace pcr
