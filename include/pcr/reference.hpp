#pragma once
// Independent references for the tests (compiled target pcr::reference): high-accuracy solutions
// computed with SUNDIALS CVODE, and the elastic stability of an equilibrium by its energy.
//
// The same rod equations as pcr/rod.hpp (Mauze et al. 2021, Eq. 1), with the same sign
// convention (n(s), m(s) are exerted by the material beyond s on the material before it):
//
//   x' = cos(theta), y' = sin(theta), theta' = m / EI + u*(s), n' = 0,
//   m' = n_x sin(theta) - n_y cos(theta)
//
// integrated by CVODE's variable-order, variable-step multistep methods at tight tolerances, and
// the forward kinematics of pcr/kinematics.hpp solved on the residual those integrations give.
// The spatial Cosserat rod of pcr/spatial/cosserat_rod.hpp has its CVODE integration too.
// These serve to measure the discretisation error of the fixed-step RK4 core and as the
// "best available" answer; they allocate and may throw, so they are not for the real-time loop.
// SUNDIALS headers never appear here.

#include <array>
#include <limits>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/robot.hpp"
#include "pcr/rod.hpp"
#include "pcr/shooting.hpp"
#include "pcr/spatial/cosserat_rod.hpp"

namespace pcr {

struct ReferenceOptions {
  enum class Method {
    kAdams,  ///< Adams-Moulton, orders 1..12: the efficient choice for this non-stiff problem
    kBdf,    ///< BDF, orders 1..5
  };
  Method method = Method::kAdams;
  /// CVODE's relative tolerance on every state component.
  double relative_tolerance = 1e-12;
  /// CVODE's absolute tolerance, relative to each component's natural scale: the rod length for
  /// x and y, 1 rad for theta, max(EI / l, |m(0)|, |n| l) for m. Dimensionless.
  double absolute_tolerance = 1e-14;
  /// Internal CVODE steps allowed per rod before giving up (std::runtime_error).
  long max_steps = 200000;

