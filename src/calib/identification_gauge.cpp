// The gauge within the stages: the subspace manifold, the recentring inside the box.

#include <ceres/manifold.h>

#include <Eigen/QR>
#include <cmath>
#include <utility>
#include <vector>

#include "calibration_internal.hpp"
#include "identification.hpp"
#include "subspace_manifold.hpp"

namespace pcr::calib_internal {

void Identification::recentre_in_gauge(const std::vector<bool>& is_free, double bounds_scale) {
  const std::vector<GaugeGenerator> generators = this->generators();
  const std::vector<bool> present = gauges(generators, is_free);
  std::vector<int> rows, cols;
  for (int k = 0; k < count_; ++k) {
    if (is_free[static_cast<std::size_t>(k)] && bounded(k)) rows.push_back(k);
  }
  for (std::size_t j = 0; j < generators.size(); ++j) {
    if (present[j]) cols.push_back(static_cast<int>(j));
  }
  if (rows.empty() || cols.empty()) return;
  const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
  const Eigen::Index c = static_cast<Eigen::Index>(cols.size());
  Eigen::MatrixXd a(m, c);
  Eigen::VectorXd e0(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const std::size_t k = static_cast<std::size_t>(rows[static_cast<std::size_t>(i)]);
    const double h = bounds_scale * half_widths_[k];
    e0(i) = (values_[k] - nominal_values_[k]) / h;
    for (Eigen::Index j = 0; j < c; ++j)
      a(i, j) =
          generators[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])].direction[k] / h;
  }
  // Newton on f(g) = sum e^p, e = e0 + a g, from the least-squares (p = 2) minimum.
  constexpr int p = 16;
  const auto f = [&](const Eigen::VectorXd& g) { return (e0 + a * g).array().pow(p).sum(); };
  Eigen::VectorXd g = a.colPivHouseholderQr().solve(-e0);
  if (!g.allFinite()) g.setZero();
  double fg = f(g);
  for (int iter = 0; iter < 50; ++iter) {
    const Eigen::ArrayXd e = (e0 + a * g).array();
    const Eigen::VectorXd gradient = a.transpose() * (p * e.pow(p - 1)).matrix();
    const Eigen::MatrixXd hessian =
        a.transpose() * (p * (p - 1) * e.pow(p - 2)).matrix().asDiagonal() * a;
    const Eigen::VectorXd step = -hessian.ldlt().solve(gradient);
    if (!step.allFinite()) break;
    double t = 1.0, ft = f(g + step);
    for (int ls = 0; ls < 30 && !(ft < fg); ++ls) ft = f(g + (t *= 0.5) * step);
    if (!(ft < fg)) break;
    g += t * step;
    const bool done = fg - ft <= 1e-12 * fg;
    fg = ft;
    if (done) break;
  }
  double coefficient[7] = {0, 0, 0, 0, 0, 0, 0};  // in gauge_generators' order
  for (Eigen::Index j = 0; j < c; ++j) {
    coefficient[cols[static_cast<std::size_t>(j)]] = g(j);
  }
  move(GaugeMotion{
      Pose2<double>{coefficient[kProximalX], coefficient[kProximalY],
                    coefficient[kProximalRotation]},
      Pose2<double>{coefficient[kDistalX], coefficient[kDistalY], coefficient[kDistalRotation]},
      1.0 + coefficient[kStiffness]});
}

ceres::Manifold* Identification::make_manifold(const std::vector<bool>& is_free,
                                               bool remove_gauge) const {
  std::vector<int> free;
  for (int k = 0; k < block_; ++k) {
    if (is_free[static_cast<std::size_t>(k)]) free.push_back(k);
  }
  const Eigen::Index f = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd g(f, 0);
  if (remove_gauge) {
    const std::vector<GaugeGenerator> generators = this->generators();
    const std::vector<bool> present = gauges(generators, is_free);
    for (std::size_t j = 0; j < generators.size(); ++j) {
      if (!present[j]) continue;
      g.conservativeResize(f, g.cols() + 1);
      for (Eigen::Index c = 0; c < f; ++c) {
        const std::size_t k = static_cast<std::size_t>(free[static_cast<std::size_t>(c)]);
        g(c, g.cols() - 1) = generators[j].direction[k] / half_widths_[k];
      }
    }
  }
  // Orthonormal complement of the (scaled) gauge generators among the free parameters.
  Eigen::MatrixXd q = Eigen::MatrixXd::Identity(f, f);
  if (g.cols() > 0) q = Eigen::HouseholderQR<Eigen::MatrixXd>(g).householderQ();
  const Eigen::Index t = f - g.cols();
  SubspaceManifold::RowMajor basis = SubspaceManifold::RowMajor::Zero(block_, t);
  SubspaceManifold::RowMajor inverse = SubspaceManifold::RowMajor::Zero(t, block_);
  for (Eigen::Index c = 0; c < f; ++c) {
    const int k = free[static_cast<std::size_t>(c)];
    const double h = half_widths_[static_cast<std::size_t>(k)];
    basis.row(k) = h * q.block(c, g.cols(), 1, t);
    inverse.col(k) = q.block(c, g.cols(), 1, t).transpose() / h;
  }
  return new SubspaceManifold(std::move(basis), std::move(inverse));
}

}  // namespace pcr::calib_internal
