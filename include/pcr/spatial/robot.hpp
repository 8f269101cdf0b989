#pragma once
// Geometric and material description of a spatial parallel continuum robot: up to
// kMaxSpatialRods Cosserat rods (pcr/spatial/cosserat_rod.hpp) between a fixed base and a rigid
// platform, as in the continuum Stewart-Gough robot of Black, Till and Rucker (IEEE T-RO 34(1),
// 2018). The spatial counterpart of pcr/robot.hpp. SI units; orientations are quaternions
// (w, x, y, z) mapping a body frame to its parent (pcr/spatial/quaternion.hpp).
//
// Frames: W the world (base) frame; P the platform frame, whose pose ^W T_P is what FK solves.

#include <Eigen/Core>
#include <array>
#include <cmath>

#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/spatial/quaternion.hpp"

namespace pcr {

/// A rigid pose, e.g. ^W T_P: the position of the child frame's origin in the parent frame (m)
/// and its orientation child -> parent.
template <class T>
struct SpatialPose {
  Vector3<T> position = Vector3<T>::Zero();           ///< m
  Vector4<T> orientation = identity_quaternion<T>();  ///< (w, x, y, z)
  Matrix3<T> rotation() const { return rotation_of(orientation); }

  /// ^A T_C = ^A T_B * ^B T_C.
  SpatialPose operator*(const SpatialPose& other) const {
    return SpatialPose{position + rotation() * other.position,
                       quaternion_product(orientation, other.orientation)};
  }
  SpatialPose inverse() const {
    const Vector4<T> conjugate(orientation(0), -orientation(1), -orientation(2), -orientation(3));
    return SpatialPose{-(rotation().transpose() * position), conjugate};
  }
  template <class U>
  SpatialPose<U> cast() const {
    return SpatialPose<U>{position.template cast<U>(), orientation.template cast<U>()};
  }
};

/// Where the measuring system sees the platform from (Mauze et al. 2021, Eq. 5, in 3-D): it
/// measures the pose ^S T_M of a marker frame M fixed to the platform (a tag board, a tracker's
/// rigid body) in its own frame S (a camera, a tracker's base).
template <class T>
struct SpatialExtrinsics {
  SpatialPose<T> tracker;  ///< ^W T_S: the measuring system's frame in W
  SpatialPose<T> marker;   ///< ^M T_P: the platform frame in the marker frame

  /// What the measuring system reports for a platform pose ^W T_P: (^W T_S)^-1 ^W T_P (^M T_P)^-1.
  SpatialPose<T> measurement_from_platform(const SpatialPose<T>& world_T_platform) const {
    return tracker.inverse() * world_T_platform * marker.inverse();
  }
  /// The platform pose in W of a measurement ^S T_M.
  SpatialPose<T> platform_from_measurement(const SpatialPose<T>& tracker_T_marker) const {
    return tracker * tracker_T_marker * marker;
  }
  template <class U>
  SpatialExtrinsics<U> cast() const {
    return SpatialExtrinsics<U>{tracker.template cast<U>(), marker.template cast<U>()};
  }
};

/// Fixed capacity, so the hot path never allocates.
inline constexpr int kMaxSpatialRods = 8;

/// How the joint value q of a rod moves it.
enum class SpatialActuation {
  /// The rod is pushed through a fixed hole at A: its free length, from the hole to the
  /// platform, is rod.length + q (q = 0 is the nominal length; the rod behind the hole carries no
  /// load and is not modelled).
  kLengthThroughHole,
  /// The rod's proximal clamp moves by q along actuator_direction; its length stays rod.length.
  kTranslatedClamp,
};

/// How the rod's tip holds the platform.
enum class SpatialAttachment {
  /// Position and orientation: the rod's tip frame is the platform frame times tip_orientation.
  kClamped,
  /// Position only (a ball joint): the tip carries no moment.
  kSpherical,
};

template <class T>
struct SpatialLimbParams {
  /// The rod; for kLengthThroughHole rod.length is the free length at q = 0 (m).
  SpatialRod<T> rod{};
  /// The hole (or the clamp at q = 0) in W (m): the rod's proximal end.
  Vector3<T> A = Vector3<T>::Zero();
  /// The rod's frame at A, body -> W: it leaves A along d3 = R e3. Any scale (rotation_of divides
  /// by |h|^2).
  Vector4<T> base_orientation = identity_quaternion<T>();
  SpatialActuation actuation = SpatialActuation::kLengthThroughHole;
  /// kTranslatedClamp: unit direction in W along which q moves the clamp.
  Vector3<T> actuator_direction = Vector3<T>::UnitZ();
  /// The attachment point on the platform, in P (m).
  Vector3<T> B = Vector3<T>::Zero();
  /// kClamped: the rod's tip frame in P, i.e. R_tip = R_P rotation_of(tip_orientation).
  Vector4<T> tip_orientation = identity_quaternion<T>();
  SpatialAttachment attachment = SpatialAttachment::kClamped;

