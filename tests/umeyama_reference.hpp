#pragma once
// The least-squares rigid registration of one point set onto another by Eigen's Umeyama fit: a
// reference independent of pcr::fit_rigid_motion, for the tests of measured points registered into
// W and P (test_spatial_vision, test_vision_cli).
#include <Eigen/Geometry>
#include <vector>

namespace pcr::test {

/// `from` mapped by the rigid motion T minimising sum |T from[i] - to[i]|^2.
inline std::vector<Eigen::Vector3d> umeyama_registered(const std::vector<Eigen::Vector3d>& from,
                                                       const std::vector<Eigen::Vector3d>& to) {
  Eigen::MatrixXd a(3, from.size()), b(3, to.size());
  for (std::size_t i = 0; i < from.size(); ++i) {
    a.col(static_cast<Eigen::Index>(i)) = from[i];
    b.col(static_cast<Eigen::Index>(i)) = to[i];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(a, b, false);
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : from)
    out.push_back(T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>());
  return out;
}

}  // namespace pcr::test
