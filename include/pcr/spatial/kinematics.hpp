#pragma once
// Forward kinematics of a spatial parallel continuum robot (pcr/spatial/robot.hpp) by Newton
// shooting, and inverse kinematics of a six-rod one, the spatial counterparts of
// pcr/kinematics.hpp. Header-only, Eigen only, no heap, no exceptions, a bounded number of
// iterations; numerical outcomes are reported in a SolverSummary.
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
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "pcr/internal/rod_step_ladder.hpp"
#include "pcr/shooting.hpp"
#include "pcr/solver.hpp"
#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/spatial/quaternion.hpp"
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

/// A rigid pose: ^W T_P.
template <class T>
struct SpatialPose {
  Vector3<T> position = Vector3<T>::Zero();           ///< m, in W
  Vector4<T> orientation = identity_quaternion<T>();  ///< (w, x, y, z), P -> W
  Matrix3<T> rotation() const { return rotation_of(orientation); }
};

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
  double length = 0, ei = 0;
  for (int i = 0; i < robot.num_rods; ++i) {
    length += robot.limb(i).rod.length;
    ei += robot.limb(i).rod.bending_stiffness();
  }
  length /= robot.num_rods;
  ei /= robot.num_rods;
  return ShootingScale{length, ei / (length * length)};
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
/// tangent, the platform pose the rigid (least-squares, Kabsch) fit of its attachments B_i to
/// those straight tips, no wrenches. For n < 3 rods (or collinear attachments) the fit keeps the
/// platform's orientation the identity and places its origin at the tips' centroid less the
/// attachments'.
inline SpatialShootingPoint<double> straight_rods_guess(const SpatialRobotParams<double>& robot,
                                                        const SpatialJointVector& q) {
  const int n = robot.num_rods;
  SpatialShootingPoint<double> point;
  Vector3<double> tips[kMaxSpatialRods];
  Vector3<double> tip_centroid = Vector3<double>::Zero(), b_centroid = Vector3<double>::Zero();
  for (int i = 0; i < n; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    point.q[i] = q(i);
    tips[i] = limb.proximal_position(q(i)) +
              limb.rod_at(q(i)).length * rotation_of(limb.base_orientation).col(2);
    tip_centroid += tips[i] / n;
    b_centroid += limb.B / n;
  }
  Matrix3<double> H = Matrix3<double>::Zero();
  for (int i = 0; i < n; ++i) {
    H += (robot.limb(i).B - b_centroid) * (tips[i] - tip_centroid).transpose();
  }
  Matrix3<double> R = Matrix3<double>::Identity();
  const Eigen::JacobiSVD<Matrix3<double>> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (n >= 3 && svd.singularValues()(1) > 1e-9 * svd.singularValues()(0)) {
    Matrix3<double> D = Matrix3<double>::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    R = svd.matrixV() * D * svd.matrixU().transpose();
  }
  point.pose.orientation = quaternion_of(R);
  point.pose.position = tip_centroid - R * b_centroid;
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

namespace internal {

/// The largest |entry|, NaN when any is not finite (lpNorm<Infinity> can skip a NaN).
template <class Derived>
double spatial_max_norm(const Eigen::MatrixBase<Derived>& r) {
  return r.allFinite() ? r.template lpNorm<Eigen::Infinity>()
                       : std::numeric_limits<double>::quiet_NaN();
}

/// Whether a step dz moves a problem's outputs (Problem::output_change) by at most `share` of the
/// accuracy targets.
template <class Problem>
bool output_change_within(const Problem& problem, const SpatialVector& dz,
                          const SolverOptions& options, double share) {
  double position, angle;
  problem.output_change(dz, position, angle);
  return position <= share * options.position_accuracy && angle <= share * options.angle_accuracy;
}

/// The forward shooting problem at fixed joints, on the manifold of the platform's orientation.
class SpatialForwardProblem {
 public:
  SpatialForwardProblem(const SpatialRobotParams<double>& robot, int rod_steps)
      : robot_(robot),
        scale_(spatial_shooting_scale(robot)),
        n_(robot.num_rods),
        steps_(rod_steps) {}

  int size() const { return 6 * n_ + 6; }
  int rod_steps() const { return steps_; }
  void set_rod_steps(int steps) { steps_ = steps; }
  const ShootingScale& scale() const { return scale_; }
  const SpatialRobotParams<double>& robot() const { return robot_; }

  /// x (+) dz: wrenches and position added (dz scaled), the orientation turned on the right.
  SpatialShootingPoint<double> retract(const SpatialShootingPoint<double>& x,
                                       const SpatialVector& dz) const {
    SpatialShootingPoint<double> out = x;
    for (int i = 0; i < n_; ++i) {
      out.wrenches[i].force += dz.segment<3>(6 * i) * scale_.force;
      out.wrenches[i].moment += dz.segment<3>(6 * i + 3) * scale_.moment();
    }
    out.pose.position += dz.segment<3>(6 * n_) * scale_.length;
    const Vector4<double> h = quaternion_product<double>(
        x.pose.orientation, quaternion_exp<double>(dz.segment<3>(6 * n_ + 3)));
    out.pose.orientation = h / h.norm();
    return out;
  }

  void evaluate(const SpatialShootingPoint<double>& x, SpatialVector& r, SpatialJacobian* J) const {
    SpatialResidualVector<double> residual;
    spatial_residual(robot_, x, scale_, steps_, residual, J, tips_);
    r = residual;
  }

  /// d residual / d q at the point last evaluated (its tips), n columns.
  SpatialInputJacobian input_jacobian(const SpatialShootingPoint<double>& x) const {
    SpatialInputJacobian D(size(), n_);
    SpatialVector column(size());
    for (int i = 0; i < n_; ++i) {
      spatial_input_column(robot_, x, scale_, i, tips_[i], column);
      D.col(i) = column;
    }
    return D;
  }

  /// How far a step dz moves the platform: its largest coordinate (m) and turn (rad).
  void output_change(const SpatialVector& dz, double& position, double& angle) const {
    position = spatial_max_norm(dz.segment(6 * n_, 3)) * scale_.length;
    angle = spatial_max_norm(dz.segment(6 * n_ + 3, 3));
  }

 private:
  const SpatialRobotParams<double>& robot_;
  ShootingScale scale_;
  int n_;
  int steps_;
  mutable SpatialRodState<double> tips_[kMaxSpatialRods];
};

/// Damped Newton on the manifold from x (updated in place), as pcr::internal::newton_solve: a
/// backtracking line search on |r|^2, chord steps with the last factorisation while they
/// contract by 10 or more, and the simplified-Newton stopping rule (the last chord step taken
/// unevaluated when it moves the pose by less than chord_output_share of the accuracy targets).
/// A separate loop from the planar one: that one's matrices are sized for 6 planar limbs
/// (21 unknowns), these for 8 spatial rods (54), and its steps add, these retract.
/// With `carried` (a factorised Jacobian of a nearby solution, as a warm start keeps), the first
/// steps are chord steps with it: a warm solve then evaluates residuals only (a fifth of the cost
/// of one with the rods' tangents) unless the chord steps stop contracting.
/// On return, `lu` holds the factorisation of the last Jacobian evaluated (or the carried one).
/// Problem: size(), retract(x, dz), evaluate(x, r, J*), output_change(dz, position, angle)
/// (SpatialForwardProblem, SpatialInverseProblem).
template <class Problem>
SolveStatus spatial_newton(Problem& problem, SpatialShootingPoint<double>& x,
                           const SolverOptions& options, int max_iterations, SolverSummary& summary,
                           Eigen::PartialPivLU<SpatialJacobian>& lu, double& initial_norm,
                           double& final_norm,
                           const Eigen::PartialPivLU<SpatialJacobian>* carried = nullptr) {
  constexpr double kWarmNorm = 1e-2;
  constexpr double kChordContraction = 0.1;
  constexpr double kRoundingFloor = 1e-9;
  SpatialVector r, r_trial, step;
  SpatialJacobian J, J_trial;
  const bool chord = carried != nullptr && carried->rows() == problem.size();
  problem.evaluate(x, r, chord ? nullptr : &J);
  ++summary.residual_evaluations;
  double norm = spatial_max_norm(r);
  initial_norm = final_norm = norm;
  if (!std::isfinite(norm)) return SolveStatus::kNonFinite;
  const bool chord_start = chord && norm <= kWarmNorm;
  if (chord && !chord_start) {  // too far for chord steps: Newton from here
    problem.evaluate(x, r, &J);
    ++summary.residual_evaluations;
  }
  if (chord_start) lu = *carried;
  bool factorised = chord_start;  // lu holds the factorisation of J (or the carried one)
  bool lu_at_x = !chord_start;    // J (and lu once factorised) is the Jacobian at x
  bool damped = false;            // J is singular: Levenberg steps instead of Newton's
  for (int iter = 0; iter <= max_iterations; ++iter) {
    if (norm <= options.tolerance) {
      // Callers keep the factorisation (warm starts, the error estimate): J is the one at x.
      if (!factorised) lu.compute(J);
      return SolveStatus::kConverged;
    }
    if (iter == max_iterations) break;
    ++summary.iterations;
    if (!factorised) {
      lu.compute(J);
      factorised = true;
      damped = !(lu.rcond() > 1e-14);
    }
    if (damped) {
      // A singular Jacobian, as at the straight-rod guess of rods that all leave the base in
      // one direction: their axial forces move no tip of a straight, unloaded inextensible rod
      // and enter the platform's balance through fewer than 6 directions. A Levenberg step
      // (J^T J + mu I) dz = -J^T r with a tiny mu is the least-squares step of least norm: it
      // bends the rods, after which the axial forces act on the tips and J is regular.
      SpatialJacobian normal = J.transpose() * J;
      normal.diagonal().array() += 1e-10 * normal.diagonal().maxCoeff();
      step = -Eigen::PartialPivLU<SpatialJacobian>(normal).solve(J.transpose() * r);
      if (!step.allFinite()) return SolveStatus::kSingular;
    } else {
      step = -lu.solve(r);
    }
    const bool warm = norm <= kWarmNorm;
    const double norm2 = r.squaredNorm();
    double t = 1.0;
    bool accepted = false, trial_has_jacobian = false;
    SpatialShootingPoint<double> trial;
    for (int ls = 0; ls <= options.max_line_search; ++ls, t *= 0.5) {
      trial = problem.retract(x, t * step);
      // The Jacobian with the full step's residual (the usual accepted trial); a shortened
      // step's trials take residuals alone, their Jacobian once accepted.
      trial_has_jacobian = !warm && ls == 0;
      problem.evaluate(trial, r_trial, trial_has_jacobian ? &J_trial : nullptr);
      ++summary.residual_evaluations;
      const double trial2 = r_trial.squaredNorm();
      if (std::isfinite(trial2) && trial2 <= (1.0 - 1e-4 * t) * norm2) {
        accepted = true;
        break;
      }
      if (std::isfinite(trial2) && ls == 0 && spatial_max_norm(r_trial) <= options.tolerance) {
        accepted = true;
        break;
      }
      if (!lu_at_x) break;  // a chord step that fails: refresh the Jacobian instead of halving
    }
    if (!accepted && !lu_at_x) {
      problem.evaluate(x, r, &J);
      ++summary.residual_evaluations;
      norm = spatial_max_norm(r);
      factorised = false;
      lu_at_x = true;
      continue;
    }
    if (!accepted && norm <= kRoundingFloor && step.lpNorm<Eigen::Infinity>() <= kRoundingFloor) {
      return SolveStatus::kConverged;  // within rounding of a solution
    }
    if (!accepted) {
      // No descent along the Newton direction, which a nearly singular Jacobian makes huge (rods
      // nearly straight and parallel: their axial forces barely act). Levenberg steps
      // (J^T J + mu I) dz = -J^T r with mu growing from small to large turn it towards the
      // gradient, which descends for a small enough step.
      SpatialJacobian normal = J.transpose() * J;
      const SpatialVector gradient = J.transpose() * r;
      const double largest = normal.diagonal().maxCoeff();
      for (double mu = 1e-6; mu <= 1e2 && !accepted; mu *= 100) {
        SpatialJacobian damped_normal = normal;
        damped_normal.diagonal().array() += mu * largest;
        step = -Eigen::PartialPivLU<SpatialJacobian>(damped_normal).solve(gradient);
        trial = problem.retract(x, step);
        problem.evaluate(trial, r_trial, warm ? nullptr : &J_trial);
        trial_has_jacobian = !warm;
        ++summary.residual_evaluations;
        const double trial2 = r_trial.squaredNorm();
        accepted = std::isfinite(trial2) && trial2 <= (1.0 - 1e-4) * norm2;
      }
      t = 0.0;  // not a full Newton step: no chord from here
    }
    if (!accepted) {
      const SpatialVector gradient = J.transpose() * r;
      return gradient.norm() <= 1e-6 * J.norm() * r.norm() || lu.rcond() < 1e-8
                 ? SolveStatus::kSingular
                 : SolveStatus::kMaxIterations;
    }
    const double trial_norm = spatial_max_norm(r_trial);
    const double contraction = trial_norm / norm;
    x = trial;
    r = r_trial;
    norm = trial_norm;
    final_norm = norm;
    if (trial_has_jacobian) {
      J = J_trial;
      factorised = false;
      lu_at_x = true;
    } else if (!damped &&
               ((t == 1.0 && contraction <= kChordContraction) || norm <= options.tolerance)) {
      lu_at_x = false;  // chord from here with the current factorisation
      if (norm <= options.tolerance) continue;
      step = -lu.solve(r);
      if (contraction * norm <= options.tolerance ||
          output_change_within(problem, contraction * step, options, options.chord_output_share)) {
        x = problem.retract(x, step);
        ++summary.iterations;
        final_norm = contraction * norm;  // predicted
        return SolveStatus::kConverged;
      }
    } else {
      problem.evaluate(x, r, &J);
      ++summary.residual_evaluations;
      norm = spatial_max_norm(r);
      final_norm = norm;
      factorised = false;
      lu_at_x = true;
    }
  }
  return SolveStatus::kMaxIterations;
}

/// Estimates the discretisation error of a converged solution x of the N-step model (as the
/// planar core's estimate_discretisation_error: RK4's residual error at N/2 steps is f = 2^4
/// times that at N, so r_{N/2}(x) = (f - 1) e_N and the exact model's solution lies at
/// x - J^-1 e_N), stores it in the summary and returns its ratio to the accuracy targets. `lu`:
/// a factorised Jacobian near x (its direction matters, not its last digits).
template <class Problem>
double spatial_discretisation_error(Problem& problem, const SpatialShootingPoint<double>& x,
                                    const Eigen::PartialPivLU<SpatialJacobian>& lu,
                                    const SolverOptions& options, SolverSummary& summary) {
  const int steps = problem.rod_steps();
  const int half = std::max(1, steps / 2);
  SpatialVector r_half;
  problem.set_rod_steps(half);
  problem.evaluate(x, r_half, nullptr);
  problem.set_rod_steps(steps);
  ++summary.residual_evaluations;  // at half the steps: half the cost of the others
  const double f = std::pow(double(steps) / half, 4.0);
  const SpatialVector dz = lu.solve(r_half / (f - 1.0));
  problem.output_change(dz, summary.position_error_estimate, summary.angle_error_estimate);
  const double position = summary.position_error_estimate / options.position_accuracy;
  const double angle = summary.angle_error_estimate / options.angle_accuracy;
  return std::isfinite(position) && std::isfinite(angle) ? std::max(position, angle)
                                                         : std::numeric_limits<double>::infinity();
}

/// Solves a converged solution x again (from itself, with chord steps) at the RK4 step count its
/// estimated discretisation error calls for (pcr/internal/rod_step_ladder.hpp), until the estimate
/// meets the targets; near a fold, where the whole change of model is too much for Newton, one
/// rung at a time. With a fixed options.rod_steps, nothing to do. `lu` as for spatial_newton.
template <class Problem>
SolveStatus spatial_refine_rod_steps(Problem& problem, SpatialShootingPoint<double>& x,
                                     Eigen::PartialPivLU<SpatialJacobian>& lu,
                                     const SolverOptions& options, SolverSummary& summary,
                                     SolveStatus status) {
  double initial_norm, final_norm;
  for (int pass = 0; status == SolveStatus::kConverged && options.rod_steps <= 0; ++pass) {
    const double ratio = spatial_discretisation_error(problem, x, lu, options, summary);
    const int start = problem.rod_steps();
    const int needed = rod_steps_for_error(options, start, ratio);
    if (needed == start || pass == 4) break;
    const SpatialShootingPoint<double> x_start = x;
    const Eigen::PartialPivLU<SpatialJacobian> carried = lu;
    problem.set_rod_steps(needed);
    status = spatial_newton(problem, x, options, options.max_iterations, summary, lu, initial_norm,
                            final_norm, &carried);
    if (status != SolveStatus::kConverged) {
      x = x_start;
      for (int steps = start; steps != needed;) {
        steps = rod_steps_rung_towards(options, steps, needed);
        problem.set_rod_steps(steps);
        const Eigen::PartialPivLU<SpatialJacobian> rung_carried = lu;
        status = spatial_newton(problem, x, options, options.max_iterations, summary, lu,
                                initial_norm, final_norm, &rung_carried);
        if (status != SolveStatus::kConverged) break;
      }
    }
    if (status == SolveStatus::kConverged) summary.final_residual_norm = final_norm;
  }
  return status;
}

/// Solves at joints q1 from the solution x at q0 (x updated): the whole step first, predicted
/// along the tangent when `warm` holds the Jacobian at x, then, if that fails and
/// options.continuation, natural continuation in joint space with step halving (each step
/// predicted along the tangent at the last solved point). On a failure x is the last solved
/// point and summary.path_fraction says where it lies.
inline SolveStatus spatial_solve_path(SpatialForwardProblem& problem,
                                      SpatialShootingPoint<double>& x, const SpatialJointVector& q0,
                                      const SpatialJointVector& q1, SpatialWarmStart& warm,
                                      const SolverOptions& options, SolverSummary& summary) {
  const int n = problem.robot().num_rods;
  const SpatialJointVector dq = q1 - q0;
  const auto set_q = [&](SpatialShootingPoint<double>& p, const SpatialJointVector& q) {
    for (int i = 0; i < n; ++i) p.q[i] = q(i);
  };
  const auto predict = [&](const SpatialShootingPoint<double>& from, const SpatialJointVector& step,
                           SpatialShootingPoint<double>& to) {
    to = from;
    if (warm.valid && warm.lu.rows() == problem.size()) {
      const SpatialVector dz = -warm.lu.solve(warm.input_jacobian * step);
      if (dz.allFinite()) to = problem.retract(from, dz);
    }
  };
  // After a converged solve: the Jacobian there and d r / d q, for the next predictor.
  const auto keep_tangent = [&](const SpatialShootingPoint<double>& at,
                                const Eigen::PartialPivLU<SpatialJacobian>& lu) {
    warm.lu = lu;
    warm.input_jacobian = problem.input_jacobian(at);
    warm.valid = true;
  };
  const SpatialShootingPoint<double> x0 = x;
  double initial_norm, final_norm;
  Eigen::PartialPivLU<SpatialJacobian> lu;
  SpatialShootingPoint<double> trial;
  predict(x0, dq, trial);
  set_q(trial, q1);
  const auto carried = [&] { return warm.valid ? &warm.lu : nullptr; };
  SolveStatus status = spatial_newton(problem, trial, options, options.max_iterations, summary, lu,
                                      initial_norm, final_norm, carried());
  summary.initial_residual_norm = initial_norm;
  summary.final_residual_norm = final_norm;
  if (status == SolveStatus::kConverged) {
    x = trial;
    keep_tangent(x, lu);
    summary.path_fraction = 1.0;
    return status;
  }
  summary.path_fraction = 0.0;
  if (!options.continuation || (dq.array() == 0.0).all()) return status;
  SpatialShootingPoint<double> last = x0;
  double t = 0.0, dt = 0.5;
  while (t < 1.0) {
    if (summary.continuation_steps >= options.max_continuation_steps) {
      status = SolveStatus::kMaxIterations;
      break;
    }
    ++summary.continuation_steps;
    const double t_next = std::min(1.0, t + dt);
    predict(last, (t_next - t) * dq, trial);
    set_q(trial, q0 + t_next * dq);
    status = spatial_newton(problem, trial, options, options.max_continuation_iterations, summary,
                            lu, initial_norm, final_norm, carried());
    if (status == SolveStatus::kConverged) {
      last = trial;
      t = t_next;
      dt = std::min(2.0 * dt, 0.5);
      summary.final_residual_norm = final_norm;
      keep_tangent(last, lu);
      continue;
    }
    dt *= 0.5;
    if (dt < options.min_continuation_step) break;
  }
  x = last;
  summary.path_fraction = t;
  return t >= 1.0 ? SolveStatus::kConverged : status;
}

inline bool spatial_inputs_valid(const SpatialRobotParams<double>& robot,
                                 const SpatialJointVector& q, const SolverOptions& options) {
  return robot.num_rods >= 1 && robot.num_rods <= kMaxSpatialRods && q.size() == robot.num_rods &&
         q.allFinite() && options.is_valid();
}

inline void fill_solution(const SpatialForwardProblem& problem,
                          const SpatialShootingPoint<double>& x, SpatialForwardSolution& out) {
  const int n = problem.robot().num_rods;
  out.pose = x.pose;
  out.q.resize(n);
  for (int i = 0; i < n; ++i) {
    out.q(i) = x.q[i];
    out.wrenches[i] = x.wrenches[i];
  }
  out.summary.rod_steps = problem.rod_steps();
}

}  // namespace internal

/// Forward kinematics warm-started from a previous solution (the normal case in a control loop):
/// its pose and wrenches predicted along the tangent to q, then chord steps with its factorised
/// Jacobian (Newton's when they stop contracting); if that fails, natural continuation from the
/// warm start's q. RK4 steps per rod: options.rod_steps, or, when 0, chosen from the solution's
/// estimated discretisation error (spatial_refine_rod_steps), starting from the warm start's.
inline SpatialForwardSolution spatial_forward_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
    const SpatialForwardSolution& warm_start, const SolverOptions& options = SolverOptions()) {
  SpatialForwardSolution out;
  if (!internal::spatial_inputs_valid(robot, q, options) || warm_start.q.size() != robot.num_rods ||
      !warm_start.q.allFinite()) {
    out.summary.status = SolveStatus::kInvalidInput;
    return out;
  }
  internal::SpatialForwardProblem problem(
      robot, internal::starting_rod_steps(options, warm_start.summary.rod_steps));
  SpatialShootingPoint<double> x;
  x.pose = warm_start.pose;
  for (int i = 0; i < robot.num_rods; ++i) {
    x.q[i] = warm_start.q(i);
    x.wrenches[i] = warm_start.wrenches[i];
  }
  out.warm = warm_start.warm;
  out.summary.status =
      internal::spatial_solve_path(problem, x, warm_start.q, q, out.warm, options, out.summary);
  out.summary.status = internal::spatial_refine_rod_steps(problem, x, out.warm.lu, options,
                                                          out.summary, out.summary.status);
  internal::fill_solution(problem, x, out);
  return out;
}

