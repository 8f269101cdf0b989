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
// sensitivities (at half a solution's RK4 steps in the solvers: stability_rod_steps) and a few
// 3 x 3 blocks, about one residual-plus-Jacobian evaluation of the solution or less
// (docs/stability.md).

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "pcr/internal/solver_linkage.hpp"
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
  /// How near the forward problem is to a singularity: the reciprocal condition number
  /// 1 / (|J|_1 |J^-1|_1), computed exactly, of the scaled forward Jacobian
  /// J = d residual / d (wrenches, pose) with the rods' axial compliance (as in the stiffness; it
  /// differs from the inextensible solvers' Jacobian by O((d / l)^2) relative): zero at a fold or
  /// a bifurcation; it stands for the smallest singular value relative to the largest (within a
  /// factor of 3n + 3) at a fraction of an SVD's cost.
  double singularity = std::numeric_limits<double>::quiet_NaN();
  /// The first rod with a conjugate point in (0, l] and where it lies (m), or -1 and NaN.
  int conjugate_limb = -1;
  double conjugate_arc_length = std::numeric_limits<double>::quiet_NaN();
  /// The platform's scaled tangent stiffness (symmetric part), as in margin.
  Eigen::Matrix3d stiffness = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

namespace internal {

/// The conjugate-point test of the rods in the N lanes of a bundle (RodBundle), node by node as
/// they are integrated, lane by lane in SIMD: the running integral of t t^T / EA (the axial
/// compliance taken into the tips' positions) and the sign of the Jacobi determinant.
template <int N>
struct LaneJacobiMonitor {
  using Lanes = LaneArray<N>;
  Lanes half_h_over_ea;                ///< trapezoid weight h / 2 / EA (m / N), EA at s = 0
  Lanes cxx{0.0}, cxy{0.0}, cyy{0.0};  ///< int_0^s t t^T ds / EA (m / N)
  Lanes txx, txy, tyy;   ///< t t^T at the previous node (tapered: times h / 2 / EA(s) there)
  bool tapered = false;  ///< some lane's EA varies along s: each node weighs by its own EA(s)
  Lanes det_prev{0.0};   ///< Jacobi determinant at the previous node
  double conjugate[N];   ///< first conjugate point (m), else NaN
  int rods = 0;

  /// For n initialised rods (before their first step) of axial stiffnesses ea[i] (N).
  LaneJacobiMonitor(const RodStepper<double, true>* start, int n, const double* ea) : rods(n) {
    for (int i = 0; i < N; ++i) {
      const RodStepper<double, true>& rod = start[i < n ? i : 0];  // as in integrate_rods_bundled
      half_h_over_ea[i] = rod.half_h / ea[i < n ? i : 0];
      txx[i] = rod.c * rod.c;
      txy[i] = rod.c * rod.s;
      tyy[i] = rod.s * rod.s;
      conjugate[i] = std::numeric_limits<double>::quiet_NaN();
      tapered |= rod.law == RodLaw::kTapered;
    }
    if (tapered) {
      txx *= half_h_over_ea;
      txy *= half_h_over_ea;
      tyy *= half_h_over_ea;
    }
  }

  /// At node k of the bundle b.
  void step(int k, const RodBundle<N, true>& b) {
    if (tapered) {
      step_with<true>(k, b);
    } else {
      step_with<false>(k, b);
    }
  }

  /// Rod i's scaled Jacobi matrix a (a block of the forward Jacobian) with its axial compliance
  /// up to the current node added.
  Eigen::Matrix3d with_axial_compliance(int i, Eigen::Matrix3d a,
                                        const ShootingScale& scale) const {
    const double axial = scale.force / scale.length;
    a(0, 0) += cxx[i] * axial;
    a(0, 1) += cxy[i] * axial;
    a(1, 0) += cxy[i] * axial;
    a(1, 1) += cyy[i] * axial;
    return a;
  }

