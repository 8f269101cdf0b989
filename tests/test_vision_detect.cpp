// Rendering and detection against the renderer's ground truth (the exact projection of the tag's
// corners through the camera model).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "pcr/vision/render.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {
namespace {

// 25 um per pixel: f = 2000 px at 0.5 m... (f / Z = px per m): 40000 px/m.
CameraModel closeup_camera(int size_px, double k1 = 0.0) {
  CameraModel cam;
  cam.width = cam.height = size_px;
  cam.K << 8000, 0, size_px / 2.0 - 0.3, 0, 8000, size_px / 2.0 + 0.7, 0, 0, 1;
  cam.distortion = Eigen::VectorXd::Zero(5);
  cam.distortion[0] = k1;
  return cam;
}

Scene closeup_scene(double k1, double theta, double tilt = 0.0) {
  Scene scene;
  scene.camera = closeup_camera(700, k1);
  scene.plane = PlanePose::looking_down(0.2, tilt, -0.5 * tilt);  // 8000 / 0.2 = 40 px/mm
  RenderTag tag;
  tag.id = 7;
  tag.size_m = 0.010;
  tag.pose = Pose2<double>{0.0006, -0.0011, theta};
  scene.tags.push_back(tag);
  return scene;
}

double corner_rms(const Scene& scene, const TagDetection& d) {
  const auto truth = tag_corner_pixels(scene, scene.tags[0]);
  double sum = 0;
  for (int k = 0; k < 4; ++k) sum += (d.corners[k] - truth[k]).squaredNorm();
  return std::sqrt(sum / 4);
}

TEST(VisionDetect, CornerOrderAndAccuracyOnCleanImages) {
  for (double theta : {0.0, 0.3, -2.0, 3.0}) {
    for (double k1 : {0.0, -0.3}) {
      const Scene scene = closeup_scene(k1, theta, 0.05);
      RenderOptions opt;
      opt.supersampling = 5;
      const GrayImage im = render_scene(scene, opt);
      const auto dets = detect_tags(im, DetectorOptions{}, &scene.camera);
      ASSERT_EQ(dets.size(), 1u) << theta;
      EXPECT_EQ(dets[0].id, 7);
      const double rms = corner_rms(scene, dets[0]);
      std::printf("theta %.2f k1 %.2f corner rms %.4f px\n", theta, k1, rms);
      EXPECT_LT(rms, 0.05);
      // Without refinement, AprilTag's own corners (shifted by -0.5 px) are within a pixel.
      DetectorOptions raw;
      raw.refine = false;
      const auto d2 = detect_tags(im, raw, &scene.camera);
      ASSERT_EQ(d2.size(), 1u);
      EXPECT_LT(corner_rms(scene, d2[0]), 1.0);
    }
  }
}

}  // namespace
}  // namespace pcr::vision
