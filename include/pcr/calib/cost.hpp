#pragma once
// Ceres cost functor of the identification (Mauze et al. 2021, Eq. 6), in the shape of Ceres'
// pose_graph_2d error term: one measured configuration, one parameter block holding the whole flat
// parameter vector (pcr/parameters.hpp), three residuals.
//
// Residual, whitened by the position noise sigma_p so that it is O(1) at the noise floor:
//   F_j / sigma_p = [w (theta_hat - theta) (wrapped), x_hat - x, y_hat - y] / sigma_p
// where (x_hat, y_hat, theta_hat) = (^W T_Se)^-1 . FK(q_j) . (^M T_P)^-1 is the predicted
// measurement and w the orientation weight (m/rad). Scaling by a constant changes neither the
// minimiser nor the ratios, but keeps Ceres' absolute tolerances meaningful.
//
// Derivatives are exact: FK is converged in double (the last converged solution of this
// configuration, kept in a cache the functor points to, continued to the new parameters: the
// equilibrium the robot holds, followed as its geometry is identified), then the implicit function
// theorem gives d pose / d p = -(dr/dz)^-1 dr/dp. A configuration whose equilibrium cannot be
// continued makes the evaluation return false, so Ceres rejects the step.
//
// Two exact implementations of that derivative:
// - DerivativeMode::kImplicit (default), PoseMeasurementCost: assembled per limb. Rod i's residual
//   rows depend only on limb i's parameters, and of those the rod integration itself only on
//   (alpha_i, EI_i, l_i, u0_i): the rod's symmetries give them from the tip's sensitivities to its
//   wrench, which the Jacobian dr/dz already integrated (limb_residual_partials); A, gamma, E, d,
//   B, beta enter by hand-written chain rules. The pose rows of (dr/dz)^-1 come from one
//   transposed solve with the LU of that Jacobian, and the extrinsics (which enter only the final
//   measurement transform) through a Jet<double, 9>. No RK4 pass beyond the Jacobian's: far
//   cheaper than the auto-diff pass below, which pushes all 39 lanes through every RK4 step of
//   every rod.
// - DerivativeMode::kAutoDiff: one Newton step in Jet (forward_pose_implicit) through the whole
//   residual: AutoDiffCostFunction<3, 39> for n = 3, DynamicAutoDiffCostFunction with
//   Jet<double, 16> chunks otherwise. Kept as the independent cross-check of the assembly.

#include <ceres/autodiff_cost_function.h>
#include <ceres/dynamic_autodiff_cost_function.h>
#include <ceres/dynamic_numeric_diff_cost_function.h>
#include <ceres/numeric_diff_cost_function.h>

#include <algorithm>
#include <array>
#include <memory>
#include <type_traits>

#include "pcr/calib/jet_traits.hpp"  // before the core templates meet a Jet
#include "pcr/implicit_kinematics.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/parameters.hpp"

