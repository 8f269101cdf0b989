#pragma once
// Helpers shared by the spatial robot's tests (test_spatial_kinematics.cpp,
// test_spatial_accuracy.cpp, test_spatial_stability.cpp): a forward kinematics whose rods are
// integrated by CVODE, pose errors through Eigen's quaternions, random robots drawn around the
// reference, and a planar robot described as a spatial one.

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>
#include <vector>

#include "pcr/reference.hpp"
#include "pcr/robot.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/robot.hpp"

namespace pcr::testing {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Eigen::Vector4d;
using Point = SpatialShootingPoint<double>;

inline Eigen::Quaterniond eigen_quaternion(const Vector4d& h) {
  return Eigen::Quaterniond(h[0], h[1], h[2], h[3]).normalized();
}

/// The angle of the rotation between two orientations (rad), through Eigen.
inline double angle_between(const Vector4d& a, const Vector4d& b) {
  return eigen_quaternion(a).angularDistance(eigen_quaternion(b));
}

inline SpatialJointVector equal_joints(int n, double q) {
  return SpatialJointVector::Constant(n, q);
}

// ---- The CVODE reference FK ---------------------------------------------------------------------

/// x (+) dz written here with Eigen's quaternions, not the solver's retract.
inline Point reference_retract(const Point& x, const Eigen::VectorXd& dz, int n,
                               const ShootingScale& scale) {
  Point out = x;
  for (int i = 0; i < n; ++i) {
    out.wrenches[i].force += dz.segment<3>(6 * i) * scale.force;
    out.wrenches[i].moment += dz.segment<3>(6 * i + 3) * scale.moment();
  }
  out.pose.position += dz.segment<3>(6 * n) * scale.length;
  const Vector3d delta = dz.segment<3>(6 * n + 3);
  const Eigen::Quaterniond turn =
      delta.norm() > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(delta.norm(), delta.normalized()))
                       : Eigen::Quaterniond::Identity();
  const Eigen::Quaterniond h = eigen_quaternion(x.pose.orientation) * turn;
  out.pose.orientation = Vector4d(h.w(), h.x(), h.y(), h.z());
  return out;
}

inline SpatialRodState<double> cvode_tip(const SpatialRobotParams<double>& robot, const Point& x,
                                         int i) {
  const SpatialLimbParams<double>& limb = robot.limb(i);
  return integrate_spatial_rod_reference(spatial_proximal_state(limb, x.q[i], x.wrenches[i]),
                                         limb.rod_at(x.q[i]), robot.gravity);
}

inline Eigen::VectorXd residual_of(const SpatialRobotParams<double>& robot, const Point& x,
                                   const ShootingScale& scale,
                                   const SpatialRodState<double>* tips) {
  SpatialResidualVector<double> r;
  spatial_residual_from_tips(robot, x, scale, tips, r);
  return r;
}

/// A solution of the CVODE residual (ReferenceFk: FK's; the IK of test_spatial_accuracy.cpp).
struct ReferenceFk {
  Point x;
  double residual = 0;
  int iterations = 0;
};

