#pragma once
// The shooting problem of a spatial parallel continuum robot (pcr/spatial/robot.hpp): its
// unknowns, its scaled residual and exact Jacobian, and the solutions the solvers return
// (pcr/spatial/kinematics.hpp); the spatial counterpart of pcr/shooting.hpp.
//
// Unknowns (6 n + 6): each rod's proximal wrench (n, m)(0) (6, in W), then the platform pose:
// its position (3, in W) and its orientation, a unit quaternion that Newton updates by a rotation
// vector delta composed on the right, h <- h (x) exp(delta / 2), i.e. R_P <- R_P exp([delta]x).
// Three parameters for three degrees of freedom keep the Jacobian square and free of the
// quaternion's norm direction; on the right, delta is the platform's turn in its own frame P, in
// which the attachments B_i and tip frames are given, so d (R_P B) / d delta = -R_P [B]x, and the
// step does not depend on where W is.
//
// Residuals (6 n + 6), scaled as the planar core's (pcr/shooting.hpp): lengths by L (the mean
// rod length at q = 0), forces by F = EI / L^2 (mean EI), moments by F L.
//   per rod, tip position - (p_P + R_P B_i)                                   (3, / L)
//   per clamped rod, vee(E - E^T) / 2 with E = R_target^T R_tip and
//     R_target = R_P rotation_of(tip_orientation): sin(angle) times the axis of the rotation
//     that takes the target to the tip, in the target frame (3, rad); smooth everywhere, and the
//     sign of the tip's quaternion (either one for a rotation) does not matter
//   per spherical rod, the tip moment m(L)                                    (3, / F L)
//   platform force: sum n_i(L) - m_P g - f_ext                                (3, / F)
//   platform moment about its origin:
//     sum (R_P B_i x n_i(L) + m_i(L)) - (R_P c) x m_P g - m_ext               (3, / F L)
// n_i(L), m_i(L) is what the platform exerts on rod i (the rod's sign convention), so the rods
// exert -n_i(L), -m_i(L) on the platform, and the last two rows are its equilibrium.
//
// The Jacobian is exact for the discrete (RK4) model: the rods' variational sensitivities
// (integrate_spatial_rod_with_sensitivity) for the wrench columns, closed forms for the pose.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "pcr/shooting.hpp"
#include "pcr/solver.hpp"
#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/spatial/quaternion.hpp"
#include "pcr/spatial/rigid_fit.hpp"
#include "pcr/spatial/robot.hpp"

namespace pcr {

inline constexpr int kMaxSpatialUnknowns = 6 * kMaxSpatialRods + 6;

using SpatialJointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxSpatialRods, 1>;
using SpatialVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxSpatialUnknowns, 1>;
template <class T>
using SpatialResidualVector = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, kMaxSpatialUnknowns, 1>;
using SpatialJacobian = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0,
                                      kMaxSpatialUnknowns, kMaxSpatialUnknowns>;
/// d residual / d q (scaled residual per metre of each joint).
using SpatialInputJacobian =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxSpatialUnknowns, kMaxSpatialRods>;

/// A force (N) and a moment (N m), in W.
template <class T>
struct SpatialWrench {
  Vector3<T> force = Vector3<T>::Zero();
  Vector3<T> moment = Vector3<T>::Zero();
};

/// Physical values of every shooting unknown and input.
template <class T>
struct SpatialShootingPoint {
  std::array<T, kMaxSpatialRods> q{};                        ///< joint values (m)
  SpatialPose<T> pose;                                       ///< platform pose ^W T_P
  std::array<SpatialWrench<T>, kMaxSpatialRods> wrenches{};  ///< proximal (n, m)(0) of each rod
};

/// The unit quaternion of the rotation vector v (rad): exp(v / 2), with the series near zero.
template <class T>
Vector4<T> quaternion_exp(const Vector3<T>& v) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T angle2 = v.squaredNorm();
  Vector4<T> h;
  if (scalar_value(angle2) < 1e-12) {
    // cos(a/2) and sin(a/2)/a to within rounding for a < 1e-6.
    h << T(1) - angle2 / T(8), T(0.5) * v - (angle2 / T(48)) * v;
    return h;
  }
  const T angle = sqrt(angle2);
  h << cos(angle / T(2)), (sin(angle / T(2)) / angle) * v;
  return h;
}