namespace pcr {

/// The paper's weight: residuals in orientation and position proportional to the repeatabilities.
inline constexpr double kDefaultOrientationWeight = 9.13e-9 / 1.2e-6;  ///< m/rad
/// Position scale that whitens the residuals (the paper's position repeatability).
inline constexpr double kDefaultResidualScale = 9.13e-9;  ///< m

enum class DerivativeMode {
  kImplicit,        ///< implicit function theorem, assembled per limb (exact, fast)
  kNumericCentral,  ///< central finite differences (what the paper's lsqnonlin did)
  kAutoDiff,        ///< implicit function theorem, one Jet through the whole residual (exact)
};

/// The constant platform load (f_x, f_y, m_z; N, N, N m, in W, the moment about the platform
/// origin) as identified parameters: appended to the flat parameters in the cost's block.
inline constexpr int kLoadParameters = 3;

/// Warm-start cache of one configuration: the last converged double FK solution, and the
/// equilibrium at the last accepted parameters that every solve starts from.
struct FkCache {
  ForwardSolution solution;
  bool valid = false;
  /// The flat parameters `solution` was solved at: Ceres evaluates the Jacobian at the point whose
  /// residual it has just evaluated, and that solve is then reused as is.
  std::array<double, kMaxParameters + kLoadParameters> parameters{};
  /// The equilibrium at the parameters last accepted (accept(): a step Ceres kept, the end of a
  /// solve, a move along the gauge). Solves start from it, never from a trial point Ceres
  /// rejected: a trial step across a fold may have reached another equilibrium, from which the
  /// way back to the accepted parameters does not exist.
  ForwardSolution anchor;
  std::array<double, kMaxParameters + kLoadParameters> anchor_parameters{};
  bool anchored = false;
  /// Makes `solution` the start of the following solves.
  void accept() {
    if (!valid) return;
    anchor = solution;
    anchor_parameters = parameters;
    anchored = true;
  }
  int failures = 0;  ///< evaluations where FK did not converge
  // Profiling counters (written by every evaluation).
  int evaluations = 0;           ///< double FK solves requested (residual or Jacobian)
  int jacobian_evaluations = 0;  ///< of which with a Jacobian (analytic mode only)
  int warm_start_failures = 0;  ///< warm solves that did not converge (continued in the parameters)
  int newton_iterations = 0;    ///< FK Newton iterations, all solves
};

namespace internal {

/// Scaled partial derivatives of limb i's shooting residual rows with respect to its ten flat
/// parameters (E, d, l, A_x, A_y, alpha, B_x, B_y, beta, gamma), at a fixed point (wrench, pose):
/// rows 0..2 = closure rows 3i..3i+2, row 3 = limb i's term of the moment balance (row 3n + 2).
/// The force balance rows do not depend on the parameters. `tip`: the rod's tip at that point
/// with its sensitivities to (n_x, n_y, m(0)).
///
/// The rod's own parameters (start angle, EI, l, u0) need no integration: three symmetries of the
/// planar rod, which RK4 at a fixed step count keeps exactly, turn them into the sensitivities:
///   turning the start angle and the force by delta turns the rod about its start by delta;
///   (EI, n, m) -> c (EI, n, m) leaves the shape and scales m;
///   l -> c l with (n, m, u0, u1) -> (n / c^2, m / c, u0 / c, u1 / c^2) scales the shape about its
///   start by c and m by 1/c (u0, u1: the intrinsic curvature u* = u0 + u1 s, Rod).
/// and on a uniform rod u0 enters theta' = m / EI + u0 as a moment EI u0 would: d/du0 =
/// EI d/dm(0), less EI on m(l). A pre-curved rod's length column takes d/du0 and d/du1 too; u1 has
/// no such twin and is differentiated by a Jet through the rod's rod_steps RK4 steps (rods with
/// u1 != 0 only: the slope is described, not identified). A tapered rod (d' != 0) breaks two
/// twins: EI(s) is no longer a constant times a profile fixed by d, and u0 no longer acts as a
/// moment. Its Jet then also takes u0 and d': d (d, d') -> c (d, d') scales EI(s) by c^4, so
/// d d/dd = 4 EI d/dEI - d' d/dd'; l -> c l takes d' -> d' / c (the taper scales with the rod).
inline void limb_residual_partials(const LimbParams<double>& limb, double q,
                                   const Wrench<double>& w, const RodTip<double>& tip,
                                   const Pose2<double>& pose, const ShootingScale& scale,
                                   int rod_steps, Eigen::Matrix<double, 4, kLimbParameters>& out) {
  const double ca = std::cos(limb.alpha + limb.gamma), sa = std::sin(limb.alpha + limb.gamma);
  const double ei = limb.rod.bending_stiffness();
  const double dx = tip.state.x - (limb.A.x() + q * ca), dy = tip.state.y - (limb.A.y() + q * sa);
  const Eigen::Matrix<double, 4, 3>& S = tip.sensitivity;  // d (x, y, theta, m)(l) / d (n, m(0))
  const Eigen::Vector4d d_start_angle =
      Eigen::Vector4d(-dy, dx, 1.0, 0.0) + S * Eigen::Vector3d(w.ny, -w.nx, 0.0);
  const Eigen::Vector4d d_ei =
      (Eigen::Vector4d(0.0, 0.0, 0.0, tip.state.m) - S * Eigen::Vector3d(w.nx, w.ny, w.m)) / ei;
  Eigen::Vector4d d_length =
      Eigen::Vector4d(dx, dy, 0.0, -tip.state.m) + S * Eigen::Vector3d(2.0 * w.nx, 2.0 * w.ny, w.m);
  Eigen::Vector4d d_u0 = ei * (S.col(2) - Eigen::Vector4d(0.0, 0.0, 0.0, 1.0));
  Eigen::Vector4d d_diameter = d_ei * 4.0 * ei / limb.rod.diameter;
  const bool tapered = !limb.rod.uniform();
  if (limb.rod.precurvature_slope != 0.0 || tapered) {
    using Dual = ceres::Jet<double, 3>;  // d / d(u0, u1, d')
    const LimbParams<Dual> dual = limb.template cast<Dual>();
    Rod<Dual> rod = dual.rod;
    rod.precurvature.v[0] = 1.0;
    rod.precurvature_slope.v[1] = 1.0;
    rod.diameter_slope.v[2] = 1.0;
    const RodState<Dual> end =
        integrate_rod(proximal_rod_state(dual, Dual(q), w.template cast<Dual>()), rod, rod_steps);
    const auto column = [&](int j) {
      return Eigen::Vector4d(end.x.v[j], end.y.v[j], end.theta.v[j], end.m.v[j]);
    };
    if (tapered) d_u0 = column(0);
    d_length += limb.rod.precurvature * d_u0;
    d_length += 2.0 * limb.rod.precurvature_slope * column(1);
    if (tapered) {
      const Eigen::Vector4d d_slope = column(2);
      d_length += limb.rod.diameter_slope * d_slope;
      d_diameter -= limb.rod.diameter_slope * d_slope / limb.rod.diameter;
    }
  } else {
    d_length += limb.rod.precurvature * d_u0;
  }
  d_length /= limb.rod.length;
  Eigen::Matrix<double, 4, kLimbParameters> d = Eigen::Matrix<double, 4, kLimbParameters>::Zero();
  const int kE = static_cast<int>(ParameterKind::kYoungModulus);
  const int kD = static_cast<int>(ParameterKind::kDiameter);
  const int kL = static_cast<int>(ParameterKind::kLength);
  const int kAx = static_cast<int>(ParameterKind::kAx), kAy = static_cast<int>(ParameterKind::kAy);
  const int kAlpha = static_cast<int>(ParameterKind::kAlpha);
  const int kBx = static_cast<int>(ParameterKind::kBx), kBy = static_cast<int>(ParameterKind::kBy);
  const int kBeta = static_cast<int>(ParameterKind::kBeta);
  const int kGamma = static_cast<int>(ParameterKind::kGamma);
  d.col(kE) = d_ei * ei / limb.rod.young_modulus;  // EI = E pi d^4 / 64
  d.col(kD) = d_diameter;
  d.col(kL) = d_length;
  d.col(static_cast<int>(ParameterKind::kPrecurvature)) = d_u0;
  d.col(kAlpha) = d_start_angle;
  // The start point A + q (cos, sin)(alpha + gamma) shifts the whole rod.
  d(0, kAx) = 1.0;
  d(1, kAy) = 1.0;
  d(0, kAlpha) += -q * sa;
  d(1, kAlpha) += q * ca;
  d(0, kGamma) = -q * sa;
  d(1, kGamma) = q * ca;

  // Residual rows: closure (tip - (pose + R B)) / L, tip.theta - theta - beta, and the moment
  // term (arm x n + m(l)) / M with arm = R(theta) B.
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const double inv_l = 1.0 / scale.length, inv_m = 1.0 / scale.moment();
  out.row(0) = d.row(0) * inv_l;
  out.row(1) = d.row(1) * inv_l;
  out.row(2) = d.row(2);
  out.row(3) = d.row(3) * inv_m;
  const double arm_dx[2] = {c, -s}, arm_dy[2] = {s, c};  // d arm / d (B_x, B_y)
  const int cols[2] = {kBx, kBy};
  for (int k = 0; k < 2; ++k) {
    out(0, cols[k]) -= arm_dx[k] * inv_l;
    out(1, cols[k]) -= arm_dy[k] * inv_l;
    out(3, cols[k]) += (arm_dx[k] * w.ny - arm_dy[k] * w.nx) * inv_m;
  }
  out(2, kBeta) -= 1.0;
}

}  // namespace internal

/// d ^W T_P / d (flat parameters), physical units (m or rad per parameter unit), at the
/// converged double solution `solution` of `robot`, by the implicit function theorem assembled
/// per limb (see the header comment). `jacobian` is 3 x num_parameters, row-major; the extrinsic
/// columns are zero. With `load_jacobian`, also d ^W T_P / d (f_x, f_y, m_z) of the constant
/// platform load, 3 x 3 row-major. Returns false when the solution did not converge or is
/// singular.
inline bool platform_pose_jacobian(const RobotParams<double>& robot,
                                   const PlatformLoad<double>& load,
                                   const ForwardSolution& solution, const SolverOptions& options,
                                   double* jacobian, double* load_jacobian = nullptr) {
  const internal::LinearisedForward linear(robot, load, solution, options);
  if (!linear.ok) return false;
  const int n = robot.num_limbs;
  const int count = num_parameters(n);
  const internal::ShootingProblem& problem = linear.problem;
  const auto& lu = linear.lu;
  // Pose rows of J^-1, as the columns of Y with J^T Y = [e_3n, e_3n+1, e_3n+2].
  const int m = 3 * n + 3;
  Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxResiduals, 3> e =
      Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxResiduals, 3>::Zero(m, 3);
  for (int k = 0; k < 3; ++k) e(3 * n + k, k) = 1.0;
  const Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxResiduals, 3> y = lu.transpose().solve(e);
  if (!y.allFinite()) return false;

  const ShootingScale& scale = problem.scale();
  const double unscale[3] = {scale.length, scale.length, 1.0};  // z_pose = (x / L, y / L, theta)
  for (int k = 0; k < count; ++k) {
    for (int row = 0; row < 3; ++row) jacobian[row * count + k] = 0.0;
  }
  if (load_jacobian) {
    // The load enters the equilibrium rows only: d r_3n+j / d load_j = -1 / (F, F, F L).
    const double per_load[3] = {1.0 / scale.force, 1.0 / scale.force, 1.0 / scale.moment()};
    for (int k = 0; k < 3; ++k) {
      for (int j = 0; j < 3; ++j)
        load_jacobian[k * 3 + j] = y(3 * n + j, k) * per_load[j] * unscale[k];
    }
  }
  Eigen::Matrix<double, 4, kLimbParameters> dr;
  for (int i = 0; i < n; ++i) {
    internal::limb_residual_partials(robot.limb(i), solution.q(i), solution.wrenches[i],
                                     linear.tips[i], solution.pose, scale,
                                     solution.summary.rod_steps, dr);
    const int rows[4] = {3 * i, 3 * i + 1, 3 * i + 2, 3 * n + 2};
    for (int k = 0; k < 3; ++k) {
      for (int j = 0; j < kLimbParameters; ++j) {
        double dz = 0;
        for (int a = 0; a < 4; ++a) dz -= y(rows[a], k) * dr(a, j);
        jacobian[k * count + kLimbParameters * i + j] = dz * unscale[k];
      }
    }
  }
  return true;
}

class PoseMeasurementError {
 public:
  /// `base` supplies what the flat vector does not hold (limb count, strokes). `cache` must
  /// outlive the functor; it is written by every evaluation (single-threaded Ceres). With
  /// `identify_load`, the parameter block holds num_parameters(n) + kLoadParameters values: the
  /// flat parameters, then the constant platform load FK is solved under.
  PoseMeasurementError(const RobotParams<double>& base, const JointVector& q,
                       const Pose2<double>& measured, double orientation_weight,
                       double residual_scale, FkCache* cache,
                       const SolverOptions& options = SolverOptions(), bool identify_load = false)
      : base_(base),
        q_(q),
        measured_(measured),
        weight_(orientation_weight),
        inverse_scale_(1.0 / residual_scale),
        cache_(cache),
        options_(options),
        identify_load_(identify_load) {}

