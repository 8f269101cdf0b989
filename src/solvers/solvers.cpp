// The solvers' entry points, compiled once for what links pcr::solvers
// (pcr/internal/solver_linkage.hpp): every header that declares one is included here, in this
// one file, so that each is defined exactly once.
#ifndef PCR_SOLVERS_SOURCE
#error "pcr::solvers compiles this file with PCR_SOLVERS_SOURCE and PCR_COMPILED_SOLVERS"
#endif

#include "pcr/kinematics.hpp"
#include "pcr/spatial/arclength.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/sequence.hpp"
#include "pcr/spatial/stability.hpp"
#include "pcr/stability.hpp"

namespace pcr {

// The traces through folds without a visitor of their own (declared extern in the headers).
template ForwardSolution forward_kinematics_through_folds<NoPathVisitor>(
    const RobotParams<double>&, const JointVector&, const ForwardSolution&, const SolverOptions&,
    const PlatformLoad<double>&, NoPathVisitor&&);
template InverseSolution inverse_kinematics_through_folds<NoPathVisitor>(
    const RobotParams<double>&, const Pose2<double>&, const InverseSolution&, const SolverOptions&,
    const PlatformLoad<double>&, NoPathVisitor&&);
template SpatialForwardSolution spatial_forward_kinematics_through_folds<NoPathVisitor>(
    const SpatialRobotParams<double>&, const SpatialJointVector&, const SpatialForwardSolution&,
    const SolverOptions&, NoPathVisitor&&);
template SpatialInverseSolution spatial_inverse_kinematics_through_folds<NoPathVisitor>(
    const SpatialRobotParams<double>&, const SpatialPose<double>&, const SpatialInverseSolution&,
    const SolverOptions&, NoPathVisitor&&);

}  // namespace pcr