/// Straight rods are far from most equilibria and near a degenerate point (their axial forces do
/// not act on their tips): Newton's globalised phase from there (line searches, Levenberg steps)
/// takes tens of iterations, where a warm start takes a few. On 12 random robots around the
/// reference, 11 solved from straight rods within 100 iterations, most within 40.
inline constexpr int kColdIterationFactor = 5;

/// Forward kinematics from a cold start: Newton from the straight-rod guess at q
/// (straight_rods_guess); if that fails and options.continuation, the home solution (q = 0, from
/// its straight-rod guess) followed by natural continuation in joint space from 0 to q. Both
/// solves from straight rods have kColdIterationFactor times options.max_iterations.
inline SpatialForwardSolution spatial_forward_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
    const SolverOptions& options = SolverOptions()) {
  SpatialForwardSolution out;
  if (!internal::spatial_inputs_valid(robot, q, options)) {
    out.summary.status = SolveStatus::kInvalidInput;
    return out;
  }
  internal::SpatialForwardProblem problem(robot, internal::starting_rod_steps(options, 0));
  // A cold solve at q, then (if it fails) home and the path from it: both from straight rods, so
  // they are the same solve when q = 0.
  SolverOptions direct = options;
  direct.continuation = false;
  direct.max_iterations = kColdIterationFactor * options.max_iterations;
  SpatialShootingPoint<double> x = straight_rods_guess(robot, q);
  SpatialJointVector from = q;
  out.summary.status =
      internal::spatial_solve_path(problem, x, from, q, out.warm, direct, out.summary);
  const SpatialJointVector home = SpatialJointVector::Zero(robot.num_rods);
  if (!out.summary.converged() && options.continuation && !q.isZero(0.0)) {
    const SolveStatus cold = out.summary.status;
    x = straight_rods_guess(robot, home);
    out.summary.status =
        internal::spatial_solve_path(problem, x, home, home, out.warm, direct, out.summary);
    if (out.summary.converged()) {
      out.summary.status =
          internal::spatial_solve_path(problem, x, home, q, out.warm, options, out.summary);
    } else {
      out.summary.status = cold;
    }
  }
  out.summary.status = internal::spatial_refine_rod_steps(problem, x, out.warm.lu, options,
                                                          out.summary, out.summary.status);
  internal::fill_solution(problem, x, out);
  return out;
}

