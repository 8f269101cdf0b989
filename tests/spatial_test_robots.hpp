#pragma once
// Spatial robots the tests build: a random robot with every kind of rod, and a planar robot
// described as a spatial one.

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "pcr/robot.hpp"
#include "pcr/spatial/quaternion.hpp"
#include "pcr/spatial/robot.hpp"

namespace pcr::testing {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Eigen::Vector4d;

/// A robot with every kind of rod: clamped and spherical tips, holes and translated clamps,
/// tilted and twisted frames, under gravity with a payload off its centre.
inline SpatialRobotParams<double> mixed_robot(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
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
    limb.A = Vector3d(base_radius * std::cos(base_angle), base_radius * std::sin(base_angle),
                      0.002 * u(rng));
    limb.B = Vector3d(platform_radius * std::cos(platform_angle),
                      platform_radius * std::sin(platform_angle), 0.002 * u(rng));
    limb.rod.length = 0.4 + 0.002 * u(rng);
    limb.rod.diameter = 2e-3 * (1 + 0.2 * u(rng));
    const Matrix3d base = (Eigen::AngleAxisd(0.1 * u(rng), Vector3d::UnitX()) *
                           Eigen::AngleAxisd(0.1 * u(rng), Vector3d::UnitY()) *
                           Eigen::AngleAxisd(M_PI * u(rng), Vector3d::UnitZ()))
                              .toRotationMatrix();
    limb.base_orientation = quaternion_of<double>(base);
    // The tip frame: the base frame (as if the platform were W) turned by up to 0.1 rad about
    // each axis: clamped rods bend and twist by that much on top of the layout's S shapes.
    const Matrix3d tip = (Eigen::AngleAxisd(0.1 * u(rng), Vector3d::UnitX()) *
                          Eigen::AngleAxisd(0.1 * u(rng), Vector3d::UnitY()) *
                          Eigen::AngleAxisd(0.1 * u(rng), Vector3d::UnitZ()))
                             .toRotationMatrix() *
                         base;
    limb.tip_orientation = quaternion_of<double>(tip);
    limb.attachment = u(rng) > 0 ? SpatialAttachment::kClamped : SpatialAttachment::kSpherical;
    if (u(rng) > 0) {
      limb.actuation = SpatialActuation::kTranslatedClamp;
      limb.actuator_direction =
          (base.col(2) + 0.05 * Vector3d(u(rng), u(rng), u(rng))).normalized();
    }
  }
  robot.platform_mass = 0.1 + 0.2 * (u(rng) + 1);
  robot.platform_centre_of_mass = Vector3d(0.01 * u(rng), 0.01 * u(rng), 0.02 * u(rng));
  robot.external_force = Vector3d(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng));
  robot.external_moment = Vector3d(0.02 * u(rng), 0.02 * u(rng), 0.02 * u(rng));
  return robot;
}

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
