#pragma once
// Pseudo-arclength continuation of a shooting problem along its straight input path: follows the
// curve of solutions (z, t) through folds, where the input t turns back, instead of stopping
// there (Keller's method: the tangent of the curve from the bordered Jacobian, a predictor along
// it, a corrector on the hyperplane normal to it).

#include <Eigen/LU>
#include <cmath>

#include "pcr/internal/newton.hpp"
#include "pcr/internal/shooting_problem.hpp"

namespace pcr::internal {

using BorderedMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxResiduals + 1, kMaxResiduals + 1>;
using BorderedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxResiduals + 1, 1>;

/// Where the trace ended and where it turned.
struct ArclengthTrace {
  bool reached = false;  ///< the curve came to t = 1 (moving forward)
  int points = 0;        ///< solved points along the curve
  int folds = 0;         ///< turns of t along the way
  double first_fold = std::numeric_limits<double>::quiet_NaN();  ///< t at the first turn
  double t = 0;                                                  ///< t of the last solved point (z)
};

/// The bordered system's matrix [J_z, J_t; tangent^T] at (z, t); r receives the residual.
inline bool bordered_jacobian(const ShootingProblem& problem, const ShootingVector& z,
                              const ShootingVector& du, const BorderedVector& tangent,
                              ShootingVector& r, BorderedMatrix& m, SolverSummary& summary) {
  JacobianMatrix j;
  problem.evaluate(z, r, &j);
  ++summary.residual_evaluations;
  const int n = problem.size();
  m.resize(n + 1, n + 1);
  m.topLeftCorner(n, n) = j;
  m.topRightCorner(n, 1) = problem.input_derivative(z, du);
  m.bottomRows(1) = tangent.transpose();
  return m.allFinite() && r.allFinite();
}

/// Traces the solutions of `problem` from z (a solution at u0) along u(t) = u0 + t (u1 - u0) by
/// pseudo-arclength steps (in the scaled unknowns and t), calling visit(z, t) at each solved point;
/// stops at t = 1 reached forward, at t < 0, after max_steps points, or when a step cannot be
/// corrected even when short. On return z and trace.t are the last solved point (with reached,
/// the point past t = 1 the caller solves back onto t = 1).
template <class Visitor>
ArclengthTrace trace_arclength(ShootingProblem& problem, const ShootingVector& u0,
                               const ShootingVector& u1, ShootingVector& z,
                               const SolverOptions& options, SolverSummary& summary, int max_steps,
                               Visitor&& visit) {
  ArclengthTrace trace;
  const int n = problem.size();
  const ShootingVector du = u1 - u0;
  ShootingVector r;
  BorderedMatrix m;
  // The first tangent continues along +t.
  BorderedVector tangent = BorderedVector::Zero(n + 1);
  tangent(n) = 1.0;
  const auto new_tangent = [&](const BorderedVector& previous) -> bool {
    problem.set_input(u0 + trace.t * du);
    if (!bordered_jacobian(problem, z, du, previous, r, m, summary)) return false;
    BorderedVector rhs = BorderedVector::Zero(n + 1);
    rhs(n) = 1.0;
    BorderedVector t = m.partialPivLu().solve(rhs);
    if (!t.allFinite() || t.norm() == 0) return false;
    t /= t.norm();
    if (t.dot(previous) < 0) t = -t;  // keep the direction of travel
    tangent = t;
    return true;
  };
  if (!new_tangent(tangent)) return trace;
  double ds = 0.05;
  const double tolerance = std::max(options.tolerance, 1e-10);
  while (trace.points < max_steps) {
    // Predictor along the tangent, corrector on the hyperplane through it.
    BorderedVector y(n + 1), predicted(n + 1);
    y << z, trace.t;
    predicted = y + ds * tangent;
    BorderedVector x = predicted;
    bool converged = false;
    int iterations = 0;
    for (; iterations < 8; ++iterations) {
      problem.set_input(u0 + x(n) * du);
      const ShootingVector zx = x.head(n);
      if (!bordered_jacobian(problem, zx, du, tangent, r, m, summary)) break;
      ++summary.iterations;
      BorderedVector g(n + 1);
      g << r, tangent.dot(x - predicted);
      if (max_norm(r) <= tolerance && iterations > 0) {
        converged = true;
        break;
      }
      const BorderedVector step = m.partialPivLu().solve(-g);
      if (!step.allFinite()) break;
      x += step;
    }
    if (!converged) {
      ds *= 0.5;
      if (ds < 1e-7) return trace;
      continue;
    }
    const double t_before = trace.t;
    const double direction_before = tangent(n);
    z = x.head(n);
    trace.t = x(n);
    ++trace.points;
    ++summary.continuation_steps;
    if (!new_tangent(tangent)) return trace;
    if ((tangent(n) > 0) != (direction_before > 0)) {
      if (trace.folds == 0) trace.first_fold = 0.5 * (t_before + trace.t);
      ++trace.folds;
    }
    visit(z, trace.t);
    if (t_before < 1.0 && trace.t >= 1.0 && tangent(n) > 0) {
      trace.reached = true;
      return trace;
    }
    if (trace.t < 0.0) return trace;
    if (iterations <= 4) ds = std::min(2.0 * ds, 0.25);
  }
  return trace;
}

}  // namespace pcr::internal