namespace internal {

/// The inverse shooting problem of a six-rod robot at an imposed platform pose: unknowns each
/// rod's proximal wrench (6) and joint q_i (1, scaled by L), 7 n = 6 n + 6 for n = 6; the residual
/// is the forward one.
class SpatialInverseProblem {
 public:
  SpatialInverseProblem(const SpatialRobotParams<double>& robot, int rod_steps)
      : robot_(robot),
        scale_(spatial_shooting_scale(robot)),
        n_(robot.num_rods),
        steps_(rod_steps) {}

  int size() const { return 7 * n_; }
  int rod_steps() const { return steps_; }
  void set_rod_steps(int steps) { steps_ = steps; }

  SpatialShootingPoint<double> retract(const SpatialShootingPoint<double>& x,
                                       const SpatialVector& dz) const {
    SpatialShootingPoint<double> out = x;
    for (int i = 0; i < n_; ++i) {
      out.wrenches[i].force += dz.segment<3>(6 * i) * scale_.force;
      out.wrenches[i].moment += dz.segment<3>(6 * i + 3) * scale_.moment();
      out.q[i] += dz(6 * n_ + i) * scale_.length;
    }
    return out;
  }

  /// The Jacobian's joint columns are d r / d q (spatial_input_column): exact for translated
  /// clamps, within RK4's error for rods pushed through their holes, which leaves Newton a linear
  /// rate of about that error (1e-9 at 256 steps) instead of a quadratic one.
  void evaluate(const SpatialShootingPoint<double>& x, SpatialVector& r, SpatialJacobian* J) const {
    SpatialResidualVector<double> residual;
    spatial_residual(robot_, x, scale_, steps_, residual, J ? &forward_ : nullptr, tips_);
    r = residual;
    if (!J) return;
    *J = forward_;  // the wrench columns stay; the pose columns become the joints'
    SpatialVector column(size());
    for (int i = 0; i < n_; ++i) {
      spatial_input_column(robot_, x, scale_, i, tips_[i], column);
      J->col(6 * n_ + i) = column * scale_.length;
    }
  }

