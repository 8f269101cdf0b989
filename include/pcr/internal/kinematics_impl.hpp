#pragma once
// The bodies of the functions pcr/kinematics.hpp declares (included at its end).

#include <cmath>

#include "pcr/internal/path.hpp"
#include "pcr/internal/shooting_problem.hpp"

namespace pcr {
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

/// FK or IK along the straight input path from a warm start's input u0 to u1: the one body of
/// both, which differ only in which unknowns are inputs.
template <class Solution>
Solution solve_from_warm_start(ShootingProblem::Kind kind, const RobotParams<double>& robot,
                               const ShootingVector& u0, const ShootingVector& u1,
                               const Solution& warm, const SolverOptions& options,
                               const PlatformLoad<double>& load) {
  Solution solution;
  ShootingProblem problem(kind, robot, load, options);
  ShootingPoint<double> start;
  start.pose = warm.pose;
  for (int i = 0; i < robot.num_limbs; ++i) {
    start.q[i] = warm.q(i);
    start.wrenches[i] = warm.wrenches[i];
  }
  problem.set_input(u0);
  ShootingVector z = problem.pack(start);
  solution.jacobian = warm.jacobian;
  solution.summary.status = solve_along_path(problem, u0, u1, z, options, solution.summary,
                                             warm.summary.rod_steps, &solution.jacobian);
  store_configuration(problem, z, solution);
  return solution;
}

}  // namespace internal

inline ForwardSolution forward_kinematics(const RobotParams<double>& robot, const JointVector& q,
                                          const ForwardSolution& warm_start,
                                          const SolverOptions& options,
                                          const PlatformLoad<double>& load) {
  if (!internal::valid_robot(robot) || q.size() != robot.num_limbs || !q.allFinite() ||
      warm_start.q.size() != robot.num_limbs) {
    ForwardSolution invalid;
    invalid.q = q;
    invalid.summary.status = SolveStatus::kInvalidInput;
    return invalid;
  }
  return internal::solve_from_warm_start(internal::ShootingProblem::Kind::kForward, robot,
                                         warm_start.q, q, warm_start, options, load);
}

inline ForwardSolution home_solution(const RobotParams<double>& robot, const SolverOptions& options,
                                     const PlatformLoad<double>& load) {
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
  home.summary.path_fraction = 1.0;
  internal::store_configuration(problem, z, home);
  return home;
}

inline ForwardSolution forward_kinematics(const RobotParams<double>& robot, const JointVector& q,
                                          const SolverOptions& options,
                                          const PlatformLoad<double>& load) {
  ForwardSolution home = home_solution(robot, options, load);
  if (!home.summary.converged()) return home;  // q = 0 then, path_fraction 0: nothing solved
  ForwardSolution solution = forward_kinematics(robot, q, home, options, load);
  solution.summary.iterations += home.summary.iterations;
  solution.summary.residual_evaluations += home.summary.residual_evaluations;
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
        problem, u, options, solution.summary, z, &solution.jacobian);
    if (status == SolveStatus::kConverged) {
      internal::store_configuration(problem, z, solution);
      solution.summary.path_fraction = 1.0;
    }
    // Not found from the variant either: the path's own verdict stands.
    solution.summary.status = status == SolveStatus::kConverged ? status : path_status;
  }
  return solution;
}