/// [v]x, the cross-product matrix.
template <class T>
Matrix3<T> cross_matrix(const Vector3<T>& v) {
  Matrix3<T> m;
  m << T(0), -v.z(), v.y(), v.z(), T(0), -v.x(), -v.y(), v.x(), T(0);
  return m;
}

/// The clamp's orientation mismatch vee(E - E^T) / 2, E = target^T tip (see the header).
template <class T>
Vector3<T> orientation_mismatch(const Matrix3<T>& target, const Matrix3<T>& tip) {
  const Matrix3<T> E = target.transpose() * tip;
  return T(0.5) * Vector3<T>(E(2, 1) - E(1, 2), E(0, 2) - E(2, 0), E(1, 0) - E(0, 1));
}

/// Reference magnitudes of the scaled problem: the mean rod length at q = 0 and the mean EI.
inline ShootingScale spatial_shooting_scale(const SpatialRobotParams<double>& robot) {
  return mean_rod_scale(robot.num_rods,
                        [&](int i) -> const SpatialRod<double>& { return robot.limb(i).rod; });
}

/// Rod i's proximal state: at its hole (or moved clamp), in its base frame, the wrench unknown.
template <class T>
SpatialRodState<T> spatial_proximal_state(const SpatialLimbParams<T>& limb, const T& q,
                                          const SpatialWrench<T>& wrench) {
  SpatialRodState<T> state;
  state.position = limb.proximal_position(q);
  state.orientation = limb.base_orientation;
  state.force = wrench.force;
  state.moment = wrench.moment;
  return state;
}

/// The scaled residual (6 n + 6, see the header) from the rods' tip states, however they were
/// integrated (RK4 here, CVODE in the tests' reference).
template <class T>
void spatial_residual_from_tips(const SpatialRobotParams<T>& robot,
                                const SpatialShootingPoint<T>& point, const ShootingScale& scale,
                                const SpatialRodState<T>* tips,
                                SpatialResidualVector<T>& residual) {
  const int n = robot.num_rods;
  residual.resize(6 * n + 6);
  const T inv_length = T(1.0 / scale.length), inv_force = T(1.0 / scale.force);
  const T inv_moment = T(1.0 / scale.moment());
  const Matrix3<T> R_P = point.pose.rotation();
  const Vector3<T> weight = robot.platform_mass * robot.gravity;
  Vector3<T> force_sum = -weight - robot.external_force;
  Vector3<T> moment_sum =
      -(R_P * robot.platform_centre_of_mass).cross(weight) - robot.external_moment;
  for (int i = 0; i < n; ++i) {
    const SpatialLimbParams<T>& limb = robot.limb(i);
    const SpatialRodState<T>& tip = tips[i];
    const Vector3<T> arm = R_P * limb.B;
    residual.template segment<3>(6 * i) = (tip.position - (point.pose.position + arm)) * inv_length;
    if (limb.attachment == SpatialAttachment::kClamped) {
      residual.template segment<3>(6 * i + 3) =
          orientation_mismatch<T>(R_P * rotation_of(limb.tip_orientation), tip.rotation());
    } else {
      residual.template segment<3>(6 * i + 3) = tip.moment * inv_moment;
    }
    force_sum += tip.force;
    moment_sum += arm.cross(tip.force) + tip.moment;
  }
  residual.template segment<3>(6 * n) = force_sum * inv_force;
  residual.template segment<3>(6 * n + 3) = moment_sum * inv_moment;
}

