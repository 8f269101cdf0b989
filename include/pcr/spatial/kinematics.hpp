#pragma once
// Forward kinematics of a spatial parallel continuum robot (pcr/spatial/robot.hpp) by Newton
// shooting on the problem of pcr/spatial/shooting.hpp, and its inverse kinematics (3, 5 or 6 rods),
// the spatial counterparts of pcr/kinematics.hpp; every converged solution's elastic stability
// checked (pcr/spatial/stability.hpp). Header-only, Eigen only, no heap, no exceptions, a bounded
// number of iterations; numerical outcomes are reported in a SolverSummary.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "pcr/internal/arclength.hpp"
#include "pcr/internal/branch_rule.hpp"
#include "pcr/internal/rod_step_ladder.hpp"
#include "pcr/internal/solver_linkage.hpp"
#include "pcr/solver.hpp"
#include "pcr/spatial/shooting.hpp"
#include "pcr/spatial/stability.hpp"
#include "pcr/stability.hpp"

namespace pcr {

/// Straight rods are far from most equilibria and near a degenerate point (their axial forces do
/// not act on their tips): Newton's globalised phase from there (line searches, Levenberg steps)
/// takes tens of iterations, where a warm start takes a few. On 12 random robots around the
/// reference, 11 solved from straight rods within 100 iterations, most within 40; the twelfth by
/// the bowed cold start (spatial_homotopy_solve), in 137 continuation steps.
inline constexpr int kColdIterationFactor = 5;

namespace internal {

/// The rotation vector w of R_from^T R_to (to = from exp(w), |w| <= pi), of unit quaternions.
inline Vector3<double> relative_turn(const Vector4<double>& from, const Vector4<double>& to) {
  const Vector4<double> conjugate(from(0), -from(1), -from(2), -from(3));
  return quaternion_log<double>(quaternion_product<double>(conjugate, to));
}

/// The scaled wrench steps from `from` to `to` (the first 6 n entries of dz), as both shooting
/// problems' unknowns step.
inline void wrench_steps(const SpatialShootingPoint<double>& from,
                         const SpatialShootingPoint<double>& to, int n, const ShootingScale& scale,
                         SpatialVector& dz) {
  for (int i = 0; i < n; ++i) {
    dz.segment<3>(6 * i) = (to.wrenches[i].force - from.wrenches[i].force) / scale.force;
    dz.segment<3>(6 * i + 3) = (to.wrenches[i].moment - from.wrenches[i].moment) / scale.moment();
  }
}

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

