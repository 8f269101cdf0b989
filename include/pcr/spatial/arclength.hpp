#pragma once
// Spatial FK and IK through folds: pseudo-arclength continuation (pcr/internal/arclength.hpp's
// trace_curve, the rule the planar core follows) along the straight input path from a warm start,
// on the spatial shooting problems of pcr/spatial/kinematics.hpp, as the curve that header defines
// (SpatialArclengthCurve, which the bowed cold start traces too). Header-only, no heap, no
// exceptions, at most SolverOptions::max_arclength_steps points.

#include <Eigen/Core>
#include <Eigen/LU>

#include "pcr/internal/arclength.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace pcr {
namespace internal {

/// FK's input path: the joints from q0 to q1 on a line.
struct SpatialJointPath {
  SpatialJointVector q0;
  SpatialJointVector dq;

  void place(SpatialShootingPoint<double>& x, double t) const {
    for (int i = 0; i < q0.size(); ++i) x.q[i] = q0(i) + t * dq(i);
  }
  void prepare(double) const {}
  /// d residual / d t at x, the point `problem` last evaluated.
  SpatialVector rate(const SpatialForwardProblem& problem, const SpatialShootingPoint<double>& x,
                     double, SolverSummary&) const {
    return problem.input_jacobian(x) * dq;
  }
};

/// IK's input path: the straight pose path (SpatialPosePath), of which each point imposes what IK
/// imposes, the free orientation directions kept (spatial_imposed_pose).
struct SpatialPoseCurvePath {
  SpatialPosePath path;
  int num_rods;

  SpatialPose<double> imposed(const SpatialPose<double>& current, double t) const {
    return spatial_imposed_pose(num_rods, path.at(t), current);
  }
  void place(SpatialShootingPoint<double>& x, double t) const { x.pose = imposed(x.pose, t); }
  void prepare(double) const {}
  /// d residual / d t at x, the point `problem` last evaluated: the pose columns times the imposed
  /// pose's rate, by a central difference of the path (a closed form, no rod integrated).
  SpatialVector rate(const SpatialInverseProblem& problem, const SpatialShootingPoint<double>& x,
                     double t, SolverSummary&) const {
    constexpr double h = 1e-6;
    const Eigen::Matrix<double, 6, 1> rate =
        problem.pose_step(imposed(x.pose, t - h), imposed(x.pose, t + h)) / (2 * h);
    return problem.pose_jacobian(x) * rate;
  }
};

/// FK or IK from `warm` (a solution at the path's start) along `path` by pseudo-arclength
/// continuation (see spatial_forward_kinematics_through_folds). solve_at_end(last) solves the
/// input itself from the last point traced, just past it.
template <class Solution, class Problem, class InputPath, class SolveAtEnd, class Visitor>
Solution spatial_solve_through_folds(const SpatialRobotParams<double>& robot, Problem& problem,
                                     const InputPath& path, const Solution& warm,
                                     const SolverOptions& options, SolveAtEnd&& solve_at_end,
                                     Visitor&& visit) {
  Solution out;
  SolverSummary& summary = out.summary;
  SpatialCurvePoint point;
  point.x = spatial_shooting_point(robot, warm);
  SpatialArclengthCurve<Problem, InputPath> curve(problem, path);
  const ArclengthTrace trace = trace_curve(
      curve, point, options, summary, options.max_arclength_steps, [&](const SpatialCurvePoint& p) {
        Solution at;
        at.summary.status = SolveStatus::kConverged;
        at.summary.path_fraction = p.t;
        fill_solution(problem, p.x, at);
        report_spatial_solution(robot, options, at);
        visit(static_cast<const Solution&>(at));
      });
  summary.folds_passed = trace.folds;
  summary.first_fold = trace.first_fold;
  fill_solution(problem, point.x, out);
  if (trace.reached) {
    Solution reached = solve_at_end(static_cast<const Solution&>(out));
    reached.summary.iterations += summary.iterations;
    reached.summary.residual_evaluations += summary.residual_evaluations;
    reached.summary.continuation_steps += summary.continuation_steps;
    reached.summary.folds_passed = trace.folds;
    reached.summary.first_fold = trace.first_fold;
    if (reached.summary.converged()) return reached;
  }
  summary.status = SolveStatus::kSingular;
  summary.path_fraction = trace.t;
  return out;
}

}  // namespace internal

