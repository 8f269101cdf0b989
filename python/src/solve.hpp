#pragma once
// The batch loops behind Robot.forward / Robot.inverse, kept out of the wrappers: rows solved as a
// pcr::SequenceSolver in the mode asked for (each on its own, or a path), as `pcr fk` and `pcr ik`
// do. Plain C++, called with the GIL released.

#include <limits>

#include "pcr/kinematics.hpp"

namespace pcr::python {

/// Row-major output buffers of a batch of N rows for a robot with n limbs.
struct BatchBuffers {
  double* q;                 ///< N x n (m)
  double* pose;              ///< N x 3 (m, m, rad)
  double* wrenches;          ///< N x n x 3 (N, N, N m)
  bool* converged;           ///< N
  int* status;               ///< N, SolveStatus
  int* iterations;           ///< N
  double* residual;          ///< N
  double* max_strain;        ///< N
  int* rod_steps;            ///< N
  bool* stable;              ///< N (false when not checked)
  double* stability_margin;  ///< N
  double* singularity;       ///< N
};

/// Fills row r of the buffers; invalid results (not usable as a warm start) get NaN values.
template <class Solution>
void store_row(const Solution& s, bool usable, int n, std::ptrdiff_t r, const BatchBuffers& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    out.q[r * n + i] = usable ? s.q(i) : nan;
    out.wrenches[(r * n + i) * 3 + 0] = usable ? s.wrenches[i].nx : nan;
    out.wrenches[(r * n + i) * 3 + 1] = usable ? s.wrenches[i].ny : nan;
    out.wrenches[(r * n + i) * 3 + 2] = usable ? s.wrenches[i].m : nan;
  }
  out.pose[r * 3 + 0] = usable ? s.pose.x : nan;
  out.pose[r * 3 + 1] = usable ? s.pose.y : nan;
  out.pose[r * 3 + 2] = usable ? s.pose.theta : nan;
  out.converged[r] = s.summary.converged();
  out.status[r] = static_cast<int>(s.summary.status);
  out.iterations[r] = s.summary.iterations;
  out.residual[r] = s.summary.final_residual_norm;
  out.max_strain[r] = usable ? s.summary.max_strain : nan;
  out.rod_steps[r] = s.summary.rod_steps;
  out.stable[r] = s.summary.stability == Stability::kStable;
  out.stability_margin[r] = s.summary.stability_margin;
  out.singularity[r] = s.summary.singularity;
}

/// Robot.forward's and Robot.inverse's `path` keyword as a sequence mode.
inline SequenceMode sequence_mode(bool path) {
  return path ? SequenceMode::kPath : SequenceMode::kIndependent;
}

/// FK of every row of q (N x n, row-major), as a sequence in `mode`. `solutions` (optional, size
/// N) receives the full solutions (for the shapes).
inline void forward_batch(const RobotParams<double>& robot, const double* q, std::ptrdiff_t rows,
                          const SolverOptions& options, const PlatformLoad<double>& load,
                          SequenceMode mode, const BatchBuffers& out,
                          ForwardSolution* solutions = nullptr) {
  const int n = robot.num_limbs;
  ForwardSequence sequence(robot, options, load, mode);
  JointVector joints(n);
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    for (int i = 0; i < n; ++i) joints(i) = q[r * n + i];
    const ForwardSolution& s = sequence.solve(joints);
    // FK's joints are the input, echoed even when the solve failed.
    store_row(s, usable_as_warm_start(s.summary), n, r, out);
    for (int i = 0; i < n; ++i) out.q[r * n + i] = joints(i);
    if (solutions != nullptr) solutions[r] = s;
  }
}

/// IK of every row of poses (N x 3, row-major), as a sequence in `mode`.
inline void inverse_batch(const RobotParams<double>& robot, const double* poses,
                          std::ptrdiff_t rows, const SolverOptions& options,
                          const PlatformLoad<double>& load, SequenceMode mode,
                          const BatchBuffers& out, InverseSolution* solutions = nullptr) {
  const int n = robot.num_limbs;
  InverseSequence sequence(robot, options, load, mode);
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    const Pose2<double> pose{poses[r * 3], poses[r * 3 + 1], poses[r * 3 + 2]};
    const InverseSolution& s = sequence.solve(pose);
    store_row(s, is_equilibrium(s.summary), n, r, out);
    // The requested pose is echoed; with 2 limbs theta is the solved one (NaN on failure).
    out.pose[r * 3 + 0] = pose.x;
    out.pose[r * 3 + 1] = pose.y;
    if (n != 2) out.pose[r * 3 + 2] = pose.theta;
    if (solutions != nullptr) solutions[r] = s;
  }
}

}  // namespace pcr::python
