#pragma once
// The subspace manifold of the identification's stages, planar and spatial: steps confined to
// the span of a basis (the free parameters, less the gauge directions).

#include <ceres/manifold.h>

#include <Eigen/Core>
#include <utility>

namespace pcr::calib_internal {

/// x + B delta on the flat vector: B spans the free parameters (in half-width units) minus the
/// gauge directions, so the step neither moves a held parameter nor drifts along a gauge orbit.
class SubspaceManifold final : public ceres::Manifold {
 public:
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  SubspaceManifold(RowMajor basis, RowMajor inverse)
      : basis_(std::move(basis)), inverse_(std::move(inverse)) {}
  int AmbientSize() const override { return static_cast<int>(basis_.rows()); }
  int TangentSize() const override { return static_cast<int>(basis_.cols()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    Eigen::Map<Eigen::VectorXd>(x_plus_delta, basis_.rows()) =
        Eigen::Map<const Eigen::VectorXd>(x, basis_.rows()) +
        basis_ * Eigen::Map<const Eigen::VectorXd>(delta, basis_.cols());
    return true;
  }
  bool PlusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<RowMajor>(jacobian, basis_.rows(), basis_.cols()) = basis_;
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    Eigen::Map<Eigen::VectorXd>(y_minus_x, inverse_.rows()) =
        inverse_ * (Eigen::Map<const Eigen::VectorXd>(y, basis_.rows()) -
                    Eigen::Map<const Eigen::VectorXd>(x, basis_.rows()));
    return true;
  }
  bool MinusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<RowMajor>(jacobian, inverse_.rows(), inverse_.cols()) = inverse_;
    return true;
  }

 private:
  RowMajor basis_;    // ambient x tangent
  RowMajor inverse_;  // tangent x ambient, inverse_ * basis_ = I
};

}  // namespace pcr::calib_internal
