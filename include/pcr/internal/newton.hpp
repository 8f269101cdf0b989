#pragma once
// Damped Newton with chord steps, generic over a square problem, and its building blocks. No heap,
// no exceptions, a bounded number of evaluations.

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "pcr/shooting.hpp"
#include "pcr/solver.hpp"

namespace pcr::internal {

using JacobianLU = Eigen::PartialPivLU<JacobianMatrix>;

/// The matrix of Newton's chord steps, an approximation of the inverse Jacobian carried from one
/// solve to the next (a warm start's). It starts as the factorisation of an evaluated Jacobian;
/// each chord step then corrects it with the secant its residual measured (Broyden's "good"
/// update of the inverse, a rank-one Sherman-Morrison term), so that along a sequence of nearby
/// solves it follows the Jacobian as the configuration moves instead of ageing, and a warm solve
/// rarely needs a new Jacobian (which costs about four residuals).
class ChordMatrix {
 public:
  /// Factorises a freshly evaluated Jacobian (dropping the secant corrections).
  void compute(const JacobianMatrix& J) {
    lu_.compute(J);
    rcond_ = lu_.rcond();
    has_inverse_ = false;
  }
  /// Size of the Jacobian; 0 when there is none.
  int rows() const { return lu_.rows(); }
  /// Reciprocal condition number of the last factorised Jacobian.
  double rcond() const { return rcond_; }
  /// The chord step's solution of J x = b.
  ShootingVector solve(const ShootingVector& b) const {
    if (has_inverse_) return inverse_ * b;
    return lu_.solve(b);
  }
  /// The secant condition of a step s that changed the residual by y: afterwards solve(y) = s.
  /// Skipped when s is not seen through the current matrix (s . solve(y) near zero).
  void secant_update(const ShootingVector& s, const ShootingVector& y) {
    if (!has_inverse_) {
      invert_factorisation();
      has_inverse_ = true;
    }
    const ShootingVector Hy = inverse_ * y;
    const double denominator = s.dot(Hy);
    if (!(std::abs(denominator) > 1e-3 * s.norm() * Hy.norm())) return;
    inverse_ += ((s - Hy) / denominator) * (s.transpose() * inverse_);
  }

 private:
  /// inverse_ = J^-1 = U^-1 L^-1 P from the factorisation P J = L U. Eigen's lu_.inverse() goes
  /// through its blocked triangular solves (packing, a matrix kernel), which at 12 x 12 cost more
  /// than the arithmetic: about a tenth of a warm IK solve. Substituting one column at a time was
  /// slower still (each column a chain of dependent divisions).
  void invert_factorisation() {
    const int n = lu_.rows();
    const JacobianMatrix& LU = lu_.matrixLU();
    // Row operations on all the columns at once: each row update is a vector operation, and the
    // columns' substitutions are independent, so none waits on the latency of another.
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor,
                                   kMaxResiduals, kMaxResiduals>;
    RowMajor X = RowMajor::Zero(n, n);
    const auto& to_row = lu_.permutationP().indices();  // P e_c = e_{to_row(c)}
    for (int c = 0; c < n; ++c) X(to_row(c), c) = 1.0;
    for (int k = 0; k < n - 1; ++k) {  // L, unit lower
      for (int i = k + 1; i < n; ++i) X.row(i) -= LU(i, k) * X.row(k);
    }
    for (int k = n - 1; k >= 0; --k) {  // U
      X.row(k) /= LU(k, k);
      for (int i = 0; i < k; ++i) X.row(i) -= LU(i, k) * X.row(k);
    }
    inverse_ = X;
  }

