#pragma once
// Forward and inverse kinematics by Newton shooting (Mauze et al. 2021, Section 2.2).
//
// Real-time safe: no heap allocation, no exceptions, a bounded number of iterations. Numerical
// outcomes are reported in a SolverSummary, never thrown.
//
//   FK: unknowns = proximal wrenches (3n) + platform pose (3), inputs = joints q (n).
//   IK: unknowns = proximal wrenches (3n) + joints (n) [+ theta when n = 2], inputs = pose.
// IK is square for n = 3 (full pose) and for n = 2 (x, y imposed, theta free); other n are refused.

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/LU>

#include "pcr/robot.hpp"
#include "pcr/shooting.hpp"

namespace pcr {

enum class SolveStatus {
  kConverged,      ///< the scaled residual is below the tolerance
  kMaxIterations,  ///< the iteration or continuation budget ran out
  kSingular,       ///< no solution on this branch: the Jacobian became singular along the path
  kBifurcation,    ///< the path starts on a bifurcation (solutions exist on other branches)
  kNonFinite,      ///< the residual became NaN or infinite
  kOutOfRange,     ///< IK converged, but a joint value lies outside its stroke
  kUnsupported,    ///< the request is not a square problem (IK with n > 3 limbs)
  kInvalidInput,   ///< wrong sizes, NaN inputs, or a robot with fewer than 2 / more than kMaxLimbs limbs
};

inline const char* to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::kConverged: return "converged";
    case SolveStatus::kMaxIterations: return "max_iterations";
    case SolveStatus::kSingular: return "singular";
    case SolveStatus::kBifurcation: return "bifurcation";
    case SolveStatus::kNonFinite: return "non_finite";
    case SolveStatus::kOutOfRange: return "out_of_range";
    case SolveStatus::kUnsupported: return "unsupported";
    case SolveStatus::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

struct SolverOptions {
  /// RK4 steps per rod; 0 chooses them from an estimate of the solution's own discretisation
  /// error (RK4 is fourth order: the residual of the N/2-step model at the N-step solution gives
  /// it, through the Jacobian, for the solved outputs themselves), so that the outputs stay within
  /// position_accuracy and angle_accuracy of the exact model's (tests/test_reference.cpp checks
  /// it against CVODE on random robots).
  int rod_steps = 0;
  /// Target of that estimate on the solved lengths (m): FK's platform x, y; IK's joints.
  double position_accuracy = 2.5e-10;
  /// Target of that estimate on the solved angles (rad): FK's theta; IK's theta for n = 2.
  double angle_accuracy = 2.5e-7;
  int min_rod_steps = 16;
  int max_rod_steps = 512;
  /// Newton iterations per solve (each sub-solve of a continuation has its own budget).
  int max_iterations = 20;
  /// Convergence: max-norm of the scaled residual (lengths / L, forces / (EI / L^2)).
  double tolerance = 1e-12;
  /// Step halvings of the backtracking line search.
  int max_line_search = 12;
  /// When a direct solve fails, step the input from the last solution in smaller increments.
  bool continuation = true;
  /// Sub-solves a continuation may use in total.
  int max_continuation_steps = 64;
  /// Newton iterations per sub-solve of a continuation. From its predictor a sub-solve converges
  /// in a few iterations or crawls along its line search: a shorter step is cheaper than more.
  int max_continuation_iterations = 8;
  /// Smallest continuation increment, as a fraction of the whole path.
  double min_continuation_step = 1.0 / 1024.0;
};

struct SolverSummary {
  SolveStatus status = SolveStatus::kMaxIterations;
  int iterations = 0;             ///< Newton iterations, all sub-solves included
  int residual_evaluations = 0;   ///< residual (+ Jacobian) evaluations
  int continuation_steps = 0;     ///< sub-solves of the continuation; 0 for a direct solve
  double initial_residual_norm = std::numeric_limits<double>::quiet_NaN();  ///< scaled max-norm
  double final_residual_norm = std::numeric_limits<double>::quiet_NaN();    ///< scaled max-norm
  double max_strain = std::numeric_limits<double>::quiet_NaN();  ///< max |kappa| d / 2 over the rods
  int rod_steps = 0;  ///< RK4 steps per rod of the returned solution
  /// Estimated discretisation error of the returned outputs against the exact model (NaN when
  /// not estimated: a fixed rod_steps, or no converged solution): lengths (m) and angles (rad).
  double position_error_estimate = std::numeric_limits<double>::quiet_NaN();
  double angle_error_estimate = std::numeric_limits<double>::quiet_NaN();
  bool converged() const { return status == SolveStatus::kConverged; }
};

struct ForwardSolution {
  JointVector q;                                     ///< the joints solved for (m)
  Pose2<double> pose;                                ///< platform pose ^W T_P
  std::array<Wrench<double>, kMaxLimbs> wrenches{};  ///< proximal wrench (n, m)(0) of each rod
  SolverSummary summary;
  /// The last Jacobian the solver evaluated (scaled units; empty if none): a warm start from this
  /// solution uses it for its first, chord, step instead of evaluating a new one.
  JacobianMatrix jacobian;
};

struct InverseSolution {
  Pose2<double> pose;                                ///< the pose (theta solved for when n = 2)
  JointVector q;                                     ///< joint values (m)
  std::array<Wrench<double>, kMaxLimbs> wrenches{};  ///< proximal wrench (n, m)(0) of each rod
  SolverSummary summary;
  /// As ForwardSolution::jacobian, for the inverse problem.
  JacobianMatrix jacobian;
};

namespace internal {

inline bool all_finite(const ShootingVector& v) { return v.allFinite(); }

/// One shooting problem (FK or IK) along a straight input path u(t) = u0 + t (u1 - u0).
class ShootingProblem {
 public:
  enum class Kind { kForward, kInverse };