inline InverseSolution inverse_kinematics(const RobotParams<double>& robot,
                                          const Pose2<double>& pose,
                                          const InverseSolution& warm_start,
                                          const SolverOptions& options,
                                          const PlatformLoad<double>& load) {
  const int n = robot.num_limbs;
  InverseSolution refused;
  refused.pose = pose;
  if (!internal::valid_robot(robot) || warm_start.q.size() != n || !std::isfinite(pose.x) ||
      !std::isfinite(pose.y) || !std::isfinite(pose.theta)) {
    refused.summary.status = SolveStatus::kInvalidInput;
    return refused;
  }
  if (n > 3) {
    refused.summary.status = SolveStatus::kUnsupported;
    return refused;
  }
  ShootingVector u0(3), u1(3);
  u0 << warm_start.pose.x, warm_start.pose.y, warm_start.pose.theta;
  u1 << pose.x, pose.y, n == 2 ? warm_start.pose.theta : pose.theta;
  InverseSolution solution = internal::solve_from_warm_start(
      internal::ShootingProblem::Kind::kInverse, robot, u0, u1, warm_start, options, load);
  if (solution.summary.converged()) {
    for (int i = 0; i < n; ++i) {
      if (solution.q(i) < robot.limb(i).q_min || solution.q(i) > robot.limb(i).q_max) {
        solution.summary.status = SolveStatus::kOutOfRange;
      }
    }
  }
  return solution;
}

inline InverseSolution inverse_kinematics(const RobotParams<double>& robot,
                                          const Pose2<double>& pose, const SolverOptions& options,
                                          const PlatformLoad<double>& load) {
  const ForwardSolution home = home_solution(robot, options, load);  // no IK factorisation
  if (!home.summary.converged()) {
    InverseSolution failed = as_inverse_warm_start(home);
    failed.summary.path_fraction = 0.0;
    return failed;
  }
  InverseSolution solution =
      inverse_kinematics(robot, pose, as_inverse_warm_start(home), options, load);
  solution.summary.iterations += home.summary.iterations;
  solution.summary.residual_evaluations += home.summary.residual_evaluations;
  return solution;
}

inline InverseSolution as_inverse_warm_start(const ForwardSolution& fk) {
  InverseSolution warm;
  warm.pose = fk.pose;
  warm.q = fk.q;
  warm.wrenches = fk.wrenches;
  warm.summary = fk.summary;
  return warm;
}

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

inline ForwardSolution forward_kinematics_or_cold(const RobotParams<double>& robot,
                                                  const JointVector& q, const ForwardSolution* warm,
                                                  const SolverOptions& options,
                                                  const PlatformLoad<double>& load) {
  return internal::solve_with_cold_fallback(
      warm,
      [&](const ForwardSolution& w) { return forward_kinematics(robot, q, w, options, load); },
      [&] { return forward_kinematics(robot, q, options, load); });
}

inline InverseSolution inverse_kinematics_or_cold(const RobotParams<double>& robot,
                                                  const Pose2<double>& pose,
                                                  const InverseSolution* warm,
                                                  const SolverOptions& options,
                                                  const PlatformLoad<double>& load) {
  return internal::solve_with_cold_fallback(
      warm,
      [&](const InverseSolution& w) { return inverse_kinematics(robot, pose, w, options, load); },
      [&] { return inverse_kinematics(robot, pose, options, load); });
}

template <class Solution>
const Solution& SequenceSolver<Solution>::solve(const Input& input) {
  const int latest = has_last_ ? 1 - last_ : last_;
  const Solution* warm = has_last_ ? &slots_[last_] : nullptr;
  if constexpr (std::is_same_v<Solution, ForwardSolution>) {
    slots_[latest] = forward_kinematics_or_cold(robot_, input, warm, options_, load_);
  } else {
    slots_[latest] = inverse_kinematics_or_cold(robot_, input, warm, options_, load_);
  }
  if (usable_as_warm_start(slots_[latest].summary)) {
    last_ = latest;
    has_last_ = true;
  }
  return slots_[latest];
}

template <class Visitor>
void visit_rod_shapes(const RobotParams<double>& robot, const JointVector& q,
                      const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps,
                      Visitor&& visit) {
  for (int i = 0; i < robot.num_limbs; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    sample_rod(proximal_rod_state(limb, q(i), wrenches[i]), limb.bending_stiffness(), limb.length,
               rod_steps, [&](double s, const RodState<double>& state) { visit(i, s, state); });
  }
}

}  // namespace pcr
