#pragma once
// Pseudo-arclength continuation of a shooting problem along its straight input path: follows the
// curve of solutions (z, t) through folds, where the input t turns back, instead of stopping
// there (Keller's method: the tangent of the curve from the bordered Jacobian, a predictor along
// it, a corrector on the hyperplane normal to it).
//
// The rule (trace_curve: the tangent's direction of travel, the step-length control, the fold
// count) is shared by the planar problem here (trace_arclength) and the spatial ones
// (pcr/spatial/arclength.hpp), whose unknowns lie on a manifold: a curve says how a point moves
// by a step in its local coordinates (scaled unknowns, then t) and how far apart two points are
// in them.

#include <Eigen/LU>
#include <cmath>
#include <limits>

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
  double t = 0;                                                  ///< t of the last solved point
};

/// Traces the curve of solutions of `curve` from `point` (a solution at t = 0) by pseudo-arclength
/// steps in the curve's local coordinates (its scaled unknowns and t), calling visit(point) at
/// each solved point; stops at t = 1 reached forward, at t < 0, after max_steps points, or when a
/// step cannot be corrected even when short. On return `point` and trace.t are the last solved
/// point (with reached, the point past t = 1 the caller solves back onto t = 1).
/// Curve: Point, Vector and Matrix (the bordered system's, n + 1 rows), size() (n), t(point),
/// advance(point, step) (the point moved by a step of its local coordinates), offset(from, to)
/// (the step that moves `from` to `to`), and bordered(point, tangent, g, m, summary): m the
/// bordered matrix [J_z, J_t; tangent^T] at the point, g's first n entries its residual; false
/// when not finite.
template <class Curve, class Visitor>
ArclengthTrace trace_curve(Curve& curve, typename Curve::Point& point, const SolverOptions& options,
                           SolverSummary& summary, int max_steps, Visitor&& visit) {
  using Vector = typename Curve::Vector;
  using Matrix = typename Curve::Matrix;
  ArclengthTrace trace;
  const int n = curve.size();
  Vector g(n + 1);
  Matrix m;
  // The first tangent continues along +t.
  Vector tangent = Vector::Zero(n + 1);
  tangent(n) = 1.0;
  const auto new_tangent = [&](const Vector& previous) -> bool {
    if (!curve.bordered(point, previous, g, m, summary)) return false;
    Vector rhs = Vector::Zero(n + 1);
    rhs(n) = 1.0;
    Vector t = m.partialPivLu().solve(rhs);
    if (!t.allFinite() || t.norm() == 0) return false;
    t /= t.norm();
    if (t.dot(previous) < 0) t = -t;  // keep the direction of travel
    tangent = t;
    return true;
  };
  if (!new_tangent(tangent)) return trace;
  double ds = 0.05;
  const double tolerance = std::max(options.tolerance, 1e-10);
  trace.t = curve.t(point);
  while (trace.points < max_steps) {
    // Predictor along the tangent, corrector on the hyperplane through it.
    const typename Curve::Point predicted = curve.advance(point, Vector(ds * tangent));
    typename Curve::Point x = predicted;
    bool converged = false;
    int iterations = 0;
    for (; iterations < 8; ++iterations) {
      if (!curve.bordered(x, tangent, g, m, summary)) break;
      ++summary.iterations;
      g(n) = tangent.dot(curve.offset(predicted, x));
      const double norm = g.head(n).allFinite() ? g.head(n).template lpNorm<Eigen::Infinity>()
                                                : std::numeric_limits<double>::quiet_NaN();
      if (norm <= tolerance && iterations > 0) {
        converged = true;
        break;
      }
      const Vector step = m.partialPivLu().solve(-g);
      if (!step.allFinite()) break;
      x = curve.advance(x, step);
    }
    if (!converged) {
      ds *= 0.5;
      if (ds < 1e-7) return trace;
      continue;
    }
    const double t_before = trace.t;
    const double direction_before = tangent(n);
    point = x;
    trace.t = curve.t(point);
    ++trace.points;
    ++summary.continuation_steps;
    if (!new_tangent(tangent)) return trace;
    if ((tangent(n) > 0) != (direction_before > 0)) {
      if (trace.folds == 0) trace.first_fold = 0.5 * (t_before + trace.t);
      ++trace.folds;
    }
    visit(static_cast<const typename Curve::Point&>(point));
    if (t_before < 1.0 && trace.t >= 1.0 && tangent(n) > 0) {
      trace.reached = true;
      return trace;
    }
    if (trace.t < 0.0) return trace;
    if (iterations <= 4) ds = std::min(2.0 * ds, 0.25);
  }
  return trace;
}

/// The planar shooting problem along u(t) = u0 + t (u1 - u0), as a curve of points (z, t).
class PlanarArclengthCurve {
 public:
  using Point = BorderedVector;
  using Vector = BorderedVector;
  using Matrix = BorderedMatrix;

  PlanarArclengthCurve(ShootingProblem& problem, const ShootingVector& u0, const ShootingVector& u1)
      : problem_(problem), u0_(u0), du_(u1 - u0) {}

  int size() const { return problem_.size(); }
  double t(const Point& y) const { return y(size()); }
  Point advance(const Point& y, const Vector& step) const { return y + step; }
  Vector offset(const Point& from, const Point& to) const { return to - from; }

  /// The bordered system's matrix [J_z, J_t; tangent^T] at y = (z, t); g's head the residual.
  bool bordered(const Point& y, const Vector& tangent, Vector& g, Matrix& m,
                SolverSummary& summary) {
    const int n = size();
    problem_.set_input(u0_ + y(n) * du_);
    const ShootingVector z = y.head(n);
    ShootingVector r;
    JacobianMatrix j;
    problem_.evaluate(z, r, &j);
    ++summary.residual_evaluations;
    m.resize(n + 1, n + 1);
    m.topLeftCorner(n, n) = j;
    m.topRightCorner(n, 1) = problem_.input_derivative(z, du_);
    m.bottomRows(1) = tangent.transpose();
    g.head(n) = r;
    return m.allFinite() && r.allFinite();
  }

 private:
  ShootingProblem& problem_;
  ShootingVector u0_;
  ShootingVector du_;
};

/// Traces the solutions of `problem` from z (a solution at u0) along u(t) = u0 + t (u1 - u0)
/// (trace_curve), calling visit(z, t) at each solved point. On return z and trace.t are the last
/// solved point.
template <class Visitor>
ArclengthTrace trace_arclength(ShootingProblem& problem, const ShootingVector& u0,
                               const ShootingVector& u1, ShootingVector& z,
                               const SolverOptions& options, SolverSummary& summary, int max_steps,
                               Visitor&& visit) {
  PlanarArclengthCurve curve(problem, u0, u1);
  const int n = problem.size();
  BorderedVector y(n + 1);
  y << z, 0.0;
  const ArclengthTrace trace =
      trace_curve(curve, y, options, summary, max_steps, [&](const BorderedVector& point) {
        const ShootingVector point_z = point.head(n);
        visit(point_z, point(n));
      });
  z = y.head(n);
  return trace;
}

}  // namespace pcr::internal