  /// Values in the parameter block.
  int block_size() const {
    return num_parameters(base_.num_limbs) + (identify_load_ ? kLoadParameters : 0);
  }

  template <class T>
  bool operator()(const T* const params, T* residuals) const {
    const int size = block_size();
    double values[kMaxParameters + kLoadParameters];
    for (int k = 0; k < size; ++k) values[k] = scalar_value(params[k]);
    const RobotParams<double> robot = with_parameters(base_, values);
    const ForwardSolution* solution = solve(robot, values);
    if (solution == nullptr) return false;

    Pose2<T> platform;
    RobotParams<T> robot_t;
    if constexpr (std::is_same_v<T, double>) {
      platform = solution->pose;
      robot_t = robot;
    } else {
      robot_t = with_parameters(base_.template cast<T>(), params);
      if (!forward_pose_implicit(robot_t, load_of(params), robot, load_of(values), *solution,
                                 options_, &platform)) {
        return false;
      }
    }
    residual(robot_t.extrinsics.measurement_from_platform(platform), residuals);
    return true;
  }

  /// Residuals and, when `jacobian` is not null, their exact Jacobian (3 x num_parameters,
  /// row-major) by the per-limb assembly (platform_pose_jacobian) chained through the extrinsics.
  bool evaluate(const double* params, double* residuals, double* jacobian) const {
    const int count = num_parameters(base_.num_limbs);
    const int size = block_size();
    const RobotParams<double> robot = with_parameters(base_, params);
    const ForwardSolution* solution = solve(robot, params);
    if (solution == nullptr) return false;
    if (jacobian == nullptr) {
      residual(robot.extrinsics.measurement_from_platform(solution->pose), residuals);
      return true;
    }
    ++cache_->jacobian_evaluations;
    double dpose[3 * kMaxParameters], dpose_load[3 * kLoadParameters];
    if (!platform_pose_jacobian(robot, load_of(params), *solution, options_, dpose,
                                identify_load_ ? dpose_load : nullptr)) {
      return false;
    }
    // The measurement transform, differentiated w.r.t. (platform pose, camera, pattern).
    using J9 = ceres::Jet<double, 9>;
    const Pose2<double>& p = solution->pose;
    const Pose2<J9> platform{J9(p.x, 0), J9(p.y, 1), J9(p.theta, 2)};
    const Pose2<double>& cam = robot.extrinsics.camera;
    const Pose2<double>& pat = robot.extrinsics.pattern;
    const Extrinsics<J9> extrinsics{Pose2<J9>{J9(cam.x, 3), J9(cam.y, 4), J9(cam.theta, 5)},
                                    Pose2<J9>{J9(pat.x, 6), J9(pat.y, 7), J9(pat.theta, 8)}};
    J9 res[3];
    residual(extrinsics.measurement_from_platform(platform), res);
    const int extrinsic_column = kLimbParameters * base_.num_limbs;
    for (int r = 0; r < 3; ++r) {
      residuals[r] = res[r].a;
      double* row = jacobian + r * size;
      for (int k = 0; k < count; ++k) {
        row[k] = res[r].v[0] * dpose[k] + res[r].v[1] * dpose[count + k] +
                 res[r].v[2] * dpose[2 * count + k];
      }
      for (int e = 0; e < kExtrinsicParameters; ++e) row[extrinsic_column + e] += res[r].v[3 + e];
      for (int j = 0; j < size - count; ++j) {
        row[count + j] = res[r].v[0] * dpose_load[j] + res[r].v[1] * dpose_load[3 + j] +
                         res[r].v[2] * dpose_load[6 + j];
      }
    }
    return true;
  }

