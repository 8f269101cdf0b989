#pragma once
// The shooting residual of a planar PCR: closure of every rod on its distal clamp (Eq. 2) and the
// static equilibrium of the platform (Eq. 4), 3n + 3 equations, templated on the scalar.
//
// Unknowns and residuals are scaled so that Newton sees numbers of order one: lengths by the mean
// rod length L, forces by F = EI / L^2 (mean EI), moments by F L.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>

#include "pcr/option_range.hpp"
#include "pcr/robot.hpp"
#include "pcr/rod.hpp"
#include "pcr/scalar_traits.hpp"
#include "pcr/se2.hpp"

namespace pcr {

static_assert(kMaxLimbs <= 8, "shooting_residual integrates the rods in at most 8 SIMD lanes");
inline constexpr int kMaxResiduals = 3 * kMaxLimbs + 3;
/// Columns of the full partial-derivative matrix: wrenches (3n), pose (3), joints (n).
inline constexpr int kMaxPartials = 4 * kMaxLimbs + 3;

using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxLimbs, 1>;
using ShootingVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPartials, 1>;
using ShootingMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxResiduals, kMaxPartials>;
/// The square Jacobian of a shooting problem (FK: 3n + 3, IK: 4n [+ 1]).
using JacobianMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxResiduals, kMaxResiduals>;
template <class T>
using ResidualVector = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, kMaxResiduals, 1>;

/// A planar wrench: force (N) and moment (N m), in W.
template <class T>
struct Wrench {
  T nx{0}, ny{0}, m{0};
  template <class U>
  Wrench<U> cast() const {
    return Wrench<U>{U(nx), U(ny), U(m)};
  }
};

/// External load on the platform: a force at the origin of P and a moment, both in W.
template <class T>
struct PlatformLoad {
  Vector2<T> force{T(0), T(0)};  ///< N
  T moment{0};                   ///< N m
  template <class U>
  PlatformLoad<U> cast() const {
    return PlatformLoad<U>{force.template cast<U>(), U(moment)};
  }

  /// A kilonewton metre on a robot of this scale is a unit typo (N mm typed as N m).
  static constexpr OptionRange kMoment{"moment", -1e3, 1e3, "N m"};
  /// Whether the force is finite and the moment in its range; if not, *error (when given) names
  /// the field with `prefix` ("effects.load." when nested). The options that carry a load check
  /// it with theirs; the solvers take any load.
  bool is_valid(std::string* error = nullptr, const char* prefix = "") const {
    if (!force.allFinite()) {
      if (error != nullptr) *error = std::string(prefix) + "force: not finite";
      return false;
    }
    return kMoment.check(moment, error, prefix);
  }
};

/// Reference magnitudes of the scaled problem.
struct ShootingScale {
  double length{1};  ///< m
  double force{1};   ///< N
  double moment() const { return force * length; }
};

/// The scale of n rods (rod_of(i) each, planar or spatial): their mean length L and mean EI, so
/// lengths by L, forces by EI / L^2, moments by EI / L.
template <class RodOf>
ShootingScale mean_rod_scale(int n, RodOf&& rod_of) {
  double length = 0, ei = 0;
  for (int i = 0; i < n; ++i) {
    length += rod_of(i).length;
    ei += rod_of(i).bending_stiffness();
  }
  length /= n;
  ei /= n;
  return ShootingScale{length, ei / (length * length)};
}

inline ShootingScale shooting_scale(const RobotParams<double>& robot) {
  return mean_rod_scale(robot.num_limbs,
                        [&](int i) -> const Rod<double>& { return robot.limb(i).rod; });
}

/// Physical values of every shooting unknown and input.
template <class T>
struct ShootingPoint {
  std::array<T, kMaxLimbs> q{};                 ///< joint values (m)
  Pose2<T> pose;                                ///< platform pose ^W T_P
  std::array<Wrench<T>, kMaxLimbs> wrenches{};  ///< proximal wrench of each rod, (n, m)(0)