 private:
  /// Built for AVX2 as well, like the step itself (four lanes in one instruction: half the cost
  /// on the machines that have it); the taper a template argument, so the loop has no branch.
  template <bool Tapered>
  PCR_SIMD_CLONES void step_with(int k, const RodBundle<N, true>& b) {
    Lanes det;
    // One lane at a time in a loop the compiler vectorises (ivdep: the bundle is not the
    // monitor; as LaneArray expressions, GCC scalarised this through memory).
#pragma GCC ivdep
    for (int i = 0; i < N; ++i) {
      // Trapezoidal rule: its O(h^2) error is well below RK4's effect on the stiffness (the
      // Jacobi fields along a bent rod, tests/test_stability.cpp).
      const double c = b.c[i], s = b.s[i];
      double xx = c * c, xy = c * s, yy = s * s;
      if constexpr (Tapered) {  // EA(s) = EA (d(s) / d)^2 at each node, d(s) / d = 1 + taper s
        const double w = 1.0 + b.taper[i] * b.s_node[i];
        const double weight = half_h_over_ea[i] / (w * w);
        xx *= weight;
        xy *= weight;
        yy *= weight;
        cxx[i] += txx[i] + xx;
        cxy[i] += txy[i] + xy;
        cyy[i] += tyy[i] + yy;
      } else {
        cxx[i] += half_h_over_ea[i] * (txx[i] + xx);
        cxy[i] += half_h_over_ea[i] * (txy[i] + xy);
        cyy[i] += half_h_over_ea[i] * (tyy[i] + yy);
      }
      txx[i] = xx;
      txy[i] = xy;
      tyy[i] = yy;
      // The determinant of [dx; dy; dtheta] / d(n_x, n_y, m)(0) with the compliance added, in
      // physical units: positive scalings of rows and columns change neither its sign nor where
      // it crosses zero.
      const double a00 = b.tx[0][i] + cxx[i], a01 = b.tx[1][i] + cxy[i], a02 = b.tx[2][i];
      const double a10 = b.ty[0][i] + cxy[i], a11 = b.ty[1][i] + cyy[i], a12 = b.ty[2][i];
      const double t0 = b.tth[0][i], t1 = b.tth[1][i], t2 = b.tth[2][i];
      det[i] =
          a00 * (a11 * t2 - a12 * t1) - a01 * (a10 * t2 - a12 * t0) + a02 * (a10 * t1 - a11 * t0);
    }
    bool all_positive = true;
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) all_positive &= det[i] > 0;
    if (!all_positive) {
      for (int i = 0; i < rods; ++i) {
        if (det[i] > 0 || !std::isnan(conjugate[i])) continue;
        // Where the determinant crosses zero, linearly between the nodes.
        const double t =
            det_prev[i] > 0 && std::isfinite(det[i]) ? det_prev[i] / (det_prev[i] - det[i]) : 1.0;
        conjugate[i] = (k - 1 + t) * b.h[i];
      }
    }
    det_prev = det;
  }
};

/// The forward Jacobian J = [A B; C D] (Bn + B square, scaled) of the rods with their axial
/// compliance, by its B x B blocks (B = 3 for planar robots, 6 for spatial ones): A
/// block-diagonal (A_i: rod i's closure by its proximal wrench, compliance included), B_i (rod
/// i's closure by the pose), C_i (the platform's equilibrium by rod i's wrench) and D (by the
/// pose). Eliminating the rods leaves the platform's tangent stiffness, the Schur complement
/// K = D - sum_i C_i A_i^-1 B_i.
template <int B, int MaxLimbs>
struct BlockForwardJacobian {
  using Block = Eigen::Matrix<double, B, B>;
  /// Row blocks of n limbs, stacked (B n rows).
  using Stacked = Eigen::Matrix<double, Eigen::Dynamic, B, 0, B * MaxLimbs, B>;

  int n = 0;
  Block a_inv[MaxLimbs];  ///< A_i^-1
  Block y[MaxLimbs];      ///< C_i A_i^-1
  Stacked x;              ///< A_i^-1 B_i
  Block stiffness;        ///< K
  double norm = 0;        ///< |J|_1, the largest column sum of magnitudes

  /// The blocks of the first B n + B columns of `partials` (the inextensible rods),
  /// with_compliance(i, A_i) adding rod i's.
  template <class Matrix, class Compliance>
  BlockForwardJacobian(const Matrix& partials, int limbs, Compliance&& with_compliance)
      : n(limbs), x(B * limbs, B) {
    stiffness = partials.template block<B, B>(B * n, B * n);
    Eigen::Matrix<double, 1, B> pose_sums = stiffness.cwiseAbs().colwise().sum();
    for (int i = 0; i < n; ++i) {
      const Block a = with_compliance(i, Block(partials.template block<B, B>(B * i, B * i)));
      const Block b = partials.template block<B, B>(B * i, B * n);
      const Block c = partials.template block<B, B>(B * n, B * i);
      a_inv[i] = a.inverse();
      const Block xi = a_inv[i].lazyProduct(b);
      x.template middleRows<B>(B * i) = xi;
      y[i] = c.lazyProduct(a_inv[i]);
      stiffness -= c.lazyProduct(xi);
      pose_sums += b.cwiseAbs().colwise().sum();
      norm =
          std::max(norm, (a.cwiseAbs().colwise().sum() + c.cwiseAbs().colwise().sum()).maxCoeff());
    }
    norm = std::max(norm, pose_sums.maxCoeff());
  }

