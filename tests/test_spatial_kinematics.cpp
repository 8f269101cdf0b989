// Forward kinematics of spatial parallel continuum robots (pcr/spatial/kinematics.hpp) against
// independent references: the symmetry of the reference Stewart-Gough robot, a forward kinematics
// whose rods are integrated by CVODE (pcr::integrate_spatial_rod_reference) and whose Newton
// steps use central-difference Jacobians, the platform's balance recomputed from CVODE rods,
// central differences of the residual, and the planar core's FK (pcr::forward_kinematics).

// Eigen asserts on any heap allocation while set_is_malloc_allowed(false), in builds with
// assertions (SolvesNeverAllocate; operator new is counted in every build).
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "allocation_counter.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/reference.hpp"
#include "pcr/robot.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/robot.hpp"
#include "spatial_test_support.hpp"

namespace pcr {
namespace {

using namespace pcr::testing;  // spatial_test_support.hpp

SpatialRobotParams<double> without_gravity(SpatialRobotParams<double> robot) {
  robot.gravity.setZero();
  return robot;
}

// ---- The model
// -----------------------------------------------------------------------------------

TEST(SpatialRobot, ReferenceRobotLayout) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  ASSERT_EQ(robot.num_rods, 6);
  for (int i = 0; i < 6; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    EXPECT_NEAR(limb.A.norm(), 0.087, 1e-15);
    EXPECT_NEAR(limb.B.norm(), 0.087, 1e-15);
    EXPECT_EQ(limb.A.z(), 0.0);
    // Each rod meets the platform 40 degrees round from its base hole.
    const double turn = std::acos(limb.A.dot(limb.B) / (0.087 * 0.087));
    EXPECT_NEAR(turn, 40.0 * M_PI / 180.0, 1e-12);
    EXPECT_NEAR(limb.rod.bending_stiffness(), 200e9 * M_PI * std::pow(2e-3, 4) / 64, 1e-12);
  }
  // The published pattern: a pair's holes 20 degrees apart in the base, 100 in the platform.
  EXPECT_NEAR(std::acos(robot.limb(0).A.dot(robot.limb(1).A) / (0.087 * 0.087)),
              20.0 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR(std::acos(robot.limb(0).B.dot(robot.limb(1).B) / (0.087 * 0.087)),
              100.0 * M_PI / 180.0, 1e-12);
}

TEST(SpatialKinematics, QuaternionExpMatchesEigen) {
  for (const Vector3d& v : {Vector3d(0.3, -0.2, 1.1), Vector3d(1e-7, 2e-7, -3e-8),
                            Vector3d(0, 0, 0), Vector3d(-2.5, 0.1, 0.4)}) {
    const Vector4d h = quaternion_exp<double>(v);
    const Eigen::Quaterniond expected =
        v.norm() > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(v.norm(), v.normalized()))
                     : Eigen::Quaterniond::Identity();
    EXPECT_LT(
        std::min((h - Vector4d(expected.w(), expected.x(), expected.y(), expected.z())).norm(),
                 (h + Vector4d(expected.w(), expected.x(), expected.y(), expected.z())).norm()),
        1e-15);
  }
}

// ---- Symmetry -----------------------------------------------------------------------------------

TEST(SpatialKinematics, SymmetricRobotStaysOnItsAxis) {
  // Turns of 120 degrees about z and the mirror y -> -y map the robot onto itself, gravity along
  // -z included: the platform stays on the z axis, untilted and unturned, and all six rods are
  // loaded alike (without gravity, by nothing: six equal forces summing to zero).
  SolverOptions options;
  options.chord_output_share = 0;  // every solve to the tolerance
  for (const SpatialRobotParams<double>& robot :
       {continuum_stewart_gough(), without_gravity(continuum_stewart_gough())})
    for (double q : {0.0, 0.012, -0.015}) {
      const SpatialForwardSolution fk =
          spatial_forward_kinematics(robot, equal_joints(6, q), options);
      ASSERT_TRUE(fk.summary.converged()) << to_string(fk.summary.status);
      const double tilt = angle_between(fk.pose.orientation, identity_quaternion<double>());
      EXPECT_LT(std::abs(fk.pose.position.x()), 1e-12);
      EXPECT_LT(std::abs(fk.pose.position.y()), 1e-12);
      EXPECT_LT(tilt, 1e-12);
      // The same axial force n(0) . d3(0) in every rod (d3 = e3 at the base).
      double low = 1e300, high = -1e300;
      for (int i = 0; i < 6; ++i) {
        low = std::min(low, fk.wrenches[i].force.z());
        high = std::max(high, fk.wrenches[i].force.z());
      }
      EXPECT_LT(high - low, 1e-12 * spatial_shooting_scale(robot).force);
      if (robot.gravity.isZero()) {
        EXPECT_LT(std::abs(high), 1e-12 * spatial_shooting_scale(robot).force);
      } else {
        // Vertical balance: each rod pushes its hole down (n(0) is what the rod exerts there) by
        // a sixth of the platform's weight and its own weight.
        const SpatialRod<double>& rod = robot.limb(0).rod;
        const double weight =
            robot.platform_mass * 9.81 / 6 + rod.mass_per_length() * (rod.length + q) * 9.81;
        EXPECT_NEAR(high, -weight, 1e-12 * weight);
      }
      std::printf(
          "gravity %s, q %+.3f: height %.9f m, off axis %.1e m, tilt %.1e rad, axial force %.6e N "
          "(spread %.1e), %d evaluations\n",
          robot.gravity.isZero() ? "off" : "on", q, fk.pose.position.z(),
          fk.pose.position.head<2>().norm(), tilt, high, high - low,
          fk.summary.residual_evaluations);
    }
}

// ---- Jacobian -----------------------------------------------------------------------------------
TEST(SpatialKinematics, JacobianMatchesCentralDifferences) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 3 + trial % 4;
    const SpatialRobotParams<double> robot =
        trial == 0 ? continuum_stewart_gough() : mixed_robot(rng, n);
    const int m = 6 * robot.num_rods + 6;
    SpatialJointVector q(robot.num_rods);
    for (int i = 0; i < robot.num_rods; ++i) q(i) = 0.02 * u(rng);
    // A point near, not at, an equilibrium: loaded rods, a turned platform.
    Point x = straight_rods_guess(robot, q);
    const ShootingScale scale = spatial_shooting_scale(robot);
    for (int i = 0; i < robot.num_rods; ++i) {
      x.wrenches[i].force = scale.force * Vector3d(u(rng), u(rng), u(rng));
      x.wrenches[i].moment = scale.moment() * Vector3d(u(rng), u(rng), u(rng));
    }
    x.pose.orientation = quaternion_product<double>(
        x.pose.orientation, quaternion_exp<double>(Vector3d(0.2 * u(rng), 0.2 * u(rng), u(rng))));
    constexpr int kSteps = 64;
    SpatialResidualVector<double> r;
    SpatialJacobian J;
    spatial_residual(robot, x, scale, kSteps, r, &J);
    const internal::SpatialForwardProblem problem(robot, kSteps);
    const double h = 1e-6;
    for (int k = 0; k < m; ++k) {
      SpatialResidualVector<double> plus, minus;
      spatial_residual(robot, problem.retract(x, h * SpatialVector::Unit(m, k)), scale, kSteps,
                       plus);
      spatial_residual(robot, problem.retract(x, -h * SpatialVector::Unit(m, k)), scale, kSteps,
                       minus);
      const Eigen::VectorXd numeric = (plus - minus) / (2 * h);
      const double column_scale = std::max(1.0, numeric.lpNorm<Eigen::Infinity>());
      const double error = (J.col(k) - numeric).lpNorm<Eigen::Infinity>() / column_scale;
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-7) << "trial " << trial << " column " << k;
    }
  }
  std::printf("Jacobian vs central differences: worst column error %.2e (of max(1, |column|))\n",
              worst);
}