  /// The scaled step dz with retract(from, dz) = to (the turn's rotation vector below pi).
  SpatialVector step_between(const SpatialShootingPoint<double>& from,
                             const SpatialShootingPoint<double>& to) const {
    SpatialVector dz(size());
    wrench_steps(from, to, n_, scale_, dz);
    dz.segment<3>(6 * n_) = (to.pose.position - from.pose.position) / scale_.length;
    dz.segment<3>(6 * n_ + 3) = relative_turn(from.pose.orientation, to.pose.orientation);
    return dz;
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

/// Solves at joints q1 from the solution x at q0 (x updated), on x's branch: the whole step first,
/// predicted along the tangent when `warm` holds the Jacobian at x, then, if that fails and
/// options.continuation, natural continuation in joint space with step halving (each step
/// predicted along the tangent at the last solved point). As on the planar paths
/// (pcr/internal/path.hpp), a predicted step is kept only when its corrector stayed near the
/// predictor (corrector_on_branch): a long jump of the joints never lands on another equilibrium.
/// On a failure x is the last solved point and summary.path_fraction says where it lies.
inline SolveStatus spatial_solve_path(SpatialForwardProblem& problem,
                                      SpatialShootingPoint<double>& x, const SpatialJointVector& q0,
                                      const SpatialJointVector& q1, SpatialWarmStart& warm,
                                      const SolverOptions& options, SolverSummary& summary) {
  const int n = problem.robot().num_rods;
  const SpatialJointVector dq = q1 - q0;
  const auto set_q = [&](SpatialShootingPoint<double>& p, const SpatialJointVector& q) {
    for (int i = 0; i < n; ++i) p.q[i] = q(i);
  };
  // The predictor's scaled length, or -1 when there is no tangent to predict along. With no input
  // change there is no branch to follow (the same joints on another robot): no check.
  const auto predict = [&](const SpatialShootingPoint<double>& from, const SpatialJointVector& step,
                           SpatialShootingPoint<double>& to) {
    to = from;
    if (warm.valid && warm.lu.rows() == problem.size() && (step.array() != 0.0).any()) {
      const SpatialVector dz = -warm.lu.solve(warm.input_jacobian * step);
      if (dz.allFinite()) {
        to = problem.retract(from, dz);
        return dz.norm();
      }
    }
    return -1.0;
  };
  const auto on_branch = [&](double predictor, const SpatialShootingPoint<double>& predicted,
                             const SpatialShootingPoint<double>& solved) {
    return predictor < 0.0 ||
           corrector_on_branch(problem.step_between(predicted, solved).norm(), predictor);
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
  double predictor = predict(x0, dq, trial);
  set_q(trial, q1);
  SpatialShootingPoint<double> predicted = trial;
  const auto carried = [&] { return warm.valid ? &warm.lu : nullptr; };
  SolveStatus status = spatial_newton(problem, trial, options, options.max_iterations, summary, lu,
                                      initial_norm, final_norm, carried());
  summary.initial_residual_norm = initial_norm;
  summary.final_residual_norm = final_norm;
  // A corrector that left the branch is a step too long, as one that did not converge.
  if (status == SolveStatus::kConverged && !on_branch(predictor, predicted, trial)) {
    status = SolveStatus::kMaxIterations;
  }
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
    predictor = predict(last, (t_next - t) * dq, trial);
    set_q(trial, t_next == 1.0 ? q1 : SpatialJointVector(q0 + t_next * dq));  // q1 to the bit
    predicted = trial;
    status = spatial_newton(problem, trial, options, options.max_continuation_iterations, summary,
                            lu, initial_norm, final_norm, carried());
    if (status == SolveStatus::kConverged && !on_branch(predictor, predicted, trial)) {
      status = SolveStatus::kMaxIterations;
    }
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

/// The largest bending strain over the nodes of every rod of a configuration, its rods integrated
/// in rod_steps steps: (d / 2) |(u - u*)_1,2| = (d / 2) |(R^T m)_1,2| / EI, the strain of the
/// outermost fibre relative to the stress-free rod (SolverSummary::max_strain, as the planar
/// solvers report it; torsion's shear strain is not counted).
inline double spatial_max_strain(const SpatialRobotParams<double>& robot,
                                 const SpatialShootingPoint<double>& x, int rod_steps) {
  double strain = 0;
  for (int i = 0; i < robot.num_rods; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    const SpatialRod<double> rod = limb.rod_at(x.q[i]);
    const double per_moment = rod.diameter / (2 * rod.bending_stiffness());
    sample_spatial_rod(spatial_proximal_state(limb, x.q[i], x.wrenches[i]), rod, robot.gravity,
                       rod_steps, [&](double, const SpatialRodState<double>& node) {
                         const Vector3<double> m = node.rotation().transpose() * node.moment;
                         const double e = per_moment * std::hypot(m.x(), m.y());
                         strain = std::isnan(e) ? e : std::max(strain, e);
                       });
  }
  return strain;
}

/// What the summary reports of a converged solution beyond the solve: kInaccurate when its error
/// estimate exceeds the targets (mark_inaccurate), its largest bending strain
/// and, with SolverOptions::check_stability, its elastic stability at half its RK4 steps
/// (stability_rod_steps) as the planar solvers do. Returns the first rod with a conjugate point
/// (SpatialEquilibriumStability::conjugate_limb), -1 when none or unchecked.
template <class Solution>
int report_spatial_solution(const SpatialRobotParams<double>& robot, const SolverOptions& options,
                            Solution& solution) {
  SolverSummary& summary = solution.summary;
  summary.max_strain = summary.stability_margin = summary.singularity =
      std::numeric_limits<double>::quiet_NaN();
  summary.stability = Stability::kUnchecked;
  mark_inaccurate(options, summary);
  if (!summary.converged() && summary.status != SolveStatus::kInaccurate) return -1;
  const SpatialShootingPoint<double> point = spatial_shooting_point(robot, solution);
  summary.max_strain = spatial_max_strain(robot, point, summary.rod_steps);
  if (!options.check_stability) return -1;
  const SpatialEquilibriumStability s =
      spatial_equilibrium_stability(robot, point, stability_rod_steps(summary.rod_steps));
  summary.stability = s.stable ? Stability::kStable : Stability::kUnstable;
  summary.stability_margin = s.margin;
  summary.singularity = s.singularity;
  return s.conjugate_limb;
}

inline bool spatial_inputs_valid(const SpatialRobotParams<double>& robot,
                                 const SpatialJointVector& q, const SolverOptions& options) {
  return robot.num_rods >= 1 && robot.num_rods <= kMaxSpatialRods && q.size() == robot.num_rods &&
         q.allFinite() && options.is_valid();
}

/// A point of a spatial curve of solutions: the shooting point and where its input lies on the
/// path.
struct SpatialCurvePoint {
  SpatialShootingPoint<double> x;
  double t = 0;
};

/// A spatial shooting problem along its input path, as the curve trace_curve
/// (pcr/internal/arclength.hpp) follows. Its local coordinates are spatial_newton's (the scaled
/// wrench and joint steps, the platform's turn on the right as a rotation vector:
/// Problem::retract), then t; the unit quaternion itself never enters the bordered system.
/// InputPath: place(x, t) (the inputs x carries, at t), prepare(t) (those the problem holds, at t)
/// and rate(problem, x, t, summary) (d residual / d t at x, after prepare(t) and an evaluation at
/// x).
template <class Problem, class InputPath>
class SpatialArclengthCurve {
 public:
  using Point = SpatialCurvePoint;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxSpatialUnknowns + 1, 1>;
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxSpatialUnknowns + 1,
                               kMaxSpatialUnknowns + 1>;

  SpatialArclengthCurve(Problem& problem, const InputPath& path) : problem_(problem), path_(path) {}

  int size() const { return problem_.size(); }
  double t(const Point& p) const { return p.t; }

  /// The unknowns retracted as spatial_newton steps them, the input moved along its path.
  Point advance(const Point& p, const Vector& step) const {
    const int n = size();
    Point out;
    out.t = p.t + step(n);
    out.x = problem_.retract(p.x, SpatialVector(step.head(n)));
    path_.place(out.x, out.t);
    return out;
  }

  Vector offset(const Point& from, const Point& to) const {
    const int n = size();
    Vector d(n + 1);
    d << problem_.step_between(from.x, to.x), to.t - from.t;
    return d;
  }

  bool bordered(const Point& p, const Vector& tangent, Vector& g, Matrix& m,
                SolverSummary& summary) {
    const int n = size();
    SpatialVector r;
    SpatialJacobian J;
    path_.prepare(p.t);
    problem_.evaluate(p.x, r, &J);
    ++summary.residual_evaluations;
    m.resize(n + 1, n + 1);
    m.topLeftCorner(n, n) = J;
    m.topRightCorner(n, 1) = path_.rate(problem_, p.x, p.t, summary);
    m.bottomRows(1) = tangent.transpose();
    g.head(n) = r;
    return m.allFinite() && r.allFinite();
  }

 private:
  Problem& problem_;
  const InputPath& path_;
};

/// A solution's configuration from the point x of `problem` (forward or inverse).
template <class Problem, class Solution>
void fill_solution(const Problem& problem, const SpatialShootingPoint<double>& x, Solution& out) {
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
PCR_SOLVER_INLINE SpatialForwardSolution spatial_forward_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
    const SpatialForwardSolution& warm_start, const SolverOptions& options = SolverOptions());

/// Forward kinematics from a cold start, from up to four starts in turn: Newton from the
/// straight-rod guess at q (straight_rods_guess); with options.continuation, the bowed cold start
/// (spatial_homotopy_solve: natural continuation from the robot of which straight rods at q are
/// the equilibrium to the robot itself); the home solution (q = 0, from its straight-rod guess)
/// followed by natural continuation in joint space from 0 to q; and, where the bowed start stalled
/// at a fold, its curve traced on through the fold (spatial_trace_bowed_start). Each start's
/// solution is refined (spatial_refine_rod_steps) and checked. Newton from straight rods can land
/// on a far, strongly bent equilibrium, so with SolverOptions::check_stability a start that gives
/// an unstable one is not the answer while a later start may give a stable one: the first stable
/// solution is returned, else the first converged one. The solves from straight rods have
/// kColdIterationFactor times options.max_iterations. A failure reports the first start's status;
/// the summary counts the work of every start tried.
PCR_SOLVER_INLINE SpatialForwardSolution
spatial_forward_kinematics(const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
                           const SolverOptions& options = SolverOptions());

/// Orientation directions that spatial IK solves for rather than imposes, by rod count, so that its
/// problem is square (7 n + free = 6 n + 6 unknowns): none for six rods (the whole pose imposed);
/// the twist about the platform's z axis for five (position and platform normal R e3 imposed); the
/// whole orientation for three (the position imposed, as the planar IK of two limbs solves theta).
/// -1 for other rod counts, whose IK is not supported: four rods would leave two of the three
/// rotation directions to choose, and more than six make the joints redundant.
inline int spatial_inverse_free_angles(int num_rods) {
  return num_rods == 6 ? 0 : num_rods == 5 ? 1 : num_rods == 3 ? 3 : -1;
}

/// The pose nearest `current` that imposes what IK imposes of `request`
/// (spatial_inverse_free_angles): the request for six rods; its position with current's orientation
/// for three; for five, its position and the orientation R_request exp(psi e3) whose twist psi is
/// that of R_request^T R_current about e3.
inline SpatialPose<double> spatial_imposed_pose(int num_rods, const SpatialPose<double>& request,
                                                const SpatialPose<double>& current) {
  const int free = spatial_inverse_free_angles(num_rods);
  if (free <= 0) return request;
  SpatialPose<double> out{request.position, current.orientation};
  if (free == 3) return out;
  const Vector4<double> conjugate(request.orientation(0), -request.orientation(1),
                                  -request.orientation(2), -request.orientation(3));
  const Vector4<double> relative = quaternion_product<double>(conjugate, current.orientation);
  Vector4<double> twist(relative(0), 0, 0, relative(3));
  const double norm = twist.norm();
  twist = norm > 0 ? Vector4<double>(twist / norm) : identity_quaternion<double>();
  const Vector4<double> h = quaternion_product<double>(request.orientation, twist);
  out.orientation = h / h.norm();
  return out;
}

namespace internal {

/// The inverse shooting problem at an imposed platform pose: unknowns each rod's proximal wrench
/// (6) and joint q_i (1, scaled by L), and the orientation directions left free
/// (spatial_inverse_free_angles: the last `free` of the body-frame rotation, turned on the right
/// as the forward problem's); the residual is the forward one.
class SpatialInverseProblem {
 public:
  SpatialInverseProblem(const SpatialRobotParams<double>& robot, int rod_steps)
      : robot_(robot),
        scale_(spatial_shooting_scale(robot)),
        n_(robot.num_rods),
        free_(std::max(spatial_inverse_free_angles(robot.num_rods), 0)),
        steps_(rod_steps) {}

  int size() const { return 7 * n_ + free_; }
  int rod_steps() const { return steps_; }
  void set_rod_steps(int steps) { steps_ = steps; }
  const SpatialRobotParams<double>& robot() const { return robot_; }

  SpatialShootingPoint<double> retract(const SpatialShootingPoint<double>& x,
                                       const SpatialVector& dz) const {
    SpatialShootingPoint<double> out = x;
    for (int i = 0; i < n_; ++i) {
      out.wrenches[i].force += dz.segment<3>(6 * i) * scale_.force;
      out.wrenches[i].moment += dz.segment<3>(6 * i + 3) * scale_.moment();
      out.q[i] += dz(6 * n_ + i) * scale_.length;
    }
    if (free_ > 0) {
      Vector3<double> turn = Vector3<double>::Zero();
      turn.tail(free_) = dz.segment(7 * n_, free_);
      const Vector4<double> h =
          quaternion_product<double>(x.pose.orientation, quaternion_exp<double>(turn));
      out.pose.orientation = h / h.norm();
    }
    return out;
  }

  /// The scaled step dz with retract(from, dz) = to, for points at the same imposed pose but for
  /// the free angles.
  SpatialVector step_between(const SpatialShootingPoint<double>& from,
                             const SpatialShootingPoint<double>& to) const {
    SpatialVector dz(size());
    wrench_steps(from, to, n_, scale_, dz);
    for (int i = 0; i < n_; ++i) dz(6 * n_ + i) = (to.q[i] - from.q[i]) / scale_.length;
    if (free_ > 0) {
      dz.segment(7 * n_, free_) =
          relative_turn(from.pose.orientation, to.pose.orientation).tail(free_);
    }
    return dz;
  }

  /// The Jacobian's joint columns are d r / d q (spatial_input_column): exact for translated
  /// clamps, within RK4's error for rods pushed through their holes, which leaves Newton a linear
  /// rate of about that error (1e-9 at 256 steps) instead of a quadratic one.
  void evaluate(const SpatialShootingPoint<double>& x, SpatialVector& r, SpatialJacobian* J) const {
    SpatialResidualVector<double> residual;
    spatial_residual(robot_, x, scale_, steps_, residual, J ? &forward_ : nullptr, tips_);
    r = residual;
    if (!J) return;
    // The wrench columns stay, and so do the free rotation columns (the last free_ of the pose's,
    // at 7 n since 6 n + 6 - free_ = 7 n); the others become the joints'.
    *J = forward_;
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

  /// How far a step dz moves the joints (m) and the free orientation (rad).
  void output_change(const SpatialVector& dz, double& position, double& angle) const {
    position = spatial_max_norm(dz.segment(6 * n_, n_)) * scale_.length;
    angle = free_ > 0 ? spatial_max_norm(dz.segment(7 * n_, free_)) : 0.0;
  }

 private:
  const SpatialRobotParams<double>& robot_;
  ShootingScale scale_;
  int n_;
  int free_;
  int steps_;
  mutable SpatialJacobian forward_;
  mutable SpatialRodState<double> tips_[kMaxSpatialRods];
};

}  // namespace internal

/// Seeds of a spatial solution's other equilibria at the same input, per rod.
inline constexpr int kSpatialBuckledSeedsPerRod = 8;

/// Seed k (0 <= k < kSpatialBuckledSeedsPerRod n) of the other equilibria at `at`'s input: one rod
/// bent further, its proximal moment moved by +-1 and +-2 times 2 pi EI / l (a clamped-clamped
/// rod's buckled shapes, as the planar buckled_seed) about either axis normal to its proximal
/// tangent (d1, d2: a straight rod buckles in any plane); the rods in turn from `first_rod`.
template <class Solution>
Solution spatial_buckled_seed(const SpatialRobotParams<double>& robot, const Solution& at, int k,
                              int first_rod = 0) {
  constexpr double kTurns[4] = {1.0, -1.0, 2.0, -2.0};
  const int rod = (first_rod + k / kSpatialBuckledSeedsPerRod) % robot.num_rods;
  const int kind = k % kSpatialBuckledSeedsPerRod;
  const SpatialLimbParams<double>& limb = robot.limb(rod);
  Solution seed = at;
  seed.warm = SpatialWarmStart();  // not at the seed
  const auto i = static_cast<std::size_t>(rod);
  const SpatialRod<double> bent = limb.rod_at(at.q(rod));
  const Matrix3<double> frame = spatial_proximal_state(limb, at.q(rod), at.wrenches[i]).rotation();
  seed.wrenches[i].moment +=
      kTurns[kind / 2] * 2.0 * M_PI * bent.bending_stiffness() / bent.length * frame.col(kind % 2);
  return seed;
}

namespace internal {

/// The straight pose path of IK from `start` to the pose that `request` imposes
/// (spatial_imposed_pose, nearest start): a line for the position, a constant-rate turn for the
/// orientation; at(1) is that pose to the bit.
struct SpatialPosePath {
  SpatialPosePath(const SpatialInverseProblem& problem, const SpatialPose<double>& from,
                  const SpatialPose<double>& request)
      : start(from),
        pose(spatial_imposed_pose(problem.robot().num_rods, request, from)),
        whole(problem.pose_step(start, pose)) {}

  SpatialPose<double> at(double t) const {
    if (t == 1.0) return pose;
    SpatialPose<double> out;
    out.position = start.position + t * (pose.position - start.position);
    out.orientation = quaternion_product<double>(start.orientation / start.orientation.norm(),
                                                 quaternion_exp<double>(t * whole.tail<3>()));
    return out;
  }

  SpatialPose<double> start;
  SpatialPose<double> pose;
  Eigen::Matrix<double, 6, 1> whole;
};

/// Solves the inverse problem at the pose that `request` imposes (spatial_imposed_pose, nearest
/// x.pose) from the solution x at x.pose (x updated): the whole step
/// first, predicted along the tangent -J^-1 (d r / d pose) d pose when `warm` holds them, with
/// chord steps on its factorisation; on failure (and options.continuation), natural continuation
/// along the straight pose path (a line for the position, a constant-rate turn for the
/// orientation), halving the step on failure. A predicted step is kept only on its branch
/// (corrector_on_branch), as in spatial_solve_path. Returns the status and sets
/// summary.path_fraction; x is the last point solved, `warm` what it leaves for the next solve.
inline SolveStatus spatial_inverse_path(SpatialInverseProblem& problem,
                                        SpatialShootingPoint<double>& x,
                                        const SpatialPose<double>& request, SpatialWarmStart& warm,
                                        const SolverOptions& options, SolverSummary& summary) {
  const SpatialPosePath path(problem, x.pose, request);
  // The predictor's scaled length, or -1 when there is no tangent to predict along (or no pose
  // change: no branch to follow).
  const auto predict = [&](const SpatialShootingPoint<double>& from, const SpatialPose<double>& to,
                           SpatialShootingPoint<double>& trial) {
    trial = from;
    double length = -1.0;
    const Eigen::Matrix<double, 6, 1> step = problem.pose_step(from.pose, to);
    if (warm.valid && warm.lu.rows() == problem.size() && warm.input_jacobian.cols() == 6 &&
        (step.array() != 0.0).any()) {
      const SpatialVector dz = -warm.lu.solve(warm.input_jacobian * step);
      if (dz.allFinite()) {
        trial = problem.retract(from, dz);
        length = dz.norm();
      }
    }
    trial.pose = to;
    return length;
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
    const double predictor = predict(x, path.at(t_next), trial);
    const SpatialShootingPoint<double> predicted = trial;
    status = spatial_newton(problem, trial, options,
                            first ? options.max_iterations : options.max_continuation_iterations,
                            summary, lu, initial_norm, final_norm, warm.valid ? &warm.lu : nullptr);
    if (first) summary.initial_residual_norm = initial_norm;
    // A corrector that left the branch is a step too long, as one that did not converge.
    if (status == SolveStatus::kConverged && predictor >= 0.0 &&
        !corrector_on_branch(problem.step_between(predicted, trial).norm(), predictor)) {
      status = SolveStatus::kMaxIterations;
    }
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
                                            const SolverOptions& options);

/// IK has converged on an unstable equilibrium at `pose`: looks for a stable one there, first from
/// home (the branch that continuation from the straight rods follows), then from the buckled seeds
/// (spatial_buckled_seed) rod by rod, the rod with a conjugate point (conjugate_limb, or -1) first.
/// Each seed is solved at the pose itself (no continuation), within
/// options.max_continuation_iterations. The search stops after the first of these groups (home,
/// then each rod's seeds) that gives a stable equilibrium, since a seed that leads nowhere costs
/// tens of evaluations; it takes that group's stable solution whose joints lie nearest. Else it
/// reports kUnstable with the unstable solution. The summary counts every seed's iterations and
/// evaluations.
inline void look_for_stable_spatial_inverse(const SpatialRobotParams<double>& robot,
                                            const SpatialPose<double>& pose,
                                            const SolverOptions& options, int conjugate_limb,
                                            SpatialInverseSolution& solution) {
  SolverOptions seed_options = options;
  seed_options.stable_inverse = false;
  SolverSummary totals = solution.summary;
  SpatialInverseSolution best;
  bool found = false;
  double best_distance = HUGE_VAL;
  const auto consider = [&](const SpatialInverseSolution& candidate) {
    totals.iterations += candidate.summary.iterations;
    totals.residual_evaluations += candidate.summary.residual_evaluations;
    totals.continuation_steps += candidate.summary.continuation_steps;
    if (!candidate.summary.converged() || candidate.summary.stability != Stability::kStable) return;
    const double distance = (candidate.q - solution.q).norm();
    if (!found || distance < best_distance) {
      best = candidate;
      found = true;
      best_distance = distance;
    }
  };
  const SpatialForwardSolution home =
      spatial_forward_kinematics(robot, SpatialJointVector::Zero(robot.num_rods), seed_options);
  totals.iterations += home.summary.iterations;
  totals.residual_evaluations += home.summary.residual_evaluations;
  if (home.summary.converged()) {
    consider(spatial_inverse_from(robot, pose, home, nullptr, seed_options));
  }
  // The seeds are at the pose: no path to continue along, and a seed that leads to an equilibrium
  // converges in a few iterations (as a continuation's sub-solve) or not at all.
  seed_options.continuation = false;
  seed_options.max_iterations = options.max_continuation_iterations;
  // Rod by rod, the one with a conjugate point first, until a group gives a stable equilibrium.
  for (int rod = 0; !found && rod < robot.num_rods; ++rod) {
    for (int k = rod * kSpatialBuckledSeedsPerRod; k < (rod + 1) * kSpatialBuckledSeedsPerRod;
         ++k) {
      consider(spatial_inverse_from(
          robot, pose, spatial_buckled_seed(robot, solution, k, std::max(conjugate_limb, 0)),
          nullptr, seed_options));
    }
  }
  if (found) {
    best.summary.iterations = totals.iterations;
    best.summary.residual_evaluations = totals.residual_evaluations;
    best.summary.continuation_steps = totals.continuation_steps;
    solution = best;
  } else {
    totals.status = SolveStatus::kUnstable;
    solution.summary = totals;
  }
}

template <class Start>
SpatialInverseSolution spatial_inverse_from(const SpatialRobotParams<double>& robot,
                                            const SpatialPose<double>& pose, const Start& start,
                                            const SpatialWarmStart* warm,
                                            const SolverOptions& options) {
  SpatialInverseSolution out;
  const int n = robot.num_rods;
  if (spatial_inverse_free_angles(n) < 0) {
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
  fill_solution(problem, x, out);
  const int conjugate_limb = report_spatial_solution(robot, options, out);
  if (out.summary.stability == Stability::kUnstable && options.stable_inverse) {
    look_for_stable_spatial_inverse(robot, pose, options, conjugate_limb, out);
  }
  return out;
}

}  // namespace internal

/// Inverse kinematics from a forward solution near the pose: Newton from its wrenches and joints
/// at the requested pose. Six rods impose the whole pose; five its position and platform normal
/// R e3, three its position, and the orientation left free is solved for
/// (spatial_inverse_free_angles; the solution's pose is the solved one). Other rod counts:
/// SolveStatus::kUnsupported. On failure (and options.continuation), natural continuation along the
/// straight pose path from the start's pose (position on a line, orientation at a constant rate),
/// halving the step on failure. RK4 steps as spatial_forward_kinematics. An equilibrium that would
/// not hold is replaced by a stable one at the pose when one is found
/// (SolverOptions::stable_inverse, look_for_stable_spatial_inverse), else kUnstable.
PCR_SOLVER_INLINE SpatialInverseSolution spatial_inverse_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialForwardSolution& start, const SolverOptions& options = SolverOptions());

/// Inverse kinematics warm-started from a previous inverse solution (IK along a path, the normal
/// case in a control loop): its joints and wrenches predicted along the tangent to the pose, then
/// chord steps with its factorised Jacobian; on failure, as from a forward solution.
PCR_SOLVER_INLINE SpatialInverseSolution spatial_inverse_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialInverseSolution& warm_start, const SolverOptions& options = SolverOptions());

/// Inverse kinematics from the home solution (FK at q = 0): as from any forward solution; a home
/// that did not converge is returned as a failed solution with its status (the summary does not
/// count the home solve's iterations).
PCR_SOLVER_INLINE SpatialInverseSolution spatial_inverse_kinematics_from_home(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialForwardSolution& home, const SolverOptions& options = SolverOptions());

/// Inverse kinematics from a cold start: the home solution (a cold FK at q = 0), then
/// spatial_inverse_kinematics_from_home.
PCR_SOLVER_INLINE SpatialInverseSolution
spatial_inverse_kinematics(const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
                           const SolverOptions& options = SolverOptions());

#if PCR_SOLVER_DEFINITIONS
// The bodies of the entry points declared above (pcr/internal/solver_linkage.hpp).

namespace internal {

/// The robot whose equilibrium at x's joints is x's pose with unloaded rods: each rod integrated
/// from its proximal end with no wrench (straight, or its intrinsic shape), and the platform
/// attachment and tip frame moved to where it ends, seen from x's pose; no gravity, mass or
/// external load. The start of the bowed cold start (spatial_homotopy_solve).
inline SpatialRobotParams<double> spatial_relaxed_robot(const SpatialRobotParams<double>& robot,
                                                        const SpatialShootingPoint<double>& x,
                                                        int rod_steps) {
  SpatialRobotParams<double> relaxed = robot;
  relaxed.gravity.setZero();
  relaxed.platform_mass = 0;
  relaxed.external_force.setZero();
  relaxed.external_moment.setZero();
  const Matrix3<double> R = x.pose.rotation();
  for (int i = 0; i < robot.num_rods; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    const SpatialRodState<double> tip =
        integrate_spatial_rod(spatial_proximal_state(limb, x.q[i], SpatialWrench<double>()),
                              limb.rod_at(x.q[i]), Vector3<double>::Zero().eval(), rod_steps);
    relaxed.limb(i).B = R.transpose() * (tip.position - x.pose.position);
    relaxed.limb(i).tip_orientation = quaternion_of<double>(R.transpose() * tip.rotation());
  }
  return relaxed;
}

/// The robot a fraction t of the way from `from` to `to` (which differ in the platform
/// attachments, tip frames and loads): those blended linearly, the tip frames on the shortest
/// arc; `to` itself at t = 1, and extrapolated past it (where a traced curve steps beyond t = 1).
inline SpatialRobotParams<double> spatial_blended_robot(const SpatialRobotParams<double>& from,
                                                        const SpatialRobotParams<double>& to,
                                                        double t) {
  if (t == 1.0) return to;
  const auto blend = [t](const auto& a, const auto& b) { return (a + t * (b - a)).eval(); };
  SpatialRobotParams<double> out = to;
  for (int i = 0; i < to.num_rods; ++i) {
    const Vector4<double>& a = from.limb(i).tip_orientation;
    const Vector4<double>& b = to.limb(i).tip_orientation;
    const Eigen::Quaterniond turn =
        Eigen::Quaterniond(a(0), a(1), a(2), a(3))
            .normalized()
            .slerp(t, Eigen::Quaterniond(b(0), b(1), b(2), b(3)).normalized());
    out.limb(i).B = blend(from.limb(i).B, to.limb(i).B);
    out.limb(i).tip_orientation = Vector4<double>(turn.w(), turn.x(), turn.y(), turn.z());
  }
  out.gravity = blend(from.gravity, to.gravity);
  out.platform_mass = from.platform_mass + t * (to.platform_mass - from.platform_mass);
  out.external_force = blend(from.external_force, to.external_force);
  out.external_moment = blend(from.external_moment, to.external_moment);
  return out;
}

/// The point a fraction f of the step from `before` to `last` beyond `last` (a secant predictor):
/// wrenches and position extrapolated linearly, the orientation turned on by f times the turn
/// between them.
inline SpatialShootingPoint<double> spatial_secant_prediction(
    int num_rods, const SpatialShootingPoint<double>& before,
    const SpatialShootingPoint<double>& last, double f) {
  SpatialShootingPoint<double> out = last;
  for (int i = 0; i < num_rods; ++i) {
    out.wrenches[i].force += f * (last.wrenches[i].force - before.wrenches[i].force);
    out.wrenches[i].moment += f * (last.wrenches[i].moment - before.wrenches[i].moment);
  }
  out.pose.position += f * (last.pose.position - before.pose.position);
  const Vector4<double>& h = before.pose.orientation;
  const Vector4<double> turn =
      quaternion_product<double>(Vector4<double>(h(0), -h(1), -h(2), -h(3)), last.pose.orientation);
  const Vector4<double> turned = quaternion_product<double>(
      last.pose.orientation, quaternion_exp<double>((f * quaternion_log<double>(turn)).eval()));
  out.pose.orientation = turned / turned.norm();
  return out;
}

/// The bowed cold start's input path: the robot blended a fraction t of the way from `from` to
/// `to` (spatial_blended_robot), held in `at`, which the traced problem solves. The rate is a
/// central difference of the blend: two residual evaluations without sensitivities.
struct SpatialHomotopyPath {
  const SpatialRobotParams<double>& from;
  const SpatialRobotParams<double>& to;
  SpatialRobotParams<double>& at;

  void place(SpatialShootingPoint<double>&, double) const {}
  void prepare(double t) const { at = spatial_blended_robot(from, to, t); }
  SpatialVector rate(const SpatialForwardProblem& problem, const SpatialShootingPoint<double>& x,
                     double t, SolverSummary& summary) const {
    constexpr double h = 1e-6;  // the blend is smooth in t: an error of order h^2
    SpatialVector plus, minus;
    prepare(t + h);
    problem.evaluate(x, plus, nullptr);
    prepare(t - h);
    problem.evaluate(x, minus, nullptr);
    prepare(t);
    summary.residual_evaluations += 2;
    return (plus - minus) / (2 * h);
  }
};

/// Where the bowed cold start's natural continuation stopped short of the robot itself: the
/// relaxed robot it starts from and the last equilibrium it reached, a fraction t of the way.
struct SpatialBowedStall {
  SpatialRobotParams<double> relaxed;
  SpatialCurvePoint last;
};

/// The bowed cold start: FK at x's joints by natural continuation from the relaxed robot
/// (spatial_relaxed_robot, of which x with no wrenches is the equilibrium) to the robot itself
/// (spatial_blended_robot), each step from a secant predictor, halved on failure and doubled (up to
/// a half) on success. Where straight rods are too far from the equilibrium for Newton, the rods
/// bow gradually as the attachments move into place and the loads come on; the path can turn
/// sharply (one random robot around the reference took 137 steps), so it has kColdIterationFactor
/// times options.max_continuation_steps. kConverged with x the robot's equilibrium; otherwise
/// `stall` says where it stopped (spatial_trace_bowed_start goes on from there).
inline SolveStatus spatial_homotopy_solve(const SpatialRobotParams<double>& robot,
                                          SpatialShootingPoint<double>& x, int rod_steps,
                                          const SolverOptions& options, SolverSummary& summary,
                                          SpatialBowedStall& stall) {
  for (int i = 0; i < robot.num_rods; ++i) x.wrenches[i] = SpatialWrench<double>();
  stall.relaxed = spatial_relaxed_robot(robot, x, rod_steps);
  const SpatialRobotParams<double>& relaxed = stall.relaxed;
  Eigen::PartialPivLU<SpatialJacobian> lu;
  SpatialShootingPoint<double> before = x;
  double t = 0.0, t_before = -1.0, dt = 0.25, initial_norm, final_norm;
  for (int step = 0; t < 1.0 && step < kColdIterationFactor * options.max_continuation_steps;
       ++step) {
    ++summary.continuation_steps;
    const double t_next = std::min(1.0, t + dt);
    const SpatialRobotParams<double> at = spatial_blended_robot(relaxed, robot, t_next);
    SpatialForwardProblem problem(at, rod_steps);
    SpatialShootingPoint<double> trial =
        t_before < 0
            ? x
            : spatial_secant_prediction(robot.num_rods, before, x, (t_next - t) / (t - t_before));
    if (spatial_newton(problem, trial, options, options.max_continuation_iterations, summary, lu,
                       initial_norm, final_norm) == SolveStatus::kConverged) {
      before = x;
      t_before = t;
      x = trial;
      t = t_next;
      dt = std::min(2.0 * dt, 0.5);
    } else {
      dt *= 0.5;
      if (dt < options.min_continuation_step) break;
    }
  }
  stall.last = SpatialCurvePoint{x, t};
  return t >= 1.0 ? SolveStatus::kConverged : SolveStatus::kMaxIterations;
}

/// The bowed cold start on from where its natural continuation stalled, at a fold of the blend
/// (the rods snap through as the attachments move into place): the curve of equilibria traced
/// through it by pseudo-arclength steps (trace_curve, at most options.max_arclength_steps points)
/// until the blend comes to the robot itself again, forward, and x solved there. kConverged with
/// x the robot's equilibrium, which after folds may be an unstable one.
inline SolveStatus spatial_trace_bowed_start(const SpatialRobotParams<double>& robot,
                                             const SpatialBowedStall& stall,
                                             SpatialShootingPoint<double>& x, int rod_steps,
                                             const SolverOptions& options, SolverSummary& summary) {
  SpatialRobotParams<double> at = spatial_blended_robot(stall.relaxed, robot, stall.last.t);
  SpatialForwardProblem traced(at, rod_steps);
  const SpatialHomotopyPath path{stall.relaxed, robot, at};
  SpatialArclengthCurve<SpatialForwardProblem, SpatialHomotopyPath> curve(traced, path);
  SpatialCurvePoint point = stall.last;
  const ArclengthTrace trace = trace_curve(
      curve, point, options, summary, options.max_arclength_steps, [](const SpatialCurvePoint&) {});
  if (!trace.reached) return SolveStatus::kMaxIterations;
  x = point.x;
  SpatialForwardProblem problem(robot, rod_steps);
  Eigen::PartialPivLU<SpatialJacobian> lu;
  double initial_norm, final_norm;
  return spatial_newton(problem, x, options, options.max_iterations, summary, lu, initial_norm,
                        final_norm);
}

}  // namespace internal

PCR_SOLVER_INLINE SpatialForwardSolution
spatial_forward_kinematics(const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
                           const SpatialForwardSolution& warm_start, const SolverOptions& options) {
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
  internal::report_spatial_solution(robot, options, out);
  return out;
}

PCR_SOLVER_INLINE SpatialForwardSolution
spatial_forward_kinematics(const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
                           const SolverOptions& options) {
  SpatialForwardSolution out;
  if (!internal::spatial_inputs_valid(robot, q, options)) {
    out.summary.status = SolveStatus::kInvalidInput;
    return out;
  }
  SolverOptions direct = options;
  direct.continuation = false;
  direct.max_iterations = kColdIterationFactor * options.max_iterations;
  const SpatialJointVector home = SpatialJointVector::Zero(robot.num_rods);
  enum class Start { kStraight, kBowed, kFromHome, kBowedTraced };
  internal::SpatialBowedStall stall;
  bool stalled = false;
  // Solves x at q from `start` (x set here), in problem at its starting step count.
  const auto solve_from = [&](Start start, internal::SpatialForwardProblem& problem,
                              SpatialShootingPoint<double>& x) {
    SolverSummary& summary = out.summary;
    switch (start) {
      case Start::kStraight:
        x = straight_rods_guess(robot, q);
        return internal::spatial_solve_path(problem, x, q, q, out.warm, direct, summary);
      case Start::kBowed:
      case Start::kBowedTraced: {
        SolveStatus status;
        if (start == Start::kBowed) {
          x = straight_rods_guess(robot, q);
          status = internal::spatial_homotopy_solve(robot, x, problem.rod_steps(), options, summary,
                                                    stall);
          stalled = status != SolveStatus::kConverged;
        } else {
          status = internal::spatial_trace_bowed_start(robot, stall, x, problem.rod_steps(),
                                                       options, summary);
        }
        if (status != SolveStatus::kConverged) return status;
        // There: its Jacobian and tangent, for the refinement.
        return internal::spatial_solve_path(problem, x, q, q, out.warm, direct, summary);
      }
      case Start::kFromHome: {
        x = straight_rods_guess(robot, home);
        const SolveStatus status =
            internal::spatial_solve_path(problem, x, home, home, out.warm, direct, summary);
        if (status != SolveStatus::kConverged) return status;
        return internal::spatial_solve_path(problem, x, home, q, out.warm, options, summary);
      }
    }
    return SolveStatus::kMaxIterations;
  };
  SpatialForwardSolution unstable;  // the first converged start's, when it is unstable
  SolveStatus first = SolveStatus::kMaxIterations;
  for (const Start start :
       {Start::kStraight, Start::kBowed, Start::kFromHome, Start::kBowedTraced}) {
    if (start != Start::kStraight && !options.continuation) break;
    if (start == Start::kFromHome && q.isZero(0.0)) continue;
    if (start == Start::kBowedTraced && !stalled) break;
    internal::SpatialForwardProblem problem(robot, internal::starting_rod_steps(options, 0));
    SpatialShootingPoint<double> x;
    out.summary.status = solve_from(start, problem, x);
    if (start == Start::kStraight) first = out.summary.status;
    out.summary.status = internal::spatial_refine_rod_steps(problem, x, out.warm.lu, options,
                                                            out.summary, out.summary.status);
    internal::fill_solution(problem, x, out);
    internal::report_spatial_solution(robot, options, out);
    if (!usable_as_warm_start(out.summary)) continue;
    if (out.summary.stability != Stability::kUnstable) return out;
    if (!usable_as_warm_start(unstable.summary)) unstable = out;
  }
  if (usable_as_warm_start(unstable.summary)) {  // no start gave a stable equilibrium
    unstable.summary.iterations = out.summary.iterations;
    unstable.summary.residual_evaluations = out.summary.residual_evaluations;
    unstable.summary.continuation_steps = out.summary.continuation_steps;
    return unstable;
  }
  out.summary.status = first;
  internal::report_spatial_solution(robot, options, out);
  return out;
}

PCR_SOLVER_INLINE SpatialInverseSolution
spatial_inverse_kinematics(const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
                           const SpatialForwardSolution& start, const SolverOptions& options) {
  // The forward solution's factorisation is of another problem: no carried Jacobian.
  return internal::spatial_inverse_from(robot, pose, start, nullptr, options);
}

PCR_SOLVER_INLINE SpatialInverseSolution
spatial_inverse_kinematics(const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
                           const SpatialInverseSolution& warm_start, const SolverOptions& options) {
  return internal::spatial_inverse_from(robot, pose, warm_start, &warm_start.warm, options);
}

PCR_SOLVER_INLINE SpatialInverseSolution spatial_inverse_kinematics_from_home(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialForwardSolution& home, const SolverOptions& options) {
  if (!home.summary.converged()) {
    SpatialInverseSolution out;
    out.summary = home.summary;
    out.summary.iterations = 0;
    out.summary.path_fraction = 0.0;
    return out;
  }
  return spatial_inverse_kinematics(robot, pose, home, options);
}

PCR_SOLVER_INLINE SpatialInverseSolution
spatial_inverse_kinematics(const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
                           const SolverOptions& options) {
  const SpatialForwardSolution home =
      spatial_forward_kinematics(robot, SpatialJointVector::Zero(robot.num_rods), options);
  return spatial_inverse_kinematics_from_home(robot, pose, home, options);
}

#endif  // PCR_SOLVER_DEFINITIONS

}  // namespace pcr