  template <class U>
  ShootingPoint<U> cast() const {
    ShootingPoint<U> out;
    for (int i = 0; i < kMaxLimbs; ++i) {
      out.q[i] = U(q[i]);
      out.wrenches[i] = wrenches[i].template cast<U>();
    }
    out.pose = pose.template cast<U>();
    return out;
  }
};

/// Angle difference wrapped to (-pi, pi], by a whole number of turns chosen on the plain value so
/// the derivative is exactly that of the difference.
template <class T>
T angle_difference(const T& a, const T& b) {
  const T d = a - b;
  const double turns = std::round(scalar_value(d) / (2.0 * M_PI));
  return d - T(turns * 2.0 * M_PI);
}

/// Rod i's state at its proximal clamp: the clamp moved by the actuator, the wrench unknown.
template <class T>
RodState<T> proximal_rod_state(const LimbParams<T>& limb, const T& q, const Wrench<T>& wrench) {
  const Vector2<T> start = limb.proximal_position(q);
  return RodState<T>{start.x(), start.y(), limb.alpha, wrench.nx, wrench.ny, wrench.m};
}

/// The distal clamp of a limb relative to the platform origin, in W, for a platform turned by
/// (c, s) = (cos theta, sin theta).
template <class T>
Vector2<T> distal_arm(const LimbParams<T>& limb, const T& c, const T& s) {
  return Vector2<T>(c * limb.B.x() - s * limb.B.y(), s * limb.B.x() + c * limb.B.y());
}

/// The residual from the rods' tip states, however they were integrated (RK4 here, CVODE in
/// pcr::shooting_residual_reference): each tip meets its distal clamp in position and angle
/// (Eq. 2) and the platform is in equilibrium (Eq. 4). Returns the largest bending strain.
template <class T>
T shooting_residual_from_tips(const RobotParams<T>& robot, const ShootingPoint<T>& point,
                              const PlatformLoad<T>& load, const ShootingScale& scale,
                              const RodTip<T>* tips, ResidualVector<T>& residual) {
  using std::cos;
  using std::sin;
  const int n = robot.num_limbs;
  residual.resize(3 * n + 3);
  const T inv_length = T(1.0 / scale.length);
  const T c = cos(point.pose.theta), s = sin(point.pose.theta);
  Vector2<T> force_sum = -load.force;
  T moment_sum = -load.moment;
  T max_strain(0);
  for (int i = 0; i < n; ++i) {
    const LimbParams<T>& limb = robot.limb(i);
    const Wrench<T>& w = point.wrenches[i];
    const Vector2<T> arm = distal_arm(limb, c, s);
    const Vector2<T> clamp = point.pose.translation() + arm;
    const RodState<T>& tip = tips[i].state;
    residual(3 * i + 0) = (tip.x - clamp.x()) * inv_length;
    residual(3 * i + 1) = (tip.y - clamp.y()) * inv_length;
    residual(3 * i + 2) = angle_difference(tip.theta, point.pose.theta + limb.beta);
    force_sum += Vector2<T>(w.nx, w.ny);
    moment_sum += arm.x() * w.ny - arm.y() * w.nx + tip.m;
    const T strain =
        tips[i].max_abs_moment * limb.rod.diameter / (T(2) * limb.rod.bending_stiffness());
    if (strain > max_strain) max_strain = strain;
  }
  residual(3 * n + 0) = force_sum.x() * T(1.0 / scale.force);
  residual(3 * n + 1) = force_sum.y() * T(1.0 / scale.force);
  residual(3 * n + 2) = moment_sum * T(1.0 / scale.moment());
  return max_strain;
}

/// The columns of the scaled partials (see shooting_residual) w.r.t. the pose (3n, 3n + 3) and the
/// joints (3n + 3, 4n + 3, unless not `joints`): the problems' inputs. Neither needs the rods
/// integrated: the clamps move rigidly with the pose and the rods translate with their joints.
template <class T>
void input_partials(const RobotParams<T>& robot, const ShootingPoint<T>& point,
                    const ShootingScale& scale, ShootingMatrix& partials, bool joints = true) {
  const int n = robot.num_limbs;
  const double c = std::cos(scalar_value(point.pose.theta));
  const double s = std::sin(scalar_value(point.pose.theta));
  const int pose_col = 3 * n;
  partials(3 * n + 2, pose_col + 2) = 0.0;
  for (int i = 0; i < n; ++i) {
    const LimbParams<T>& limb = robot.limb(i);
    const Vector2<T> arm = distal_arm(limb, T(c), T(s));
    const double arm_x = scalar_value(arm.x()), arm_y = scalar_value(arm.y());
    // Pose: the clamp moves with (x, y) and turns with theta; d arm / d theta = (-arm_y, arm_x).
    partials(3 * i + 0, pose_col + 0) = -1.0;
    partials(3 * i + 1, pose_col + 1) = -1.0;
    partials(3 * i + 0, pose_col + 2) = arm_y / scale.length;
    partials(3 * i + 1, pose_col + 2) = -arm_x / scale.length;
    partials(3 * i + 2, pose_col + 2) = -1.0;
    const double nx = scalar_value(point.wrenches[i].nx), ny = scalar_value(point.wrenches[i].ny);
    // d/dtheta of (arm x n) = (-arm_y, arm_x) x n = -arm_y ny - arm_x nx.
    partials(3 * n + 2, pose_col + 2) += (-arm_y * ny - arm_x * nx) / scale.moment();
    if (!joints) continue;
    // Joints: the whole rod translates along the actuator direction.
    const Vector2<T> dir = limb.actuator_direction();
    partials(3 * i + 0, 3 * n + 3 + i) = scalar_value(dir.x());
    partials(3 * i + 1, 3 * n + 3 + i) = scalar_value(dir.y());
  }
}

/// The scaled partials of the residual (see shooting_residual) from the rods' tips with their
/// sensitivities; without `joints`, the forward Jacobian alone (3n + 3 columns).
template <class T>
void shooting_partials_from_tips(const RobotParams<T>& robot, const ShootingPoint<T>& point,
                                 const ShootingScale& scale, const RodTip<T>* tips,
                                 ShootingMatrix& partials, bool joints = true) {
  const int n = robot.num_limbs;
  partials.setZero(3 * n + 3, joints ? 4 * n + 3 : 3 * n + 3);
  const double c = std::cos(scalar_value(point.pose.theta));
  const double s = std::sin(scalar_value(point.pose.theta));
  for (int i = 0; i < n; ++i) {
    const LimbParams<T>& limb = robot.limb(i);
    const RodTip<T>& rod = tips[i];
    const Vector2<T> arm = distal_arm(limb, T(c), T(s));
    const double arm_x = scalar_value(arm.x()), arm_y = scalar_value(arm.y());
    // d r / d (scaled wrench): physical derivative times the unknown's scale.
    const double to_scaled[3] = {scale.force, scale.force, scale.moment()};
    for (int j = 0; j < 3; ++j) {
      const int col = 3 * i + j;
      partials(3 * i + 0, col) = scalar_value(rod.sensitivity(0, j)) * to_scaled[j] / scale.length;
      partials(3 * i + 1, col) = scalar_value(rod.sensitivity(1, j)) * to_scaled[j] / scale.length;
      partials(3 * i + 2, col) = scalar_value(rod.sensitivity(2, j)) * to_scaled[j];
      // Moment balance: arm x n + m(l).
      double dmoment = scalar_value(rod.sensitivity(3, j));
      if (j == 0) dmoment += -arm_y;
      if (j == 1) dmoment += arm_x;
      partials(3 * n + 2, col) = dmoment * to_scaled[j] / scale.moment();
    }
    partials(3 * n + 0, 3 * i + 0) = 1.0;
    partials(3 * n + 1, 3 * i + 1) = 1.0;
  }
  input_partials(robot, point, scale, partials, joints);
}

/// Evaluates the scaled residual (3n + 3) at a point. With `partials`, also fills
/// d residual / d (wrenches, pose, q) in scaled units: columns [3i, 3i+3) rod i's wrench,
/// [3n, 3n+3) the pose (x, y, theta), [3n+3, 4n+3) the joints. Returns the largest bending strain
/// |m| d / (2 EI) over the rods' RK4 nodes. With `tips` (n entries), also the rods' tips (with
/// their sensitivities when `partials` is requested).
template <class T>
T shooting_residual(const RobotParams<T>& robot, const ShootingPoint<T>& point,
                    const PlatformLoad<T>& load, const ShootingScale& scale, int rod_steps,
                    ResidualVector<T>& residual, ShootingMatrix* partials = nullptr,
                    RodTip<T>* tips_out = nullptr) {
  const int n = robot.num_limbs;
  // Rod tips (and sensitivities with partials). In double the rods are integrated together, one
  // per SIMD lane: each is a serial chain of dependent multiplies, side by side they share the
  // instructions (and the results are bit for bit those of one rod at a time).
  RodTip<T> tips[kMaxLimbs];
  const auto proximal_state = [&](int i) {
    return proximal_rod_state(robot.limb(i), point.q[i], point.wrenches[i]);
  };
  const auto integrate_all = [&](auto sens) {
    constexpr bool kSens = decltype(sens)::value;
    internal::RodStepper<T, kSens> rods[kMaxLimbs];
    for (int i = 0; i < n; ++i) {
      rods[i].init(proximal_state(i), robot.limb(i).rod, rod_steps);
    }
    internal::integrate_rods_in_lanes(rods, n, rod_steps);
    for (int i = 0; i < n; ++i) tips[i] = internal::tip_of(rods[i]);
  };
  if constexpr (std::is_same_v<T, double>) {
    if (partials) {
      integrate_all(std::true_type{});
    } else {
      integrate_all(std::false_type{});
    }
  } else {
    for (int i = 0; i < n; ++i) {
      const LimbParams<T>& limb = robot.limb(i);
      if (partials) {
        tips[i] = integrate_rod_with_sensitivity(proximal_state(i), limb.rod, rod_steps);
      } else {
        tips[i].state =
            integrate_rod(proximal_state(i), limb.rod, rod_steps, &tips[i].max_abs_moment);
      }
    }
  }
  const T strain = shooting_residual_from_tips(robot, point, load, scale, tips, residual);
  if (tips_out) std::copy(tips, tips + n, tips_out);
  if (partials) shooting_partials_from_tips(robot, point, scale, tips, *partials);
  return strain;
}

}  // namespace pcr
