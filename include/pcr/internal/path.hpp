#pragma once
// Paths of FK and IK solutions: continuation along an input path, the RK4 step count chosen from
// an error estimate of the solution, and the homotopies that reach a robot's home configuration.

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "pcr/internal/branch_rule.hpp"
#include "pcr/internal/newton.hpp"
#include "pcr/internal/shooting_problem.hpp"
#include "pcr/robot.hpp"
#include "pcr/solver.hpp"

namespace pcr::internal {

/// Paths from a solution at the input u0 to the input u1 (solve_path_at_fixed_steps): the whole
/// step first, then continuation with step halving, every step predicted along the tangent and
/// kept only when its corrector stays on the predicted branch. When the continuation stalls, the
/// Jacobian's conditioning along the solved part of the path tells a singularity ahead (no
/// solution on this branch: rcond^2, linear in t near a fold, extrapolates to zero before the
/// end of the path) from a plain failure to converge.

/// Reciprocal condition number below which a solved start counts as a bifurcation point.
inline constexpr double kBifurcationRcond = 1e-13;

/// Reciprocal condition number of the last solved point at or below which a stalled path counts
/// as stopped at a singularity even when rcond's trend did not show it coming (its last steps too
/// short to extrapolate). Over 1357 FK solutions within 1 % strain of 30 robots drawn inside the
/// paper's intervals (n = 2 to 6) the median is 1e-3 and 1 % lie below 1.6e-7.
inline constexpr double kStallSingularRcond = 1e-7;

/// A rod whose bending turns it by less than this along its length (rad) counts as straight.
inline constexpr double kStraightTurn = 1e-6;

/// Whether z has four or more straight rods. A straight rod carries an axial force, which does no
/// work on an inextensible rod: with four or more, the platform's three balance equations leave
/// n - 3 combinations of their axial forces (a self-stress) undetermined, so the Jacobian is
/// singular there, and the branches of rods bowed to either side meet (a 5-limb robot with one
/// limb longer: four rods stay straight at home and the fifth bows). Bending along a rod is
/// m(s) = m0 - n_perp s, n_perp the force across its tangent at the proximal clamp.
inline bool self_stressed(const ShootingProblem& problem, const ShootingVector& z) {
  const ShootingPoint<double> p = problem.unpack(z);
  int straight = 0;
  for (int i = 0; i < problem.robot().num_limbs; ++i) {
    const LimbParams<double>& limb = problem.robot().limb(i);
    const Wrench<double>& w = p.wrenches[i];
    const double across = -w.nx * std::sin(limb.alpha) + w.ny * std::cos(limb.alpha);
    // A pre-curved rod is not straight even unloaded: its intrinsic turn counts. A tapered
    // rod's bound takes its thinner end's EI.
    const double least_ei =
        std::min(limb.rod.bending_stiffness(), limb.rod.bending_stiffness_at(limb.rod.length));
    const double turn =
        (std::abs(w.m) + 0.5 * std::abs(across) * limb.rod.length) * limb.rod.length / least_ei +
        std::abs(limb.rod.intrinsic_turn(limb.rod.length));
    straight += turn < kStraightTurn ? 1 : 0;
  }
  return straight >= 4;
}

/// At the last solved point z of a path that stalled at a nearly singular Jacobian, whether the
/// path meets a bifurcation there rather than a fold. At a fold the path turns back: the input
/// direction pushes the residual along J's left null vector w (w . dr/du du != 0), so no solution
/// lies ahead on this branch. Where branches cross, the input direction stays in the range of J
/// (w . dr/du du -> 0 as the path nears the crossing). Measured on the default robot's folds and on
/// a 4-limb robot driven through its straight home, |w . g| / |g| is above 0.03 at the former and
/// near 0.003 at the latter: the threshold sits between them, and w must be a distinct null
/// direction (the smallest singular value well below the next).
inline bool stalled_at_bifurcation(const ShootingProblem& problem, const ShootingVector& z,
                                   const ShootingVector& du, SolverSummary& summary) {
  if (self_stressed(problem, z)) return true;
  ShootingVector r;
  JacobianMatrix J;
  problem.evaluate(z, r, &J);
  ++summary.residual_evaluations;
  if (!J.allFinite()) return false;
  const Eigen::JacobiSVD<JacobianMatrix> svd(J, Eigen::ComputeFullU);
  const int m = static_cast<int>(J.rows());
  const auto& sigma = svd.singularValues();
  if (m < 2 || !(sigma(m - 1) < 0.1 * sigma(m - 2))) return false;
  const ShootingVector g = problem.input_derivative(z, du);
  const double g_norm = g.norm();
  return g_norm > 0.0 && std::abs(svd.matrixU().col(m - 1).dot(g)) <= 0.01 * g_norm;
}

/// Whether a corrector from the tangent predictor z_predicted of a step from z_start stayed on the
/// branch it predicted: it moved z by at most kMaxCorrectorShare of the predictor's step.
inline bool stayed_on_branch(const ShootingVector& z_start, const ShootingVector& z_predicted,
                             const ShootingVector& z) {
  return corrector_on_branch((z - z_predicted).norm(), (z_predicted - z_start).norm());
}

/// The tangent predictor of a step du of the input from the solution z: z - J^-1 (dr/du) du, with
/// the chord matrix as J^-1. False (z unchanged) at a singular Jacobian (a bifurcation point,
/// where the tangent is not unique) or when it is not finite.
inline bool predict_along_tangent(const ShootingProblem& problem, const ChordMatrix& chord,
                                  const ShootingVector& du, ShootingVector& z) {
  if (chord.rows() != problem.size() || !(chord.rcond() > kBifurcationRcond)) return false;
  const ShootingVector z_predicted = z - chord.solve(problem.input_derivative(z, du));
  if (!z_predicted.allFinite()) return false;
  z = z_predicted;
  return true;
}

/// Solves at the end of the input path from a solution z0 at its start, on z0's branch: each step
/// (first the whole path, then continuation steps halved on failure) is predicted along the
/// tangent and corrected by Newton, and is accepted only when the corrector stayed near the
/// predictor (stayed_on_branch), so that a warm start never lands on another equilibrium at the
/// same input however far the input moves. A path with no input change (the same input on another
/// robot, or from a seed) has no branch to follow and is corrected directly.
inline SolveStatus solve_path_at_fixed_steps(ShootingProblem& problem, const ShootingVector& u0,
                                             const ShootingVector& u1, ShootingVector& z,
                                             const SolverOptions& options, SolverSummary& summary,
                                             ChordMatrix* carried) {
  const ShootingVector z0 = z;
  const ShootingVector du = u1 - u0;
  const bool moves = (du.array() != 0.0).any();
  ChordMatrix own;
  ChordMatrix& chord = carried ? *carried : own;
  if (moves && chord.rows() != problem.size()) {
    // No Jacobian came with the start (IK from a forward solution): the tangent needs one.
    ShootingVector r;
    JacobianMatrix J;
    problem.set_input(u0);
    problem.evaluate(z0, r, &J);
    ++summary.residual_evaluations;
    if (J.allFinite()) chord.compute(J);
  }
  const bool predicted = moves && predict_along_tangent(problem, chord, du, z);
  const ShootingVector z_direct = z;
  problem.set_input(u1);
  NewtonResult direct = newton_solve(problem, z, options, summary, &chord);
  summary.initial_residual_norm = direct.initial_norm;
  summary.final_residual_norm = direct.final_norm;
  summary.max_strain = direct.max_strain;
  summary.path_fraction = 1.0;
  const bool direct_on_branch = !predicted || stayed_on_branch(z0, z_direct, z);
  if (direct.status == SolveStatus::kConverged && direct_on_branch) return direct.status;
  if (direct.status == SolveStatus::kConverged) direct.status = SolveStatus::kMaxIterations;
  // A rejected step leaves the chord matrix where Newton took it; the continuation below
  // factorises the Jacobian at the start again (no copy kept on every solve for it).
  // What a failure returns is the last solved point: the start.
  z = z0;
  problem.set_input(u0);
  summary.path_fraction = 0.0;
  if (!options.continuation) return direct.status;
  // A start that is not finite (a broken warm start) has no path to continue along.
  if (!predicted && !std::isfinite(direct.initial_norm)) return SolveStatus::kNonFinite;

  SolverOptions sub_options = options;
  sub_options.max_iterations = options.max_continuation_iterations;
  ShootingVector z_last = z0, z_prev = z0;
  double t = 0.0, t_prev = 0.0, dt = 0.5;
  // (t, rcond) at the last two solved points of the path.
  problem.set_input(u0);
  // The Jacobian at each solved point of the path gives both its conditioning (for the
  // singularity test) and the next step's exact tangent.
  const auto factorise_at = [&](const ShootingVector& at) {
    ShootingVector r;
    JacobianMatrix J;
    problem.evaluate(at, r, &J);
    ++summary.residual_evaluations;
    if (!J.allFinite()) return 0.0;
    chord.compute(J);
    return std::isfinite(chord.rcond()) ? chord.rcond() : 0.0;
  };
  double rc_last = factorise_at(z0), rc_prev = rc_last;
  if (rc_last <= kBifurcationRcond || self_stressed(problem, z0)) {
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
  // The status of a path that stalls at a singular Jacobian, from its last solved point z_last.
  const auto singular_status = [&]() {
    return stalled_at_bifurcation(problem, z_last, du, summary) ? SolveStatus::kBifurcation
                                                                : SolveStatus::kSingular;
  };
  // The status of a stalled path: `otherwise` unless it stalled at a singularity.
  const auto stall_status = [&](SolveStatus otherwise) {
    return singular_ahead() || rc_last <= kStallSingularRcond ? singular_status() : otherwise;
  };
  // With no input change there is no path to step along: the direct solve was the whole attempt
  // (steps would retry the same problem from the same start, up to max_continuation_steps times).
  if (!moves) return stall_status(direct.status);
  ChordMatrix chord_at_last = chord;
  while (t < 1.0) {
    if (summary.continuation_steps >= options.max_continuation_steps) {
      z = z_last;  // the last solved point of the path
      problem.set_input(u0 + t * du);
      summary.path_fraction = t;
      return stall_status(SolveStatus::kMaxIterations);
    }
    ++summary.continuation_steps;
    const double t_next = std::min(1.0, t + dt);
    // Tangent predictor from the last solution (else the secant of the last two).
    z = z_last;
    const bool step_predicted =
        moves && predict_along_tangent(problem, chord, (t_next - t) * du, z);
    if (!step_predicted && t > t_prev) z += (z_last - z_prev) * ((t_next - t) / (t - t_prev));
    const ShootingVector z_predicted = z;
    problem.set_input(u0 + t_next * du);
    NewtonResult sub = newton_solve(problem, z, sub_options, summary, &chord);
    if (sub.status == SolveStatus::kConverged &&
        (!step_predicted || stayed_on_branch(z_last, z_predicted, z))) {
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
        rc_last = factorise_at(z_last);
        t_rc_last = t;
      }
      chord_at_last = chord;
      continue;
    }
    // A corrector that left the branch is a step too long, as one that did not converge.
    if (sub.status == SolveStatus::kConverged) sub.status = SolveStatus::kMaxIterations;
    chord = chord_at_last;
    dt *= 0.5;
    if (dt < options.min_continuation_step) {
      z = z_last;
      problem.set_input(u0 + t * du);
      summary.path_fraction = t;
      summary.final_residual_norm = sub.final_norm;
      return sub.status == SolveStatus::kSingular ? singular_status() : stall_status(sub.status);
    }
  }
  return SolveStatus::kConverged;
}

/// Estimates the discretisation error of a converged solution z of the N-step model and stores it
/// in the summary; returns its ratio to the accuracy targets. RK4 is fourth order: the residual
/// error of the M = N/2-step model is f = (N/M)^4 times that of the N-step one, e_N, so at z
/// r_M(z) - r_N(z) = (f - 1) e_N, and the exact model's solution lies at z + J^-1 e_N. J is the
/// last Jacobian the solve factorised (`carried`; one at z when there is none): the estimate needs
/// its direction, not its last digits.
inline double estimate_discretisation_error(ShootingProblem& problem, const ShootingVector& z,
                                            const SolverOptions& options, SolverSummary& summary,
                                            const ChordMatrix* carried) {
  const int steps = problem.rod_steps();
  const int half = std::max(1, steps / 2);
  ChordMatrix at_z;
  const ChordMatrix* lu = carried;
  if (lu == nullptr || lu->rows() != problem.size()) {
    ShootingVector r;
    JacobianMatrix J;
    problem.evaluate(z, r, &J);
    ++summary.residual_evaluations;
    at_z.compute(J);
    lu = &at_z;
  }
  ShootingVector r_half;
  problem.set_rod_steps(half);
  problem.evaluate(z, r_half, nullptr);
  problem.set_rod_steps(steps);
  ++summary.residual_evaluations;  // at half the steps: half the cost of the others
  // r_N(z) is within the solve's tolerance of zero, so r_M(z) alone is (f - 1) e_N.
  const double f = std::pow(double(steps) / half, 4.0);
  const ShootingVector dz = lu->solve(r_half / (f - 1.0));
  problem.output_change(dz, summary.position_error_estimate, summary.angle_error_estimate);
  return std::max(summary.position_error_estimate / options.position_accuracy,
                  summary.angle_error_estimate / options.angle_accuracy);
}

/// Solves a converged solution again (from itself: one or two Newton iterations) at the RK4 step
/// count its estimated discretisation error calls for, until the estimate meets the targets.
inline SolveStatus refine_rod_steps(ShootingProblem& problem, ShootingVector& z,
                                    const SolverOptions& options, SolverSummary& summary,
                                    SolveStatus status, ChordMatrix* carried) {
  for (int pass = 0; status == SolveStatus::kConverged && options.rod_steps <= 0; ++pass) {
    const double ratio = estimate_discretisation_error(problem, z, options, summary, carried);
    const int needed = rod_steps_for_error(options, problem.rod_steps(), ratio);
    const int start = problem.rod_steps();
    if (needed == start || pass == 4) break;
    const ShootingVector z_start = z;
    problem.set_rod_steps(needed);
    NewtonResult refined = newton_solve(problem, z, options, summary, carried);
    if (refined.status != SolveStatus::kConverged) {
      // Near a fold the models of two step counts can be too far apart for Newton: ramp the
      // count up (or down) the ladder one rung at a time instead.
      z = z_start;
      for (int steps = start; steps != needed;) {
        steps = rod_steps_rung_towards(options, steps, needed);
        problem.set_rod_steps(steps);
        refined = newton_solve(problem, z, options, summary, carried);
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
                                    int start_steps, ChordMatrix* carried) {
  problem.set_rod_steps(starting_rod_steps(options, start_steps));
  const SolveStatus status =
      solve_path_at_fixed_steps(problem, u0, u1, z, options, summary, carried);
  return refine_rod_steps(problem, z, options, summary, status, carried);
}

/// Curvature times length of the rods of the bowed variant (bowed_variant_homotopy): a bow of
/// about 2.5% of the length, far from the straight rods' bifurcation yet mildly bent.
inline constexpr double kVariantBow = 0.2;

/// Forward kinematics at the joints u by a homotopy in the geometry, for robots whose straight
/// guess sits on a bifurcation. With n >= 4 limbs straight rods admit a self-stress (axial forces
/// that balance on the platform and deform nothing), so the Jacobian there is singular and the
/// robot's configurations branch off: each rod bows to one side or the other. The branch taken is
/// the one connected to a variant of the robot whose solution is known: every rod i a circular arc
/// turning by bow (1 + i / 10) s_i (bow > 0: to its left, counterclockwise, seen from its proximal
/// clamp, which puts the arc's middle to the right of its chord; s_i = -1 for a rod said to bow
/// to its left at home, LimbParams::home_bow, else 1; unequal, so that the variant has none of
/// the robot's symmetry, whose symmetric bifurcations the path would otherwise meet),
/// the platform at the rigid fit of the straight rods' tips onto the distal clamps, the variant's
/// distal clamps where the arcs end, and a platform moment balancing the rods' moments. From that
/// exact solution (n = 0, m = EI kappa) the distal clamps, their angles and the load move to the
/// robot's by natural continuation with a secant predictor. Returns the status and, in z, the
/// unknowns of the robot's FK problem (same scaling: it depends on l and EI only).
inline SolveStatus bowed_variant_homotopy(const RobotParams<double>& robot,
                                          const PlatformLoad<double>& load, const ShootingVector& u,
                                          double bow, const SolverOptions& options,
                                          SolverSummary& summary, ShootingVector& z) {
  const int n = robot.num_limbs;
  // Stress-free rods' tips from the moved proximal clamps, and their rigid fit (2D Procrustes).
  Vector2<double> tips[kMaxLimbs], b_mean(0, 0), t_mean(0, 0);
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    if (limb.rod.straight()) {
      tips[i] = limb.proximal_position(u(i)) +
                limb.rod.length * Vector2<double>(std::cos(limb.alpha), std::sin(limb.alpha));
    } else {
      const RodState<double> tip = integrate_rod(proximal_rod_state(limb, u(i), Wrench<double>{}),
                                                 limb.rod, options.max_rod_steps);
      tips[i] = Vector2<double>(tip.x, tip.y);
    }
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
    const double side = limb.home_bow > 0 ? -1.0 : 1.0;  // an arc turning left bulges right
    const double turn = side * bow * (1.0 + 0.1 * i), kappa = turn / limb.rod.length;
    start.q[i] = u(i);
    start.wrenches[i] = Wrench<double>{0.0, 0.0, limb.rod.bending_stiffness() * kappa};
    // With n = 0 the moment stays EI kappa: a straight uniform rod takes a circular arc; a
    // pre-curved or tapered one takes a curve its own integration gives.
    Vector2<double> end;
    double end_angle;
    if (limb.rod.straight() && limb.rod.uniform()) {
      end = limb.proximal_position(u(i)) +
            Vector2<double>(std::sin(limb.alpha + turn) - std::sin(limb.alpha),
                            std::cos(limb.alpha) - std::cos(limb.alpha + turn)) /
                kappa;
      end_angle = limb.alpha + turn;
    } else {
      const RodState<double> tip = integrate_rod(proximal_rod_state(limb, u(i), start.wrenches[i]),
                                                 limb.rod, options.max_rod_steps);
      end = Vector2<double>(tip.x, tip.y);
      end_angle = tip.theta;
    }
    const Vector2<double> d = end - origin;
    limb.B = Vector2<double>(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
    limb.beta = end_angle - theta;
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
  JacobianLU lu;
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
  for (int steps = 0;
       steps < 4 * options.max_continuation_steps && ds >= options.min_continuation_step; ++steps) {
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
      const double g = last ? 0.0
                            : tangent_z.dot(zz - z_last - step * tangent_z) +
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

/// Whether the robot says which home it is in (LimbParams::home_bow on some rod).
inline bool home_bows_said(const RobotParams<double>& robot) {
  for (int i = 0; i < robot.num_limbs; ++i) {
    if (robot.limb(i).home_bow != 0) return true;
  }
  return false;
}

/// bowed_variant_homotopy with the rods bowed to their left, then, if that path fails, to their
/// right; then the same with twice and half the bow (the documented order of the branches tried).
/// A robot that says which home it is in (home_bows_said) keeps its rods' sides, with the three
/// bows. Next to a bifurcation (rods that are straight at home, moved a few um) the path from one
/// bow can wander off where another reaches the robot.
inline SolveStatus solve_from_bowed_variant(const RobotParams<double>& robot,
                                            const PlatformLoad<double>& load,
                                            const ShootingVector& u, const SolverOptions& options,
                                            SolverSummary& summary, ShootingVector& z) {
  SolveStatus status = SolveStatus::kMaxIterations;
  const bool said = home_bows_said(robot);
  for (const double bow : {kVariantBow, -kVariantBow, 2 * kVariantBow, -2 * kVariantBow,
                           kVariantBow / 2, -kVariantBow / 2}) {
    if (said && bow < 0) continue;
    status = bowed_variant_homotopy(robot, load, u, bow, options, summary, z);
    if (status == SolveStatus::kConverged) break;
  }
  return status;
}

/// solve_from_bowed_variant at the unknowns' step count, then refine_rod_steps. Near a fold of the
/// blended geometry the path of a coarse model can cross to a neighbouring branch that the finer
/// models do not reach (two equilibria of a 5-limb robot 0.6 um apart: 16 steps reach one, 24 and
/// more the other). So the homotopy is run again at the step count the refinement settles on, until
/// the two agree: the branch returned is the one the returned solution's own model reaches. Should
/// a finer homotopy fail, the coarser one's refined solution, an equilibrium as accurate, stands.
inline SolveStatus solve_from_bowed_variant_at_refined_steps(
    ShootingProblem& problem, const ShootingVector& u, const SolverOptions& options,
    SolverSummary& summary, ShootingVector& z, ChordMatrix* carried) {
  SolverOptions fixed = options;
  fixed.rod_steps = problem.rod_steps();
  SolveStatus status =
      solve_from_bowed_variant(problem.robot(), problem.load(), u, fixed, summary, z);
  for (int pass = 0; status == SolveStatus::kConverged; ++pass) {
    problem.set_rod_steps(fixed.rod_steps);
    if (carried) *carried = ChordMatrix();  // the homotopy's last Jacobian was not this problem's
    status = refine_rod_steps(problem, z, options, summary, status, carried);
    if (status != SolveStatus::kConverged || problem.rod_steps() <= fixed.rod_steps || pass == 2)
      break;
    const ShootingVector kept_z = z;
    const SolverSummary kept = summary;
    const ChordMatrix kept_jacobian = carried ? *carried : ChordMatrix();
    fixed.rod_steps = problem.rod_steps();
    if (solve_from_bowed_variant(problem.robot(), problem.load(), u, fixed, summary, z) !=
        SolveStatus::kConverged) {
      z = kept_z;
      const SolverSummary spent = summary;
      summary = kept;
      summary.iterations = spent.iterations;
      summary.residual_evaluations = spent.residual_evaluations;
      summary.continuation_steps = spent.continuation_steps;
      if (carried) *carried = kept_jacobian;
      break;
    }
  }
  return status;
}

/// The solution at q = 0: from the unloaded straight guess (exact for a stress-free robot); when
/// Newton fails from there, by a Newton homotopy from it (n <= 3) and from a bowed variant of the
/// robot (n >= 4, where the straight guess is on a bifurcation, or when that homotopy fails).
inline ShootingVector home_unknowns(ShootingProblem& fk, const SolverOptions& options,
                                    SolverSummary& summary, SolveStatus& status,
                                    ChordMatrix* carried) {
  ShootingVector u = ShootingVector::Zero(fk.num_inputs());
  fk.set_input(u);
  ShootingVector z = ShootingVector::Zero(fk.size());
  // Newton hands back the Jacobian it evaluated last, the estimate's below when it converged.
  NewtonResult home = newton_solve(fk, z, options, summary, carried);
  summary.initial_residual_norm = home.initial_norm;
  if (home.status != SolveStatus::kConverged && carried) *carried = ChordMatrix();  // not at z
  if (home.status != SolveStatus::kConverged && options.continuation && fk.robot().num_limbs <= 3) {
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
    if (t < 1.0 && home.status == SolveStatus::kConverged)
      home.status = SolveStatus::kMaxIterations;
  }
  summary.final_residual_norm = home.final_norm;
  summary.max_strain = home.max_strain;
  if (home.status != SolveStatus::kConverged && options.continuation) {
    status = solve_from_bowed_variant_at_refined_steps(fk, u, options, summary, z, carried);
    return z;
  }
  status = refine_rod_steps(fk, z, options, summary, home.status, carried);
  return z;
}

}  // namespace pcr::internal