  /// Signature used by the dynamic adapters.
  template <class T>
  bool operator()(T const* const* params, T* residuals) const {
    return (*this)(params[0], residuals);
  }

  /// A cost function with one parameter block of block_size() values and three residuals. The
  /// caller owns the result (or hands it to a ceres::Problem).
  static ceres::CostFunction* Create(const RobotParams<double>& base, const JointVector& q,
                                     const Pose2<double>& measured, double orientation_weight,
                                     double residual_scale, FkCache* cache,
                                     const SolverOptions& options = SolverOptions(),
                                     DerivativeMode mode = DerivativeMode::kImplicit,
                                     bool identify_load = false);

 private:
  /// The load FK is solved under: the block's last values, or none.
  template <class T>
  PlatformLoad<T> load_of(const T* params) const {
    if (!identify_load_) return PlatformLoad<T>();
    const int count = num_parameters(base_.num_limbs);
    return PlatformLoad<T>{Vector2<T>(params[count], params[count + 1]), params[count + 2]};
  }

  template <class T>
  void residual(const Pose2<T>& predicted, T* residuals) const {
    residuals[0] = T(weight_ * inverse_scale_) * wrap_angle(predicted.theta - T(measured_.theta));
    residuals[1] = (predicted.x - T(measured_.x)) * T(inverse_scale_);
    residuals[2] = (predicted.y - T(measured_.y)) * T(inverse_scale_);
  }