  // ---- forward_kinematics_reference ----
  /// Quasi-Newton iterations on the CVODE residual.
  int max_iterations = 30;
  /// Convergence: max-norm of the scaled residual (the same scaling as pcr::shooting_residual).
  /// CVODE's own error puts a floor of about 1e-11 under it at 1% bending strain (the tip
  /// moment's relative error times m L / EI ~ 5); 1e-10 is 3 pm on a 30 mm rod.
  double tolerance = 1e-10;
  /// RK4 steps per rod of the Jacobian used as Newton matrix (only the speed of convergence
  /// depends on it, never the solution).
  int jacobian_rod_steps = 256;
};

/// Integrates one rod over [0, rod.length] from its proximal state with CVODE.
/// With max_abs_moment, also returns max |m(s)| (d / d(s))^3 (N m) over CVODE's internal steps
/// (max |m| for a uniform rod; RodTip::max_abs_moment).
/// Throws std::invalid_argument on non-finite input or non-positive EI / length, and
/// std::runtime_error when CVODE fails.
RodState<double> integrate_rod_reference(const RodState<double>& start, const Rod<double>& rod,
                                         const ReferenceOptions& options = ReferenceOptions(),
                                         double* max_abs_moment = nullptr);

/// The rod state at each of the given arc lengths (m), which must be non-decreasing and lie in
/// [0, rod.length]; computed by CVODE's dense output, as accurate as the integration itself.
std::vector<RodState<double>> sample_rod_reference(
    const RodState<double>& start, const Rod<double>& rod, const std::vector<double>& arc_lengths,
    const ReferenceOptions& options = ReferenceOptions());

/// Integrates one spatial rod (pcr/spatial/cosserat_rod.hpp: the same equations and sign
/// convention) over [0, rod.length] from its proximal state under gravity (m/s^2) with CVODE.
/// An independent integration of the orientation: CVODE carries the rotation matrix itself
/// (R' = R [u]x, 9 states, never re-orthonormalised: it leaves SO(3) only by CVODE's error), not
/// the core's quaternion, and n(s) = n(0) - f s in closed form; the base quaternion is turned into
/// R, and the tip's R into a quaternion, by Eigen's Quaternion, not by the core's rotation_of and
/// quaternion_of. The tip's orientation is a unit quaternion of either sign: compare rotations.
/// ReferenceOptions::absolute_tolerance scales with L for p, 1 for R and
/// max(EI / L, |m(0)|, |n(0)| L, |f| L^2) for m. Throws std::invalid_argument on non-finite
/// input, a zero quaternion, or a non-positive length, diameter, E or G (or negative density),
/// and std::runtime_error when CVODE fails.
SpatialRodState<double> integrate_spatial_rod_reference(
    const SpatialRodState<double>& base, const SpatialRod<double>& rod,
    const Vector3<double>& gravity, const ReferenceOptions& options = ReferenceOptions());

/// The scaled shooting residual of pcr::shooting_residual (closure of each rod, Eq. 2, then the
/// platform equilibrium, Eq. 4), with every rod integrated by CVODE. Returns the largest bending
/// strain |m| d / (2 EI) over CVODE's internal steps.
double shooting_residual_reference(const RobotParams<double>& robot,
                                   const ShootingPoint<double>& point,
                                   const PlatformLoad<double>& load, const ShootingScale& scale,
                                   ResidualVector<double>& residual,
                                   const ReferenceOptions& options = ReferenceOptions());

/// Forward kinematics on the CVODE residual: quasi-Newton from `start` (normally the RK4
/// forward_kinematics solution at the same q), with the RK4 Jacobian at
/// options.jacobian_rod_steps as Newton matrix. No continuation: `start` must be close.
/// The summary reports convergence (a numerical outcome, not thrown); CVODE failures throw
/// std::runtime_error, wrong sizes std::invalid_argument.
ForwardSolution forward_kinematics_reference(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution& start,
    const ReferenceOptions& options = ReferenceOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

// ---- Elastic stability by the energy ----------------------------------------------------------
// An equilibrium is stable when the total potential energy (the rods' bending energy minus the
// work of the platform load) has a strict local minimum among the configurations that respect the
// clamps. This reference discretises each rod's tangent angle at the midpoints of N equal
// segments (the clamps' angles at both ends), finds the discrete equilibrium next to a start by
// Newton on its first-order conditions, and projects the Hessian of the Lagrangian on the null
// space of the constraints (each rod's tip at its distal clamp). Its smallest eigenvalue,
// in a metric that makes it independent of N, is positive for a stable equilibrium. It shares
// no code with the shooting solver: no rod ODE, no sensitivities. Dense matrices of size
// n N + 3: for tests.

/// A rod clamped at A (in W) with tangent angle alpha (in W), its tip attached to the platform at
/// B (in P) with tangent angle beta (in P). Length l (m), EI (N m^2) at s = 0, varying as
/// EI(s) = EI (1 + taper s)^4 along a tapered rod (taper = d' / d, 1/m), intrinsic curvature
/// u*(s) = precurvature + precurvature_slope s (1/m, 1/m^2): bending energy
/// int EI(s) (theta' - u*)^2 / 2.
struct EnergyRod {
  Vector2<double> A;
  double alpha = 0;
  Vector2<double> B;
  double beta = 0;
  double length = 0;
  double ei = 0;
  double precurvature = 0;
  double precurvature_slope = 0;
  double taper = 0;
};

struct EnergyProblem {
  std::vector<EnergyRod> rods;
  PlatformLoad<double> load;  ///< dead force at the origin of P and moment, in W
  /// The platform's free components (x, y, theta); a held one keeps its start value. A single
  /// rod with a held platform is a rod clamped at both ends.
  std::array<bool, 3> platform_free{true, true, true};
};

/// A configuration of the discrete model: the platform pose and each rod's N midpoint angles.
struct EnergyState {
  Pose2<double> pose;
  std::vector<std::vector<double>> angles;
};

struct EnergyOptions {
  int max_iterations = 30;
  /// On the first-order conditions: closure / l and gradient / (EI / l) (per unit of each unknown).
  double tolerance = 1e-11;
};

struct EnergyStability {
  bool converged = false;  ///< the discrete equilibrium was found next to the start
  int iterations = 0;
  EnergyState state;  ///< the discrete equilibrium (or the last iterate)
  /// Smallest eigenvalue of the reduced Hessian, energy in units of EI / l (means over the rods),
  /// per unit of the metric int dtheta^2 ds / l + |dP|^2 / l^2 + dphi^2. Positive: stable.
  double min_eigenvalue = std::numeric_limits<double>::quiet_NaN();
};

/// The discrete equilibrium next to `start` and its stability (the angles' count sets N). Plain
/// Newton: next to a fold the discrete model's own fold lies O(1 / N^2) away, and Newton may
/// fail there, or end on another branch: compare the state's pose with the start's.
/// Throws std::invalid_argument on a malformed problem.
EnergyStability energy_stability(const EnergyProblem& problem, const EnergyState& start,
                                 const EnergyOptions& options = EnergyOptions());

/// The energy problem of a robot at joints q (rod i from limb i, its clamp moved by q_i).
EnergyProblem energy_problem(const RobotParams<double>& robot, const JointVector& q,
                             const PlatformLoad<double>& load = PlatformLoad<double>());

/// A start for energy_stability from a shooting solution (pose and proximal wrenches at q): each
/// rod's angles at the midpoints of `segments` segments.
EnergyState energy_start(const RobotParams<double>& robot, const JointVector& q,
                         const Pose2<double>& pose,
                         const std::array<Wrench<double>, kMaxLimbs>& wrenches, int segments);

}  // namespace pcr