  JacobianLU lu_;
  JacobianMatrix inverse_;
  double rcond_ = 0.0;
  bool has_inverse_ = false;
};

/// Max-norm of a residual; NaN when a component is not finite (Eigen's max-norm may skip a NaN,
/// which made a NaN warm start look converged).
inline double max_norm(const ShootingVector& r) {
  return r.allFinite() ? r.lpNorm<Eigen::Infinity>() : std::numeric_limits<double>::quiet_NaN();
}

struct NewtonResult {
  SolveStatus status = SolveStatus::kMaxIterations;
  double initial_norm = std::numeric_limits<double>::quiet_NaN();
  double final_norm = std::numeric_limits<double>::quiet_NaN();
  double max_strain = std::numeric_limits<double>::quiet_NaN();
};

/// Damped Newton from z (updated in place). A stall at a non-zero minimum of |r| means the
/// Jacobian is singular there (J^T r = 0 with r != 0): reported as kSingular.
///
/// A Jacobian costs about two plain residuals, so it is evaluated only where it pays: near a
/// solution (a warm start) a step that shrinks the residual by kChordContraction or more is
/// followed by chord steps with the same factorisation, which keep contracting by about as much
/// (the Jacobian barely changes over the step). A chord step that does not contract that well,
/// and every step far from the solution, falls back to a fresh Jacobian and a line search.
///
/// `carried` (optional) carries a factorised Jacobian between solves: on entry, one evaluated near
/// z (say, at the previous solution of a control loop) to try as the chord matrix of the first
/// step when z is near the solution; on exit, the factorisation of the last Jacobian evaluated.
///
/// Problem: size(); evaluate(z, r, J*) filling the residual and, when J is not null, its
/// Jacobian, and returning a by-product kept with the accepted point (the shooting problem's
/// largest bending strain); output_change_within(dz, share), whether a step dz moves the solved
/// outputs by at most that share of their accuracy targets.
template <class Problem>
NewtonResult newton_solve(const Problem& problem, ShootingVector& z, const SolverOptions& options,
                          SolverSummary& summary, ChordMatrix* carried = nullptr) {
  // Residual norms below this ask for no Jacobian at the trial point: Newton from there is
  // expected to contract by kChordContraction, so the old factorisation will do.
  constexpr double kWarmNorm = 1e-2;
  constexpr double kChordContraction = 0.1;
  // A residual and a Newton step this small (scaled: 3e-11 m on a 30 mm rod) are rounding noise.
  constexpr double kRoundingFloor = 1e-9;
  NewtonResult result;
  ShootingVector r, r_trial, z_trial, step, r_corrected, z_corrected;
  JacobianMatrix J, J_trial;
  ChordMatrix lu_corrector;
  const bool try_chord = carried && carried->rows() == problem.size();
  result.max_strain = problem.evaluate(z, r, try_chord ? nullptr : &J);
  ++summary.residual_evaluations;
  double norm = max_norm(r);
  result.initial_norm = norm;
  result.final_norm = norm;
  if (!std::isfinite(norm)) {
    result.status = SolveStatus::kNonFinite;
    return result;
  }
  ChordMatrix own;
  ChordMatrix& lu = carried ? *carried : own;  // the caller's, updated in place (not copied)
  bool jacobian_at_z = true;  // J is the Jacobian at z (else: at an earlier iterate, chord)
  bool factorised = false;    // lu holds the factorisation of the newest Jacobian
  bool step_ready = false;    // step is the chord step from z with lu
  if (try_chord) {
    if (norm <= kWarmNorm || norm <= options.tolerance) {
      factorised = true;
      jacobian_at_z = false;
    } else {
      result.max_strain = problem.evaluate(z, r, &J);  // far: the carried one would not do
      ++summary.residual_evaluations;
    }
  }
  // Leaves the caller the factorisation of the newest Jacobian on every exit.
  struct HandBack {
    ChordMatrix* out;
    const JacobianMatrix& J;
    const bool& factorised;
    ~HandBack() {
      if (out != nullptr && !factorised && J.rows() > 0) out->compute(J);
    }
  } hand_back{carried, J, factorised};
  // Near a fold a full step from a warm start (a tangent predictor) overshoots along the nearly
  // singular direction, and halving it crawls (tens of evaluations). A Newton corrector from the
  // overshot point z_trial usually lands next to the solution: kept if it beats z.
  double corrected_strain = 0;
  const auto try_corrector = [&](double norm2) {
    corrected_strain = problem.evaluate(z_trial, r_trial, &J_trial);
    ++summary.residual_evaluations;
    lu_corrector.compute(J_trial);
    if (!(lu_corrector.rcond() > 1e-14)) return false;
    z_corrected = z_trial - lu_corrector.solve(r_trial);
    corrected_strain = problem.evaluate(z_corrected, r_corrected, nullptr);
    ++summary.residual_evaluations;
    const double corrected2 = r_corrected.squaredNorm();
    return std::isfinite(corrected2) && corrected2 <= (1.0 - 1e-4) * norm2;
  };
  const auto accept_corrector = [&]() {
    // Chord from the corrected point with the factorisation at the predictor.
    z = z_corrected;
    r = r_corrected;
    norm = max_norm(r);
    result.final_norm = norm;
    result.max_strain = corrected_strain;
    J = J_trial;
    lu = lu_corrector;
    factorised = true;
    jacobian_at_z = false;
  };
  for (int iter = 0; iter <= options.max_iterations; ++iter) {
    if (norm <= options.tolerance) {
      result.status = SolveStatus::kConverged;
      return result;
    }
    if (iter == options.max_iterations) break;
    ++summary.iterations;
    if (!jacobian_at_z) {
      // Chord step: accepted only if it contracts as a Newton step near the solution would.
      // A carried factorisation: a bad one fails the contraction test. The stopping rule below
      // may have computed this step already.
      if (!step_ready) step = -lu.solve(r);
      step_ready = false;
      z_trial = z + step;
      const double strain = problem.evaluate(z_trial, r_trial, nullptr);
      ++summary.residual_evaluations;
      const double trial_norm = max_norm(r_trial);
      if (std::isfinite(trial_norm)) lu.secant_update(step, r_trial - r);
      if (std::isfinite(trial_norm) &&
          (trial_norm <= kChordContraction * norm || trial_norm <= options.tolerance)) {
        const double contraction = trial_norm / norm;
        z = z_trial;
        r = r_trial;
        norm = trial_norm;
        result.final_norm = norm;
        result.max_strain = strain;
        // The stopping rule of simplified Newton (Hairer and Wanner, Solving ODEs II, IV.8):
        // chord steps contract at a steady rate, so the next one is taken without evaluating
        // the residual after it when it is due to bring the residual below the tolerance, or
        // when the error it leaves on the outputs, about the contraction times its own size,
        // is a negligible share of the accuracy targets.
        if (norm <= options.tolerance) continue;
        step = -lu.solve(r);
        step_ready = true;
        if (contraction * norm <= options.tolerance ||
            problem.output_change_within(contraction * step, options.chord_output_share)) {
          z += step;
          ++summary.iterations;
          result.final_norm = contraction * norm;  // predicted
          result.status = SolveStatus::kConverged;
          return result;
        }
        continue;
      }
      if (std::isfinite(trial_norm) && trial_norm < norm) {
        z = z_trial;  // not contracting well, but still progress: keep it
      } else if (std::isfinite(trial_norm) && trial_norm <= kWarmNorm &&
                 try_corrector(r.squaredNorm())) {
        accept_corrector();
        continue;
      }
      // Refresh the Jacobian at z and take a Newton step from there instead.
      result.max_strain = problem.evaluate(z, r, &J);
      ++summary.residual_evaluations;
      norm = max_norm(r);
      result.final_norm = norm;
      jacobian_at_z = true;
      factorised = false;
    }
    if (!factorised) {
      lu.compute(J);
      factorised = true;
      if (!(lu.rcond() > 1e-14)) {
        result.status = SolveStatus::kSingular;
        return result;
      }
    }
    step = -lu.solve(r);
    // Backtracking on the Euclidean norm, whose decrease the Newton direction guarantees. Near
    // the solution the full step is evaluated without its Jacobian (the chord may reuse J).
    const bool warm = norm <= kWarmNorm;
    const double norm2 = r.squaredNorm();
    double t = 1.0;
    bool accepted = false;
    bool trial_has_jacobian = false;
    bool corrected = false;
    double strain = result.max_strain;
    for (int ls = 0; ls <= options.max_line_search; ++ls, t *= 0.5) {
      z_trial = z + t * step;
      trial_has_jacobian = !warm;
      strain = problem.evaluate(z_trial, r_trial, trial_has_jacobian ? &J_trial : nullptr);
      ++summary.residual_evaluations;
      const double trial2 = r_trial.squaredNorm();
      if (std::isfinite(trial2) && trial2 <= (1.0 - 1e-4 * t) * norm2) {
        accepted = true;
        break;
      }
      // Rounding floor: a full step that cannot decrease an already tiny residual.
      if (std::isfinite(trial2) && ls == 0 && max_norm(r_trial) <= options.tolerance) {
        accepted = true;
        break;
      }
      // Near a fold the full step (a tangent predictor, warm) overshoots along the nearly
      // singular direction and halving it crawls (tens of evaluations). A Newton corrector from
      // the overshot point usually lands next to the solution: keep it if it beats the start.
      if (warm && ls == 0 && std::isfinite(trial2) && max_norm(r_trial) <= kWarmNorm &&
          try_corrector(norm2)) {
        corrected = true;
        break;
      }
    }
    if (corrected) {
      ++summary.iterations;
      accept_corrector();
      continue;
    }
    if (!accepted && norm <= kRoundingFloor && step.lpNorm<Eigen::Infinity>() <= kRoundingFloor) {
      // A Newton step within rounding of a solution that cannot decrease its residual any
      // further: an ill-conditioned Jacobian (pre-stressed rods, some pulled nearly straight)
      // puts the rounding floor above the tolerance. The solution is as exact as it can be.
      result.status = SolveStatus::kConverged;
      return result;
    }
    if (!accepted) {
      // No descent along the Newton direction: a minimum of |r| with r != 0 has J^T r = 0.
      const ShootingVector gradient = J.transpose() * r;
      const double scale = J.norm() * r.norm();
      result.status = gradient.norm() <= 1e-6 * scale || lu.rcond() < 1e-8
                          ? SolveStatus::kSingular
                          : SolveStatus::kMaxIterations;
      return result;
    }
    const double trial_norm = max_norm(r_trial);
    const bool contracted = t == 1.0 && trial_norm <= kChordContraction * norm;
    z = z_trial;
    r = r_trial;
    norm = trial_norm;
    result.final_norm = norm;
    result.max_strain = strain;
    if (trial_has_jacobian) {
      J = J_trial;
      factorised = false;
    } else if (contracted || norm <= options.tolerance) {
      jacobian_at_z = false;  // chord from here with the current factorisation
    } else {
      result.max_strain = problem.evaluate(z, r, &J);
      ++summary.residual_evaluations;
      norm = max_norm(r);
      factorised = false;
    }
  }
  result.status = SolveStatus::kMaxIterations;
  return result;
}

/// Reciprocal condition number of the Jacobian at z (for the singularity test of a path).
template <class Problem>
double jacobian_rcond(const Problem& problem, const ShootingVector& z, SolverSummary& summary) {
  ShootingVector r;
  JacobianMatrix J;
  problem.evaluate(z, r, &J);
  ++summary.residual_evaluations;
  const JacobianLU lu(J);
  const double rcond = lu.rcond();
  return std::isfinite(rcond) ? rcond : 0.0;
}

}  // namespace pcr::internal