TEST(SpatialKinematics, TipGrowthMatchesCentralDifferences) {
  // The predictor's d r / d q: for a rod pushed through its hole, the rod's right-hand side at
  // its tip (the exact model's derivative), for a translated clamp the actuator direction.
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const SpatialRobotParams<double> robot = mixed_robot(rng, 4);
  const ShootingScale scale = spatial_shooting_scale(robot);
  SpatialJointVector q = SpatialJointVector::Constant(4, 0.01);
  Point x = straight_rods_guess(robot, q);
  for (int i = 0; i < 4; ++i) {
    x.wrenches[i].force = scale.force * Vector3d(u(rng), u(rng), u(rng));
    x.wrenches[i].moment = scale.moment() * Vector3d(u(rng), u(rng), u(rng));
  }
  const internal::SpatialForwardProblem problem(robot, 256);
  SpatialVector r;
  problem.evaluate(x, r, nullptr);
  const SpatialInputJacobian D = problem.input_jacobian(x);
  for (int i = 0; i < 4; ++i) {
    const double h = 1e-5;
    Point plus = x, minus = x;
    plus.q[i] += h;
    minus.q[i] -= h;
    SpatialVector rp, rm;
    problem.evaluate(plus, rp, nullptr);
    problem.evaluate(minus, rm, nullptr);
    const Eigen::VectorXd numeric = (rp - rm) / (2 * h);
    EXPECT_LT((D.col(i) - numeric).lpNorm<Eigen::Infinity>(),
              1e-6 * std::max(1.0, numeric.lpNorm<Eigen::Infinity>()))
        << "rod " << i;
  }
}

