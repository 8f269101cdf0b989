#pragma once
// Elastic stability of a solved equilibrium of a spatial robot, with the joints held: the spatial
// counterpart of pcr/stability.hpp (Till and Rucker, "Elastic Stability of Cosserat Rods and
// Parallel Continuum Robots", IEEE T-RO 33(3), 2017; docs/stability.md, "Spatial robots").
//
// The equilibrium is a strict local minimum of the potential energy (the rods' elastic energy
// minus the work of the dead loads: the rods' and the platform's weight, the external force) when
//  1. every rod, with the platform held, is stable:
//     - a clamped tip: no conjugate point in (0, L]. The Jacobi matrix
//       d(p, turn)(s) / d(n, m)(0) (6 x 6: the position and the body-frame turn of the rod's frame
//       at s, by the proximal wrench), which the rod's variational tangents give at every RK4
//       node, stays non-singular: its determinant stays positive from 0+, and does not touch
//       zero either (a circular section makes double conjugate points generic: a straight rod
//       buckles in every plane through its axis at once);
//     - a spherical tip (its rotation free, its moment zero): the same test (a conjugate point in
//       (0, L] makes the rod unstable whatever its tip's rotation does), and the tip's rotational
//       stiffness, the 3 x 3 Schur complement S = d(R^T m(L)) / d(turn of the tip) with the tip's
//       position held, positive definite (else the rod is reported with its conjugate point at
//       L: the rod pinned at its tip is unstable there);
//  2. the platform's tangent stiffness, the Schur complement K = D - sum_i C_i A_i^-1 B_i of the
//     rods' blocks in the forward Jacobian, its moment rows taken into the platform's frame (the
//     pose's turn delta is in P: d^2 V / d(p, delta)^2 = diag(I, R_P^T) K at an equilibrium), is
//     positive definite. For a spherical rod A_i's rows are its tip's position and moment: its
//     tip turns freely as the platform moves.
// The joints held: a rod pushed through its hole is clamped there at its free length L + q, a
// translated clamp at its moved position; both are the same clamped base.
// As in the planar check, an inextensible straight rod has no axial stiffness to offer: the tests
// take the rods' axial compliance, int d3 d3^T ds / EA, into the tips' positions (Kirchhoff rods
// only; a rod with shear and extension has it in its model already).
//
// A dead external moment is not conservative in 3-D (a constant moment does work M . omega dt,
// not the differential of a function of the orientation): with one, K's antisymmetric part is not
// zero and the symmetric part the check reports is the energy-like criterion, not a proof.
//
// Real-time safe: no heap, no exceptions; one pass over the rods with their tangents, a 6 x 6
// determinant at every node and a few 6 x 6 blocks (cost in docs/stability.md).

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "pcr/internal/solver_linkage.hpp"
#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/spatial/robot.hpp"
#include "pcr/spatial/shooting.hpp"
#include "pcr/stability.hpp"

