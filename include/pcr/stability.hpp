#pragma once
// Elastic stability of a solved equilibrium, with the joints held (docs/stability.md; Till and
// Rucker, "Elastic Stability of Cosserat Rods and Parallel Continuum Robots", IEEE T-RO 33(3),
// 2017, for the spatial case).
//
// The equilibrium is a strict local minimum of the potential energy (the rods' bending energy
// minus the work of the dead platform load) when
//  1. no rod, clamped at both ends, has a conjugate point in (0, l]: the Jacobi matrix
//     d(x, y, theta)(s) / d(n_x, n_y, m)(0), which the rod's sensitivities give along s, stays
//     non-singular (its determinant stays positive from 0+);
//  2. the platform's tangent stiffness K = d(platform wrench) / d(pose) with every rod held in
//     equilibrium, the Schur complement of the rods' blocks in the forward Jacobian, is positive
//     definite.
// An inextensible straight rod has no stiffness along its axis to offer these tests (the Jacobi
// matrix's axial column vanishes, at every s): the tests take the rods' axial compliance
// 1 / EA (EA = E pi d^2 / 4) into the tips' positions, as the real rods have it. That moves a
// critical load by O((d / l)^2) relative (4e-6 for the default robot's rods); the equilibria
// themselves stay those of the inextensible model.
//
// Real-time safe like the solvers: no heap, no exceptions; one pass over the rods with their
// sensitivities, the cost of one residual-plus-Jacobian evaluation.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <array>
#include <cmath>
#include <limits>

#include "pcr/robot.hpp"
#include "pcr/shooting.hpp"

namespace pcr {

struct EquilibriumStability {
  /// Both conditions hold (false as well when the configuration is not finite).
  bool stable = false;
  /// Dimensionless: the eigenvalue of the platform's scaled tangent stiffness (symmetric part)
  /// nearest zero, in units of EI / L per (|dp| / L)^2 + dphi^2 (EI and L the rods' means, as in
  /// ShootingScale), positive when stable and negated otherwise. It passes through zero where the
  /// equilibrium meets a fold of the forward problem, where stability is gained or lost.
  double margin = std::numeric_limits<double>::quiet_NaN();
  /// Reciprocal condition number (1-norm, estimated from the LU factors) of the scaled forward
  /// Jacobian d residual / d (wrenches, pose) of the inextensible model, the one the solvers
  /// use: zero at a fold or a bifurcation; it stands for the smallest singular value relative to
  /// the largest at a fraction of an SVD's cost.
  double singularity = std::numeric_limits<double>::quiet_NaN();
  /// The first rod with a conjugate point in (0, l] and where it lies (m), or -1 and NaN.
  int conjugate_limb = -1;
  double conjugate_arc_length = std::numeric_limits<double>::quiet_NaN();
  /// The platform's scaled tangent stiffness (symmetric part), as in margin.
  Eigen::Matrix3d stiffness = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

namespace internal {

/// One rod's conjugate-point test as it is integrated: the running integral of t t^T / EA (the
/// axial compliance taken into the tip's position) and the sign of the Jacobi determinant.
struct JacobiMonitor {
  double inv_ea = 0;                 ///< 1 / EA (1 / N)
  double cxx = 0, cxy = 0, cyy = 0;  ///< int_0^s t t^T ds / EA (m / N)
  double c_prev = 1, s_prev = 0;     ///< tangent at the previous node
  double det_prev = 0;               ///< Jacobi determinant (scaled) at the previous node
  double conjugate = std::numeric_limits<double>::quiet_NaN();  ///< first conjugate point (m)

  void start(const RodState<double>& proximal, double axial_stiffness) {
    inv_ea = 1.0 / axial_stiffness;
    c_prev = std::cos(proximal.theta);
    s_prev = std::sin(proximal.theta);
  }

  /// After a step of length h to arc length s, where the tangent is (c, sn) and the Jacobi
  /// matrix without the axial compliance is `a` (scaled: see scaled_jacobi_block).
  void step(double s, double h, double c, double sn, const Eigen::Matrix3d& a,
            const ShootingScale& scale) {
    // Trapezoidal rule: the compliance is a regularisation, its O(h^2) error moves nothing
    // that matters.
    const double w = 0.5 * h * inv_ea;
    cxx += w * (c_prev * c_prev + c * c);
    cxy += w * (c_prev * s_prev + c * sn);
    cyy += w * (s_prev * s_prev + sn * sn);
    c_prev = c;
    s_prev = sn;
    const double det = with_axial_compliance(a, scale).determinant();
    if (std::isnan(conjugate) && !(det > 0)) {
      // Where the determinant crosses zero, linearly between the nodes.
      const double t = det_prev > 0 && std::isfinite(det) ? det_prev / (det_prev - det) : 1.0;
      conjugate = s - h + t * h;
    }
    det_prev = det;
  }