// ---- Against the CVODE reference ----------------------------------------------------------------

TEST(SpatialKinematics, ReferenceRobotMatchesCvode) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const double q_level = joint_for_height(robot, 0.4);
  std::printf("equal joints %.9f m (free length %.9f m) hold the platform 0.4 m up\n", q_level,
              0.4 + q_level);
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::vector<int> step_counts = {16, 32, 64, 128, 256};
  std::vector<PoseError> worst(step_counts.size());
  for (int trial = 0; trial < 6; ++trial) {
    SpatialJointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = q_level + 0.02 * u(rng);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q);
    ASSERT_TRUE(fk.summary.converged()) << to_string(fk.summary.status);
    Point start;
    start.pose = fk.pose;
    for (int i = 0; i < 6; ++i) {
      start.q[i] = q(i);
      start.wrenches[i] = fk.wrenches[i];
    }
    const ReferenceFk reference = reference_forward_kinematics(robot, start);
    ASSERT_LT(reference.residual, 1e-11) << "trial " << trial;
    SpatialPose<double> exact = reference.x.pose;
    for (std::size_t k = 0; k < step_counts.size(); ++k) {
      SolverOptions options;
      options.rod_steps = step_counts[k];
      const SpatialForwardSolution at = spatial_forward_kinematics(robot, q, fk, options);
      ASSERT_TRUE(at.summary.converged());
      const PoseError e = pose_error(at.pose, exact);
      worst[k].position = std::max(worst[k].position, e.position);
      worst[k].angle = std::max(worst[k].angle, e.angle);
    }
    const PoseError e = pose_error(fk.pose, exact);
    EXPECT_LT(e.position, 1e-9) << "trial " << trial;
    EXPECT_LT(e.angle, 1e-6) << "trial " << trial;
    std::printf(
        "trial %d: tilt %.3f rad, default FK %d evaluations, error %.2e m %.2e rad "
        "(CVODE FK residual %.1e after %d iterations)\n",
        trial, angle_between(fk.pose.orientation, identity_quaternion<double>()),
        fk.summary.residual_evaluations, e.position, e.angle, reference.residual,
        reference.iterations);
  }
  for (std::size_t k = 0; k < step_counts.size(); ++k) {
    std::printf("%4d RK4 steps per rod: worst pose error %.2e m, %.2e rad\n", step_counts[k],
                worst[k].position, worst[k].angle);
  }
}

/// The balance of the platform recomputed from the solved proximal wrenches with every rod
/// integrated by CVODE, written out here (not spatial_residual_from_tips): the rods exert
/// -n(L), -m(L) at their tips.
void expect_platform_balanced(const SpatialRobotParams<double>& robot,
                              const SpatialForwardSolution& fk, double& worst_force,
                              double& worst_moment) {
  const Matrix3d R = eigen_quaternion(fk.pose.orientation).toRotationMatrix();
  const Vector3d weight = robot.platform_mass * robot.gravity;
  Vector3d force = weight + robot.external_force;
  Vector3d moment = (R * robot.platform_centre_of_mass).cross(weight) + robot.external_moment;
  double force_scale = weight.norm() + robot.external_force.norm();
  for (int i = 0; i < robot.num_rods; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    SpatialRodState<double> base;
    base.position = limb.proximal_position(fk.q(i));
    base.orientation = limb.base_orientation;
    base.force = fk.wrenches[i].force;
    base.moment = fk.wrenches[i].moment;
    const SpatialRodState<double> tip =
        integrate_spatial_rod_reference(base, limb.rod_at(fk.q(i)), robot.gravity);
    force -= tip.force;
    moment -= (tip.position - fk.pose.position).cross(tip.force) + tip.moment;
    force_scale = std::max(force_scale, tip.force.norm());
  }
  const double length = spatial_shooting_scale(robot).length;
  worst_force = std::max(worst_force, force.norm() / force_scale);
  worst_moment = std::max(worst_moment, moment.norm() / (force_scale * length));
  EXPECT_LT(force.norm(), 1e-9 * force_scale);
  EXPECT_LT(moment.norm(), 1e-9 * force_scale * length);
}