  /// Converged double FK at `robot`: the anchored equilibrium continued to these parameters (see
  /// continue_in_parameters); a cold start from home only for the first solve, which anchors.
  /// Null when the equilibrium cannot be continued: the evaluation fails, and Ceres rejects the
  /// step.
  const ForwardSolution* solve(const RobotParams<double>& robot, const double* params) const {
    const int count = block_size();
    if (cache_->valid && std::equal(params, params + count, cache_->parameters.begin())) {
      return &cache_->solution;
    }
    ++cache_->evaluations;
    const PlatformLoad<double> load = load_of(params);
    if (cache_->valid && cache_->anchored) {  // an emptied cache (valid false) solves cold
      ForwardSolution s = forward_kinematics(robot, q_, cache_->anchor, options_, load);
      cache_->newton_iterations += s.summary.iterations;
      if (!is_equilibrium(s.summary)) {
        ++cache_->warm_start_failures;
        if (!continue_in_parameters(params, s)) {
          ++cache_->failures;
          return nullptr;
        }
      }
      cache_->solution = s;
      std::copy(params, params + count, cache_->parameters.begin());
      return &cache_->solution;
    }
    ForwardSolution s = forward_kinematics(robot, q_, options_, load);
    cache_->newton_iterations += s.summary.iterations;
    if (!is_equilibrium(s.summary)) {
      ++cache_->failures;
      return nullptr;
    }
    cache_->solution = s;
    cache_->valid = true;
    std::copy(params, params + count, cache_->parameters.begin());
    cache_->accept();
    return &cache_->solution;
  }

