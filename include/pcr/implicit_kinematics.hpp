#pragma once
// Derivatives of the forward kinematics with respect to the robot parameters, by the implicit
// function theorem. Newton is converged in double; one Newton step is then taken with the residual
// evaluated in T (e.g. ceres::Jet) at the converged point:
//
//   z_T = z* - J^-1 r_T(z*, params_T)
//
// Since r(z*) = 0 the value is z* and the derivative part is exactly -J^-1 dr/dparams.

#include <Eigen/LU>

#include "pcr/kinematics.hpp"

namespace pcr {

namespace internal {

/// The forward shooting problem of `robot` linearised at its converged solution: the packed point
/// z* and the LU factors of the residual's Jacobian there, at the solution's RK4 step count.
/// `ok` is false when the solution did not converge or the Jacobian is singular.
struct LinearisedForward {
  LinearisedForward(const RobotParams<double>& robot, const PlatformLoad<double>& load,
                    const ForwardSolution& solution, const SolverOptions& options)
      : problem(ShootingProblem::Kind::kForward, robot, load, options) {
    if (!is_equilibrium(solution.summary)) return;
    problem.set_input(solution.q);
    problem.set_rod_steps(solution.summary.rod_steps);
    point.pose = solution.pose;
    for (int i = 0; i < robot.num_limbs; ++i) {
      point.q[i] = solution.q(i);
      point.wrenches[i] = solution.wrenches[i];
    }
    z = problem.pack(point);
    ShootingVector r;
    JacobianMatrix J;
    problem.evaluate(z, r, &J, tips);
    lu.compute(J);
    ok = lu.rcond() > 1e-14;
  }

  ShootingProblem problem;
  ShootingPoint<double> point;
  ShootingVector z;
  Eigen::PartialPivLU<JacobianMatrix> lu;
  RodTip<double> tips[kMaxLimbs];  ///< the rods' tips at z*, with their sensitivities
  bool ok = false;
};

}  // namespace internal

/// Platform pose ^W T_P as a function of `robot_t` (scalar T), at the converged double solution
/// `solution` of `robot` (the same parameters as plain values). Returns false when the solution
/// did not converge or its Jacobian is singular.
template <class T>
bool forward_pose_implicit(const RobotParams<T>& robot_t, const PlatformLoad<T>& load_t,
                           const RobotParams<double>& robot, const PlatformLoad<double>& load,
                           const ForwardSolution& solution, const SolverOptions& options,
                           Pose2<T>* pose) {
  const internal::LinearisedForward linear(robot, load, solution, options);
  if (!linear.ok) return false;
  const int n = robot.num_limbs;
  const internal::ShootingProblem& problem = linear.problem;
  const ShootingPoint<double>& point = linear.point;
  const ShootingVector& z = linear.z;
  const auto& lu = linear.lu;
  const JacobianMatrix inverse = lu.inverse();  // only its pose rows are used
  const auto pose_rows = inverse.middleRows(3 * n, 3);

  ResidualVector<T> r_t;
  shooting_residual(robot_t, point.template cast<T>(), load_t, problem.scale(), problem.rod_steps(),
                    r_t);
  T scaled[3];
  for (int k = 0; k < 3; ++k) {
    scaled[k] = T(z(3 * n + k));
    for (int j = 0; j < r_t.size(); ++j) scaled[k] -= pose_rows(k, j) * r_t(j);
  }
  const double length = problem.scale().length;
  *pose = Pose2<T>{scaled[0] * length, scaled[1] * length, scaled[2]};
  return true;
}

}  // namespace pcr
