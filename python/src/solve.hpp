#pragma once
// The batch loops behind Robot.forward / Robot.inverse and SpatialRobot's, kept out of the
// wrappers: rows solved as a pcr::SequenceSolver in the mode asked for (each on its own, or a
// path), as `pcr fk` and `pcr ik` do. Plain C++, called with the GIL released.

#include <limits>

#include "pcr/kinematics.hpp"
#include "pcr/spatial/sequence.hpp"
#include "summary.hpp"

namespace pcr::python {

/// Row-major output buffers of a batch of N rows for a robot with n limbs.
struct BatchBuffers {
  double* q;         ///< N x n (m)
  double* pose;      ///< N x 3 (m, m, rad)
  double* wrenches;  ///< N x n x 3 (N, N, N m)
  SummaryBuffers summary;
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
  out.summary.store(s.summary, usable, r);
}

/// Robot.forward's and Robot.inverse's `path` keyword as a sequence mode.
inline SequenceMode sequence_mode(bool path) {
  return path ? SequenceMode::kPath : SequenceMode::kIndependent;
}

/// FK of every row of q (N x n, row-major) by `sequence` (planar or spatial): store(solution, r)
/// fills row r, then the row's joints are echoed in q_out (FK's joints are the input, echoed even
/// when the solve failed). `solutions` (optional, size N) receives the full solutions (for the
/// shapes).
template <class Solution, class Store>
void forward_rows(SequenceSolver<Solution>& sequence, int n, const double* q, std::ptrdiff_t rows,
                  double* q_out, Store&& store, Solution* solutions) {
  typename SequenceSolver<Solution>::Input joints(n);
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    for (int i = 0; i < n; ++i) joints(i) = q[r * n + i];
    const Solution& s = sequence.solve(joints);
    store(s, r);
    for (int i = 0; i < n; ++i) q_out[r * n + i] = joints(i);
    if (solutions != nullptr) solutions[r] = s;
  }
}

/// FK of every row of q (N x n, row-major), as a sequence in `mode`.
inline void forward_batch(const RobotParams<double>& robot, const double* q, std::ptrdiff_t rows,
                          const SolverOptions& options, const PlatformLoad<double>& load,
                          SequenceMode mode, const BatchBuffers& out,
                          ForwardSolution* solutions = nullptr) {
  const int n = robot.num_limbs;
  ForwardSequence sequence(robot, options, load, mode);
  const auto store = [&](const ForwardSolution& s, std::ptrdiff_t r) {
    store_row(s, usable_as_warm_start(s.summary), n, r, out);
  };
  forward_rows(sequence, n, q, rows, out.q, store, solutions);
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

/// Row-major output buffers of a spatial batch of N rows for a robot with n rods.
struct SpatialBatchBuffers {
  double* q;                ///< N x n (m)
  double* position;         ///< N x 3 (m)
  double* quaternion;       ///< N x 4 (w, x, y, z)
  double* rotation;         ///< N x 3 x 3
  double* rotation_vector;  ///< N x 3 (rad)
  double* wrenches;         ///< N x n x 6 (N, N m)
  SummaryBuffers summary;
};

/// A platform orientation as Python gives it: the unit quaternion of h whose w >= 0 (h and -h
/// are one rotation), so that equal rotations read equal.
inline Vector4<double> canonical_quaternion(const Vector4<double>& h) {
  const Vector4<double> unit = h / h.norm();
  return unit(0) < 0 ? Vector4<double>(-unit) : unit;
}

/// Row r's pose: position, quaternion, its matrix and rotation vector (NaN when not usable).
inline void store_spatial_pose(const SpatialPose<double>& pose, bool usable, std::ptrdiff_t r,
                               const SpatialBatchBuffers& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vector4<double> h = canonical_quaternion(pose.orientation);
  const Matrix3<double> R = rotation_of(h);
  const Vector3<double> v = quaternion_log(h);
  for (int k = 0; k < 3; ++k) {
    out.position[r * 3 + k] = usable ? pose.position(k) : nan;
    out.rotation_vector[r * 3 + k] = usable ? v(k) : nan;
    for (int c = 0; c < 3; ++c) out.rotation[r * 9 + 3 * k + c] = usable ? R(k, c) : nan;
  }
  for (int k = 0; k < 4; ++k) out.quaternion[r * 4 + k] = usable ? h(k) : nan;
}

/// Fills row r of the buffers; values NaN when the solution is not usable.
template <class Solution>
void store_spatial_row(const Solution& s, bool usable, int n, std::ptrdiff_t r,
                       const SpatialBatchBuffers& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    out.q[r * n + i] = usable ? s.q(i) : nan;
    for (int k = 0; k < 3; ++k) {
      out.wrenches[(r * n + i) * 6 + k] = usable ? s.wrenches[i].force(k) : nan;
      out.wrenches[(r * n + i) * 6 + 3 + k] = usable ? s.wrenches[i].moment(k) : nan;
    }
  }
  store_spatial_pose(s.pose, usable, r, out);
  out.summary.store(s.summary, usable, r);
}

/// Spatial FK of every row of q (N x n, row-major), as a sequence in `mode`.
inline void spatial_forward_batch(const SpatialRobotParams<double>& robot, const double* q,
                                  std::ptrdiff_t rows, const SolverOptions& options,
                                  SequenceMode mode, const SpatialBatchBuffers& out,
                                  SpatialForwardSolution* solutions = nullptr) {
  const int n = robot.num_rods;
  SpatialForwardSequence sequence(robot, options, mode);
  const auto store = [&](const SpatialForwardSolution& s, std::ptrdiff_t r) {
    store_spatial_row(s, is_equilibrium(s.summary), n, r, out);
  };
  forward_rows(sequence, n, q, rows, out.q, store, solutions);
}

/// Spatial IK of every pose, as a sequence in `mode`: the requested positions echoed, and where
/// the rod count imposes the whole pose (spatial_inverse_free_angles), the requested orientations
/// too (fewer rods leave some of it to the solve: the solved one, NaN on failure).
inline void spatial_inverse_batch(const SpatialRobotParams<double>& robot,
                                  const SpatialPose<double>* poses, std::ptrdiff_t rows,
                                  const SolverOptions& options, SequenceMode mode,
                                  const SpatialBatchBuffers& out,
                                  SpatialInverseSolution* solutions = nullptr) {
  const int n = robot.num_rods;
  SpatialInverseSequence sequence(robot, options, mode);
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    const SpatialInverseSolution& s = sequence.solve(poses[r]);
    store_spatial_row(s, is_equilibrium(s.summary), n, r, out);
    if (spatial_inverse_free_angles(n) == 0) {
      store_spatial_pose(poses[r], true, r, out);
    } else {
      for (int k = 0; k < 3; ++k) out.position[r * 3 + k] = poses[r].position(k);
    }
    if (solutions != nullptr) solutions[r] = s;
  }
}

}  // namespace pcr::python