TEST(SpatialKinematics, PlatformBalancesOnCvodeRods) {
  // At 512 RK4 steps, solved to the tolerance: the rods' own discretisation error (their tip
  // moments within about 5e-10 EI / L of CVODE's at 256 steps) then stays below the 1e-9 checked.
  SolverOptions options;
  options.rod_steps = 512;
  options.chord_output_share = 0;
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_force = 0, worst_moment = 0;
  for (int trial = 0; trial < 6; ++trial) {
    SpatialJointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = 0.01 + 0.02 * u(rng);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q, options);
    ASSERT_TRUE(fk.summary.converged());
    expect_platform_balanced(robot, fk, worst_force, worst_moment);
  }
  std::printf(
      "platform balance on CVODE rods: worst force %.2e of the largest force, moment "
      "%.2e of it times L\n",
      worst_force, worst_moment);
}

// ---- The planar robot in space ------------------------------------------------------------------

TEST(SpatialKinematics, PlanarRobotMatchesThePlanarCore) {
  const RobotParams<double> planar = femto_3pf();
  const SpatialRobotParams<double> robot = spatial_of_planar(planar);
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PoseError worst;
  for (int trial = 0; trial < 8; ++trial) {
    JointVector q(3);
    for (int i = 0; i < 3; ++i) q(i) = 0.004 * u(rng);
    const ForwardSolution expected = forward_kinematics(planar, q);
    ASSERT_TRUE(expected.summary.converged())
        << to_string(expected.summary.status) << " q " << q.transpose();
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, SpatialJointVector(q));
    ASSERT_TRUE(fk.summary.converged()) << to_string(fk.summary.status);
    SpatialPose<double> planar_pose;
    planar_pose.position = Vector3d(expected.pose.x, expected.pose.y, 0);
    planar_pose.orientation =
        Vector4d(std::cos(expected.pose.theta / 2), 0, 0, std::sin(expected.pose.theta / 2));
    const PoseError e = pose_error(fk.pose, planar_pose);
    worst.position = std::max(worst.position, e.position);
    worst.angle = std::max(worst.angle, e.angle);
    EXPECT_LT(e.position, 1e-9) << "trial " << trial;
    EXPECT_LT(e.angle, 1e-6) << "trial " << trial;
  }
  std::printf("planar 3-PF in space vs pcr::forward_kinematics: worst %.2e m, %.2e rad\n",
              worst.position, worst.angle);
}

// ---- Warm starts --------------------------------------------------------------------------------