  /// The anchored equilibrium carried to `params` along the straight line from the anchored
  /// parameters, in steps halved where a warm solve fails: the same equilibrium as the robot's
  /// geometry moves, never another one a cold start from home would give where the robot has
  /// several (a configuration past a fold of the design, reached on the robot measured). False
  /// when the steps fall below 1/8 of the line: the step is rejected, and Ceres tries a shorter
  /// one, which costs less than continuing a long step finely (a long trial step of a model
  /// that cannot fit its data is rejected anyway).
  bool continue_in_parameters(const double* params, ForwardSolution& out) const {
    const int count = block_size();
    double values[kMaxParameters + kLoadParameters];
    const double* from = cache_->anchor_parameters.data();
    ForwardSolution at = cache_->anchor;
    SolverOptions step_options = options_;
    step_options.max_iterations = options_.max_continuation_iterations;
    double t = 0.0, dt = 0.5;
    while (t < 1.0 && dt >= 1.0 / 8) {
      const double t_next = std::min(1.0, t + dt);
      for (int k = 0; k < count; ++k) values[k] = from[k] + t_next * (params[k] - from[k]);
      const ForwardSolution s =
          forward_kinematics(with_parameters(base_, values), q_, at, step_options, load_of(values));
      cache_->newton_iterations += s.summary.iterations;
      if (is_equilibrium(s.summary)) {
        at = s;
        t = t_next;
        dt = std::min(2.0 * dt, 0.5);
      } else {
        dt *= 0.5;
      }
    }
    if (t < 1.0) return false;
    out = at;
    return true;
  }