namespace internal {

/// The 3 x 4 map dh -> omega, the body-frame turn of rotation_of(h) (dR = R [omega]x):
/// omega = 2 vec(conj(h) (x) dh) / |h|^2 (the rod's tangents use the same formula).
inline Eigen::Matrix<double, 3, 4> body_turn_of_quaternion(const Vector4<double>& h) {
  const double w = h[0], x = h[1], y = h[2], z = h[3];
  const double k = 2.0 / h.squaredNorm();
  Eigen::Matrix<double, 3, 4> m;
  m << -x, w, z, -y,  //
      -y, -z, w, x,   //
      -z, y, -x, w;
  return k * m;
}

/// d orientation_mismatch / d omega for a turn omega of the tip in its own frame
/// (dR_tip = R_tip [omega]x): vee of the skew part of E [omega]x is (tr(E) I - E^T) omega / 2.
inline Matrix3<double> mismatch_per_tip_turn(const Matrix3<double>& E) {
  return 0.5 * (E.trace() * Matrix3<double>::Identity() - E.transpose());
}

}  // namespace internal

/// The pose columns of the scaled Jacobian, d residual / d (p / L, delta) ((6 n + 6) x 6), in
/// closed form from the rods' tip states (tip_of(i)): the forward problem's last six columns and
/// the inverse problem's d residual / d pose, for its predictor.
template <class TipOf>
void spatial_pose_columns(const SpatialRobotParams<double>& robot,
                          const SpatialShootingPoint<double>& point, const ShootingScale& scale,
                          TipOf&& tip_of, Eigen::Ref<Eigen::MatrixXd> D) {
  const int n = robot.num_rods;
  const int balance = 6 * n;
  D.setZero();
  const Matrix3<double> R_P = point.pose.rotation();
  const Matrix3<double> I = Matrix3<double>::Identity();
  for (int i = 0; i < n; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    const SpatialRodState<double>& tip = tip_of(i);
    const int w = 6 * i;
    D.block<3, 3>(w, 0) = -I;
    // d (-R_P exp([delta]x) B) = R_P [B]x delta.
    D.block<3, 3>(w, 3) = R_P * cross_matrix(limb.B) / scale.length;
    if (limb.attachment == SpatialAttachment::kClamped) {
      const Matrix3<double> R_B = rotation_of(limb.tip_orientation);
      const Matrix3<double> E = (R_P * R_B).transpose() * tip.rotation();
      // R_target turns by R_B^T delta in its own frame: dE = -[R_B^T delta]x E, and the vee of
      // the skew part of -[b]x E is -(tr(E) I - E) b / 2.
      D.block<3, 3>(w + 3, 3) = -0.5 * (E.trace() * I - E) * R_B.transpose();
    }
    // d (R_P B x n) / d delta = [n]x R_P [B]x.
    D.block<3, 3>(balance + 3, 3) +=
        cross_matrix(tip.force) * R_P * cross_matrix(limb.B) / scale.moment();
  }
  // d (-(R_P c) x m g) / d delta = -[m g]x R_P [c]x.
  const Vector3<double> weight = robot.platform_mass * robot.gravity;
  D.block<3, 3>(balance + 3, 3) -=
      cross_matrix(weight) * R_P * cross_matrix(robot.platform_centre_of_mass) / scale.moment();
}

