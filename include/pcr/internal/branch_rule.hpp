#pragma once
// The rule that keeps a continuation step on its branch, shared by the planar and spatial paths
// (pcr/internal/path.hpp, pcr/spatial/kinematics.hpp).

namespace pcr::internal {

/// The largest corrector a path step may take, as a share of its tangent predictor's own step.
/// Along a branch of curvature k the tangent predictor of a step h misses it by about k h^2 / 2:
/// a share of 1/4 lets the tangent turn by up to half a radian over a step (the step length
/// control of predictor-corrector continuation, Allgower and Georg, Introduction to Numerical
/// Continuation Methods, 6.1). A corrector that goes further may have converged on another branch
/// (another equilibrium at the same input), so the step is shortened instead.
inline constexpr double kMaxCorrectorShare = 0.25;

/// Scaled distance below which a corrector is rounding, whatever the step (3e-10 m on a 30 mm
/// rod): two branches are never that close but at a fold, where the path stops.
inline constexpr double kCorrectorFloor = 1e-8;

/// Whether a corrector that moved the unknowns by `corrector` from a tangent predictor that moved
/// them by `predictor` (both scaled norms) stayed on the branch it predicted.
inline bool corrector_on_branch(double corrector, double predictor) {
  return corrector <= kMaxCorrectorShare * predictor + kCorrectorFloor;
}

}  // namespace pcr::internal