  /// The reciprocal condition number 1 / (|J|_1 |J^-1|_1) (call with a finite stiffness),
  /// exactly, with J^-1 from the blocks:
  ///   J^-1 = [A^-1 + X K^-1 Y, -X K^-1; -K^-1 Y, K^-1],  X = A^-1 B,  Y = C A^-1,
  /// a tenth of an LU factorisation with a condition estimate at 12 x 12. Zero when K is
  /// singular (so is J).
  double rcond() const {
    if (stiffness.determinant() == 0) return 0.0;
    const Block k_inv = stiffness.inverse();
    // The pose's block column: [-X K^-1; K^-1].
    Stacked column = x.lazyProduct(k_inv);
    double inverse_norm =
        (column.cwiseAbs().colwise().sum() + k_inv.cwiseAbs().colwise().sum()).maxCoeff();
    // Rod j's block column: [A_j^-1 in row block j + X W_j; -W_j], W_j = K^-1 Y_j.
    for (int j = 0; j < n; ++j) {
      const Block w = k_inv.lazyProduct(y[j]);
      column = x.lazyProduct(w);
      column.template middleRows<B>(B * j) += a_inv[j];
      inverse_norm =
          std::max(inverse_norm,
                   (column.cwiseAbs().colwise().sum() + w.cwiseAbs().colwise().sum()).maxCoeff());
    }
    return 1.0 / (norm * inverse_norm);
  }
};

/// The planar robots' blocks: 3 x 3.
using ForwardJacobianBlocks = BlockForwardJacobian<3, kMaxLimbs>;

/// equilibrium_stability, optionally without the rods' axial compliance (tests compare the
/// platform stiffness of the inextensible model with finite differences).
template <int N>
EquilibriumStability equilibrium_stability_in_lanes(
    const RobotParams<double>& robot, const JointVector& q, const Pose2<double>& pose,
    const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps, bool axial_compliance) {
  EquilibriumStability result;
  const int n = robot.num_limbs;
  const ShootingScale scale = shooting_scale(robot);
  ShootingPoint<double> point;
  point.pose = pose;
  internal::RodStepper<double, true> rods[kMaxLimbs];
  double ea[kMaxLimbs];
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    point.q[i] = q(i);
    point.wrenches[i] = wrenches[i];
    const RodState<double> start = proximal_rod_state(limb, q(i), wrenches[i]);
    rods[i].init(start, limb.rod, rod_steps);
    ea[i] = axial_compliance ? limb.rod.axial_stiffness() : HUGE_VAL;
  }
  LaneJacobiMonitor<N> monitor(rods, n, ea);
  internal::integrate_rods_bundled<N>(rods, n, rod_steps,
                                      [&](int k, const auto& bundle) { monitor.step(k, bundle); });
  RodTip<double> tips[kMaxLimbs];
  for (int i = 0; i < n; ++i) {
    tips[i] = internal::tip_of(rods[i]);
    if (result.conjugate_limb < 0 && !std::isnan(monitor.conjugate[i])) {
      result.conjugate_limb = i;
      result.conjugate_arc_length = monitor.conjugate[i];
    }
  }
  ShootingMatrix partials;
  shooting_partials_from_tips(robot, point, scale, tips, partials, /*joints=*/false);
  const ForwardJacobianBlocks blocks(partials, n, [&](int i, const Eigen::Matrix3d& a) {
    return monitor.with_axial_compliance(i, a, scale);
  });
  const Eigen::Matrix3d& stiffness = blocks.stiffness;
  if (!stiffness.allFinite()) return result;
  result.singularity = blocks.rcond();
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

PCR_SOLVER_INLINE EquilibriumStability equilibrium_stability(
    const RobotParams<double>& robot, const JointVector& q, const Pose2<double>& pose,
    const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps, bool axial_compliance);

}  // namespace internal

/// The RK4 steps per rod over which the solvers check a solution of rod_steps steps
/// (SolverOptions::check_stability): half of them, at least 8 (at most rod_steps). A solution's
/// step count is set by its positions' accuracy target; at half the steps RK4's error is 2^4 = 16
/// times that. On random robots (tests/test_stability.cpp) the verdict is a fine integration's,
/// the margin within 1e-4 where the softest direction bends the rods (where stability can be
/// lost), within 10 % where it stretches them (margins of 1e4 and more), and the check costs about
/// one residual-plus-Jacobian evaluation of the solution or less.
inline int stability_rod_steps(int rod_steps) {
  return std::min(rod_steps, std::max(8, rod_steps / 2));
}

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

#if PCR_SOLVER_DEFINITIONS
// The bodies of the entry points declared above (pcr/internal/solver_linkage.hpp).

PCR_SOLVER_INLINE EquilibriumStability internal::equilibrium_stability(
    const RobotParams<double>& robot, const JointVector& q, const Pose2<double>& pose,
    const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps, bool axial_compliance) {
  const int n = robot.num_limbs;
  if (n < 1 || n > kMaxLimbs || q.size() != n || rod_steps < 1) return EquilibriumStability();
  return with_lane_count(n, [&](auto lanes) {
    return equilibrium_stability_in_lanes<decltype(lanes)::value>(robot, q, pose, wrenches,
                                                                  rod_steps, axial_compliance);
  });
}

#endif  // PCR_SOLVER_DEFINITIONS

}  // namespace pcr
