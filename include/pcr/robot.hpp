#pragma once
// Geometric and material description of a planar parallel continuum robot (n-PF).
// Notation of Mauze et al. 2021 (Fig. 3): W world frame, P platform frame, A_i proximal clamps
// (moved by the actuators), B_i distal clamps on the platform. SI units, angles in radians.

#include <Eigen/Core>
#include <array>
#include <cmath>

#include "pcr/rod.hpp"
#include "pcr/se2.hpp"

namespace pcr {

/// Fixed capacity, so the hot path never allocates. IK supports 2 and 3 limbs.
inline constexpr int kMaxLimbs = 6;

template <class T>
struct LimbParams {
  Vector2<T> A{T(0), T(0)};  ///< proximal clamp in W at q = 0 (m)
  T alpha{0};                ///< rod tangent angle at the proximal clamp, in W (rad)
  T gamma{0};                ///< actuator misalignment: the clamp moves along alpha + gamma (rad)
  Vector2<T> B{T(0), T(0)};  ///< distal clamp in P (m)
  T beta{0};                 ///< rod tangent angle at the distal clamp, in P (rad)
  Rod<T> rod{};              ///< the rod between the clamps: l, d, E and its intrinsic curvature
  double q_min{0};           ///< actuator stroke, lower end (m)
  double q_max{0};           ///< actuator stroke, upper end (m)
  /// Which home a pre-stressed robot (n >= 4, docs/kinematics.md, "Accuracy and branches") is in:
  /// the side of the line from its proximal to its distal clamp the rod bows to in the bowed
  /// variant the home solve starts from, +1 left, -1 right, 0 not said (the solve's documented
  /// order). Two patterns can reach the same home, and a rod nearly straight at home bows to no
  /// clear side: choose_home sets them from a measured home pose. A robot whose home is unique
  /// ignores it.
  int home_bow{0};

  /// Whether the actuator reaches joint value q: q_min <= q <= q_max. The one stroke test of pcr:
  /// the solvers report a solution outside it as SolveStatus::kOutOfRange.
  bool within_stroke(double q) const { return q >= q_min && q <= q_max; }

  /// Unit vector of the actuator's translation, in W.
  Vector2<T> actuator_direction() const {
    using std::cos;
    using std::sin;
    return Vector2<T>(cos(alpha + gamma), sin(alpha + gamma));
  }

  /// Proximal clamp position A(q) = A + q (cos(alpha + gamma), sin(alpha + gamma)).
  Vector2<T> proximal_position(const T& q) const { return A + q * actuator_direction(); }

  template <class U>
  LimbParams<U> cast() const {
    LimbParams<U> out;
    out.A = A.template cast<U>();
    out.alpha = U(alpha);
    out.gamma = U(gamma);
    out.B = B.template cast<U>();
    out.beta = U(beta);
    out.rod = rod.template cast<U>();
    out.q_min = q_min;
    out.q_max = q_max;
    out.home_bow = home_bow;
    return out;
  }
};

/// Measurement extrinsics (Eq. 5): ^W T_P = camera * (^Se T_M) * pattern.
template <class T>
struct Extrinsics {
  Pose2<T> camera;   ///< ^W T_Se: the measuring camera frame in W
  Pose2<T> pattern;  ///< ^M T_P: the platform frame in the pattern frame

  /// Platform pose in W from a measured pattern pose in the camera frame.
  Pose2<T> platform_from_measurement(const Pose2<T>& camera_T_pattern) const {
    return camera * camera_T_pattern * pattern;
  }
  /// What the camera measures (^Se T_M) for a platform pose ^W T_P.
  Pose2<T> measurement_from_platform(const Pose2<T>& world_T_platform) const {
    return camera.inverse() * world_T_platform * pattern.inverse();
  }

  template <class U>
  Extrinsics<U> cast() const {
    return Extrinsics<U>{camera.template cast<U>(), pattern.template cast<U>()};
  }
};

template <class T>
struct RobotParams {
  int num_limbs{0};
  std::array<LimbParams<T>, kMaxLimbs> limbs{};
  Extrinsics<T> extrinsics{};

  const LimbParams<T>& limb(int i) const { return limbs[static_cast<std::size_t>(i)]; }
  LimbParams<T>& limb(int i) { return limbs[static_cast<std::size_t>(i)]; }

  template <class U>
  RobotParams<U> cast() const {
    RobotParams<U> out;
    out.num_limbs = num_limbs;
    for (int i = 0; i < kMaxLimbs; ++i) out.limb(i) = limb(i).template cast<U>();
    out.extrinsics = extrinsics.template cast<U>();
    return out;
  }
};

/// The paper's 3-PF robot as inferred from its figures (see docs/kinematics.md, "The default
/// robot"). Limb i sits at phi_i = -90 + 120 i degrees; the rods point inwards, 20 degrees
/// clockwise from the radial, and are straight and stress-free at q = 0, so the home pose is
/// (0, 0, 0).
inline RobotParams<double> femto_3pf() {
  constexpr double kDeg = M_PI / 180.0;
  constexpr double kLength = 0.030;
  const double r_a = 0.060 * std::cos(20.0 * kDeg);
  RobotParams<double> robot;
  robot.num_limbs = 3;
  for (int i = 0; i < 3; ++i) {
    const double phi = (-90.0 + 120.0 * i) * kDeg;
    LimbParams<double>& limb = robot.limb(i);
    limb.A = Vector2<double>(r_a * std::cos(phi), r_a * std::sin(phi));
    limb.alpha = phi + (180.0 - 20.0) * kDeg;
    limb.gamma = 0.0;
    limb.B = limb.A + kLength * Vector2<double>(std::cos(limb.alpha), std::sin(limb.alpha));
    limb.beta = limb.alpha;
    limb.rod.length = kLength;
    limb.rod.diameter = 125e-6;
    limb.rod.young_modulus = 69e9;
    limb.q_min = -0.0105;
    limb.q_max = 0.0105;
  }
  return robot;
}

}  // namespace pcr