/// The scaled Jacobian (6 n + 6 square) w.r.t. the scaled unknowns: the wrench columns
/// (n / F, m / (F L)) from the tips' sensitivities, the pose columns (p / L, delta) in closed form.
inline void spatial_jacobian_from_tips(const SpatialRobotParams<double>& robot,
                                       const SpatialShootingPoint<double>& point,
                                       const ShootingScale& scale,
                                       const SpatialRodTip<double>* tips, SpatialJacobian& J) {
  using Index = SpatialRodIndex;
  const int n = robot.num_rods;
  const int pose = 6 * n;
  J.resize(6 * n + 6, 6 * n + 6);
  const Matrix3<double> R_P = point.pose.rotation();
  Eigen::Matrix<double, 1, 6> to_scaled;
  to_scaled << scale.force, scale.force, scale.force, scale.moment(), scale.moment(),
      scale.moment();
  J.leftCols(pose).setZero();
  for (int i = 0; i < n; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    const SpatialRodState<double>& tip = tips[i].state;
    // d tip / d (scaled wrench).
    const SpatialRodSensitivity<double> S =
        tips[i].sensitivity.array().rowwise() * to_scaled.array();
    const Vector3<double> arm = R_P * limb.B;
    const int w = 6 * i;
    J.block<3, 6>(w, w) = S.middleRows<3>(Index::kPosition) / scale.length;
    if (limb.attachment == SpatialAttachment::kClamped) {
      const Matrix3<double> E =
          (R_P * rotation_of(limb.tip_orientation)).transpose() * tip.rotation();
      J.block<3, 6>(w + 3, w) = internal::mismatch_per_tip_turn(E) *
                                internal::body_turn_of_quaternion(tip.orientation) *
                                S.middleRows<4>(Index::kOrientation);
    } else {
      J.block<3, 6>(w + 3, w) = S.middleRows<3>(Index::kMoment) / scale.moment();
    }
    J.block<3, 6>(pose, w) = S.middleRows<3>(Index::kForce) / scale.force;
    J.block<3, 6>(pose + 3, w) =
        (cross_matrix(arm) * S.middleRows<3>(Index::kForce) + S.middleRows<3>(Index::kMoment)) /
        scale.moment();
  }
  spatial_pose_columns(
      robot, point, scale, [&](int i) -> const SpatialRodState<double>& { return tips[i].state; },
      J.middleCols(pose, 6));
}

/// d residual / d q_i (scaled residual per metre) from rod i's tip state. A translated clamp moves
/// the whole rod rigidly. A rod pushed through its hole grows at its tip by the rod's equations'
/// right-hand side there, y'(L): the derivative of the exact model, which that of the discrete
/// RK4 map differs from by RK4's own error (a predictor's direction, not a Newton Jacobian).
inline void spatial_input_column(const SpatialRobotParams<double>& robot,
                                 const SpatialShootingPoint<double>& point,
                                 const ShootingScale& scale, int i,
                                 const SpatialRodState<double>& tip,
                                 Eigen::Ref<SpatialVector> column) {
  using Index = SpatialRodIndex;
  const int n = robot.num_rods;
  column.setZero();
  const SpatialLimbParams<double>& limb = robot.limb(i);
  if (limb.actuation == SpatialActuation::kTranslatedClamp) {
    column.segment<3>(6 * i) = limb.actuator_direction / scale.length;
    return;
  }
  const internal::SpatialRodLaw<double> law(limb.rod_at(point.q[i]), robot.gravity);
  internal::SpatialRodSlope<double> slope;
  const SpatialRodVector<double> y = tip.vector();
  slope.evaluate(law, y.data());
  const Vector3<double> dp(slope.dy[Index::kPosition], slope.dy[Index::kPosition + 1],
                           slope.dy[Index::kPosition + 2]);
  const Vector3<double> dn(slope.dy[Index::kForce], slope.dy[Index::kForce + 1],
                           slope.dy[Index::kForce + 2]);
  const Vector3<double> dm(slope.dy[Index::kMoment], slope.dy[Index::kMoment + 1],
                           slope.dy[Index::kMoment + 2]);
  column.segment<3>(6 * i) = dp / scale.length;
  if (limb.attachment == SpatialAttachment::kClamped) {
    const Matrix3<double> E =
        (point.pose.rotation() * rotation_of(limb.tip_orientation)).transpose() * tip.rotation();
    const Vector3<double> u(2 * slope.half_u[0], 2 * slope.half_u[1], 2 * slope.half_u[2]);
    column.segment<3>(6 * i + 3) = internal::mismatch_per_tip_turn(E) * u;
  } else {
    column.segment<3>(6 * i + 3) = dm / scale.moment();
  }
  const Vector3<double> arm = point.pose.rotation() * limb.B;
  column.segment<3>(6 * n) = dn / scale.force;
  column.segment<3>(6 * n + 3) = (arm.cross(dn) + dm) / scale.moment();
}