TEST(SpatialKinematics, WarmStartConvergesInFewEvaluations) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  std::mt19937_64 rng(51);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const ShootingScale scale = spatial_shooting_scale(robot);
  int worst = 0;
  for (int trial = 0; trial < 8; ++trial) {
    SpatialJointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = 0.005 + 0.01 * u(rng);
    const SpatialForwardSolution start = spatial_forward_kinematics(robot, q);
    ASSERT_TRUE(start.summary.converged());
    // Joints that move the platform by 1 mm and 1 degree (to first order): the pose rows of
    // -J^-1 dr/dq map dq to the pose step.
    const Eigen::MatrixXd pose_per_joint =
        -(start.warm.lu.solve(Eigen::MatrixXd(start.warm.input_jacobian))).bottomRows(6);
    Eigen::Matrix<double, 6, 1> target;
    target.head<3>() = 1e-3 / scale.length * Vector3d(u(rng), u(rng), u(rng)).normalized();
    target.tail<3>() = M_PI / 180 * Vector3d(u(rng), u(rng), u(rng)).normalized();
    const SpatialJointVector next = q + pose_per_joint.partialPivLu().solve(target);
    const SpatialForwardSolution warm = spatial_forward_kinematics(robot, next, start);
    ASSERT_TRUE(warm.summary.converged());
    const SpatialForwardSolution cold = spatial_forward_kinematics(robot, next);
    const PoseError moved = pose_error(warm.pose, start.pose);
    const PoseError off = pose_error(warm.pose, cold.pose);
    EXPECT_LE(warm.summary.residual_evaluations, 5) << "trial " << trial;
    // Both within the accuracy targets of the exact solution of the discrete model.
    EXPECT_LT(off.position, 2 * SolverOptions().position_accuracy);
    EXPECT_LT(off.angle, 2 * SolverOptions().angle_accuracy);
    worst = std::max(worst, warm.summary.residual_evaluations);
    std::printf(
        "warm step %.2f mm %.2f deg (|dq| %.2f mm): residual %.1e at the predictor, "
        "%d evaluations, %d iterations (cold %d); differs from cold by %.1e m %.1e rad\n",
        moved.position * 1e3, moved.angle * 180 / M_PI, (next - q).norm() * 1e3,
        warm.summary.initial_residual_norm, warm.summary.residual_evaluations,
        warm.summary.iterations, cold.summary.residual_evaluations, off.position, off.angle);
  }
  std::printf("warm starts: at most %d residual evaluations\n", worst);
}

// ---- Random robots ------------------------------------------------------------------------------

/// Robot `trial` of a random set: 3 to 6 rods in turn (mixed_robot), gravity off on every other
/// one and the payload off on every third, and joints drawn within +-10 mm.
SpatialRobotParams<double> random_robot_and_joints(std::mt19937_64& rng, int trial,
                                                   SpatialJointVector& q) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 3 + trial % 4;
  SpatialRobotParams<double> robot = mixed_robot(rng, n);
  if (trial % 2 == 1) robot.gravity.setZero();
  if (trial % 3 == 2) {
    robot.platform_mass = 0;
    robot.external_force.setZero();
    robot.external_moment.setZero();
  }
  q.resize(n);
  for (int i = 0; i < n; ++i) q(i) = 0.01 * u(rng);
  return robot;
}

TEST(SpatialKinematics, RandomRobotsMatchCvode) {
  std::mt19937_64 rng(61);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PoseError worst;
  double worst_force = 0, worst_moment = 0;
  int most_evaluations = 0, cold_failures = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 3 + trial % 4;
    SpatialJointVector q;
    const SpatialRobotParams<double> robot = random_robot_and_joints(rng, trial, q);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q);
    if (!fk.summary.converged()) {
      // A known limitation, counted below: Newton from straight rods (and from home) can fail.
      ++cold_failures;
      std::printf(
          "robot %2d: %d rods: the cold solve failed (%s after %d evaluations, residual "
          "%.1e)\n",
          trial, n, to_string(fk.summary.status), fk.summary.residual_evaluations,
          fk.summary.final_residual_norm);
      continue;
    }
    Point start;
    start.pose = fk.pose;
    for (int i = 0; i < n; ++i) {
      start.q[i] = q(i);
      start.wrenches[i] = fk.wrenches[i];
    }
    const ReferenceFk reference = reference_forward_kinematics(robot, start);
    ASSERT_LT(reference.residual, 1e-11) << "trial " << trial;
    const PoseError e = pose_error(fk.pose, reference.x.pose);
    EXPECT_LT(e.position, 1e-9) << "trial " << trial;
    EXPECT_LT(e.angle, 1e-6) << "trial " << trial;
    worst.position = std::max(worst.position, e.position);
    worst.angle = std::max(worst.angle, e.angle);
    most_evaluations = std::max(most_evaluations, fk.summary.residual_evaluations);
    SolverOptions fine;  // as in PlatformBalancesOnCvodeRods
    fine.rod_steps = 512;
    fine.chord_output_share = 0;
    const SpatialForwardSolution balanced = spatial_forward_kinematics(robot, q, fk, fine);
    ASSERT_TRUE(balanced.summary.converged());
    expect_platform_balanced(robot, balanced, worst_force, worst_moment);
    int spherical = 0, clamps = 0;
    for (int i = 0; i < n; ++i) {
      spherical += robot.limb(i).attachment == SpatialAttachment::kSpherical;
      clamps += robot.limb(i).actuation == SpatialActuation::kTranslatedClamp;
    }
    std::printf(
        "robot %2d: %d rods (%d spherical, %d translated clamps), gravity %s, payload "
        "%s: %d evaluations, %d continuation steps, error %.2e m %.2e rad\n",
        trial, n, spherical, clamps, robot.gravity.isZero() ? "off" : "on",
        robot.platform_mass > 0 ? "on" : "off", fk.summary.residual_evaluations,
        fk.summary.continuation_steps, e.position, e.angle);
  }
  std::printf(
      "random robots: worst %.2e m, %.2e rad; balance %.2e, %.2e; at most %d "
      "evaluations; %d of 12 cold solves failed\n",
      worst.position, worst.angle, worst_force, worst_moment, most_evaluations, cold_failures);
  // Robot 3 (six rods) has no solution from straight rods or from home: the bowed cold start
  // reaches it.
  EXPECT_EQ(cold_failures, 0);
}