/// Newton on the CVODE residual from `start` (an RK4 solution) over `size` scaled unknowns that
/// retract(x, dz) steps, with central-difference Jacobians in which column k re-integrates rod
/// rod_of(k) alone (none when negative: a pose column).
template <class Retract, class RodOf>
ReferenceFk reference_newton(const SpatialRobotParams<double>& robot, const Point& start, int size,
                             Retract&& retract, RodOf&& rod_of) {
  const int n = robot.num_rods;
  const ShootingScale scale = spatial_shooting_scale(robot);
  constexpr double kStep = 1e-6;
  ReferenceFk out{start};
  std::vector<SpatialRodState<double>> tips(n);
  for (; out.iterations < 8; ++out.iterations) {
    for (int i = 0; i < n; ++i) tips[i] = cvode_tip(robot, out.x, i);
    const Eigen::VectorXd r = residual_of(robot, out.x, scale, tips.data());
    out.residual = r.lpNorm<Eigen::Infinity>();
    if (out.residual <= 2e-12) break;
    Eigen::MatrixXd J(size, size);
    for (int k = 0; k < size; ++k) {
      const int rod = rod_of(k);
      Eigen::VectorXd sides[2];
      for (int s = 0; s < 2; ++s) {
        const Point moved =
            retract(out.x, (s == 0 ? kStep : -kStep) * Eigen::VectorXd::Unit(size, k));
        std::vector<SpatialRodState<double>> moved_tips = tips;
        if (rod >= 0) moved_tips[rod] = cvode_tip(robot, moved, rod);
        sides[s] = residual_of(robot, moved, scale, moved_tips.data());
      }
      J.col(k) = (sides[0] - sides[1]) / (2 * kStep);
    }
    out.x = retract(out.x, -J.partialPivLu().solve(r));
  }
  return out;
}

/// FK on the CVODE residual: reference_newton over the wrenches and the pose.
inline ReferenceFk reference_forward_kinematics(const SpatialRobotParams<double>& robot,
                                                const Point& start) {
  const int n = robot.num_rods;
  const ShootingScale scale = spatial_shooting_scale(robot);
  return reference_newton(
      robot, start, 6 * n + 6,
      [&](const Point& x, const Eigen::VectorXd& dz) { return reference_retract(x, dz, n, scale); },
      [n](int k) { return k < 6 * n ? k / 6 : -1; });
}

struct PoseError {
  double position = 0, angle = 0;
};
inline PoseError pose_error(const SpatialPose<double>& a, const SpatialPose<double>& b) {
  return PoseError{(a.position - b.position).norm(), angle_between(a.orientation, b.orientation)};
}

/// The equal joint value that puts the reference robot's platform `height` above its base
/// (secant on cold FK).
inline double joint_for_height(const SpatialRobotParams<double>& robot, double height) {
  const int n = robot.num_rods;
  const auto z_at = [&](double q) {
    return spatial_forward_kinematics(robot, equal_joints(n, q)).pose.position.z() - height;
  };
  double q0 = 0.0, q1 = 0.01, f0 = z_at(q0), f1 = z_at(q1);
  for (int k = 0; k < 20 && std::abs(f1) > 1e-13; ++k) {
    const double q2 = q1 - f1 * (q1 - q0) / (f1 - f0);
    q0 = q1;
    f0 = f1;
    q1 = q2;
    f1 = z_at(q1);
  }
  return q1;
}