namespace pcr {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct SpatialEquilibriumStability {
  /// Both conditions hold (false as well when the configuration is not finite).
  bool stable = false;
  /// Dimensionless: the eigenvalue of the platform's scaled tangent stiffness (symmetric part)
  /// nearest zero, in units of EI / L per (|dp| / L)^2 + |delta|^2 (EI and L the rods' means, as
  /// in spatial_shooting_scale; delta the platform's turn in rad), positive when stable and
  /// negated otherwise. It passes through zero at a fold or a bifurcation of the forward problem.
  double margin = std::numeric_limits<double>::quiet_NaN();
  /// The reciprocal condition number 1 / (|J|_1 |J^-1|_1), exactly, of the scaled forward
  /// Jacobian J = d residual / d (wrenches, pose) with the rods' axial compliance: zero at a fold
  /// or a bifurcation.
  double singularity = std::numeric_limits<double>::quiet_NaN();
  /// The first rod that is unstable with the platform held and where (m): its first conjugate
  /// point, or its length for a spherical tip whose rotational stiffness is not positive. -1 and
  /// NaN when there is none.
  int conjugate_limb = -1;
  double conjugate_arc_length = std::numeric_limits<double>::quiet_NaN();
  /// The platform's scaled tangent stiffness (symmetric part, rows and columns (p / L, delta)),
  /// as in margin.
  Matrix6d stiffness = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
};

namespace internal {

/// See check_spatial_rod: a local minimum of the Jacobi determinant counts as a double conjugate
/// point when the parabola through it reaches this share of its neighbours' value.
inline constexpr double kDoubleRootShare = 1e-2;

/// One rod integrated with its tangents, and its own stability with the platform held.
struct SpatialRodCheck {
  SpatialRodTip<double> tip;
  /// int_0^L d3 d3^T ds / EA (m / N), trapezoidal on the RK4 nodes; zero when not taken in.
  Matrix3<double> axial = Matrix3<double>::Zero();
  /// The first conjugate point of the rod clamped at both ends (m), else NaN.
  double conjugate = std::numeric_limits<double>::quiet_NaN();
  /// The scaled clamped Jacobi matrix at the tip, rows (p / L, turn), columns (n / F, m / (F L)),
  /// axial compliance included.
  Matrix6d jacobi;
};

/// The scaled Jacobi matrix of a stepper at its current node: position (/ L) and body-frame turn
/// of the rod's frame by the scaled proximal wrench, plus the axial compliance `axial` (m / N).
inline Matrix6d scaled_jacobi(const SpatialRodSensitivity<double>& sensitivity,
                              const Vector4<double>& orientation, const Matrix3<double>& axial,
                              const ShootingScale& scale) {
  using Index = SpatialRodIndex;
  Matrix6d jacobi;
  jacobi.topRows<3>() = sensitivity.middleRows<3>(Index::kPosition) / scale.length;
  jacobi.topLeftCorner<3, 3>() += axial / scale.length;
  jacobi.bottomRows<3>() =
      body_turn_of_quaternion(orientation) * sensitivity.middleRows<4>(Index::kOrientation);
  jacobi.leftCols<3>() *= scale.force;
  jacobi.rightCols<3>() *= scale.moment();
  return jacobi;
}

/// Integrates rod i of a point with its tangents in `steps` RK4 steps, the sign of the Jacobi
/// determinant watched at every node (with the axial compliance, without which a straight
/// segment's determinant is zero and its sign rounding).
inline SpatialRodCheck check_spatial_rod(const SpatialRobotParams<double>& robot,
                                         const SpatialShootingPoint<double>& point, int i,
                                         const ShootingScale& scale, int steps) {
  const SpatialLimbParams<double>& limb = robot.limb(i);
  const SpatialRod<double> rod = limb.rod_at(point.q[i]);
  SpatialRodStepper<double, true> stepper(
      spatial_proximal_state(limb, point.q[i], point.wrenches[i]), rod, robot.gravity, steps);
  SpatialRodCheck out;
  // Trapezoid weight h / 2 / EA; the strain n / EA's own effect on the tangents is O(n / EA).
  const double weight = !rod.shear_and_extension ? stepper.half_h / rod.axial_stiffness() : 0.0;
  Vector3<double> tangent = rotation_of(limb.base_orientation).col(2);
  // The determinant at the last two nodes (k - 2, k - 1).
  double det_before = 0, det_prev = 0;
  for (int k = 1; k <= steps; ++k) {
    stepper.step();
    const SpatialRodState<double> state = stepper.state();
    const Vector3<double> next = state.rotation().col(2);
    out.axial += weight * (tangent * tangent.transpose() + next * next.transpose());
    tangent = next;
    out.jacobi = scaled_jacobi(stepper.sensitivity(), state.orientation, out.axial, scale);
    // Positive scalings of rows and columns change neither the sign nor where it crosses zero;
    // the scaled matrix keeps the pivoting's rounding small.
    const double det = out.jacobi.determinant();
    if (std::isnan(out.conjugate)) {
      if (!(det > 0)) {
        // A sign change: where the determinant crosses zero, linearly between the nodes.
        const double t = det_prev > 0 && std::isfinite(det) ? det_prev / (det_prev - det) : 1.0;
        out.conjugate = (k - 1 + t) * stepper.h;
      } else if (k >= 3 && det_before - 2 * det_prev + det > 0) {
        // A double conjugate point, which a circular section makes generic (a straight rod
        // buckles in two planes at once): the determinant touches zero without changing sign,
        // or crosses it twice between two nodes. The parabola through the last three nodes
        // finds its least value, looked at where it is nearest node k - 1 (or beyond it up to
        // node k at the tip): at or below a hundredth of the nodes' largest, the determinant
        // reached zero there (within the fit's error, O(h) of that).
        const double curvature = det_before - 2 * det_prev + det;
        const double offset = 0.5 * (det_before - det) / curvature;  // from node k - 1, in steps
        const double least = det_prev - 0.25 * (det_before - det) * offset;
        if (offset > -0.5 && offset <= (k == steps ? 1.0 : 0.5) &&
            least <= kDoubleRootShare * std::max(det_before, det)) {
          out.conjugate = (k - 1 + offset) * stepper.h;
        }
      }
    }
    det_before = det_prev;
    det_prev = det;
  }
  out.tip = SpatialRodTip<double>{stepper.state(), stepper.sensitivity()};
  return out;
}

/// A spherical rod's tip rotational stiffness with its position held, scaled (moment / (F L) per
/// rad, body frame of the tip): R^T dm(L) / d(turn) = R^T M Phi^-1 [0; I], Phi the clamped Jacobi
/// matrix at the tip and M = dm(L) / d(scaled wrench) / (F L).
inline Matrix3<double> spherical_tip_stiffness(const SpatialRodCheck& rod,
                                               const ShootingScale& scale) {
  using Index = SpatialRodIndex;
  Eigen::Matrix<double, 3, 6> moment = rod.tip.sensitivity.middleRows<3>(Index::kMoment);
  moment.leftCols<3>() *= scale.force / scale.moment();
  const Matrix6d phi_inv = rod.jacobi.inverse();
  return rod.tip.state.rotation().transpose() * moment * phi_inv.rightCols<3>();
}

/// spatial_equilibrium_stability, optionally without the rods' axial compliance in the platform's
/// stiffness (tests compare that of the inextensible model with finite differences).
PCR_SOLVER_INLINE SpatialEquilibriumStability spatial_equilibrium_stability(
    const SpatialRobotParams<double>& robot, const SpatialShootingPoint<double>& point,
    int rod_steps, bool axial_compliance);

}  // namespace internal

/// The stability of the equilibrium `point` (joints, pose, proximal wrenches) of a spatial robot
/// (1 to kMaxSpatialRods rods) under its dead loads, its rods integrated in rod_steps RK4 steps
/// (a solution's summary.rod_steps; stability_rod_steps of it checks at half the cost). The
/// configuration is taken as given: call it on a converged solution.
inline SpatialEquilibriumStability spatial_equilibrium_stability(
    const SpatialRobotParams<double>& robot, const SpatialShootingPoint<double>& point,
    int rod_steps) {
  return internal::spatial_equilibrium_stability(robot, point, rod_steps, true);
}

/// The shooting point of a forward or inverse solution (pose, q, wrenches).
template <class Solution>
SpatialShootingPoint<double> spatial_shooting_point(const SpatialRobotParams<double>& robot,
                                                    const Solution& solution) {
  SpatialShootingPoint<double> point;
  point.pose = solution.pose;
  for (int i = 0; i < robot.num_rods && i < solution.q.size(); ++i) {
    point.q[i] = solution.q(i);
    point.wrenches[i] = solution.wrenches[i];
  }
  return point;
}

/// The stability of a forward solution's equilibrium.
inline SpatialEquilibriumStability spatial_equilibrium_stability(
    const SpatialRobotParams<double>& robot, const SpatialForwardSolution& solution,
    int rod_steps) {
  if (solution.q.size() != robot.num_rods) return SpatialEquilibriumStability();
  return spatial_equilibrium_stability(robot, spatial_shooting_point(robot, solution), rod_steps);
}

/// The stability of an inverse solution's equilibrium.
inline SpatialEquilibriumStability spatial_equilibrium_stability(
    const SpatialRobotParams<double>& robot, const SpatialInverseSolution& solution,
    int rod_steps) {
  if (solution.q.size() != robot.num_rods) return SpatialEquilibriumStability();
  return spatial_equilibrium_stability(robot, spatial_shooting_point(robot, solution), rod_steps);
}

#if PCR_SOLVER_DEFINITIONS
// The bodies of the entry points declared above (pcr/internal/solver_linkage.hpp).

PCR_SOLVER_INLINE SpatialEquilibriumStability internal::spatial_equilibrium_stability(
    const SpatialRobotParams<double>& robot, const SpatialShootingPoint<double>& point,
    int rod_steps, bool axial_compliance) {
  SpatialEquilibriumStability result;
  const int n = robot.num_rods;
  if (n < 1 || n > kMaxSpatialRods || rod_steps < 1) return result;
  const ShootingScale scale = spatial_shooting_scale(robot);
  SpatialRodCheck rods[kMaxSpatialRods];
  SpatialRodTip<double> tips[kMaxSpatialRods];
  for (int i = 0; i < n; ++i) {
    rods[i] = check_spatial_rod(robot, point, i, scale, rod_steps);
    tips[i] = rods[i].tip;
    double conjugate = rods[i].conjugate;
    if (std::isnan(conjugate) && robot.limb(i).attachment == SpatialAttachment::kSpherical) {
      const Matrix3<double> s = spherical_tip_stiffness(rods[i], scale);
      Eigen::SelfAdjointEigenSolver<Matrix3<double>> eigen;
      eigen.computeDirect(0.5 * (s + s.transpose()), Eigen::EigenvaluesOnly);
      if (!(eigen.eigenvalues()(0) > 0)) conjugate = robot.limb(i).rod_at(point.q[i]).length;
    }
    if (result.conjugate_limb < 0 && !std::isnan(conjugate)) {
      result.conjugate_limb = i;
      result.conjugate_arc_length = conjugate;
    }
  }
  SpatialJacobian jacobian;
  spatial_jacobian_from_tips(robot, point, scale, tips, jacobian);
  const BlockForwardJacobian<6, kMaxSpatialRods> blocks(jacobian, n, [&](int i, Matrix6d a) {
    if (axial_compliance) a.topLeftCorner<3, 3>() += rods[i].axial * (scale.force / scale.length);
    return a;
  });
  if (!blocks.stiffness.allFinite()) return result;
  result.singularity = blocks.rcond();
  // The Hessian in (p, delta): the moment rows (in W) into P.
  Matrix6d hessian = blocks.stiffness;
  hessian.bottomRows<3>() = point.pose.rotation().transpose() * hessian.bottomRows<3>();
  result.stiffness = 0.5 * (hessian + hessian.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(result.stiffness, Eigen::EigenvaluesOnly);
  const Eigen::Matrix<double, 6, 1>& values = eigen.eigenvalues();  // ascending
  if (eigen.info() != Eigen::Success || !values.allFinite()) return result;
  result.stable = result.conjugate_limb < 0 && values(0) > 0;
  const double nearest_zero = values.cwiseAbs().minCoeff();
  result.margin = result.stable ? nearest_zero : -nearest_zero;
  return result;
}

#endif  // PCR_SOLVER_DEFINITIONS

}  // namespace pcr
