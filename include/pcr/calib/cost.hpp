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
// Derivatives are exact: FK is converged in double (warm-started from the last converged solution
// of this configuration, kept in a cache the functor points to), then one Newton step is taken in
// T (forward_pose_implicit). A configuration whose FK fails makes operator() return false, so
// Ceres rejects the step.
//
// Why a fixed-size AutoDiffCostFunction for n = 3 and a dynamic one otherwise: with 36 parameters
// one Jet<double, 36> pass evaluates the whole Jacobian at once, on the stack; other limb counts
// use DynamicAutoDiffCostFunction with Jet<double, 16> chunks, each chunk repeating the (cheap,
// already converged) warm-started double solve. Only n = 3 pays the compile time of a fixed Jet.

#include <memory>
#include <type_traits>

#include <ceres/autodiff_cost_function.h>
#include <ceres/dynamic_autodiff_cost_function.h>
#include <ceres/dynamic_numeric_diff_cost_function.h>
#include <ceres/numeric_diff_cost_function.h>

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
  kImplicit,        ///< auto-diff + implicit function theorem (exact)
  kNumericCentral,  ///< central finite differences (what the paper's lsqnonlin did)
};

/// Warm-start cache of one configuration: the last converged double FK solution.
struct FkCache {
  ForwardSolution solution;
  bool valid = false;
  int failures = 0;  ///< evaluations where FK did not converge
};

class PoseMeasurementError {
 public:
  /// `base` supplies what the flat vector does not hold (limb count, strokes). `cache` must
  /// outlive the functor; it is written by every evaluation (single-threaded Ceres).
  PoseMeasurementError(const RobotParams<double>& base, const JointVector& q,
                       const Pose2<double>& measured, double orientation_weight,
                       double residual_scale, FkCache* cache,
                       const SolverOptions& options = SolverOptions())
      : base_(base), q_(q), measured_(measured), weight_(orientation_weight),
        inverse_scale_(1.0 / residual_scale), cache_(cache), options_(options) {}

  template <class T>
  bool operator()(const T* const params, T* residuals) const {
    const int count = num_parameters(base_.num_limbs);
    double values[kMaxParameters];
    for (int k = 0; k < count; ++k) values[k] = scalar_value(params[k]);
    const RobotParams<double> robot = with_parameters(base_, values);
    const ForwardSolution* solution = solve(robot);
    if (solution == nullptr) return false;

    Pose2<T> platform;
    RobotParams<T> robot_t;
    if constexpr (std::is_same_v<T, double>) {
      platform = solution->pose;
      robot_t = robot;
    } else {
      robot_t = with_parameters(base_.template cast<T>(), params);
      if (!forward_pose_implicit(robot_t, PlatformLoad<T>(), robot, PlatformLoad<double>(),
                                 *solution, options_, &platform)) {
        return false;
      }
    }
    const Pose2<T> predicted = robot_t.extrinsics.measurement_from_platform(platform);
    residuals[0] = T(weight_ * inverse_scale_) * wrap_angle(predicted.theta - T(measured_.theta));
    residuals[1] = (predicted.x - T(measured_.x)) * T(inverse_scale_);
    residuals[2] = (predicted.y - T(measured_.y)) * T(inverse_scale_);
    return true;
  }

  /// Signature used by the dynamic adapters.
  template <class T>
  bool operator()(T const* const* params, T* residuals) const {
    return (*this)(params[0], residuals);
  }

  /// A cost function with one parameter block of num_parameters(base.num_limbs) values and three
  /// residuals. The caller owns the result (or hands it to a ceres::Problem).
  static ceres::CostFunction* Create(const RobotParams<double>& base, const JointVector& q,
                                     const Pose2<double>& measured, double orientation_weight,
                                     double residual_scale, FkCache* cache,
                                     const SolverOptions& options = SolverOptions(),
                                     DerivativeMode mode = DerivativeMode::kImplicit) {
    auto* functor = new PoseMeasurementError(base, q, measured, orientation_weight, residual_scale,
                                             cache, options);
    const int count = num_parameters(base.num_limbs);
    constexpr int kThreeLimbs = kLimbParameters * 3 + kExtrinsicParameters;
    if (mode == DerivativeMode::kImplicit) {
      if (count == kThreeLimbs) {
        return new ceres::AutoDiffCostFunction<PoseMeasurementError, 3, kThreeLimbs>(functor);
      }
      auto* cost = new ceres::DynamicAutoDiffCostFunction<PoseMeasurementError, 16>(functor);
      cost->AddParameterBlock(count);
      cost->SetNumResiduals(3);
      return cost;
    }
    if (count == kThreeLimbs) {
      return new ceres::NumericDiffCostFunction<PoseMeasurementError, ceres::CENTRAL, 3,
                                                kThreeLimbs>(functor);
    }
    auto* cost =
        new ceres::DynamicNumericDiffCostFunction<PoseMeasurementError, ceres::CENTRAL>(functor);
    cost->AddParameterBlock(count);
    cost->SetNumResiduals(3);
    return cost;
  }

 private:
  /// Converged double FK at `robot`: warm start from the cache, then a cold start from home.
  const ForwardSolution* solve(const RobotParams<double>& robot) const {
    if (cache_->valid) {
      ForwardSolution s = forward_kinematics(robot, q_, cache_->solution, options_);
      if (s.summary.converged()) {
        cache_->solution = s;
        return &cache_->solution;
      }
    }
    ForwardSolution s = forward_kinematics(robot, q_, options_);
    if (!s.summary.converged()) {
      ++cache_->failures;
      return nullptr;
    }
    cache_->solution = s;
    cache_->valid = true;
    return &cache_->solution;
  }

  RobotParams<double> base_;
  JointVector q_;
  Pose2<double> measured_;
  double weight_;
  double inverse_scale_;
  FkCache* cache_;
  SolverOptions options_;
};

}  // namespace pcr
