#pragma once
// Sensitivity analysis: the paper's Table 2 for any robot (Section 2.3).
//
// Configurations: a 3^n grid of joint values around the centre of the strokes with a step of
// `step` (default 1 mm), minus its centre: 26 configurations for 3 limbs.
// Derivatives: exact, by the implicit function theorem at the FK solution
// (pose_parameter_jacobian), of the platform pose ^W T_P w.r.t. each limb parameter. Rows, as in
// Table 2 (SI units):
//   E  all Young moduli together (d pose / dE, per Pa),  D  all diameters together,
//   d_i, alpha_i, beta_i, gamma_i, l_i, A_xi, A_yi, B_xi, B_yi  one limb at a time;
// each value is max over configurations (and limbs) of |dx/dp|, |dy/dp|, |dtheta/dp|.
// Ranking: position error = max over configurations and limbs of hypot(dx/dp, dy/dp) * h_p and
// orientation error = max |dtheta/dp| * h_p, h_p the parameter's uncertainty half-width; sorted by
// position error (ties: orientation error). For E and D, h is the global (all-limbs) half-width.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/parameters.hpp"
#include "pcr/robot_description.hpp"

namespace pcr {

struct SensitivityOptions {
  double step = 1e-3;  ///< m, grid step around the centre
  JointVector centre;  ///< m; empty: the middle of each stroke
  PlatformLoad<double> load;
  SolverOptions solver;

  /// Below, the configurations collapse onto the centre (a table of zeros); above, they leave
  /// the strokes of a robot of the paper's size.
  static constexpr OptionRange kStep{"step", 1e-6, 0.01, "m"};
  /// As SolverOptions::is_valid, for the step, the solver and the load (the centre is checked
  /// against the robot's strokes by sensitivity_configurations).
  bool is_valid(std::string* error = nullptr) const {
    return kStep.check(step, error) && solver.is_valid(error) && load.is_valid(error);
  }
};

struct SensitivityRow {
  std::string kind;                   ///< "E", "D", "d", "alpha", "beta", "gamma", "l", "A_x", ...
  double dx = 0, dy = 0, dtheta = 0;  ///< max |d pose / d p| (SI: m/unit, rad/unit)
  double half_width = 0;              ///< the largest uncertainty half-width of this kind (SI)
  double position_error = 0;          ///< m, max hypot(dx, dy) * h over configurations and limbs
  double orientation_error = 0;       ///< rad, max |dtheta| * h
};

struct SensitivityReport {
  double step = 0;
  std::vector<JointVector> configurations;
  std::vector<SensitivityRow>
      rows;                  ///< Table 2 order: E, D, d, alpha, beta, gamma, l, A_x, A_y, B_x, B_y
  std::vector<int> ranking;  ///< indices into rows, most influential first
};

/// The 3^n grid minus its centre (throws InputError on a step outside SensitivityOptions::kStep
/// or a centre outside the strokes).
std::vector<JointVector> sensitivity_configurations(const RobotParams<double>& robot, double step,
                                                    const JointVector& centre = JointVector());

/// Columns of a PoseParameterJacobian: every flat parameter, then the platform load's three.
inline constexpr int kMaxPoseJacobianColumns = kMaxParameters + 3;

/// d(^W T_P)/d(parameters) at a solved configuration: 3 rows (x, y, theta); num_parameters(n) + 3
/// columns: the flat parameters in parameters.hpp order (the extrinsic columns are zero: they do
/// not move the platform), then the constant platform load (f_x, f_y in N, m_z in N m, in W, about
/// the platform origin), as the calibration appends it (pcr/calib/cost.hpp, kLoadParameters).
/// Units: m or rad per parameter unit. Fixed maximum size: no heap.
using PoseParameterJacobian =
    Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor, 3, kMaxPoseJacobianColumns>;

/// The PoseParameterJacobian at `solution`, a converged FK solution of `robot` under `load`, by the
/// implicit function theorem at that solution (the per-limb assembly of the calibration's cost,
/// platform_pose_jacobian): no FK solve, one RK4 pass with sensitivities at the solution's step
/// count and one LU. Returns false when the solution did not converge or its Jacobian is singular.
bool pose_parameter_jacobian(const RobotParams<double>& robot, const ForwardSolution& solution,
                             PoseParameterJacobian* jacobian,
                             const PlatformLoad<double>& load = PlatformLoad<double>(),
                             const SolverOptions& solver = SolverOptions());

/// d(^W T_P)/d(limb parameters) at q: 3 rows (x, y, theta), kLimbParameters * n columns in
/// parameters.hpp order (the extrinsics do not move the platform). Exact (implicit function
/// theorem): FK from home, then pose_parameter_jacobian at its solution. Returns false when FK
/// from home does not converge at q.
bool platform_parameter_jacobian(const RobotParams<double>& robot, const JointVector& q,
                                 Eigen::MatrixXd* jacobian,
                                 const PlatformLoad<double>& load = PlatformLoad<double>(),
                                 const SolverOptions& solver = SolverOptions());

/// Throws std::runtime_error naming the configuration when FK fails.
SensitivityReport sensitivity_analysis(const RobotDescription& robot,
                                       const SensitivityOptions& options = SensitivityOptions());

std::string sensitivity_table_text(const SensitivityReport& report);
std::string sensitivity_csv(const SensitivityReport& report);
std::string sensitivity_json(const SensitivityReport& report);

}  // namespace pcr