  ShootingProblem(Kind kind, const RobotParams<double>& robot, const PlatformLoad<double>& load,
                  const SolverOptions& options)
      : kind_(kind), robot_(robot), load_(load), options_(options),
        scale_(shooting_scale(robot)), n_(robot.num_limbs) {
    steps_ = options.rod_steps > 0 ? options.rod_steps : options.min_rod_steps;
  }

  int rod_steps() const { return steps_; }
  void set_rod_steps(int steps) { steps_ = steps; }
  const RobotParams<double>& robot() const { return robot_; }
  const PlatformLoad<double>& load() const { return load_; }

  /// The physical size of a step dz of the scaled unknowns on the solved outputs: the largest
  /// length (m: FK's x, y; IK's joints) and the largest angle (rad: FK's theta; IK's theta, n = 2).
  void output_change(const ShootingVector& dz, double& position, double& angle) const {
    position = 0.0;
    angle = 0.0;
    const auto take = [](double& to, double v) { to = std::isfinite(v) ? std::max(to, v) : v; };
    if (kind_ == Kind::kForward) {
      take(position, std::abs(dz(3 * n_)) * scale_.length);
      take(position, std::abs(dz(3 * n_ + 1)) * scale_.length);
      take(angle, std::abs(dz(3 * n_ + 2)));
    } else {
      for (int i = 0; i < n_; ++i) take(position, std::abs(dz(3 * n_ + i)) * scale_.length);
      if (n_ == 2) take(angle, std::abs(dz(4 * n_)));
    }
  }

  /// The step count for a solution whose estimated error at the current count is `ratio` times
  /// its target: the smallest on the ladder that meets the target (error ~ N^-4), but a lower
  /// count only when it meets half the target, so that a sequence does not flip between two.
  int rod_steps_for_error(double ratio) const {
    if (options_.rod_steps > 0) return options_.rod_steps;
    if (!std::isfinite(ratio)) return options_.max_rod_steps;
    const auto rung_at_least = [&](double steps) {
      int ladder = options_.min_rod_steps;
      while (ladder < steps && ladder < options_.max_rod_steps) ladder = next_rung(ladder);
      return std::min(ladder, options_.max_rod_steps);
    };
    if (ratio > 1.0) return std::max(steps_, rung_at_least(steps_ * std::pow(ratio, 0.25)));
    return std::min(steps_, rung_at_least(steps_ * std::pow(2.0 * ratio, 0.25)));
  }

  /// The step count after `steps` on the ladder towards `target` (which is on the ladder).
  int rung_towards(int steps, int target) const {
    if (options_.rod_steps > 0 || steps == target) return target;
    int ladder = options_.min_rod_steps, below = ladder;
    while (ladder < std::max(steps, target) && ladder < options_.max_rod_steps) {
      if (ladder < steps) below = ladder;
      ladder = next_rung(ladder);
      if (target > steps && ladder > steps) return std::min(ladder, target);
    }
    return std::max(below, target);
  }

  static int next_rung(int steps) { return steps % 3 == 0 ? steps / 3 * 4 : steps / 2 * 3; }

  int size() const { return kind_ == Kind::kForward ? 3 * n_ + 3 : 4 * n_ + (n_ == 2 ? 1 : 0); }
  int num_inputs() const { return kind_ == Kind::kForward ? n_ : 3; }
  const ShootingScale& scale() const { return scale_; }

  void set_input(const ShootingVector& u) { input_ = u; }

  /// Newton homotopy: solve r(z) = offset instead of r(z) = 0 (empty offset: none).
  void set_residual_offset(const ShootingVector& offset) { offset_ = offset; }

  /// Unknowns in scaled units from physical values.
  ShootingVector pack(const ShootingPoint<double>& p) const {
    ShootingVector z(size());
    for (int i = 0; i < n_; ++i) {
      z(3 * i + 0) = p.wrenches[i].nx / scale_.force;
      z(3 * i + 1) = p.wrenches[i].ny / scale_.force;
      z(3 * i + 2) = p.wrenches[i].m / scale_.moment();
    }
    if (kind_ == Kind::kForward) {
      z(3 * n_ + 0) = p.pose.x / scale_.length;
      z(3 * n_ + 1) = p.pose.y / scale_.length;
      z(3 * n_ + 2) = p.pose.theta;
    } else {
      for (int i = 0; i < n_; ++i) z(3 * n_ + i) = p.q[i] / scale_.length;
      if (n_ == 2) z(4 * n_) = p.pose.theta;
    }
    return z;
  }

  ShootingPoint<double> unpack(const ShootingVector& z) const {
    ShootingPoint<double> p;
    for (int i = 0; i < n_; ++i) {
      p.wrenches[i] = Wrench<double>{z(3 * i) * scale_.force, z(3 * i + 1) * scale_.force,
                                     z(3 * i + 2) * scale_.moment()};
    }
    if (kind_ == Kind::kForward) {
      for (int i = 0; i < n_; ++i) p.q[i] = input_(i);
      p.pose = Pose2<double>{z(3 * n_) * scale_.length, z(3 * n_ + 1) * scale_.length,
                             z(3 * n_ + 2)};
    } else {
      for (int i = 0; i < n_; ++i) p.q[i] = z(3 * n_ + i) * scale_.length;
      p.pose = Pose2<double>{input_(0), input_(1), n_ == 2 ? z(4 * n_) : input_(2)};
    }
    return p;
  }

  /// Residual and, on request, the Jacobian w.r.t. the scaled unknowns. Returns max strain.
  double evaluate(const ShootingVector& z, ShootingVector& r, JacobianMatrix* jacobian) const {
    const ShootingPoint<double> p = unpack(z);

    ResidualVector<double> res;
    const double strain = shooting_residual(robot_, p, load_, scale_, steps_, res,
                                            jacobian ? &partials_ : nullptr);
    r = res;
    if (offset_.size() == r.size()) r -= offset_;
    if (jacobian) {
      const int m = 3 * n_ + 3;
      if (kind_ == Kind::kForward) {
        *jacobian = partials_.leftCols(m);
      } else {
        jacobian->resize(m, size());
        jacobian->leftCols(3 * n_) = partials_.leftCols(3 * n_);
        jacobian->middleCols(3 * n_, n_) = partials_.middleCols(3 * n_ + 3, n_);
        if (n_ == 2) jacobian->col(4 * n_) = partials_.col(3 * n_ + 2);
      }
    }
    return strain;
  }

