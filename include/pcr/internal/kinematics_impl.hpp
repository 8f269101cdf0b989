#pragma once
// The bodies of the functions pcr/kinematics.hpp declares (included at its end).

#include <algorithm>
#include <cmath>

#include "pcr/internal/arclength.hpp"
#include "pcr/internal/path.hpp"
#include "pcr/internal/shooting_problem.hpp"
#include "pcr/stability.hpp"

namespace pcr {

template <class Solution>
Solution buckled_seed(const RobotParams<double>& robot, const Solution& at, int k, int first_rod) {
  constexpr double kTurns[kBuckledSeedsPerRod] = {1.0, -1.0, 2.0, -2.0};
  const int rod = (first_rod + k / kBuckledSeedsPerRod) % robot.num_limbs;
  const LimbParams<double>& limb = robot.limb(rod);
  Solution seed = at;
  seed.jacobian.clear();  // not at the seed
  seed.wrenches[static_cast<std::size_t>(rod)].m +=
      kTurns[k % kBuckledSeedsPerRod] * 2.0 * M_PI * limb.rod.bending_stiffness() / limb.rod.length;
  return seed;
}

namespace internal {

inline bool valid_robot(const RobotParams<double>& robot) {
  return robot.num_limbs >= 2 && robot.num_limbs <= kMaxLimbs;
}

/// The configuration at z, in a solution's fields.
template <class Solution>
void store_configuration(const ShootingProblem& problem, const ShootingVector& z,
                         Solution& solution) {
  const ShootingPoint<double> p = problem.unpack(z);
  const int n = problem.robot().num_limbs;
  solution.q = JointVector(n);
  for (int i = 0; i < n; ++i) {
    solution.q(i) = p.q[i];
    solution.wrenches[i] = p.wrenches[i];
  }
  solution.pose = p.pose;
}

/// A warm FK solve's input path, from the warm start's joints to q: kConverged when the inputs are
/// valid, else the status that refuses them.
inline SolveStatus forward_path(const RobotParams<double>& robot, const JointVector& q,
                                const ForwardSolution& warm, const SolverOptions& options,
                                ShootingVector& u0, ShootingVector& u1) {
  if (!valid_robot(robot) || !options.is_valid() || q.size() != robot.num_limbs || !q.allFinite() ||
      warm.q.size() != robot.num_limbs) {
    return SolveStatus::kInvalidInput;
  }
  u0 = warm.q;
  u1 = q;
  return SolveStatus::kConverged;
}

/// A warm IK solve's input path, from the warm start's pose to `pose` (theta kept when n = 2, where
/// it is solved for), as forward_path.
inline SolveStatus inverse_path(const RobotParams<double>& robot, const Pose2<double>& pose,
                                const InverseSolution& warm, const SolverOptions& options,
                                ShootingVector& u0, ShootingVector& u1) {
  const int n = robot.num_limbs;
  if (!valid_robot(robot) || !options.is_valid() || warm.q.size() != n || !std::isfinite(pose.x) ||
      !std::isfinite(pose.y) || !std::isfinite(pose.theta)) {
    return SolveStatus::kInvalidInput;
  }
  if (n > 3) return SolveStatus::kUnsupported;
  u0.resize(3);
  u1.resize(3);
  u0 << warm.pose.x, warm.pose.y, warm.pose.theta;
  u1 << pose.x, pose.y, n == 2 ? warm.pose.theta : pose.theta;
  return SolveStatus::kConverged;
}

/// A solution that reports refused inputs (FK keeps its joints, IK its pose).
inline ForwardSolution refused(const JointVector& q, SolveStatus status) {
  ForwardSolution solution;
  solution.q = q;
  solution.summary.status = status;
  return solution;
}
inline InverseSolution refused(const Pose2<double>& pose, SolveStatus status) {
  InverseSolution solution;
  solution.pose = pose;
  solution.summary.status = status;
  return solution;
}

/// What a converged solution's status says beyond convergence: kOutOfRange for joints outside
/// the stroke, else kInaccurate for an error estimate above the targets (mark_inaccurate).
template <class Solution>
void mark_caveats(const RobotParams<double>& robot, const SolverOptions& options,
                  Solution& solution) {
  if (solution.summary.converged() && !within_stroke(robot, solution.q)) {
    solution.summary.status = SolveStatus::kOutOfRange;
  }
  mark_inaccurate(options, solution.summary);
}

/// The shooting point (joints, pose, wrenches) of a solution.
template <class Solution>
ShootingPoint<double> shooting_point(const RobotParams<double>& robot, const Solution& solution) {
  ShootingPoint<double> point;
  point.pose = solution.pose;
  for (int i = 0; i < robot.num_limbs; ++i) {
    point.q[i] = solution.q(i);
    point.wrenches[i] = solution.wrenches[i];
  }
  return point;
}

/// Checks the stability of a usable solution's equilibrium into its summary (see
/// SolverOptions::check_stability) and returns the check's details (unset when unchecked).
template <class Solution>
EquilibriumStability check_stability(const RobotParams<double>& robot, const SolverOptions& options,
                                     Solution& solution) {
  SolverSummary& summary = solution.summary;
  summary.stability = Stability::kUnchecked;
  summary.stability_margin = summary.singularity = std::numeric_limits<double>::quiet_NaN();
  if (!options.check_stability || !usable_as_warm_start(summary)) return EquilibriumStability();
  const EquilibriumStability s = equilibrium_stability(
      robot, solution.q, solution.pose, solution.wrenches, stability_rod_steps(summary.rod_steps));
  summary.stability = s.stable ? Stability::kStable : Stability::kUnstable;
  summary.stability_margin = s.margin;
  summary.singularity = s.singularity;
  return s;
}

/// The options of a solve whose solution is a step towards the requested one (cold starts' home).
inline SolverOptions unchecked(SolverOptions options) {
  options.check_stability = false;
  return options;
}

/// FK or IK along the straight input path from a warm start's input u0 to u1: the one body of
/// both, which differ only in which unknowns are inputs.
template <class Solution>
Solution solve_from_warm_start(ShootingProblem::Kind kind, const RobotParams<double>& robot,
                               const ShootingVector& u0, const ShootingVector& u1,
                               const Solution& warm, const SolverOptions& options,
                               const PlatformLoad<double>& load) {
  Solution solution;
  ShootingProblem problem(kind, robot, load, options);
  problem.set_input(u0);
  ShootingVector z = problem.pack(shooting_point(robot, warm));
  solution.jacobian = warm.jacobian;
  solution.summary.status =
      solve_along_path(problem, u0, u1, z, options, solution.summary, warm.summary.rod_steps,
                       &WarmStartAccess::chord(solution.jacobian));
  store_configuration(problem, z, solution);
  return solution;
}

/// IK has converged on an unstable equilibrium at the input u: looks for a stable one at the same
/// pose, from the buckled seeds (buckled_seed), the rod with a conjugate point (conjugate_limb,
/// or -1) first. Takes the stable solution whose joints lie nearest (one
/// within the stroke before one outside), else reports kUnstable with the unstable solution. The
/// summary counts every seed's iterations and evaluations.
inline void look_for_stable_inverse(const RobotParams<double>& robot, const ShootingVector& u,
                                    const SolverOptions& options, const PlatformLoad<double>& load,
                                    int conjugate_limb, InverseSolution& solution) {
  const int n = robot.num_limbs;

  InverseSolution best;
  bool found = false, best_in_range = false;
  double best_distance = HUGE_VAL;
  SolverSummary totals = solution.summary;
  for (int k = 0; k < kBuckledSeedsPerRod * n; ++k) {
    const InverseSolution seed = buckled_seed(robot, solution, k, std::max(conjugate_limb, 0));
    InverseSolution candidate =
        solve_from_warm_start(ShootingProblem::Kind::kInverse, robot, u, u, seed, options, load);
    totals.iterations += candidate.summary.iterations;
    totals.residual_evaluations += candidate.summary.residual_evaluations;
    if (!candidate.summary.converged()) continue;
    check_stability(robot, options, candidate);
    if (candidate.summary.stability != Stability::kStable) continue;
    const bool inside = within_stroke(robot, candidate.q);
    const double distance = (candidate.q - solution.q).norm();
    if (!found || (inside && !best_in_range) ||
        (inside == best_in_range && distance < best_distance)) {
      best = candidate;
      found = true;
      best_in_range = inside;
      best_distance = distance;
    }
  }
  if (found) {
    best.summary.iterations = totals.iterations;
    best.summary.residual_evaluations = totals.residual_evaluations;
    best.summary.continuation_steps += totals.continuation_steps;
    if (!best_in_range) best.summary.status = SolveStatus::kOutOfRange;
    solution = best;
  } else {
    totals.status = SolveStatus::kUnstable;
    solution.summary = totals;
  }
}

/// FK or IK from a warm start's input u0 to u1 by pseudo-arclength continuation (see
/// forward_kinematics_through_folds).
template <class Solution, class Visitor>
Solution solve_through_folds(ShootingProblem::Kind kind, const RobotParams<double>& robot,
                             const ShootingVector& u0, const ShootingVector& u1,
                             const Solution& warm, const SolverOptions& options,
                             const PlatformLoad<double>& load, Visitor&& visit) {
  Solution solution;
  ShootingProblem problem(kind, robot, load, options);
  problem.set_rod_steps(starting_rod_steps(options, warm.summary.rod_steps));
  problem.set_input(u0);
  ShootingVector z = problem.pack(shooting_point(robot, warm));
  SolverSummary& summary = solution.summary;
  const ArclengthTrace trace =
      trace_arclength(problem, u0, u1, z, options, summary, options.max_arclength_steps,
                      [&](const ShootingVector& point_z, double t) {
                        Solution point;
                        point.summary.status = SolveStatus::kConverged;
                        point.summary.rod_steps = problem.rod_steps();
                        point.summary.path_fraction = t;
                        store_configuration(problem, point_z, point);
                        check_stability(robot, options, point);
                        visit(static_cast<const Solution&>(point));
                      });
  summary.folds_passed = trace.folds;
  summary.first_fold = trace.first_fold;
  if (trace.reached) {
    // Back onto the input from the point just past it, by the regular solver.
    Solution last;
    last.summary.status = SolveStatus::kConverged;
    last.summary.rod_steps = problem.rod_steps();
    store_configuration(problem, z, last);
    const ShootingVector u_last = u0 + trace.t * (u1 - u0);
    Solution reached = solve_from_warm_start(kind, robot, u_last, u1, last, options, load);
    reached.summary.iterations += summary.iterations;
    reached.summary.residual_evaluations += summary.residual_evaluations;
    reached.summary.continuation_steps += summary.continuation_steps;
    reached.summary.folds_passed = trace.folds;
    reached.summary.first_fold = trace.first_fold;
    if (reached.summary.converged()) {
      check_stability(robot, options, reached);
      return reached;
    }
  }
  store_configuration(problem, z, solution);
  summary.status = SolveStatus::kSingular;
  summary.path_fraction = trace.t;
  summary.rod_steps = problem.rod_steps();
  return solution;
}

}  // namespace internal

#if PCR_SOLVER_DEFINITIONS
PCR_SOLVER_INLINE ForwardSolution forward_kinematics(const RobotParams<double>& robot,
                                                     const JointVector& q,
                                                     const ForwardSolution& warm_start,
                                                     const SolverOptions& options,
                                                     const PlatformLoad<double>& load) {
  ShootingVector u0, u1;
  const SolveStatus input = internal::forward_path(robot, q, warm_start, options, u0, u1);
  if (input != SolveStatus::kConverged) return internal::refused(q, input);
  ForwardSolution solution = internal::solve_from_warm_start(
      internal::ShootingProblem::Kind::kForward, robot, u0, u1, warm_start, options, load);
  internal::mark_caveats(robot, options, solution);
  internal::check_stability(robot, options, solution);
  return solution;
}
#endif

template <class Visitor>
ForwardSolution forward_kinematics_through_folds(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution& warm_start,
    const SolverOptions& options, const PlatformLoad<double>& load, Visitor&& visit) {
  ShootingVector u0, u1;
  const SolveStatus input = internal::forward_path(robot, q, warm_start, options, u0, u1);
  if (input != SolveStatus::kConverged) return internal::refused(q, input);
  ForwardSolution solution = internal::solve_through_folds(
      internal::ShootingProblem::Kind::kForward, robot, u0, u1, warm_start, options, load, visit);
  internal::mark_caveats(robot, options, solution);
  return solution;
}

template <class Visitor>
InverseSolution inverse_kinematics_through_folds(
    const RobotParams<double>& robot, const Pose2<double>& pose, const InverseSolution& warm_start,
    const SolverOptions& options, const PlatformLoad<double>& load, Visitor&& visit) {
  ShootingVector u0, u1;
  const SolveStatus input = internal::inverse_path(robot, pose, warm_start, options, u0, u1);
  if (input != SolveStatus::kConverged) return internal::refused(pose, input);
  InverseSolution solution = internal::solve_through_folds(
      internal::ShootingProblem::Kind::kInverse, robot, u0, u1, warm_start, options, load, visit);
  internal::mark_caveats(robot, options, solution);
  return solution;
}

#if PCR_SOLVER_DEFINITIONS
PCR_SOLVER_INLINE ForwardSolution home_solution(const RobotParams<double>& robot,
                                                const SolverOptions& options,
                                                const PlatformLoad<double>& load) {
  ForwardSolution home;
  if (!internal::valid_robot(robot) || !options.is_valid()) {
    home.summary.status = SolveStatus::kInvalidInput;
    return home;
  }
  internal::ShootingProblem problem(internal::ShootingProblem::Kind::kForward, robot, load,
                                    options);
  SolveStatus status;
  ShootingVector z = internal::home_unknowns(problem, options, home.summary, status,
                                             &internal::WarmStartAccess::chord(home.jacobian));
  home.summary.status = status;
  home.summary.path_fraction = 1.0;
  internal::store_configuration(problem, z, home);
  internal::check_stability(robot, options, home);
  return home;
}

PCR_SOLVER_INLINE bool choose_home(const RobotParams<double>& robot, const Pose2<double>& measured,
                                   RobotParams<double>& out, const SolverOptions& options,
                                   const PlatformLoad<double>& load) {
  const int n = robot.num_limbs;
  double mean_length = 0;
  for (int i = 0; i < n; ++i) mean_length += robot.limb(i).rod.length / n;
  double best = HUGE_VAL;
  RobotParams<double> trial = robot;
  // The robot saying nothing first (a tie keeps it), then every pattern of sides (n >= 4).
  for (int pattern = -1; pattern < (n >= 4 ? (1 << n) : 0); ++pattern) {
    for (int i = 0; i < n; ++i) {
      trial.limb(i).home_bow = pattern < 0 ? 0 : ((pattern >> i) & 1 ? 1 : -1);
    }
    const ForwardSolution home = home_solution(trial, options, load);
    if (!home.summary.converged()) continue;
    const double distance = pose_distance(home.pose, measured, mean_length);
    if (distance < best - 1e-9) {
      best = distance;
      out = trial;
    }
  }
  return best < HUGE_VAL;
}
#endif

namespace internal {

/// A cold solve: the home solution (no IK factorisation, and a stability the solution checks for
/// itself), then from_home(home); the summary counts the home solve's iterations too.
template <class FromHome>
auto solve_cold(const RobotParams<double>& robot, const SolverOptions& options,
                const PlatformLoad<double>& load, FromHome&& from_home) {
  const ForwardSolution home = home_solution(robot, unchecked(options), load);
  auto solution = from_home(home);
  if (home.summary.converged()) {
    solution.summary.iterations += home.summary.iterations;
    solution.summary.residual_evaluations += home.summary.residual_evaluations;
  }
  return solution;
}

}  // namespace internal

#if PCR_SOLVER_DEFINITIONS
PCR_SOLVER_INLINE ForwardSolution forward_kinematics(const RobotParams<double>& robot,
                                                     const JointVector& q,
                                                     const SolverOptions& options,
                                                     const PlatformLoad<double>& load) {
  return internal::solve_cold(robot, options, load, [&](const ForwardSolution& home) {
    return forward_kinematics_from_home(robot, q, home, options, load);
  });
}

PCR_SOLVER_INLINE ForwardSolution forward_kinematics_from_home(const RobotParams<double>& robot,
                                                               const JointVector& q,
                                                               const ForwardSolution& home,
                                                               const SolverOptions& options,
                                                               const PlatformLoad<double>& load) {
  if (!home.summary.converged()) return home;  // q = 0 then, path_fraction 0: nothing solved
  ForwardSolution solution = forward_kinematics(robot, q, home, options, load);
  // With n >= 4 limbs, straight rods at home carry a self-stress: a path from a home where some
  // rods are straight starts on, or next to, a bifurcation.
  const SolveStatus path_status = solution.summary.status;
  const bool near_bifurcation =
      path_status == SolveStatus::kBifurcation ||
      (robot.num_limbs >= 4 &&
       (path_status == SolveStatus::kSingular || path_status == SolveStatus::kMaxIterations));
  if (near_bifurcation && options.continuation) {
    internal::ShootingProblem problem(internal::ShootingProblem::Kind::kForward, robot, load,
                                      options);
    const ShootingVector u = q;
    ShootingVector z;
    problem.set_input(u);
    const SolveStatus status = internal::solve_from_bowed_variant_at_refined_steps(
        problem, u, options, solution.summary, z,
        &internal::WarmStartAccess::chord(solution.jacobian));
    if (status == SolveStatus::kConverged) {
      internal::store_configuration(problem, z, solution);
      solution.summary.path_fraction = 1.0;
    }
    // Not found from the variant either: the path's own verdict stands.
    solution.summary.status = status == SolveStatus::kConverged ? status : path_status;
    internal::mark_caveats(robot, options, solution);
    internal::check_stability(robot, options, solution);
  }
  return solution;
}

PCR_SOLVER_INLINE InverseSolution inverse_kinematics(const RobotParams<double>& robot,
                                                     const Pose2<double>& pose,
                                                     const InverseSolution& warm_start,
                                                     const SolverOptions& options,
                                                     const PlatformLoad<double>& load) {
  ShootingVector u0, u1;
  const SolveStatus input = internal::inverse_path(robot, pose, warm_start, options, u0, u1);
  if (input != SolveStatus::kConverged) return internal::refused(pose, input);
  InverseSolution solution = internal::solve_from_warm_start(
      internal::ShootingProblem::Kind::kInverse, robot, u0, u1, warm_start, options, load);
  internal::mark_caveats(robot, options, solution);
  const EquilibriumStability stability = internal::check_stability(robot, options, solution);
  if (solution.summary.stability == Stability::kUnstable && options.stable_inverse) {
    internal::look_for_stable_inverse(robot, u1, options, load, stability.conjugate_limb, solution);
  }
  return solution;
}

PCR_SOLVER_INLINE InverseSolution inverse_kinematics(const RobotParams<double>& robot,
                                                     const Pose2<double>& pose,
                                                     const SolverOptions& options,
                                                     const PlatformLoad<double>& load) {
  return internal::solve_cold(robot, options, load, [&](const ForwardSolution& home) {
    return inverse_kinematics_from_home(robot, pose, home, options, load);
  });
}

PCR_SOLVER_INLINE InverseSolution inverse_kinematics_from_home(const RobotParams<double>& robot,
                                                               const Pose2<double>& pose,
                                                               const ForwardSolution& home,
                                                               const SolverOptions& options,
                                                               const PlatformLoad<double>& load) {
  if (!home.summary.converged()) {
    InverseSolution failed = as_inverse_warm_start(home);
    failed.summary.path_fraction = 0.0;
    return failed;
  }
  return inverse_kinematics(robot, pose, as_inverse_warm_start(home), options, load);
}
#endif

inline InverseSolution as_inverse_warm_start(const ForwardSolution& fk) {
  InverseSolution warm;
  warm.pose = fk.pose;
  warm.q = fk.q;
  warm.wrenches = fk.wrenches;
  warm.summary = fk.summary;
  return warm;
}

inline ForwardSolution as_forward_solution(const InverseSolution& ik) {
  ForwardSolution fk;
  fk.q = ik.q;
  fk.pose = ik.pose;
  fk.wrenches = ik.wrenches;
  fk.summary = ik.summary;
  if (is_equilibrium(ik.summary)) fk.summary.status = SolveStatus::kConverged;
  return fk;
}

inline bool within_stroke(const RobotParams<double>& robot, const JointVector& q) {
  for (int i = 0; i < robot.num_limbs; ++i) {
    if (!robot.limb(i).within_stroke(q(i))) return false;
  }
  return true;
}

namespace internal {

/// A warm solve; when it stops at a fold and through_folds, the trace through it; then a cold
/// solve when neither is usable (and the input is valid). The summary counts the iterations and
/// residual evaluations of all.
template <class Solution, class WarmSolve, class FoldSolve, class ColdSolve>
Solution solve_with_cold_fallback(const Solution* warm, WarmSolve&& warm_solve, bool through_folds,
                                  FoldSolve&& fold_solve, ColdSolve&& cold_solve) {
  if (warm == nullptr) return cold_solve();
  Solution solution = warm_solve(*warm);
  const SolveStatus status = solution.summary.status;
  if (usable_as_warm_start(solution.summary) || status == SolveStatus::kInvalidInput ||
      status == SolveStatus::kUnsupported) {
    return solution;
  }
  int iterations = solution.summary.iterations;
  int evaluations = solution.summary.residual_evaluations;
  const auto add_counts = [&](Solution& s) {
    s.summary.iterations += iterations;
    s.summary.residual_evaluations += evaluations;
  };
  if (through_folds &&
      (status == SolveStatus::kSingular || status == SolveStatus::kMaxIterations)) {
    solution = fold_solve(*warm);
    add_counts(solution);
    if (usable_as_warm_start(solution.summary)) return solution;
    iterations = solution.summary.iterations;
    evaluations = solution.summary.residual_evaluations;
  }
  solution = cold_solve();
  add_counts(solution);
  return solution;
}

}  // namespace internal

#if PCR_SOLVER_DEFINITIONS
PCR_SOLVER_INLINE ForwardSolution forward_kinematics_or_cold(const RobotParams<double>& robot,
                                                             const JointVector& q,
                                                             const ForwardSolution* warm,
                                                             const SolverOptions& options,
                                                             const PlatformLoad<double>& load) {
  return internal::solve_with_cold_fallback(
      warm,
      [&](const ForwardSolution& w) { return forward_kinematics(robot, q, w, options, load); },
      options.through_folds,
      [&](const ForwardSolution& w) {
        return forward_kinematics_through_folds(robot, q, w, options, load);
      },
      [&] { return forward_kinematics(robot, q, options, load); });
}

PCR_SOLVER_INLINE InverseSolution inverse_kinematics_or_cold(const RobotParams<double>& robot,
                                                             const Pose2<double>& pose,
                                                             const InverseSolution* warm,
                                                             const SolverOptions& options,
                                                             const PlatformLoad<double>& load) {
  return internal::solve_with_cold_fallback(
      warm,
      [&](const InverseSolution& w) { return inverse_kinematics(robot, pose, w, options, load); },
      options.through_folds,
      [&](const InverseSolution& w) {
        return inverse_kinematics_through_folds(robot, pose, w, options, load);
      },
      [&] { return inverse_kinematics(robot, pose, options, load); });
}

PCR_SOLVER_INLINE ForwardSolution SequenceTraits<ForwardSolution>::home(
    const Robot& robot, const SolverOptions& options, const Load& load) {
  return home_solution(robot, internal::unchecked(options), load);
}
#endif

template <class Solution>
const Solution& SequenceSolver<Solution>::solve(const Input& input) {
  const int latest = has_last_ ? 1 - last_ : last_;
  Solution& solution = slots_[latest];
  if (mode_ == SequenceMode::kIndependent) {
    // The cold solve's own steps, with its home solved once.
    if (!has_home_) {
      home_ = Traits::home(robot_, options_, load_);
      has_home_ = true;
    }
    solution = Traits::independent(robot_, input, home_, options_, load_);
  } else {
    solution =
        Traits::continued(robot_, input, has_last_ ? &slots_[last_] : nullptr, options_, load_);
  }
  if (usable_as_warm_start(solution.summary)) {
    last_ = latest;
    has_last_ = true;
  }
  return solution;
}

#if !PCR_SOLVER_DEFINITIONS
// Without a visitor of its own, the trace through folds is compiled once too
// (pcr/internal/solver_linkage.hpp, src/solvers/solvers.cpp).
extern template ForwardSolution forward_kinematics_through_folds<NoPathVisitor>(
    const RobotParams<double>&, const JointVector&, const ForwardSolution&, const SolverOptions&,
    const PlatformLoad<double>&, NoPathVisitor&&);
extern template InverseSolution inverse_kinematics_through_folds<NoPathVisitor>(
    const RobotParams<double>&, const Pose2<double>&, const InverseSolution&, const SolverOptions&,
    const PlatformLoad<double>&, NoPathVisitor&&);
#endif

template <class Visitor>
void visit_rod_shapes(const RobotParams<double>& robot, const JointVector& q,
                      const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps,
                      Visitor&& visit) {
  for (int i = 0; i < robot.num_limbs; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    sample_rod(proximal_rod_state(limb, q(i), wrenches[i]), limb.rod, rod_steps,
               [&](double s, const RodState<double>& state) { visit(i, s, state); });
  }
}

}  // namespace pcr
