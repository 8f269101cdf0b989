#pragma once
// Sequences of spatial FK and IK inputs (the rows of a file, a trajectory): pcr::SequenceSolver
// (pcr/kinematics.hpp) and its policy, with the spatial solvers of pcr/spatial/kinematics.hpp.
//   kIndependent: each input exactly as its cold solve gives it, whatever came before: FK from
//     straight rods at q (spatial_forward_kinematics(robot, q)), IK from the home solution
//     (q = 0), solved once.
//   kPath: each input warm-started from the last usable solution, retried cold when that fails.
// There is no fold tracing for spatial robots yet: SolverOptions::through_folds has no effect.

#include "pcr/kinematics.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace pcr {

/// A spatial robot carries its load (gravity, external wrench) in its parameters: a sequence has
/// no separate one.
struct SpatialNoLoad {};

/// A spatial IK solution as the forward solution at its joints: a start for the next IK (or a
/// warm start for FK). The factorisation is left behind (the IK's columns are not FK's).
inline SpatialForwardSolution as_spatial_forward_solution(const SpatialInverseSolution& ik) {
  SpatialForwardSolution fk;
  fk.pose = ik.pose;
  fk.q = ik.q;
  fk.wrenches = ik.wrenches;
  fk.summary = ik.summary;
  return fk;
}

/// Spatial IK from the home solution (FK at q = 0); a home that did not converge is returned as a
/// failed solution with its status. The summary does not count the home solve's iterations.
inline SpatialInverseSolution spatial_inverse_kinematics_from_home(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SpatialForwardSolution& home, const SolverOptions& options = SolverOptions()) {
  if (!usable_as_warm_start(home.summary)) {
    SpatialInverseSolution out;
    out.summary = home.summary;
    out.summary.iterations = 0;
    out.summary.path_fraction = 0.0;
    return out;
  }
  return spatial_inverse_kinematics(robot, pose, home, options);
}

/// Spatial IK from a cold start: the home solution (a cold FK at q = 0), then
/// spatial_inverse_kinematics_from_home.
inline SpatialInverseSolution spatial_inverse_kinematics(
    const SpatialRobotParams<double>& robot, const SpatialPose<double>& pose,
    const SolverOptions& options = SolverOptions()) {
  const SpatialForwardSolution home =
      spatial_forward_kinematics(robot, SpatialJointVector::Zero(robot.num_rods), options);
  return spatial_inverse_kinematics_from_home(robot, pose, home, options);
}

template <>
struct SequenceTraits<SpatialForwardSolution> {
  using Robot = SpatialRobotParams<double>;
  using Input = SpatialJointVector;
  using Load = SpatialNoLoad;
  /// The cold FK starts from straight rods at q: it needs no home.
  struct Home {};
  static Home home(const Robot&, const SolverOptions&, const Load&) { return Home(); }
  static SpatialForwardSolution independent(const Robot& robot, const Input& q, const Home&,
                                            const SolverOptions& options, const Load&) {
    return spatial_forward_kinematics(robot, q, options);
  }
  static SpatialForwardSolution continued(const Robot& robot, const Input& q,
                                          const SpatialForwardSolution* warm,
                                          const SolverOptions& options, const Load&) {
    const auto warm_solve = [&](const SpatialForwardSolution& w) {
      return spatial_forward_kinematics(robot, q, w, options);
    };
    return internal::solve_with_cold_fallback(
        warm, warm_solve, /*through_folds=*/false, warm_solve,
        [&] { return spatial_forward_kinematics(robot, q, options); });
  }
};

template <>
struct SequenceTraits<SpatialInverseSolution> {
  using Robot = SpatialRobotParams<double>;
  using Input = SpatialPose<double>;
  using Load = SpatialNoLoad;
  using Home = SpatialForwardSolution;
  static Home home(const Robot& robot, const SolverOptions& options, const Load&) {
    return spatial_forward_kinematics(robot, SpatialJointVector::Zero(robot.num_rods), options);
  }
  static SpatialInverseSolution independent(const Robot& robot, const Input& pose, const Home& home,
                                            const SolverOptions& options, const Load&) {
    return spatial_inverse_kinematics_from_home(robot, pose, home, options);
  }
  static SpatialInverseSolution continued(const Robot& robot, const Input& pose,
                                          const SpatialInverseSolution* warm,
                                          const SolverOptions& options, const Load&) {
    const auto warm_solve = [&](const SpatialInverseSolution& w) {
      return spatial_inverse_kinematics(robot, pose, as_spatial_forward_solution(w), options);
    };
    return internal::solve_with_cold_fallback(
        warm, warm_solve, /*through_folds=*/false, warm_solve,
        [&] { return spatial_inverse_kinematics(robot, pose, options); });
  }
};

using SpatialForwardSequence = SequenceSolver<SpatialForwardSolution>;
using SpatialInverseSequence = SequenceSolver<SpatialInverseSolution>;

}  // namespace pcr