  /// d residual / d (p / L, delta) of the pose, the input, at the point last evaluated (its tips).
  SpatialInputJacobian pose_jacobian(const SpatialShootingPoint<double>& x) const {
    SpatialInputJacobian D(size(), 6);
    spatial_pose_columns(
        robot_, x, scale_, [&](int i) -> const SpatialRodState<double>& { return tips_[i]; }, D);
    return D;
  }

  /// The scaled pose step from `from` to `to`: (p_to - p_from) / L, and the rotation vector w of
  /// R_from^T R_to (R_to = R_from exp([w]x)), as the forward problem's unknowns step.
  Eigen::Matrix<double, 6, 1> pose_step(const SpatialPose<double>& from,
                                        const SpatialPose<double>& to) const {
    const Eigen::AngleAxisd turn(Eigen::Quaterniond(from.rotation().transpose() * to.rotation()));
    Eigen::Matrix<double, 6, 1> step;
    step << (to.position - from.position) / scale_.length, turn.angle() * turn.axis();
    return step;
  }

  /// How far a step dz moves the joints (m); IK has no angle output.
  void output_change(const SpatialVector& dz, double& position, double& angle) const {
    position = spatial_max_norm(dz.segment(6 * n_, n_)) * scale_.length;
    angle = 0.0;
  }