  RobotParams<double> base_;
  JointVector q_;
  Pose2<double> measured_;
  double weight_;
  double inverse_scale_;
  FkCache* cache_;
  SolverOptions options_;
  bool identify_load_;
};

/// The analytic cost function of DerivativeMode::kImplicit (any limb count): one parameter block
/// of the functor's block_size() values, three residuals. Takes ownership of the functor.
class PoseMeasurementCost final : public ceres::CostFunction {
 public:
  explicit PoseMeasurementCost(PoseMeasurementError* functor) : functor_(functor) {
    set_num_residuals(3);
    mutable_parameter_block_sizes()->push_back(functor->block_size());
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    return functor_->evaluate(parameters[0], residuals, jacobians ? jacobians[0] : nullptr);
  }

 private:
  std::unique_ptr<PoseMeasurementError> functor_;
};

inline ceres::CostFunction* PoseMeasurementError::Create(
    const RobotParams<double>& base, const JointVector& q, const Pose2<double>& measured,
    double orientation_weight, double residual_scale, FkCache* cache, const SolverOptions& options,
    DerivativeMode mode, bool identify_load) {
  auto* functor = new PoseMeasurementError(base, q, measured, orientation_weight, residual_scale,
                                           cache, options, identify_load);
  const int count = functor->block_size();
  constexpr int kThreeLimbs = kLimbParameters * 3 + kExtrinsicParameters;
  if (mode == DerivativeMode::kImplicit) return new PoseMeasurementCost(functor);
  if (mode == DerivativeMode::kAutoDiff) {
    if (count == kThreeLimbs) {
      return new ceres::AutoDiffCostFunction<PoseMeasurementError, 3, kThreeLimbs>(functor);
    }
    auto* cost = new ceres::DynamicAutoDiffCostFunction<PoseMeasurementError, 16>(functor);
    cost->AddParameterBlock(count);
    cost->SetNumResiduals(3);
    return cost;
  }
  if (count == kThreeLimbs) {
    return new ceres::NumericDiffCostFunction<PoseMeasurementError, ceres::CENTRAL, 3, kThreeLimbs>(
        functor);
  }
  auto* cost =
      new ceres::DynamicNumericDiffCostFunction<PoseMeasurementError, ceres::CENTRAL>(functor);
  cost->AddParameterBlock(count);
  cost->SetNumResiduals(3);
  return cost;
}

}  // namespace pcr