  /// d residual / dt along the input path, for the continuation's tangent predictor.
  ShootingVector input_derivative(const ShootingVector& du) const {
    const int m = 3 * n_ + 3;
    if (kind_ == Kind::kForward) return partials_.middleCols(3 * n_ + 3, n_) * (du / scale_.length);
    ShootingVector d = partials_.col(3 * n_) * (du(0) / scale_.length) +
                       partials_.col(3 * n_ + 1) * (du(1) / scale_.length);
    if (n_ != 2) d += partials_.col(3 * n_ + 2) * du(2);
    return d.head(m);
  }

 private:
  Kind kind_;
  const RobotParams<double>& robot_;
  const PlatformLoad<double>& load_;
  const SolverOptions& options_;
  ShootingScale scale_;
  int n_;
  int steps_;
  ShootingVector input_;
  ShootingVector offset_;
  mutable ShootingMatrix partials_;
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
/// `chord` (optional) carries a Jacobian between solves: on entry, one evaluated near z (say, at
/// the previous solution of a control loop) to try as the chord matrix of the first step when z is
/// near the solution; on exit, the last Jacobian evaluated.
inline NewtonResult newton_solve(const ShootingProblem& problem, ShootingVector& z,
                                 const SolverOptions& options, SolverSummary& summary,
                                 JacobianMatrix* chord = nullptr) {
  // Residual norms below this ask for no Jacobian at the trial point: Newton from there is
  // expected to contract by kChordContraction, so the old factorisation will do.
  constexpr double kWarmNorm = 1e-2;
  constexpr double kChordContraction = 0.1;
  // A residual and a Newton step this small (scaled: 3e-11 m on a 30 mm rod) are rounding noise.
  constexpr double kRoundingFloor = 1e-9;
  NewtonResult result;
  ShootingVector r, r_trial, z_trial, step, r_corrected, z_corrected;
  JacobianMatrix J, J_trial;
  Eigen::PartialPivLU<JacobianMatrix> lu_corrector;
  const bool try_chord = chord && chord->rows() == problem.size() &&
                         chord->cols() == problem.size();
  result.max_strain = problem.evaluate(z, r, try_chord ? nullptr : &J);
  ++summary.residual_evaluations;
  double norm = max_norm(r);
  result.initial_norm = norm;
  result.final_norm = norm;
  if (!std::isfinite(norm)) {
    result.status = SolveStatus::kNonFinite;
    return result;
  }
  Eigen::PartialPivLU<JacobianMatrix> lu;
  bool jacobian_at_z = true;  // J is the Jacobian at z (else: at an earlier iterate, chord)
  bool factorised = false;    // lu holds the factorisation of J
  if (try_chord) {
    if (norm <= kWarmNorm || norm <= options.tolerance) {
      J = *chord;
      jacobian_at_z = false;
    } else {
      result.max_strain = problem.evaluate(z, r, &J);  // far: the carried one would not do
      ++summary.residual_evaluations;
    }
  }
  // Hands the last evaluated Jacobian back to the caller on every exit.
  struct ChordOut {
    JacobianMatrix* out;
    const JacobianMatrix& J;
    ~ChordOut() {
      if (out && J.rows() > 0) *out = J;
    }
  } chord_out{chord, J};
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
      if (!factorised) {
        lu.compute(J);  // a carried Jacobian; a bad one fails the contraction test
        factorised = true;
      }
      step = -lu.solve(r);
      z_trial = z + step;
      const double strain = problem.evaluate(z_trial, r_trial, nullptr);
      ++summary.residual_evaluations;
      const double trial_norm = max_norm(r_trial);
      if (std::isfinite(trial_norm) &&
          (trial_norm <= kChordContraction * norm || trial_norm <= options.tolerance)) {
        z = z_trial;
        r = r_trial;
        norm = trial_norm;
        result.final_norm = norm;
        result.max_strain = strain;
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
inline double jacobian_rcond(const ShootingProblem& problem, const ShootingVector& z,
                             SolverSummary& summary) {
  ShootingVector r;
  JacobianMatrix J;
  problem.evaluate(z, r, &J);
  ++summary.residual_evaluations;
  const Eigen::PartialPivLU<JacobianMatrix> lu(J);
  const double rcond = lu.rcond();
  return std::isfinite(rcond) ? rcond : 0.0;
}

/// Solves at the end of the input path from a solution z0 at its start: directly, then by
/// continuation with a secant predictor and step halving. When the continuation stalls, the
/// Jacobian's conditioning along the solved part of the path tells a singularity ahead (no
/// solution on this branch: rcond^2, linear in t near a fold, extrapolates to zero before the
/// end of the path) from a plain failure to converge.

/// Reciprocal condition number below which a solved start counts as a bifurcation point.
inline constexpr double kBifurcationRcond = 1e-13;

inline SolveStatus solve_path_at_fixed_steps(ShootingProblem& problem, const ShootingVector& u0,
                                             const ShootingVector& u1, ShootingVector& z,
                                             const SolverOptions& options,
                                             SolverSummary& summary, JacobianMatrix* chord) {
  const ShootingVector z0 = z;
  problem.set_input(u1);
  NewtonResult direct = newton_solve(problem, z, options, summary, chord);
  summary.initial_residual_norm = direct.initial_norm;
  summary.final_residual_norm = direct.final_norm;
  summary.max_strain = direct.max_strain;
  if (direct.status == SolveStatus::kConverged || !options.continuation) return direct.status;
  // A start that is not finite (a broken warm start) has no path to continue along.
  if (!std::isfinite(direct.initial_norm)) return SolveStatus::kNonFinite;

  SolverOptions sub_options = options;
  sub_options.max_iterations = options.max_continuation_iterations;
  ShootingVector z_last = z0, z_prev = z0;
  double t = 0.0, t_prev = 0.0, dt = 0.5;
  // (t, rcond) at the last two solved points of the path.
  problem.set_input(u0);
  double rc_last = jacobian_rcond(problem, z0, summary), rc_prev = rc_last;
  if (rc_last <= kBifurcationRcond) {
    // A solution with a singular Jacobian that Newton could not leave: the straight rods of a
    // robot with n >= 4 limbs (a self-stress), where the branches of bowed rods meet.
    z = z0;
    return SolveStatus::kBifurcation;
  }
  double t_rc_last = 0.0, t_rc_prev = 0.0;
  const auto singular_ahead = [&]() {
    if (rc_last <= 1e-12) return true;
    if (t_rc_last <= t_rc_prev) return false;
    const double slope = (rc_last * rc_last - rc_prev * rc_prev) / (t_rc_last - t_rc_prev);
    return slope < 0.0 && t_rc_last - rc_last * rc_last / slope <= 1.0;
  };
  while (t < 1.0) {
    if (summary.continuation_steps >= options.max_continuation_steps) {
      z = z_last;  // the last solved point of the path
      problem.set_input(u0 + t * (u1 - u0));
      return singular_ahead() ? SolveStatus::kSingular : SolveStatus::kMaxIterations;
    }
    ++summary.continuation_steps;
    const double t_next = std::min(1.0, t + dt);
    problem.set_input(u0 + t_next * (u1 - u0));
    // Secant predictor from the last two solutions on the path.
    z = z_last;
    if (t > t_prev) z += (z_last - z_prev) * ((t_next - t) / (t - t_prev));
    NewtonResult sub = newton_solve(problem, z, sub_options, summary, chord);
    if (sub.status == SolveStatus::kConverged) {
      z_prev = z_last;
      t_prev = t;
      z_last = z;
      t = t_next;
      dt = std::min(2.0 * dt, 0.5);
      summary.final_residual_norm = sub.final_norm;
      summary.max_strain = sub.max_strain;
      if (t < 1.0) {
        rc_prev = rc_last;
        t_rc_prev = t_rc_last;
        rc_last = jacobian_rcond(problem, z_last, summary);
        t_rc_last = t;
      }
      continue;
    }
    dt *= 0.5;
    if (dt < options.min_continuation_step) {
      z = z_last;
      problem.set_input(u0 + t * (u1 - u0));
      summary.final_residual_norm = sub.final_norm;
      return singular_ahead() || sub.status == SolveStatus::kSingular ? SolveStatus::kSingular
                                                                      : sub.status;
    }
  }
  return SolveStatus::kConverged;
}

/// Estimates the discretisation error of a converged solution z of the N-step model and stores it
/// in the summary; returns its ratio to the accuracy targets. RK4 is fourth order: the residual
/// error of the M = N/2-step model is f = (N/M)^4 times that of the N-step one, e_N, so at z
/// r_M(z) - r_N(z) = (f - 1) e_N, and the exact model's solution lies at z + J^-1 e_N. J is the
/// last Jacobian the solve evaluated (`chord`; one at z when there is none): the estimate needs
/// its direction, not its last digits.
inline double estimate_discretisation_error(ShootingProblem& problem, const ShootingVector& z,
                                            const SolverOptions& options, SolverSummary& summary,
                                            const JacobianMatrix* chord) {
  const int steps = problem.rod_steps();
  const int half = std::max(1, steps / 2);
  ShootingVector r_full, r_half;
  JacobianMatrix J;
  const bool have_chord =
      chord && chord->rows() == problem.size() && chord->cols() == problem.size();
  problem.evaluate(z, r_full, have_chord ? nullptr : &J);
  problem.set_rod_steps(half);
  problem.evaluate(z, r_half, nullptr);
  problem.set_rod_steps(steps);
  summary.residual_evaluations += 2;
  const double f = std::pow(double(steps) / half, 4.0);
  const Eigen::PartialPivLU<JacobianMatrix> lu(have_chord ? *chord : J);
  const ShootingVector dz = lu.solve((r_half - r_full) / (f - 1.0));
  problem.output_change(dz, summary.position_error_estimate, summary.angle_error_estimate);
  return std::max(summary.position_error_estimate / options.position_accuracy,
                  summary.angle_error_estimate / options.angle_accuracy);
}

/// Solves a converged solution again (from itself: one or two Newton iterations) at the RK4 step
/// count its estimated discretisation error calls for, until the estimate meets the targets.
inline SolveStatus refine_rod_steps(ShootingProblem& problem, ShootingVector& z,
                                    const SolverOptions& options, SolverSummary& summary,
                                    SolveStatus status, JacobianMatrix* chord) {
  for (int pass = 0; status == SolveStatus::kConverged && options.rod_steps <= 0; ++pass) {
    const double ratio = estimate_discretisation_error(problem, z, options, summary, chord);
    const int needed = problem.rod_steps_for_error(ratio);
    const int start = problem.rod_steps();
    if (needed == start || pass == 4) break;
    const ShootingVector z_start = z;
    problem.set_rod_steps(needed);
    NewtonResult refined = newton_solve(problem, z, options, summary, chord);
    if (refined.status != SolveStatus::kConverged) {
      // Near a fold the models of two step counts can be too far apart for Newton: ramp the
      // count up (or down) the ladder one rung at a time instead.
      z = z_start;
      for (int steps = start; steps != needed;) {
        steps = problem.rung_towards(steps, needed);
        problem.set_rod_steps(steps);
        refined = newton_solve(problem, z, options, summary, chord);
        if (refined.status != SolveStatus::kConverged) break;
      }
    }
    status = refined.status;
    summary.final_residual_norm = refined.final_norm;
    summary.max_strain = refined.max_strain;
  }
  summary.rod_steps = problem.rod_steps();
  return status;
}

/// Solves along the input path with the start's step count, then refines the count for the
/// solution's estimated discretisation error.
inline SolveStatus solve_along_path(ShootingProblem& problem, const ShootingVector& u0,
                                    const ShootingVector& u1, ShootingVector& z,
                                    const SolverOptions& options, SolverSummary& summary,
                                    int start_steps, JacobianMatrix* chord) {
  if (options.rod_steps <= 0) {
    problem.set_rod_steps(
        std::min(std::max(start_steps, options.min_rod_steps), options.max_rod_steps));
  }
  const SolveStatus status =
      solve_path_at_fixed_steps(problem, u0, u1, z, options, summary, chord);
  return refine_rod_steps(problem, z, options, summary, status, chord);
}

inline bool valid_robot(const RobotParams<double>& robot) {
  return robot.num_limbs >= 2 && robot.num_limbs <= kMaxLimbs;
}

template <class Solution>
void copy_wrenches(const ShootingPoint<double>& p, int n, Solution& solution) {
  for (int i = 0; i < n; ++i) solution.wrenches[i] = p.wrenches[i];
}

/// Curvature times length of the rods of the bowed variant (bowed_variant_homotopy): a bow of
/// about 2.5% of the length, far from the straight rods' bifurcation yet mildly bent.
inline constexpr double kVariantBow = 0.2;

/// Forward kinematics at the joints u by a homotopy in the geometry, for robots whose straight
/// guess sits on a bifurcation. With n >= 4 limbs straight rods admit a self-stress (axial forces
/// that balance on the platform and deform nothing), so the Jacobian there is singular and the
/// robot's configurations branch off: each rod bows to one side or the other. The branch taken is
/// the one connected to a variant of the robot whose solution is known: every rod a circular arc
/// of curvature bow / l (bow > 0: to its left, counterclockwise, seen from its proximal clamp),
/// the platform at the rigid fit of the straight rods' tips onto the distal clamps, the variant's
/// distal clamps where the arcs end, and a platform moment balancing the rods' moments. From that
/// exact solution (n = 0, m = EI kappa) the distal clamps, their angles and the load move to the
/// robot's by natural continuation with a secant predictor. Returns the status and, in z, the
/// unknowns of the robot's FK problem (same scaling: it depends on l and EI only).
inline SolveStatus bowed_variant_homotopy(const RobotParams<double>& robot,
                                          const PlatformLoad<double>& load,
                                          const ShootingVector& u, double bow,
                                          const SolverOptions& options, SolverSummary& summary,
                                          ShootingVector& z) {
  const int n = robot.num_limbs;
  // Straight rods' tips from the moved proximal clamps, and their rigid fit (2D Procrustes).
  Vector2<double> tips[kMaxLimbs], b_mean(0, 0), t_mean(0, 0);
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    tips[i] = limb.proximal_position(u(i)) +
              limb.length * Vector2<double>(std::cos(limb.alpha), std::sin(limb.alpha));
    b_mean += limb.B / n;
    t_mean += tips[i] / n;
  }
  double dot = 0, cross = 0;
  for (int i = 0; i < n; ++i) {
    const Vector2<double> b = robot.limb(i).B - b_mean, t = tips[i] - t_mean;
    dot += b.dot(t);
    cross += b.x() * t.y() - b.y() * t.x();
  }
  const double theta = std::atan2(cross, dot), c = std::cos(theta), s = std::sin(theta);
  const Vector2<double> origin =
      t_mean - Vector2<double>(c * b_mean.x() - s * b_mean.y(), s * b_mean.x() + c * b_mean.y());
  // The variant and its solution.
  RobotParams<double> variant = robot;
  PlatformLoad<double> variant_load;
  ShootingPoint<double> start;
  start.pose = Pose2<double>{origin.x(), origin.y(), theta};
  for (int i = 0; i < n; ++i) {
    LimbParams<double>& limb = variant.limb(i);
    const double kappa = bow / limb.length, turn = bow;
    const Vector2<double> a = limb.proximal_position(u(i));
    const Vector2<double> end =
        a + Vector2<double>(std::sin(limb.alpha + turn) - std::sin(limb.alpha),
                            std::cos(limb.alpha) - std::cos(limb.alpha + turn)) /
                kappa;
    const Vector2<double> d = end - origin;
    limb.B = Vector2<double>(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
    limb.beta = limb.alpha + turn - theta;
    start.q[i] = u(i);
    start.wrenches[i] = Wrench<double>{0.0, 0.0, limb.bending_stiffness() * kappa};
    variant_load.moment += start.wrenches[i].m;
  }
  const RobotParams<double> from = variant;
  const PlatformLoad<double> from_load = variant_load;
  const auto blend = [&](double t) {
    for (int i = 0; i < n; ++i) {
      variant.limb(i).B = from.limb(i).B + t * (robot.limb(i).B - from.limb(i).B);
      variant.limb(i).beta = from.limb(i).beta + t * (robot.limb(i).beta - from.limb(i).beta);
    }
    variant_load.force = from_load.force + t * (load.force - from_load.force);
    variant_load.moment = from_load.moment + t * (load.moment - from_load.moment);
  };
  ShootingProblem problem(ShootingProblem::Kind::kForward, variant, variant_load, options);
  problem.set_input(u);
  z = problem.pack(start);
  NewtonResult sub = newton_solve(problem, z, options, summary);
  if (sub.status != SolveStatus::kConverged) return sub.status;
  // Pseudo-arclength continuation of (z, t): the path may turn back in t (a fold of the blended
  // geometry) before it reaches t = 1. Each corrector is Newton on r(z, t) = 0 and the arclength
  // condition, solved by bordering; r is affine in t (clamps, angles and load blend linearly), so
  // one residual difference gives dr/dt exactly.
  constexpr double kPathTolerance = 1e-8;
  ShootingVector r, r_shift, a, b;
  JacobianMatrix J;
  Eigen::PartialPivLU<JacobianMatrix> lu;
  const auto linearise = [&](const ShootingVector& zz, double t) {
    blend(t + 1.0);
    problem.evaluate(zz, r_shift, nullptr);
    blend(t);
    sub.max_strain = problem.evaluate(zz, r, &J);
    summary.residual_evaluations += 2;
    lu.compute(J);
    return lu.rcond() > 1e-14 && r.allFinite() && r_shift.allFinite();
  };
  ShootingVector z_last = z, tangent_z;
  double t_last = 0.0, tangent_t = 1.0;
  if (!linearise(z_last, 0.0)) return SolveStatus::kSingular;
  tangent_z = -lu.solve(ShootingVector(r_shift - r));  // dz/dt along the path at t = 0
  double norm = std::sqrt(tangent_z.squaredNorm() + 1.0);
  tangent_z /= norm;
  tangent_t /= norm;
  double ds = 0.125;
  for (int steps = 0; steps < 4 * options.max_continuation_steps && ds >= options.min_continuation_step;
       ++steps) {
    ++summary.continuation_steps;
    // Predictor; a step that would pass t = 1 is shortened to land on it.
    double step = ds;
    if (tangent_t > 0 && t_last + step * tangent_t > 1.0) step = (1.0 - t_last) / tangent_t;
    ShootingVector zz = z_last + step * tangent_z;
    double t = t_last + step * tangent_t;
    const bool last = std::abs(t - 1.0) < 1e-12;
    bool converged = false;
    for (int it = 0; it < options.max_continuation_iterations; ++it) {
      if (!linearise(zz, t)) break;
      ++summary.iterations;
      // Points along the way need not be exact (a pre-stressed path can be ill-conditioned
      // enough to put a rounding floor near the tolerance); the end point is polished below.
      if (max_norm(r) <= kPathTolerance) {
        converged = true;
        break;
      }
      // [J r_t; tangent^T] (dz, dt) = -(r, g), g = tangent . (y - y_pred) = 0 on the predictor
      // plane (the end step keeps t = 1 instead).
      a = lu.solve(r);
      b = lu.solve(ShootingVector(r_shift - r));
      const double g = last ? 0.0 : tangent_z.dot(zz - z_last - step * tangent_z) +
                                        tangent_t * (t - t_last - step * tangent_t);
      const double dt = last ? 0.0 : (-g + tangent_z.dot(a)) / (tangent_t - tangent_z.dot(b));
      zz -= a + b * dt;
      t += dt;
    }
    if (!converged) {
      ds *= 0.5;
      continue;
    }
    if (!last && t > 1.0) {
      // The corrector went past t = 1: solve there from the chord between the two points.
      blend(1.0);
      ShootingVector z_end = z_last + (zz - z_last) * ((1.0 - t_last) / (t - t_last));
      const NewtonResult end = newton_solve(problem, z_end, options, summary);
      if (end.status != SolveStatus::kConverged) {
        ds *= 0.5;
        continue;
      }
      z = z_end;
      summary.final_residual_norm = end.final_norm;
      summary.max_strain = end.max_strain;
      return SolveStatus::kConverged;
    }
    if (last) {
      const NewtonResult end = newton_solve(problem, zz, options, summary);
      if (end.status != SolveStatus::kConverged) {
        ds *= 0.5;
        continue;
      }
      z = zz;
      summary.final_residual_norm = end.final_norm;
      summary.max_strain = end.max_strain;
      return SolveStatus::kConverged;
    }
    // Secant tangent, oriented along the path.
    ShootingVector dz = zz - z_last;
    double dt = t - t_last;
    norm = std::sqrt(dz.squaredNorm() + dt * dt);
    tangent_z = dz / norm;
    tangent_t = dt / norm;
    z_last = zz;
    t_last = t;
    ds = std::min(2.0 * ds, 16.0);
  }
  z = z_last;
  return SolveStatus::kMaxIterations;
}

/// bowed_variant_homotopy with the rods bowed to their left, then, if that path fails, to their
/// right (the documented order of the branches tried).
inline SolveStatus solve_from_bowed_variant(const RobotParams<double>& robot,
                                            const PlatformLoad<double>& load,
                                            const ShootingVector& u, const SolverOptions& options,
                                            SolverSummary& summary, ShootingVector& z) {
  SolveStatus status = SolveStatus::kMaxIterations;
  for (const double bow : {kVariantBow, -kVariantBow}) {
    status = bowed_variant_homotopy(robot, load, u, bow, options, summary, z);
    if (status == SolveStatus::kConverged) break;
  }
  return status;
}

/// The solution at q = 0: from the unloaded straight guess (exact for a stress-free robot); when
/// Newton fails from there, by a Newton homotopy from it (n <= 3) and from a bowed variant of the
/// robot (n >= 4, where the straight guess is on a bifurcation, or when that homotopy fails).
inline ShootingVector home_unknowns(ShootingProblem& fk, const SolverOptions& options,
                                    SolverSummary& summary, SolveStatus& status,
                                    JacobianMatrix* chord) {
  ShootingVector u = ShootingVector::Zero(fk.num_inputs());
  fk.set_input(u);
  ShootingVector z = ShootingVector::Zero(fk.size());
  NewtonResult home = newton_solve(fk, z, options, summary);
  summary.initial_residual_norm = home.initial_norm;
  if (home.status != SolveStatus::kConverged && options.continuation &&
      fk.robot().num_limbs <= 3) {
    // Newton homotopy from the straight guess z0: r(z) = (1 - t) r(z0), t from 0 to 1.
    ShootingVector r0, z_last = ShootingVector::Zero(fk.size());
    fk.evaluate(z_last, r0, nullptr);
    double t = 0.0, dt = 0.25;
    while (t < 1.0 && summary.continuation_steps < options.max_continuation_steps &&
           dt >= options.min_continuation_step) {
      ++summary.continuation_steps;
      const double t_next = std::min(1.0, t + dt);
      fk.set_residual_offset((1.0 - t_next) * r0);
      z = z_last;
      home = newton_solve(fk, z, options, summary);
      if (home.status == SolveStatus::kConverged) {
        z_last = z;
        t = t_next;
        dt = std::min(2.0 * dt, 0.5);
      } else {
        dt *= 0.5;
      }
    }
    fk.set_residual_offset(ShootingVector());
    z = z_last;
    if (t < 1.0 && home.status == SolveStatus::kConverged) home.status = SolveStatus::kMaxIterations;
  }
  summary.final_residual_norm = home.final_norm;
  summary.max_strain = home.max_strain;
  if (home.status != SolveStatus::kConverged && options.continuation) {
    home.status = solve_from_bowed_variant(fk.robot(), fk.load(), u, options, summary, z);
  }
  status = refine_rod_steps(fk, z, options, summary, home.status, chord);
  return z;
}

}  // namespace internal

/// Forward kinematics warm-started from a previous solution (the normal case in a control loop).
inline ForwardSolution forward_kinematics(const RobotParams<double>& robot, const JointVector& q,
                                          const ForwardSolution& warm_start,
                                          const SolverOptions& options = SolverOptions(),
                                          const PlatformLoad<double>& load = PlatformLoad<double>()) {
  using internal::ShootingProblem;
  ForwardSolution solution;
  solution.q = q;
  if (!internal::valid_robot(robot) || q.size() != robot.num_limbs || !q.allFinite() ||
      warm_start.q.size() != robot.num_limbs) {
    solution.summary.status = SolveStatus::kInvalidInput;
    return solution;
  }
  const int n = robot.num_limbs;
  ShootingProblem problem(ShootingProblem::Kind::kForward, robot, load, options);
  ShootingPoint<double> start;
  start.pose = warm_start.pose;
  for (int i = 0; i < n; ++i) {
    start.q[i] = warm_start.q(i);
    start.wrenches[i] = warm_start.wrenches[i];
  }
  ShootingVector u0 = warm_start.q, u1 = q;
  problem.set_input(u0);
  ShootingVector z = problem.pack(start);
  solution.jacobian = warm_start.jacobian;
  solution.summary.status =
      internal::solve_along_path(problem, u0, u1, z, options, solution.summary,
                                 warm_start.summary.rod_steps, &solution.jacobian);
  // On failure this is the last solved point of the path, with its joints.
  const ShootingPoint<double> p = problem.unpack(z);
  for (int i = 0; i < n; ++i) solution.q(i) = p.q[i];
  solution.pose = p.pose;
  internal::copy_wrenches(p, n, solution);
  return solution;
}

/// The home solution: q = 0, solved from the straight, unloaded guess.
inline ForwardSolution home_solution(const RobotParams<double>& robot,
                                     const SolverOptions& options = SolverOptions(),
                                     const PlatformLoad<double>& load = PlatformLoad<double>()) {
  ForwardSolution home;
  if (!internal::valid_robot(robot)) {
    home.summary.status = SolveStatus::kInvalidInput;
    return home;
  }
  internal::ShootingProblem problem(internal::ShootingProblem::Kind::kForward, robot, load,
                                    options);
  SolveStatus status;
  ShootingVector z =
      internal::home_unknowns(problem, options, home.summary, status, &home.jacobian);
  home.summary.status = status;
  home.q = JointVector::Zero(robot.num_limbs);
  const ShootingPoint<double> p = problem.unpack(z);
  home.pose = p.pose;
  internal::copy_wrenches(p, robot.num_limbs, home);
  return home;
}

/// Forward kinematics from a cold start: the home solution, then a (continued) path to q. When
/// home is a bifurcation (the straight rods of a stress-free robot with n >= 4 limbs), q is solved
/// directly from a bowed variant of the robot instead (internal::bowed_variant_homotopy: the
/// branch whose rods bow to their left, else the one where they bow to their right).
inline ForwardSolution forward_kinematics(const RobotParams<double>& robot, const JointVector& q,
                                          const SolverOptions& options = SolverOptions(),
                                          const PlatformLoad<double>& load = PlatformLoad<double>()) {
  ForwardSolution home = home_solution(robot, options, load);
  if (!home.summary.converged()) {
    home.q = q;
    return home;
  }
  ForwardSolution solution = forward_kinematics(robot, q, home, options, load);
  solution.summary.iterations += home.summary.iterations;
  solution.summary.residual_evaluations += home.summary.residual_evaluations;
  if (solution.summary.status == SolveStatus::kBifurcation && options.continuation) {
    internal::ShootingProblem problem(internal::ShootingProblem::Kind::kForward, robot, load,
                                      options);
    ShootingVector u = q, z;
    problem.set_input(u);
    SolveStatus status =
        internal::solve_from_bowed_variant(robot, load, u, options, solution.summary, z);
    if (status == SolveStatus::kConverged) {
      problem.set_rod_steps(options.rod_steps > 0 ? options.rod_steps : options.min_rod_steps);
      solution.jacobian.resize(0, 0);
      status = internal::refine_rod_steps(problem, z, options, solution.summary, status,
                                          &solution.jacobian);
      const ShootingPoint<double> p = problem.unpack(z);
      solution.q = q;
      solution.pose = p.pose;
      internal::copy_wrenches(p, robot.num_limbs, solution);
    }
    solution.summary.status = status;
  }
  return solution;
}

/// Inverse kinematics warm-started from a previous solution. For n = 2 only x and y of `pose`
/// are imposed and theta is solved for.
inline InverseSolution inverse_kinematics(const RobotParams<double>& robot,
                                          const Pose2<double>& pose,
                                          const InverseSolution& warm_start,
                                          const SolverOptions& options = SolverOptions(),
                                          const PlatformLoad<double>& load = PlatformLoad<double>()) {
  using internal::ShootingProblem;
  InverseSolution solution;
  solution.pose = pose;
  const int n = robot.num_limbs;
  if (!internal::valid_robot(robot) || warm_start.q.size() != n ||
      !std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.theta)) {
    solution.summary.status = SolveStatus::kInvalidInput;
    return solution;
  }
  if (n > 3) {
    solution.summary.status = SolveStatus::kUnsupported;
    return solution;
  }
  ShootingProblem problem(ShootingProblem::Kind::kInverse, robot, load, options);
  ShootingPoint<double> start;
  start.pose = warm_start.pose;
  for (int i = 0; i < n; ++i) {
    start.q[i] = warm_start.q(i);
    start.wrenches[i] = warm_start.wrenches[i];
  }
  ShootingVector u0(3), u1(3);
  u0 << warm_start.pose.x, warm_start.pose.y, warm_start.pose.theta;
  u1 << pose.x, pose.y, n == 2 ? warm_start.pose.theta : pose.theta;
  problem.set_input(u0);
  ShootingVector z = problem.pack(start);
  solution.jacobian = warm_start.jacobian;
  SolveStatus status = internal::solve_along_path(problem, u0, u1, z, options, solution.summary,
                                                  warm_start.summary.rod_steps,
                                                  &solution.jacobian);
  const ShootingPoint<double> p = problem.unpack(z);
  solution.pose = p.pose;
  solution.q = JointVector(n);
  for (int i = 0; i < n; ++i) solution.q(i) = p.q[i];
  internal::copy_wrenches(p, n, solution);
  if (status == SolveStatus::kConverged) {
    for (int i = 0; i < n; ++i) {
      if (p.q[i] < robot.limb(i).q_min || p.q[i] > robot.limb(i).q_max) {
        status = SolveStatus::kOutOfRange;
      }
    }
  }
  solution.summary.status = status;
  return solution;
}

/// Inverse kinematics from a cold start: from the home solution along a straight pose path.
inline InverseSolution inverse_kinematics(const RobotParams<double>& robot,
                                          const Pose2<double>& pose,
                                          const SolverOptions& options = SolverOptions(),
                                          const PlatformLoad<double>& load = PlatformLoad<double>()) {
  InverseSolution warm;
  const ForwardSolution home = home_solution(robot, options, load);
  if (!home.summary.converged()) {
    warm.summary = home.summary;
    warm.pose = pose;
    return warm;
  }
  warm.pose = home.pose;
  warm.q = home.q;
  warm.wrenches = home.wrenches;
  warm.summary = home.summary;
  InverseSolution solution = inverse_kinematics(robot, pose, warm, options, load);
  solution.summary.iterations += home.summary.iterations;
  solution.summary.residual_evaluations += home.summary.residual_evaluations;
  return solution;
}

/// Inverse kinematics warm-started from a forward solution (same unknowns, other inputs). The FK
/// Jacobian is left behind: its pose columns are not the IK's joint columns, so the first IK solve
/// evaluates its own.
inline InverseSolution as_inverse_warm_start(const ForwardSolution& fk) {
  InverseSolution warm;
  warm.pose = fk.pose;
  warm.q = fk.q;
  warm.wrenches = fk.wrenches;
  warm.summary = fk.summary;
  return warm;
}

/// Whether a solution can warm-start the next solve: a converged one, or (IK) a valid equilibrium
/// whose joints lie outside their stroke.
inline bool usable_as_warm_start(const SolverSummary& summary) {
  return summary.converged() || summary.status == SolveStatus::kOutOfRange;
}

namespace internal {

/// A warm solve, then a cold one when the warm one is not usable (and the input is valid); the
/// summary counts the iterations and residual evaluations of both.
template <class Solution, class WarmSolve, class ColdSolve>
Solution solve_with_cold_fallback(const Solution* warm, WarmSolve&& warm_solve,
                                  ColdSolve&& cold_solve) {
  if (warm == nullptr) return cold_solve();
  Solution solution = warm_solve(*warm);
  const SolveStatus status = solution.summary.status;
  if (usable_as_warm_start(solution.summary) || status == SolveStatus::kInvalidInput ||
      status == SolveStatus::kUnsupported) {
    return solution;
  }
  const int iterations = solution.summary.iterations;
  const int evaluations = solution.summary.residual_evaluations;
  solution = cold_solve();
  solution.summary.iterations += iterations;
  solution.summary.residual_evaluations += evaluations;
  return solution;
}

}  // namespace internal

/// FK of one row of a sequence (a CSV file, a batch): warm-started from the last usable solution
/// when there is one (`warm`, may be null), from home when that fails (the previous row lies on
/// another branch, or too far along a fold).
inline ForwardSolution forward_kinematics_or_cold(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution* warm,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>()) {
  return internal::solve_with_cold_fallback(
      warm, [&](const ForwardSolution& w) { return forward_kinematics(robot, q, w, options, load); },
      [&] { return forward_kinematics(robot, q, options, load); });
}

/// IK of one row of a sequence; as forward_kinematics_or_cold.
inline InverseSolution inverse_kinematics_or_cold(
    const RobotParams<double>& robot, const Pose2<double>& pose, const InverseSolution* warm,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>()) {
  return internal::solve_with_cold_fallback(
      warm,
      [&](const InverseSolution& w) { return inverse_kinematics(robot, pose, w, options, load); },
      [&] { return inverse_kinematics(robot, pose, options, load); });
}

/// Calls visit(limb, s, RodState) along every rod of a solved configuration (for plots, strain).
template <class Visitor>
void visit_rod_shapes(const RobotParams<double>& robot, const JointVector& q,
                      const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps,
                      Visitor&& visit) {
  for (int i = 0; i < robot.num_limbs; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    sample_rod(proximal_rod_state(limb, q(i), wrenches[i]), limb.bending_stiffness(), limb.length,
               rod_steps,
               [&](double s, const RodState<double>& state) { visit(i, s, state); });
  }
}

}  // namespace pcr