 private:
  const SpatialRobotParams<double>& robot_;
  ShootingScale scale_;
  int n_;
  int steps_;
  mutable SpatialJacobian forward_;
  mutable SpatialRodState<double> tips_[kMaxSpatialRods];
};

}  // namespace internal

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

namespace internal {

/// Solves the inverse problem at `pose` from the solution x at x.pose (x updated): the whole step
/// first, predicted along the tangent -J^-1 (d r / d pose) d pose when `warm` holds them, with
/// chord steps on its factorisation; on failure (and options.continuation), natural continuation
/// along the straight pose path (a line for the position, a constant-rate turn for the
/// orientation), halving the step on failure. Returns the status and sets summary.path_fraction; x
/// is the last point solved, `warm` what it leaves for the next solve.
inline SolveStatus spatial_inverse_path(SpatialInverseProblem& problem,
                                        SpatialShootingPoint<double>& x,
                                        const SpatialPose<double>& pose, SpatialWarmStart& warm,
                                        const SolverOptions& options, SolverSummary& summary) {
  const SpatialPose<double> start = x.pose;
  const Eigen::Matrix<double, 6, 1> whole = problem.pose_step(start, pose);
  const auto pose_at = [&](double t) {
    if (t == 1.0) return pose;
    SpatialPose<double> at;
    at.position = start.position + t * (pose.position - start.position);
    at.orientation = quaternion_product<double>(start.orientation / start.orientation.norm(),
                                                quaternion_exp<double>(t * whole.tail<3>()));
    return at;
  };
  const auto predict = [&](const SpatialShootingPoint<double>& from, const SpatialPose<double>& to,
                           SpatialShootingPoint<double>& trial) {
    trial = from;
    if (warm.valid && warm.lu.rows() == problem.size() && warm.input_jacobian.cols() == 6) {
      const SpatialVector dz =
          -warm.lu.solve(warm.input_jacobian * problem.pose_step(from.pose, to));
      if (dz.allFinite()) trial = problem.retract(from, dz);
    }
    trial.pose = to;
  };
  Eigen::PartialPivLU<SpatialJacobian> lu;
  double initial_norm, final_norm, t = 0.0, dt = 1.0;
  SolveStatus status = SolveStatus::kMaxIterations;
  while (t < 1.0) {
    const bool first = t == 0.0 && dt == 1.0;
    if (!first) {
      if (!options.continuation || summary.continuation_steps >= options.max_continuation_steps) {
        break;
      }
      ++summary.continuation_steps;
    }
    const double t_next = std::min(1.0, t + dt);
    SpatialShootingPoint<double> trial;
    predict(x, pose_at(t_next), trial);
    status = spatial_newton(problem, trial, options,
                            first ? options.max_iterations : options.max_continuation_iterations,
                            summary, lu, initial_norm, final_norm, warm.valid ? &warm.lu : nullptr);
    if (first) summary.initial_residual_norm = initial_norm;
    if (status == SolveStatus::kConverged) {
      x = trial;
      t = t_next;
      dt = std::min(2.0 * dt, 0.5);
      summary.final_residual_norm = final_norm;
      warm.lu = lu;
      warm.input_jacobian = problem.pose_jacobian(x);
      warm.valid = true;
      continue;
    }
    dt *= 0.5;
    if (dt < options.min_continuation_step) break;
  }
  summary.path_fraction = t;
  return t >= 1.0 ? SolveStatus::kConverged : status;
}

inline bool spatial_pose_valid(const SpatialPose<double>& pose) {
  return pose.position.allFinite() && pose.orientation.allFinite() &&
         pose.orientation.squaredNorm() > 0;
}

template <class Start>
SpatialInverseSolution spatial_inverse_from(const SpatialRobotParams<double>& robot,
                                            const SpatialPose<double>& pose, const Start& start,
                                            const SpatialWarmStart* warm,
                                            const SolverOptions& options) {
  SpatialInverseSolution out;
  const int n = robot.num_rods;
  if (n != 6) {
    out.summary.status = SolveStatus::kUnsupported;
    return out;
  }
  if (!spatial_inputs_valid(robot, start.q, options) || !spatial_pose_valid(pose) ||
      !spatial_pose_valid(start.pose)) {
    out.summary.status = SolveStatus::kInvalidInput;
    return out;
  }
  SpatialInverseProblem problem(robot, starting_rod_steps(options, start.summary.rod_steps));
  SpatialShootingPoint<double> x;
  x.pose = start.pose;
  for (int i = 0; i < n; ++i) {
    x.q[i] = start.q(i);
    x.wrenches[i] = start.wrenches[i];
  }
  if (warm) out.warm = *warm;
  out.summary.status = spatial_inverse_path(problem, x, pose, out.warm, options, out.summary);
  if (out.summary.converged()) {
    out.summary.status =
        spatial_refine_rod_steps(problem, x, out.warm.lu, options, out.summary, out.summary.status);
  }
  out.summary.rod_steps = problem.rod_steps();
  out.pose = x.pose;
  out.q.resize(n);
  for (int i = 0; i < n; ++i) {
    out.q(i) = x.q[i];
    out.wrenches[i] = x.wrenches[i];
  }
  return out;
}

}  // namespace internal

/// Inverse kinematics of a six-rod robot (the square case: 7 n unknowns, 6 n + 6 residuals), from
/// a forward solution near the pose: Newton from its wrenches and joints at the requested pose;
/// on failure (and options.continuation), natural continuation along the straight pose path
/// from the start's pose (position on a line, orientation at a constant rate), halving the step
/// on failure. RK4 steps as spatial_forward_kinematics. Other rod counts:
/// SolveStatus::kUnsupported.
inline SpatialInverseSolution spatial_inverse_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialForwardSolution& start, const SolverOptions& options = SolverOptions()) {
  // The forward solution's factorisation is of another problem: no carried Jacobian.
  return internal::spatial_inverse_from(robot, pose, start, nullptr, options);
}

/// Inverse kinematics warm-started from a previous inverse solution (IK along a path, the normal
/// case in a control loop): its joints and wrenches predicted along the tangent to the pose, then
/// chord steps with its factorised Jacobian; on failure, as from a forward solution.
inline SpatialInverseSolution spatial_inverse_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialInverseSolution& warm_start, const SolverOptions& options = SolverOptions()) {
  return internal::spatial_inverse_from(robot, pose, warm_start, &warm_start.warm, options);
}

}  // namespace pcr