/// A robot with every kind of rod: clamped and spherical tips, holes and translated clamps,
/// tilted and twisted frames, under gravity with a payload off its centre.
inline SpatialRobotParams<double> mixed_robot(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Each number is drawn in a statement of its own, in order: the draws within one expression
  // (the arguments of a call, the operands of a product) have no order that C++ fixes, so gcc
  // and clang would build different robots from the same seed.
  const auto draw3 = [&](double x_scale, double y_scale, double z_scale) {
    const double x = x_scale * u(rng);
    const double y = y_scale * u(rng);
    const double z = z_scale * u(rng);
    return Vector3d(x, y, z);
  };
  const auto turn = [&](const Vector3d& angles) {
    return (Eigen::AngleAxisd(angles.x(), Vector3d::UnitX()) *
            Eigen::AngleAxisd(angles.y(), Vector3d::UnitY()) *
            Eigen::AngleAxisd(angles.z(), Vector3d::UnitZ()))
        .toRotationMatrix();
  };
  const SpatialRobotParams<double> reference = continuum_stewart_gough();
  SpatialRobotParams<double> robot = reference;
  robot.num_rods = n;
  for (int i = 0; i < n; ++i) {
    SpatialLimbParams<double>& limb = robot.limb(i);
    limb = reference.limb(0);
    // As in the reference robot, each rod meets the platform about 40 degrees round from its
    // hole, alternately clockwise and counterclockwise.
    const double base_angle = 2 * M_PI * i / n + 0.1 * u(rng);
    const double platform_angle =
        base_angle + (i % 2 == 0 ? 1 : -1) * (40 * M_PI / 180 + 0.1 * u(rng));
    const double base_radius = 0.087 * (1 + 0.1 * u(rng));
    const double platform_radius = 0.087 * (1 + 0.1 * u(rng));
    const double base_height = 0.002 * u(rng);
    limb.A = Vector3d(base_radius * std::cos(base_angle), base_radius * std::sin(base_angle),
                      base_height);
    const double platform_height = 0.002 * u(rng);
    limb.B = Vector3d(platform_radius * std::cos(platform_angle),
                      platform_radius * std::sin(platform_angle), platform_height);
    limb.rod.length = 0.4 + 0.002 * u(rng);
    limb.rod.diameter = 2e-3 * (1 + 0.2 * u(rng));
    const Matrix3d base = turn(draw3(0.1, 0.1, M_PI));
    limb.base_orientation = quaternion_of<double>(base);
    // The tip frame: the base frame (as if the platform were W) turned by up to 0.1 rad about
    // each axis: clamped rods bend and twist by that much on top of the layout's S shapes.
    const Matrix3d tip = turn(draw3(0.1, 0.1, 0.1)) * base;
    limb.tip_orientation = quaternion_of<double>(tip);
    limb.attachment = u(rng) > 0 ? SpatialAttachment::kClamped : SpatialAttachment::kSpherical;
    if (u(rng) > 0) {
      limb.actuation = SpatialActuation::kTranslatedClamp;
      limb.actuator_direction = (base.col(2) + draw3(0.05, 0.05, 0.05)).normalized();
    }
  }
  robot.platform_mass = 0.1 + 0.2 * (u(rng) + 1);
  robot.platform_centre_of_mass = draw3(0.01, 0.01, 0.02);
  robot.external_force = draw3(0.3, 0.3, 0.3);
  robot.external_moment = draw3(0.02, 0.02, 0.02);
  return robot;
}

// ---- The planar robot in space ------------------------------------------------------------------

/// The rod frame of a planar tangent angle: d3 = (cos a, sin a, 0), d1 = e3 (the in-plane bending
/// axis), d2 = d3 x d1.
inline Vector4d planar_frame(double angle) {
  Matrix3d R;
  R.col(0) = Vector3d::UnitZ();
  R.col(2) = Vector3d(std::cos(angle), std::sin(angle), 0);
  R.col(1) = R.col(2).cross(R.col(0));
  return quaternion_of<double>(R);
}

inline SpatialRobotParams<double> spatial_of_planar(const RobotParams<double>& planar) {
  SpatialRobotParams<double> robot;
  robot.num_rods = planar.num_limbs;
  robot.gravity.setZero();
  for (int i = 0; i < planar.num_limbs; ++i) {
    const LimbParams<double>& limb = planar.limb(i);
    SpatialLimbParams<double>& out = robot.limb(i);
    out.rod.length = limb.rod.length;
    out.rod.diameter = limb.rod.diameter;
    out.rod.young_modulus = limb.rod.young_modulus;
    out.rod.shear_modulus = limb.rod.young_modulus / 2.6;
    out.A = Vector3d(limb.A.x(), limb.A.y(), 0);
    out.base_orientation = planar_frame(limb.alpha);
    out.actuation = SpatialActuation::kTranslatedClamp;
    out.actuator_direction =
        Vector3d(std::cos(limb.alpha + limb.gamma), std::sin(limb.alpha + limb.gamma), 0);
    out.B = Vector3d(limb.B.x(), limb.B.y(), 0);
    out.tip_orientation = planar_frame(limb.beta);
    out.attachment = SpatialAttachment::kClamped;
  }
  return robot;
}

}  // namespace pcr::testing
