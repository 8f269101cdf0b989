#pragma once
// The rigid motion that best maps one set of points onto another (least squares): the platform
// pose of the straight-rod guess (pcr/spatial/shooting.hpp), a registration of measured points
// onto their design.

#include <Eigen/SVD>

#include "pcr/spatial/robot.hpp"

namespace pcr {

/// The pose T minimising sum_i |T from[i] - to[i]|^2 over the n point pairs (Kabsch: the SVD of
/// the centred cross-covariance, the sign of its last direction chosen so that the rotation is
/// proper). With fewer than 3 points, or collinear ones, the rotation is undetermined: the fit
/// keeps it the identity and maps the centroid of `from` onto that of `to`.
inline SpatialPose<double> fit_rigid_motion(const Vector3<double>* from, const Vector3<double>* to,
                                            int n) {
  Vector3<double> from_centroid = Vector3<double>::Zero(), to_centroid = Vector3<double>::Zero();
  for (int i = 0; i < n; ++i) {
    from_centroid += from[i] / n;
    to_centroid += to[i] / n;
  }
  Matrix3<double> H = Matrix3<double>::Zero();
  for (int i = 0; i < n; ++i) H += (from[i] - from_centroid) * (to[i] - to_centroid).transpose();
  Matrix3<double> R = Matrix3<double>::Identity();
  const Eigen::JacobiSVD<Matrix3<double>> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (n >= 3 && svd.singularValues()(1) > 1e-9 * svd.singularValues()(0)) {
    Matrix3<double> D = Matrix3<double>::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    R = svd.matrixV() * D * svd.matrixU().transpose();
  }
  return SpatialPose<double>{to_centroid - R * from_centroid, quaternion_of(R)};
}

}  // namespace pcr