  /// The rod as integrated at joint value q: its free length set for kLengthThroughHole.
  SpatialRod<T> rod_at(const T& q) const {
    SpatialRod<T> out = rod;
    if (actuation == SpatialActuation::kLengthThroughHole) out.length = rod.length + q;
    return out;
  }

  /// The rod's proximal point in W at joint value q (m).
  Vector3<T> proximal_position(const T& q) const {
    if (actuation == SpatialActuation::kTranslatedClamp) return A + q * actuator_direction;
    return A;
  }

  template <class U>
  SpatialLimbParams<U> cast() const {
    SpatialLimbParams<U> out;
    out.rod = rod.template cast<U>();
    out.A = A.template cast<U>();
    out.base_orientation = base_orientation.template cast<U>();
    out.actuation = actuation;
    out.actuator_direction = actuator_direction.template cast<U>();
    out.B = B.template cast<U>();
    out.tip_orientation = tip_orientation.template cast<U>();
    out.attachment = attachment;
    return out;
  }
};

template <class T>
struct SpatialRobotParams {
  int num_rods{0};
  std::array<SpatialLimbParams<T>, kMaxSpatialRods> limbs{};
  T platform_mass{0};                                       ///< kg
  Vector3<T> platform_centre_of_mass = Vector3<T>::Zero();  ///< in P (m)
  /// Acts on the rods (their weight rho A g per unit length) and on the platform (m).
  Vector3<T> gravity = Vector3<T>(T(0), T(0), T(-9.81));  ///< m/s^2, in W
  /// External wrench on the platform: a force at the origin of P and a moment, both in W.
  Vector3<T> external_force = Vector3<T>::Zero();   ///< N
  Vector3<T> external_moment = Vector3<T>::Zero();  ///< N m
  /// The measuring system's frames (identity unless a calibration or a file says otherwise).
  SpatialExtrinsics<T> extrinsics{};

  const SpatialLimbParams<T>& limb(int i) const { return limbs[static_cast<std::size_t>(i)]; }
  SpatialLimbParams<T>& limb(int i) { return limbs[static_cast<std::size_t>(i)]; }

  template <class U>
  SpatialRobotParams<U> cast() const {
    SpatialRobotParams<U> out;
    out.num_rods = num_rods;
    for (int i = 0; i < kMaxSpatialRods; ++i) out.limb(i) = limb(i).template cast<U>();
    out.platform_mass = U(platform_mass);
    out.platform_centre_of_mass = platform_centre_of_mass.template cast<U>();
    out.gravity = gravity.template cast<U>();
    out.external_force = external_force.template cast<U>();
    out.external_moment = external_moment.template cast<U>();
    out.extrinsics = extrinsics.template cast<U>();
    return out;
  }
};

/// The reference continuum Stewart-Gough robot: six steel rods (E 200 GPa, G 80 GPa, diameter
/// 2 mm, density 8000 kg/m^3), 0.4 m of free length each at q = 0, pushed vertically (+z)
/// through holes in the base and clamped to a 0.1 kg platform (its centre of mass at its origin)
/// under gravity.
///
/// Layout: the published one (Till's example of this robot, the hole pattern of Black, Till and
/// Rucker 2018): holes on circles of radius 87 mm in the base (z = 0) and in the platform; a pair's
/// holes 20 degrees apart in the base (rods at 120 k -+ 10 degrees) and 100 degrees apart in the
/// platform (120 k -+ 50 degrees), rod i from the one to the other (40 degrees round), so that
/// the legs lean in alternate directions as in a Stewart-Gough platform. Rod frames are the
/// identity at the base and at the platform (tip_orientation identity): an untilted platform
/// holds each rod's tip vertical, and the rods bend in S shapes. The robot is symmetric under
/// turns of 120 degrees about z and under the mirror y -> -y.
inline SpatialRobotParams<double> continuum_stewart_gough() {
  constexpr double kDeg = M_PI / 180.0;
  constexpr double kRadius = 0.087;
  SpatialRobotParams<double> robot;
  robot.num_rods = 6;
  robot.platform_mass = 0.1;
  for (int k = 0; k < 3; ++k) {
    for (int side = 0; side < 2; ++side) {
      const double sign = side == 0 ? -1.0 : 1.0;
      const double base_angle = (120.0 * k + sign * 10.0) * kDeg;
      const double platform_angle = (120.0 * k + sign * 50.0) * kDeg;
      SpatialLimbParams<double>& limb = robot.limb(2 * k + side);
      limb.rod.length = 0.4;
      limb.rod.diameter = 2e-3;
      limb.rod.young_modulus = 200e9;
      limb.rod.shear_modulus = 80e9;
      limb.rod.density = 8000;
      limb.A = Vector3<double>(kRadius * std::cos(base_angle), kRadius * std::sin(base_angle), 0);
      limb.B = Vector3<double>(kRadius * std::cos(platform_angle),
                               kRadius * std::sin(platform_angle), 0);
      limb.actuation = SpatialActuation::kLengthThroughHole;
      limb.attachment = SpatialAttachment::kClamped;
    }
  }
  return robot;
}

}  // namespace pcr
