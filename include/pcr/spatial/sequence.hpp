#pragma once
// Sequences of spatial FK and IK inputs (the rows of a file, a trajectory): pcr::SequenceSolver
// (pcr/kinematics.hpp) and its policy, with the spatial solvers of pcr/spatial/kinematics.hpp.
//   kIndependent: each input exactly as its cold solve gives it, whatever came before: FK from
//     straight rods at q (spatial_forward_kinematics(robot, q)), IK from the home solution
//     (q = 0), solved once.
//   kPath: each input continued from the last usable solution on its branch (a long jump of the
//     inputs as a path of steps where one step would leave it: spatial_solve_path), retried cold
//     when that fails; where the branch ends at a fold, followed through it first with
//     SolverOptions::through_folds (pcr/spatial/arclength.hpp), as the planar sequences do.

#include "pcr/kinematics.hpp"
#include "pcr/spatial/arclength.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace pcr {

/// A spatial robot carries its load (gravity, external wrench) in its parameters: a sequence has
/// no separate one.
struct SpatialNoLoad {};

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
                                          const SolverOptions& options, const Load&);
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
                                          const SolverOptions& options, const Load&);
};

using SpatialForwardSequence = SequenceSolver<SpatialForwardSolution>;
using SpatialInverseSequence = SequenceSolver<SpatialInverseSolution>;

#if PCR_SOLVER_DEFINITIONS
// The bodies of the entry points declared above (pcr/internal/solver_linkage.hpp).

PCR_SOLVER_INLINE SpatialForwardSolution SequenceTraits<SpatialForwardSolution>::continued(
    const Robot& robot, const Input& q, const SpatialForwardSolution* warm,
    const SolverOptions& options, const Load&) {
  const auto warm_solve = [&](const SpatialForwardSolution& w) {
    return spatial_forward_kinematics(robot, q, w, options);
  };
  return internal::solve_with_cold_fallback(
      warm, warm_solve, options.through_folds,
      [&](const SpatialForwardSolution& w) {
        return spatial_forward_kinematics_through_folds(robot, q, w, options);
      },
      [&] { return spatial_forward_kinematics(robot, q, options); });
}

PCR_SOLVER_INLINE SpatialInverseSolution SequenceTraits<SpatialInverseSolution>::continued(
    const Robot& robot, const Input& pose, const SpatialInverseSolution* warm,
    const SolverOptions& options, const Load&) {
  const auto warm_solve = [&](const SpatialInverseSolution& w) {
    return spatial_inverse_kinematics(robot, pose, w, options);
  };
  return internal::solve_with_cold_fallback(
      warm, warm_solve, options.through_folds,
      [&](const SpatialInverseSolution& w) {
        return spatial_inverse_kinematics_through_folds(robot, pose, w, options);
      },
      [&] { return spatial_inverse_kinematics(robot, pose, options); });
}

#endif  // PCR_SOLVER_DEFINITIONS

}  // namespace pcr