// The cold start on more robots drawn around the reference (3 to 6 rods, every kind of rod,
// gravity and payload on and off) at random joints within +-10 mm, each solution checked by a
// CVODE FK from it. A mechanism at its joints (the joints do not fix the pose) must say so.
// Measured: 93 of 96 solved and stable, within 3.3e-10 m and 8.5e-9 rad of CVODE; robots 39, 50
// and 67 fail (the bowed start's trace circles between two folds, or creeps, until its budget
// is spent). Without the bowed start's trace through folds (spatial_trace_bowed_start) 90: it
// solves robots 10, 23 and 54. The bound is the known limit docs/kinematics.md states.
TEST(SpatialKinematics, ColdStartOnMoreRandomRobots) {
  std::mt19937_64 rng(2027);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const SolverOptions options;
  PoseError worst;
  int bowed = 0, most_evaluations = 0, failed = 0, mechanisms = 0;
  constexpr int kRobots = 96;
  for (int trial = 0; trial < kRobots; ++trial) {
    const int n = 3 + trial % 4;
    SpatialJointVector q;
    const SpatialRobotParams<double> robot = random_robot_and_joints(rng, trial, q);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q, options);
    if (!fk.summary.converged() && fk.summary.status != SolveStatus::kInaccurate) {
      ++failed;
      std::printf("robot %d (%d rods): no cold FK (%s)\n", trial, n, to_string(fk.summary.status));
      continue;
    }
    const ReferenceFk reference =
        reference_forward_kinematics(robot, spatial_shooting_point(robot, fk));
    // CVODE's floor near a mechanism (1.4e-10 scaled: 6e-11 m on the 0.4 m rods).
    ASSERT_LT(reference.residual, 1e-9) << "robot " << trial;
    const PoseError e = pose_error(fk.pose, reference.x.pose);
    if (fk.summary.singularity < 1e-9) {  // the pose is not a function of the joints here
      ++mechanisms;
      EXPECT_GT(fk.summary.position_error_estimate, options.position_accuracy) << trial;
      EXPECT_EQ(fk.summary.status, SolveStatus::kInaccurate) << trial;  // and says so
      std::printf(
          "robot %d (%d rods): a mechanism (singularity %.1e): %.1e m from CVODE, "
          "estimated %.1e m\n",
          trial, n, fk.summary.singularity, e.position, fk.summary.position_error_estimate);
      continue;
    }
    EXPECT_TRUE(fk.summary.converged()) << "robot " << trial << to_string(fk.summary.status);
    // Small joints around home: the robot's own equilibrium is stable. (Newton from straight rods
    // can land on an unstable one with rods folded over; the cold FK goes on to a stable one.)
    EXPECT_EQ(fk.summary.stability, Stability::kStable) << "robot " << trial;
    EXPECT_LT(e.position, 1e-9) << "robot " << trial;
    EXPECT_LT(e.angle, 1e-6) << "robot " << trial;
    worst.position = std::max(worst.position, e.position);
    worst.angle = std::max(worst.angle, e.angle);
    bowed += fk.summary.continuation_steps > 0;
    most_evaluations = std::max(most_evaluations, fk.summary.residual_evaluations);
  }
  std::printf(
      "cold FK of %d random robots: %d failed, %d mechanisms, %d by continuation; at most %d "
      "evaluations; within %.2e m, %.2e rad of a CVODE FK\n",
      kRobots, failed, mechanisms, bowed, most_evaluations, worst.position, worst.angle);
  EXPECT_LE(failed, kRobots / 20);
}