  /// A Jacobi matrix (scaled) with the axial compliance up to the current node added.
  Eigen::Matrix3d with_axial_compliance(Eigen::Matrix3d a, const ShootingScale& scale) const {
    const double axial = scale.force / scale.length;
    a(0, 0) += cxx * axial;
    a(0, 1) += cxy * axial;
    a(1, 0) += cxy * axial;
    a(1, 1) += cyy * axial;
    return a;
  }
};

/// d(x / L, y / L, theta) / d(n_x / F, n_y / F, m / (F L)): physical tangents (tx[j], ty[j],
/// tth[j] for the three proximal wrench components) in the shooting residual's units.
template <class Tangent>
Eigen::Matrix3d scaled_jacobi_block(const Tangent& tx, const Tangent& ty, const Tangent& tth,
                                    const ShootingScale& scale) {
  const double to_scaled[3] = {scale.force, scale.force, scale.moment()};
  Eigen::Matrix3d a;
  for (int j = 0; j < 3; ++j) {
    a(0, j) = tx(j) * to_scaled[j] / scale.length;
    a(1, j) = ty(j) * to_scaled[j] / scale.length;
    a(2, j) = tth(j) * to_scaled[j];
  }
  return a;
}

}  // namespace internal

namespace internal {

/// equilibrium_stability, optionally without the rods' axial compliance (tests compare the
/// platform stiffness of the inextensible model with finite differences).
inline EquilibriumStability equilibrium_stability(
    const RobotParams<double>& robot, const JointVector& q, const Pose2<double>& pose,
    const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps, bool axial_compliance) {
  EquilibriumStability result;
  const int n = robot.num_limbs;
  if (n < 1 || n > kMaxLimbs || q.size() != n || rod_steps < 1) return result;
  const ShootingScale scale = shooting_scale(robot);
  ShootingPoint<double> point;
  point.pose = pose;
  internal::RodStepper<double, true> rods[kMaxLimbs];
  internal::JacobiMonitor monitors[kMaxLimbs];
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    point.q[i] = q(i);
    point.wrenches[i] = wrenches[i];
    const RodState<double> start = proximal_rod_state(limb, q(i), wrenches[i]);
    rods[i].init(start, limb.bending_stiffness(), limb.length, rod_steps);
    monitors[i].start(start, axial_compliance ? limb.axial_stiffness() : HUGE_VAL);
  }
  internal::integrate_rods_in_lanes(rods, n, rod_steps, [&](int k, const auto& bundle) {
    for (int i = 0; i < n; ++i) {
      const auto lane = [&](const auto& field) {
        return [&field, i](int j) { return field[j][i]; };
      };
      const Eigen::Matrix3d a =
          internal::scaled_jacobi_block(lane(bundle.tx), lane(bundle.ty), lane(bundle.tth), scale);
      const double h = bundle.h[i];
      monitors[i].step(k * h, h, bundle.c[i], bundle.s[i], a, scale);
    }
  });
  RodTip<double> tips[kMaxLimbs];
  for (int i = 0; i < n; ++i) {
    tips[i] = internal::tip_of(rods[i]);
    if (result.conjugate_limb < 0 && !std::isnan(monitors[i].conjugate)) {
      result.conjugate_limb = i;
      result.conjugate_arc_length = monitors[i].conjugate;
    }
  }
  ShootingMatrix partials;
  shooting_partials_from_tips(robot, point, scale, tips, partials);
  const int m = 3 * n + 3;
  const JacobianMatrix jacobian = partials.leftCols(m);
  if (!jacobian.allFinite()) return result;
  result.singularity = Eigen::PartialPivLU<JacobianMatrix>(jacobian).rcond();

  // Platform stiffness: the Schur complement D - sum_i C_i A_i^-1 B_i of the rods' blocks.
  Eigen::Matrix3d stiffness = jacobian.block<3, 3>(3 * n, 3 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d a =
        monitors[i].with_axial_compliance(jacobian.block<3, 3>(3 * i, 3 * i), scale);
    stiffness -=
        jacobian.block<3, 3>(3 * n, 3 * i) * a.inverse() * jacobian.block<3, 3>(3 * i, 3 * n);
  }
  if (!stiffness.allFinite()) return result;
  result.stiffness = 0.5 * (stiffness + stiffness.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(result.stiffness, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d& values = eigen.eigenvalues();  // ascending
  if (!values.allFinite()) return result;
  result.stable = result.conjugate_limb < 0 && values(0) > 0;
  const double nearest_zero = values.cwiseAbs().minCoeff();
  result.margin = result.stable ? nearest_zero : -nearest_zero;
  return result;
}

}  // namespace internal

/// The stability of the equilibrium (q, pose, proximal wrenches) of a robot (1 to kMaxLimbs
/// limbs) under a dead platform load (which adds no term: a force at the platform's origin and a
/// moment do the work of a linear function of the pose), its rods integrated in rod_steps RK4 steps
/// (a solution's summary.rod_steps). The configuration is taken as given: call it on a converged
/// solution.
inline EquilibriumStability equilibrium_stability(
    const RobotParams<double>& robot, const JointVector& q, const Pose2<double>& pose,
    const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps) {
  return internal::equilibrium_stability(robot, q, pose, wrenches, rod_steps, true);
}

}  // namespace pcr
