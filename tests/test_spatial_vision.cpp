// Camera measurement of a spatial robot's platform: tags with 3-D poses rendered, detected and
// located against the corners projected by the camera model.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>

#include "pcr/vision/render.hpp"

namespace pcr::vision {
namespace {

Eigen::Vector4d quaternion(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
}

// A camera of 640 x 480 px, f = 900 px, with barrel distortion, at the origin of the plane frame
// looking along its z (so a tag facing the camera has its z towards -z).
Scene camera_scene() {
  Scene scene;
  scene.camera.width = 640;
  scene.camera.height = 480;
  scene.camera.K << 900, 0, 321.3, 0, 905, 238.7, 0, 0, 1;
  scene.camera.distortion << -0.12, 0.05, 0.0003, -0.0002, 0.0;
  scene.plane.rotation.setIdentity();
  scene.plane.translation.setZero();
  return scene;
}

// A tag 0.25 m in front of the camera facing it, tilted by up to `tilt` about a random axis in
// its plane and turned at random about its normal.
RenderTag3d tilted_tag(int id, const Eigen::Vector3d& position, double tilt, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  const double axis = M_PI * u(rng), turn = M_PI * u(rng), angle = tilt * std::abs(u(rng));
  const Eigen::Matrix3d facing = Eigen::Vector3d(1, -1, -1).asDiagonal();  // z towards the camera
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(angle, Eigen::Vector3d(std::cos(axis), std::sin(axis), 0)).matrix() *
      facing * Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()).matrix();
  RenderTag3d tag;
  tag.id = id;
  tag.size_m = 0.02;
  tag.pose = SpatialPose<double>{position, quaternion(R)};
  return tag;
}

TEST(SpatialVision, TagsWithThreeDimensionalPosesAreDrawnAtTheirProjectedCorners) {
  std::mt19937 rng(5);
  double worst = 0;
  for (int trial = 0; trial < 4; ++trial) {
    Scene scene = camera_scene();
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d position((k % 2 ? 0.04 : -0.04), (k / 2 ? 0.03 : -0.03),
                                     0.25 + 0.02 * k);
      scene.tags_3d.push_back(tilted_tag(4 * trial + k, position, 0.8, rng));
    }
    // Seen from behind: not drawn (a tag lies on an opaque board).
    RenderTag3d back = tilted_tag(40, Eigen::Vector3d(0, 0, 0.3), 0.0, rng);
    back.pose.orientation = quaternion(Eigen::Matrix3d::Identity());
    scene.tags_3d.push_back(back);
    // Behind the tag nearest to the camera: hidden.
    RenderTag3d hidden = scene.tags_3d[0];
    hidden.id = 41;
    hidden.pose.position *= 1.2;
    scene.tags_3d.push_back(hidden);
    RenderOptions opt;
    opt.supersampling = 4;
    const GrayImage im = render_scene(scene, opt);
    const auto dets = detect_tags(im, DetectorOptions{}, &scene.camera);
    ASSERT_EQ(dets.size(), 4u) << "trial " << trial;
    for (const TagDetection& d : dets) {
      ASSERT_LT(d.id - 4 * trial, 4) << "trial " << trial;
      const auto truth = tag_corner_pixels(scene, scene.tags_3d[d.id - 4 * trial]);
      for (int k = 0; k < 4; ++k) worst = std::max(worst, (d.corners[k] - truth[k]).norm());
    }
  }
  std::printf("4 scenes of 4 tags tilted up to 0.8 rad: worst corner error %.4f px\n", worst);
  EXPECT_LT(worst, 0.1);
}

}  // namespace
}  // namespace pcr::vision