// ---- Inverse kinematics -------------------------------------------------------------------------

TEST(SpatialKinematics, InverseOfForwardRecoversTheJoints) {
  std::mt19937_64 rng(71);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  int mixed_tested = 0;
  for (int trial = 0; trial < 10; ++trial) {
    // The reference robot, then six-rod robots with both attachments and both actuations.
    const SpatialRobotParams<double> robot =
        trial < 5 ? continuum_stewart_gough() : mixed_robot(rng, 6);
    const SpatialJointVector q0 = equal_joints(6, 0.005);
    const SpatialForwardSolution start = spatial_forward_kinematics(robot, q0);
    if (!start.summary.converged()) {
      // A cold FK that fails is ColdStartSolvesRandomRobots' to test, not IK's.
      ASSERT_GE(trial, 5);
      std::printf("IK trial %d: no cold FK start\n", trial);
      continue;
    }
    mixed_tested += trial >= 5;
    SpatialJointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = q0(i) + 0.01 * u(rng);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q, start);
    ASSERT_TRUE(fk.summary.converged()) << "trial " << trial;
    // FK's equilibrium whether it holds or not (trial 8's does not): IK is to find it again, not
    // to look for a stable one instead.
    SolverOptions same_branch;
    same_branch.stable_inverse = false;
    const SpatialInverseSolution ik =
        spatial_inverse_kinematics(robot, fk.pose, start, same_branch);
    ASSERT_TRUE(ik.summary.converged()) << "trial " << trial << " " << to_string(ik.summary.status);
    EXPECT_EQ(ik.summary.stability, fk.summary.stability) << "trial " << trial;
    const double error = (ik.q - q).lpNorm<Eigen::Infinity>();
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-9) << "trial " << trial;
    std::printf(
        "IK of FK, |dq| %.1f mm: joints within %.1e m, %d evaluations, %d continuation "
        "steps\n",
        (q - q0).norm() * 1e3, error, ik.summary.residual_evaluations,
        ik.summary.continuation_steps);
  }
  std::printf("IK(FK(q)) = q: worst %.2e m (%d mixed robots)\n", worst, mixed_tested);
  EXPECT_GE(mixed_tested, 2);
  EXPECT_EQ(spatial_inverse_kinematics(mixed_robot(rng, 4), SpatialPose<double>(),
                                       SpatialForwardSolution())
                .summary.status,
            SolveStatus::kUnsupported);
}

TEST(SpatialKinematics, InverseAlongAPathFromItsOwnSolutions) {
  // IK warm-started from the previous IK solution along the FK poses of a closed joint path in
  // ~1 mm steps (each rod q0 + 5 mm sin(2 pi k / 32 + i)), in order and then in a shuffled order
  // (long jumps): the joints of the FK must come back.
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  constexpr int kPoints = 32;
  std::vector<SpatialJointVector> q;
  std::vector<SpatialForwardSolution> fk;
  for (int k = 0; k < kPoints; ++k) {
    SpatialJointVector joints(6);
    for (int i = 0; i < 6; ++i) joints(i) = 0.005 + 0.005 * std::sin(2 * M_PI * k / kPoints + i);
    q.push_back(joints);
    fk.push_back(k == 0 ? spatial_forward_kinematics(robot, joints)
                        : spatial_forward_kinematics(robot, joints, fk.back()));
    ASSERT_TRUE(fk.back().summary.converged()) << "point " << k;
  }
  std::vector<int> order(2 * kPoints);
  for (int k = 0; k < kPoints; ++k) order[k] = k + 1 < kPoints ? k + 1 : 0;
  std::mt19937_64 rng(81);
  for (int k = 0; k < kPoints; ++k) order[kPoints + k] = k;
  std::shuffle(order.begin() + kPoints, order.end(), rng);
  SpatialInverseSolution ik = spatial_inverse_kinematics(robot, fk[0].pose, fk[0]);
  ASSERT_TRUE(ik.summary.converged());
  double worst = 0;
  int most_in_order = 0, most_shuffled = 0;
  for (int j = 0; j < 2 * kPoints; ++j) {
    const int k = order[j];
    ik = spatial_inverse_kinematics(robot, fk[k].pose, ik);
    ASSERT_TRUE(ik.summary.converged()) << "step " << j << " " << to_string(ik.summary.status);
    const double error = (ik.q - q[k]).lpNorm<Eigen::Infinity>();
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-9) << "step " << j;
    int& most = j < kPoints ? most_in_order : most_shuffled;
    most = std::max(most, ik.summary.residual_evaluations);
  }
  std::printf(
      "IK along the path from its own solutions: joints within %.2e m; at most %d evaluations "
      "in order, %d shuffled\n",
      worst, most_in_order, most_shuffled);
}