/// Evaluates the scaled residual at a point with every rod integrated in `rod_steps` RK4 steps;
/// with `jacobian`, also its exact Jacobian w.r.t. the scaled unknowns; with `tips` (n entries),
/// also the rods' tip states.
inline void spatial_residual(const SpatialRobotParams<double>& robot,
                             const SpatialShootingPoint<double>& point, const ShootingScale& scale,
                             int rod_steps, SpatialResidualVector<double>& residual,
                             SpatialJacobian* jacobian = nullptr,
                             SpatialRodState<double>* tips_out = nullptr) {
  const int n = robot.num_rods;
  SpatialRodTip<double> tips[kMaxSpatialRods];
  SpatialRodState<double> states[kMaxSpatialRods], bases[kMaxSpatialRods];
  SpatialRod<double> rods[kMaxSpatialRods];
  for (int i = 0; i < n; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    bases[i] = spatial_proximal_state(limb, point.q[i], point.wrenches[i]);
    rods[i] = limb.rod_at(point.q[i]);
    if (jacobian) {
      tips[i] = integrate_spatial_rod_with_sensitivity(bases[i], rods[i], robot.gravity, rod_steps);
      states[i] = tips[i].state;
    }
  }
  if (!jacobian) integrate_spatial_rods(bases, rods, n, robot.gravity, rod_steps, states);
  spatial_residual_from_tips(robot, point, scale, states, residual);
  if (jacobian) spatial_jacobian_from_tips(robot, point, scale, tips, *jacobian);
  if (tips_out) std::copy(states, states + n, tips_out);
}

/// The straight-rod guess at q: every rod straight from its proximal end along its base
/// tangent, the platform pose the rigid fit of its attachments B_i to those straight tips
/// (fit_rigid_motion; for n < 3 rods or collinear attachments, the identity orientation and the
/// centroids matched), no wrenches.
inline SpatialShootingPoint<double> straight_rods_guess(const SpatialRobotParams<double>& robot,
                                                        const SpatialJointVector& q) {
  const int n = robot.num_rods;
  SpatialShootingPoint<double> point;
  Vector3<double> attachments[kMaxSpatialRods], tips[kMaxSpatialRods];
  for (int i = 0; i < n; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    point.q[i] = q(i);
    attachments[i] = limb.B;
    tips[i] = limb.proximal_position(q(i)) +
              limb.rod_at(q(i)).length * rotation_of(limb.base_orientation).col(2);
  }
  point.pose = fit_rigid_motion(attachments, tips, n);
  return point;
}

/// What a solve leaves for the next one warm-started from it: the factorised Jacobian and
/// d residual / d q at the solution, for a tangent predictor.
struct SpatialWarmStart {
  Eigen::PartialPivLU<SpatialJacobian> lu;
  SpatialInputJacobian input_jacobian;
  bool valid = false;
};

struct SpatialForwardSolution {
  /// The platform pose ^W T_P (orientation a unit quaternion).
  SpatialPose<double> pose;
  /// The joints of the returned configuration (m): the requested ones when converged; on a
  /// failure, those of the last point solved on the way (summary.path_fraction says where).
  SpatialJointVector q;
  std::array<SpatialWrench<double>, kMaxSpatialRods> wrenches{};  ///< (n, m)(0) of each rod, in W
  SolverSummary summary;
  SpatialWarmStart warm;  ///< for a warm start from this solution
};

struct SpatialInverseSolution {
  /// The pose of the returned configuration: the requested one when converged; on a failure,
  /// that of the last point solved on the way (summary.path_fraction says where).
  SpatialPose<double> pose;
  SpatialJointVector q;                                           ///< joint values (m)
  std::array<SpatialWrench<double>, kMaxSpatialRods> wrenches{};  ///< (n, m)(0) of each rod, in W
  SolverSummary summary;
  /// For a warm start from this solution: the inverse problem's factorised Jacobian, and
  /// d residual / d pose (6 columns) for the predictor.
  SpatialWarmStart warm;
};

}  // namespace pcr