/// Spatial forward kinematics from a warm start along the straight joint path to q by
/// pseudo-arclength continuation, as forward_kinematics_through_folds: through folds, where the
/// joints' path turns back (the robot snaps through). The solution at q when the curve of
/// solutions comes back to it (after an even number of folds; solved there from the point just
/// past q by spatial_forward_kinematics, its RK4 steps refined), else the last point traced with
/// status kSingular. summary.folds_passed and first_fold say where it turned. visit(point) sees
/// every point of the curve (path_fraction: where its joints lie on the path; its stability
/// checked as SolverOptions::check_stability says). The trace keeps the warm start's RK4 steps
/// (options.rod_steps when fixed).
template <class Visitor = NoPathVisitor>
SpatialForwardSolution spatial_forward_kinematics_through_folds(
    const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
    const SpatialForwardSolution& warm_start, const SolverOptions& options = SolverOptions(),
    Visitor&& visit = Visitor()) {
  if (!internal::spatial_inputs_valid(robot, q, options) || warm_start.q.size() != robot.num_rods ||
      !warm_start.q.allFinite()) {
    SpatialForwardSolution out;
    out.summary.status = SolveStatus::kInvalidInput;
    return out;
  }
  internal::SpatialForwardProblem problem(
      robot, internal::starting_rod_steps(options, warm_start.summary.rod_steps));
  const internal::SpatialJointPath path{warm_start.q, q - warm_start.q};
  return internal::spatial_solve_through_folds(
      robot, problem, path, warm_start, options,
      [&](const SpatialForwardSolution& last) {
        return spatial_forward_kinematics(robot, q, last, options);
      },
      visit);
}

/// As spatial_forward_kinematics_through_folds, for IK along the straight pose path from the
/// warm start's pose (SpatialPosePath). The pose's end solve keeps the equilibrium it reaches,
/// stable or not (no search for a stable one: the trace follows the robot's branch).
template <class Visitor = NoPathVisitor>
SpatialInverseSolution spatial_inverse_kinematics_through_folds(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialInverseSolution& warm_start, const SolverOptions& options = SolverOptions(),
    Visitor&& visit = Visitor()) {
  SpatialInverseSolution out;
  if (spatial_inverse_free_angles(robot.num_rods) < 0) {
    out.summary.status = SolveStatus::kUnsupported;
    return out;
  }
  if (!internal::spatial_inputs_valid(robot, warm_start.q, options) ||
      !internal::spatial_pose_valid(pose) || !internal::spatial_pose_valid(warm_start.pose)) {
    out.summary.status = SolveStatus::kInvalidInput;
    return out;
  }
  internal::SpatialInverseProblem problem(
      robot, internal::starting_rod_steps(options, warm_start.summary.rod_steps));
  const internal::SpatialPoseCurvePath path{
      internal::SpatialPosePath(problem, warm_start.pose, pose), robot.num_rods};
  SolverOptions on_branch = options;
  on_branch.stable_inverse = false;
  return internal::spatial_solve_through_folds(
      robot, problem, path, warm_start, options,
      [&](const SpatialInverseSolution& last) {
        return spatial_inverse_kinematics(robot, pose, last, on_branch);
      },
      visit);
}

#if !PCR_SOLVER_DEFINITIONS
// Without a visitor of their own, compiled once (pcr/internal/solver_linkage.hpp).
extern template SpatialForwardSolution spatial_forward_kinematics_through_folds<NoPathVisitor>(
    const SpatialRobotParams<double>&, const SpatialJointVector&, const SpatialForwardSolution&,
    const SolverOptions&, NoPathVisitor&&);
extern template SpatialInverseSolution spatial_inverse_kinematics_through_folds<NoPathVisitor>(
    const SpatialRobotParams<double>&, const SpatialPose<double>&, const SpatialInverseSolution&,
    const SolverOptions&, NoPathVisitor&&);
#endif

}  // namespace pcr