TEST(SpatialKinematics, MaxStrainOfAnArcIsItsClosedForm) {
  // One rod clamped at its base and to the platform, no gravity, a moment M on the platform about
  // x: the rod bends into a circular arc of curvature M / EI, so its outermost fibre's strain is
  // (d / 2) M / EI all along it. M bends it by 0.5, 1 and 2 rad; the rod's frame is turned about
  // its axis, so the bending plane is none of the body's.
  SpatialRobotParams<double> robot;
  robot.num_rods = 1;
  robot.gravity.setZero();
  SpatialLimbParams<double>& limb = robot.limb(0);
  limb.rod = continuum_stewart_gough().limb(0).rod;
  const Eigen::Quaterniond twist(Eigen::AngleAxisd(0.7, Vector3d::UnitZ()));
  limb.base_orientation = Vector4d(twist.w(), twist.x(), twist.y(), twist.z());
  limb.tip_orientation = limb.base_orientation;
  const double ei = limb.rod.bending_stiffness(), L = limb.rod.length;
  for (const double turn : {0.5, 1.0, 2.0}) {
    robot.external_moment = Vector3d(turn * ei / L, 0, 0);
    const SpatialForwardSolution fk =
        spatial_forward_kinematics(robot, SpatialJointVector::Zero(1));
    ASSERT_TRUE(fk.summary.converged()) << turn << " " << to_string(fk.summary.status);
    const double expected = limb.rod.diameter / 2 * turn / L;
    EXPECT_NEAR(fk.summary.max_strain, expected, 1e-9 * expected) << turn;
    // The arc's tip: (0, -(1 - cos) / k, sin / k) with k = turn / L, bent towards -y.
    const double k = turn / L;
    EXPECT_NEAR(fk.pose.position.y(), -(1 - std::cos(turn)) / k, 1e-9) << turn;
    EXPECT_NEAR(fk.pose.position.z(), std::sin(turn) / k, 1e-9) << turn;
    std::printf("arc of %.1f rad: max strain %.12e, closed form %.12e\n", turn,
                fk.summary.max_strain, expected);
  }
}

TEST(SpatialKinematics, SolvesNeverAllocate) {
  // Neither operator new nor Eigen's aligned malloc, in cold and warm FK and in IK.
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const SpatialJointVector q0 = equal_joints(6, 0.005);
  SpatialJointVector q1 = q0;
  q1(0) += 0.002;
  q1(3) -= 0.001;
  g_allocations = 0;
  g_counting = true;
  Eigen::internal::set_is_malloc_allowed(false);
  const SpatialForwardSolution cold = spatial_forward_kinematics(robot, q0);
  const SpatialForwardSolution warm = spatial_forward_kinematics(robot, q1, cold);
  const SpatialInverseSolution ik = spatial_inverse_kinematics(robot, warm.pose, cold);
  const SpatialInverseSolution ik_warm = spatial_inverse_kinematics(robot, cold.pose, ik);
  Eigen::internal::set_is_malloc_allowed(true);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(cold.summary.converged());
  EXPECT_TRUE(warm.summary.converged());
  EXPECT_TRUE(ik.summary.converged());
  EXPECT_TRUE(ik_warm.summary.converged());
}

TEST(SpatialKinematics, RejectsBadInput) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  EXPECT_EQ(spatial_forward_kinematics(robot, equal_joints(5, 0)).summary.status,
            SolveStatus::kInvalidInput);
  SpatialJointVector q = equal_joints(6, 0);
  q(2) = std::nan("");
  EXPECT_EQ(spatial_forward_kinematics(robot, q).summary.status, SolveStatus::kInvalidInput);
  SolverOptions options;
  options.max_iterations = 0;
  EXPECT_EQ(spatial_forward_kinematics(robot, equal_joints(6, 0), options).summary.status,
            SolveStatus::kInvalidInput);
}

}  // namespace
}  // namespace pcr
