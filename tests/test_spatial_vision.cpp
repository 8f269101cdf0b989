// Camera measurement of a spatial robot's platform: tags with 3-D poses rendered, detected and
// located against the corners projected by the camera model; the pose of a tag board on the
// virtual spatial robot's platform measured from rendered images, against the truth and against
// its own predicted covariance.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "pcr/calib/spatial_virtual_robot.hpp"
#include "pcr/input_error.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/vision/attachment_points.hpp"
#include "pcr/vision/render.hpp"
#include "pcr/vision/tag_board.hpp"
#include "umeyama_reference.hpp"

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

// ---- The platform's pose from a tag board ------------------------------------------------------

// The board on the reference robot's platform (frame P): four 24 mm tags around a 16 mm one on
// its top face (5 mm above P, facing up), and a 16 mm tag on a 30 degree bevel at its edge.
TagBoard platform_board() {
  TagBoard board;
  const auto turn = [](double angle, const Eigen::Vector3d& axis) {
    return quaternion(Eigen::AngleAxisd(angle, axis).matrix());
  };
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d at((k % 2 ? 0.035 : -0.035), (k / 2 ? 0.035 : -0.035), 0.005);
    board.tags.push_back(
        BoardTag{kDefaultTagFamily, 10 + k, 0.024, SpatialPose<double>{at, turn(0.4 * k, z)}});
  }
  board.tags.push_back(BoardTag{kDefaultTagFamily, 14, 0.016,
                                SpatialPose<double>{Eigen::Vector3d(0, 0, 0.005), turn(-0.3, z)}});
  board.tags.push_back(BoardTag{kDefaultTagFamily, 15, 0.016,
                                SpatialPose<double>{Eigen::Vector3d(0, -0.07, 0.0),
                                                    turn(-M_PI / 6, Eigen::Vector3d::UnitX())}});
  return board;
}

// The camera `height` above the base, above the platform's home (`home`, ^W T_P), looking down on
// it (0.75 m: about 0.35 m above the platform): 640 x 640 px, f = 750 px (0.47 mm/px on the
// platform), barrel distortion.
Scene platform_scene(const SpatialPose<double>& home, double height = 0.75) {
  Scene scene;
  scene.camera.width = scene.camera.height = 640;
  scene.camera.K << 750, 0, 322.4, 0, 751, 317.9, 0, 0, 1;
  scene.camera.distortion << -0.1, 0.03, 0.0002, -0.0003, 0.0;
  scene.plane = PlanePose::looking_down(height, 0.05, -0.03);
  scene.plane.translation -=
      scene.plane.rotation * Eigen::Vector3d(home.position.x(), home.position.y(), 0);
  return scene;
}

// The error of `measured` against `truth` as (dp in S, dtheta in M), the covariance's
// parametrisation: dtheta = log(R_truth^T R_measured), through Eigen.
Eigen::Matrix<double, 6, 1> pose_error(const SpatialPose<double>& measured,
                                       const SpatialPose<double>& truth) {
  const Eigen::Quaterniond qm(measured.orientation[0], measured.orientation[1],
                              measured.orientation[2], measured.orientation[3]);
  const Eigen::Quaterniond qt(truth.orientation[0], truth.orientation[1], truth.orientation[2],
                              truth.orientation[3]);
  const Eigen::AngleAxisd turn(qt.normalized().inverse() * qm.normalized());
  Eigen::Matrix<double, 6, 1> e;
  e << measured.position - truth.position, turn.angle() * turn.axis();
  return e;
}

// The 0.9999 quantile of chi-square with 6 degrees of freedom.
constexpr double kChiSquare6Quantile9999 = 27.856;

// The criterion. With a right covariance S, each image's pose error e against the truth has a
// Mahalanobis distance d2 = e^T S^-1 e distributed as chi-square with 6 degrees of freedom: every
// image must stay below its 0.9999 quantile (all 36 pass together with probability 0.996), and
// their mean is printed (6 expected). The predicted sigma itself: per component, the spread of the
// errors over the noise seeds (about each pose's mean, pooled over the poses: 30 degrees of
// freedom, a relative spread of 13 %) within a factor of 2 of the predicted sigma. The predicted
// sigma also holds the detector's systematic corner errors (0.016 px per coordinate here without
// noise), which the seeds do not vary, so the ratio lies below 1.
TEST(SpatialVision, BoardPoseOnTheVirtualRobotAgreesWithTheTruthWithinItsCovariance) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  const TagBoard board = platform_board();
  const Scene base_scene = [&] {
    SpatialVirtualRobot robot(nominal);
    const SpatialVirtualMeasurement home =
        robot.measure(SpatialJointVector::Zero(nominal.params.num_rods));
    EXPECT_TRUE(home.ok);
    return platform_scene(home.platform);
  }();
  constexpr int kTruths = 3, kPoses = 2, kSeeds = 6;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> joint(-0.008, 0.012);  // the platform within 4 cm of home
  // Per component: the sum of squared deviations from each pose's mean over the noise seeds, and
  // of the predicted variances.
  Eigen::Matrix<double, 6, 1> within = Eigen::Matrix<double, 6, 1>::Zero(),
                              predicted = Eigen::Matrix<double, 6, 1>::Zero();
  double worst_d2 = 0, sum_d2 = 0;
  std::string worst;
  int poses = 0, images = 0;
  for (int truth = 0; truth < kTruths; ++truth) {
    SpatialVirtualRobotOptions options;
    options.seed = 100 + truth;
    options.truth_at_fraction = 0.8;
    SpatialVirtualRobot robot(nominal, options);
    for (int pose = 0; pose < kPoses; ++pose) {
      SpatialJointVector q(nominal.params.num_rods);
      for (int i = 0; i < q.size(); ++i) q(i) = joint(rng);
      const SpatialVirtualMeasurement m = robot.measure(q);
      ASSERT_TRUE(m.ok) << "truth " << truth << " pose " << pose;
      Scene scene = base_scene;
      const SpatialPose<double> camera_T_world{scene.plane.translation,
                                               quaternion(scene.plane.rotation)};
      const SpatialPose<double> truth_pose = camera_T_world * m.platform;  // ^S T_P, M = P
      scene.tags_3d = board_tags(board, m.platform);
      std::vector<Eigen::Matrix<double, 6, 1>> errors;
      for (int seed = 0; seed < kSeeds; ++seed) {
        RenderOptions opt;
        opt.supersampling = 3;
        opt.blur_sigma_px = 0.8;
        opt.noise_sigma = 0.02;
        opt.gradient = 0.15;
        opt.white = 0.8;  // no clipped highlights with the gradient and the noise
        opt.seed = static_cast<unsigned>(1000 * truth + 100 * pose + seed + 1);
        const GrayImage im = render_scene(scene, opt);
        const std::string name = "truth " + std::to_string(truth) + " pose " +
                                 std::to_string(pose) + " seed " + std::to_string(seed);
        const BoardPose b = measure_board_pose(im, name, board, scene.camera);
        EXPECT_EQ(b.detections.size(), board.tags.size()) << name;
        const Eigen::Matrix<double, 6, 1> e = pose_error(b.camera_T_board, truth_pose);
        const double d2 = e.dot(b.covariance.ldlt().solve(e));
        EXPECT_LT(d2, kChiSquare6Quantile9999) << name;
        sum_d2 += d2;
        if (d2 > worst_d2) {
          worst_d2 = d2;
          char text[256];
          std::snprintf(text, sizeof text,
                        "%s: d2 %.2f, |dp| %.1f um (sigma %.1f, %.1f, %.1f um), |dtheta| %.1f "
                        "urad, corner rms %.3f px, edge sigma %.3f px",
                        name.c_str(), d2, e.head<3>().norm() * 1e6,
                        std::sqrt(b.covariance(0, 0)) * 1e6, std::sqrt(b.covariance(1, 1)) * 1e6,
                        std::sqrt(b.covariance(2, 2)) * 1e6, e.tail<3>().norm() * 1e6,
                        b.corner_rms_px, b.edge_sigma_px);
          worst = text;
        }
        predicted += b.covariance.diagonal();
        errors.push_back(e);
        ++images;
      }
      Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
      for (const auto& e : errors) mean += e / kSeeds;
      for (const auto& e : errors) within += (e - mean).cwiseAbs2();
      ++poses;
    }
  }
  // The empirical spread over the noise seeds (pooled over the poses, kPoses (kSeeds - 1)
  // degrees of freedom per truth) against the predicted sigma (rms over the images).
  const Eigen::Matrix<double, 6, 1> empirical = (within / (poses * (kSeeds - 1))).cwiseSqrt();
  const Eigen::Matrix<double, 6, 1> sigma = (predicted / images).cwiseSqrt();
  const char* names[6] = {"x", "y", "z", "rx", "ry", "rz"};
  for (int k = 0; k < 6; ++k) {
    std::printf("%-2s: predicted sigma %8.2f, empirical spread %8.2f (%s), ratio %.2f\n", names[k],
                sigma[k] * 1e6, empirical[k] * 1e6, k < 3 ? "um" : "urad", empirical[k] / sigma[k]);
    EXPECT_GT(empirical[k] / sigma[k], 0.5) << names[k];
    EXPECT_LT(empirical[k] / sigma[k], 2.0) << names[k];
  }
  std::printf("%d images, mean d2 %.2f (chi-square 6: 6), worst %s\n", images, sum_d2 / images,
              worst.c_str());
}

// ---- Attachment points from the tags next to them ----------------------------------------------

// The 0.99999 quantile of chi-square with 3 degrees of freedom: a point's covariance comes from
// one tag's pose, linearised, and a tag's pose is nonlinear in its tilt (the two poses that fit a
// square's corners seen nearly face on), which the linear covariance understates a little: mean
// d2 3.8 where 3 is expected, so the bound is one decade further out than the board's.
constexpr double kChiSquare3Quantile99999 = 25.902;

// Next to each hole A_i a 40 mm tag on the base, and next to each attachment point B_i a 30 mm
// tag on the platform's top (5 mm above P), its centre 5 mm beyond its edge from the point, on the
// side away from the nearest other point.
std::vector<TagPoint> attachment_points(const SpatialRobotParams<double>& robot) {
  std::vector<TagPoint> points;
  for (int proximal = 1; proximal >= 0; --proximal) {
    const auto at = [&](int i) { return proximal ? robot.limb(i).A : robot.limb(i).B; };
    for (int i = 0; i < robot.num_rods; ++i) {
      int nearest = i == 0 ? 1 : 0;
      for (int j = 0; j < robot.num_rods; ++j)
        if (j != i && (at(j) - at(i)).norm() < (at(nearest) - at(i)).norm()) nearest = j;
      const Eigen::Vector3d away = (at(i) - at(nearest)).normalized();
      const double size = proximal ? 0.04 : 0.03, out = 0.5 * size + 0.005;
      // Turned 0.35 rad off `away`: the renderer's s x s samples leave edges along the pixel
      // grid biased by up to 1 / (2 s) px (a real sensor integrates exactly).
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(std::atan2(away.y(), away.x()) + 0.35, Eigen::Vector3d::UnitZ())
              .matrix();
      TagPoint p;
      p.name = (proximal ? "A" : "B") + std::to_string(i + 1);
      p.tag.id = (proximal ? 20 : 30) + i;
      p.tag.size_m = size;
      const Eigen::Vector3d centre =
          at(i) + out * away + Eigen::Vector3d(0, 0, proximal ? 0.0 : 0.005);
      p.tag.pose = SpatialPose<double>{centre, quaternion(R)};
      p.offset = R.transpose() * (at(i) - centre);
      points.push_back(p);
    }
  }
  return points;
}

// Each tag's own pose is weakest in its tilt, and a small tag seen nearly face on can flip
// between the two poses that fit its corners: the points are imaged close up (as the planar
// method's mounts), the base from 0.4 m (its tags 75 px), the platform from 0.35 m at two poses
// (its tags 64 px).
TEST(SpatialVision, AttachmentPointsFromTheirOwnTagsWithinTheirCovariance) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  SpatialVirtualRobotOptions options;
  options.seed = 7;
  options.truth_at_fraction = 0.8;
  SpatialVirtualRobot robot(nominal, options);
  const SpatialRobotParams<double>& truth = robot.truth().params;
  const std::vector<TagPoint> points = attachment_points(truth);
  const int n = truth.num_rods;
  const std::vector<TagPoint> holes(points.begin(), points.begin() + n),
      attachments(points.begin() + n, points.end());
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> joint(-0.005, 0.008);
  double worst_d2 = 0, sum_d2 = 0;
  std::string worst;
  int count = 0;
  // The points of `group` (A: in W; B: in P at `platform`) in an image from `height` above the
  // base, against the truth.
  const auto check = [&](const std::vector<TagPoint>& group, bool on_platform,
                         const SpatialPose<double>& platform, double height,
                         const std::string& what) {
    const Scene base = platform_scene(platform, height);
    const SpatialPose<double> camera_T_world{base.plane.translation,
                                             quaternion(base.plane.rotation)};
    Scene scene = base;
    std::vector<Eigen::Vector3d> truths;  // in S
    for (std::size_t k = 0; k < group.size(); ++k) {
      const BoardTag& t = group[k].tag;
      scene.tags_3d.push_back(
          RenderTag3d{t.family, t.id, t.size_m, on_platform ? platform * t.pose : t.pose});
      const int limb = static_cast<int>(k);
      const Eigen::Vector3d in_world =
          on_platform ? platform.position + platform.rotation() * truth.limb(limb).B
                      : truth.limb(limb).A;
      truths.push_back(camera_T_world.position + camera_T_world.rotation() * in_world);
    }
    for (int seed = 0; seed < 3; ++seed) {
      RenderOptions opt;
      opt.supersampling = 2;
      opt.blur_sigma_px = 0.8;
      opt.noise_sigma = 0.02;
      opt.white = 0.85;
      opt.seed = static_cast<unsigned>(50 + 10 * count + seed);
      const std::string name = what + " seed " + std::to_string(seed);
      const std::vector<TagPointMeasurement> measured =
          measure_tag_points(render_scene(scene, opt), name, group, scene.camera);
      ASSERT_EQ(measured.size(), group.size());
      for (std::size_t k = 0; k < group.size(); ++k) {
        const Eigen::Vector3d e = measured[k].position - truths[k];
        const double d2 = e.dot(measured[k].covariance.ldlt().solve(e));
        EXPECT_LT(d2, kChiSquare3Quantile99999) << name << " " << group[k].name;
        sum_d2 += d2;
        ++count;
        if (d2 > worst_d2) {
          worst_d2 = d2;
          char text[200];
          std::snprintf(text, sizeof text,
                        "%s %s: d2 %.2f, error %.1f um (%.0f %.0f %.0f; sigma %.1f, %.1f, %.1f um)",
                        name.c_str(), group[k].name.c_str(), d2, e.norm() * 1e6, e.x() * 1e6,
                        e.y() * 1e6, e.z() * 1e6, std::sqrt(measured[k].covariance(0, 0)) * 1e6,
                        std::sqrt(measured[k].covariance(1, 1)) * 1e6,
                        std::sqrt(measured[k].covariance(2, 2)) * 1e6);
          worst = text;
        }
      }
    }
  };
  check(holes, false, SpatialPose<double>{}, 0.4, "base");
  for (int pose = 0; pose < 2; ++pose) {
    SpatialJointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = joint(rng);
    const SpatialVirtualMeasurement m = robot.measure(q);
    ASSERT_TRUE(m.ok) << "pose " << pose;
    check(attachments, true, m.platform, m.platform.position.z() + 0.35,
          "platform pose " + std::to_string(pose));
  }
  std::printf("%d points, mean d2 %.2f (chi-square 3: 3), worst %s\n", count, sum_d2 / count,
              worst.c_str());
}

// ---- Registration into W and P ------------------------------------------------------------------

// The design's holes moved by a known rigid motion (a camera frame) and registered back: the
// motion and the points come back exactly, and the covariance of isotropic point noise
// (sigma^2 I) becomes sigma^2 (I - Pi), Pi the orthogonal projector onto the design's
// infinitesimal rigid motions (the registration absorbs those), built here from its basis
// [I, -[d_i]x]; its trace is sigma^2 (3n - 6).
TEST(SpatialVision, RegistrationRecoversAKnownRigidMotionAndProjectsOutItsNoise) {
  const SpatialRobotParams<double> design = continuum_stewart_gough();
  const int n = design.num_rods;
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.03, -0.02, 0.61);  // ^S T_W
  constexpr double sigma = 20e-6;
  std::vector<Eigen::Vector3d> holes;
  std::vector<TagPoint> points(static_cast<std::size_t>(n));
  std::vector<TagPointMeasurement> measured;
  for (int i = 0; i < n; ++i) {
    holes.push_back(design.limb(i).A);
    TagPointMeasurement m;
    m.position = R * design.limb(i).A + t;
    m.covariance = sigma * sigma * Eigen::Matrix3d::Identity();
    measured.push_back(m);
  }
  const PointRegistration r = register_points(points, measured, holes, 3.0, "holes");
  EXPECT_LT((r.camera_T_frame.position - t).norm(), 1e-12);
  EXPECT_LT((r.camera_T_frame.rotation() - R).norm(), 1e-12);
  EXPECT_LT(r.rms, 1e-12);
  Eigen::MatrixXd basis(3 * n, 6);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& d = holes[static_cast<std::size_t>(i)];
    Eigen::Matrix3d cross;
    cross << 0, -d.z(), d.y(), d.z(), 0, -d.x(), -d.y(), d.x(), 0;
    basis.block<3, 3>(3 * i, 0).setIdentity();
    basis.block<3, 3>(3 * i, 3) = -cross;
  }
  const Eigen::MatrixXd projector =
      basis * (basis.transpose() * basis).inverse() * basis.transpose();
  const Eigen::MatrixXd expected =
      sigma * sigma * (Eigen::MatrixXd::Identity(3 * n, 3 * n) - projector);
  for (int i = 0; i < n; ++i) {
    EXPECT_LT((r.points[static_cast<std::size_t>(i)] - holes[static_cast<std::size_t>(i)]).norm(),
              1e-12);
    for (int k = 0; k < 3; ++k) {  // no tolerances: 3 sigma
      EXPECT_NEAR(r.half_widths[static_cast<std::size_t>(i)][k],
                  3 * std::sqrt(expected(3 * i + k, 3 * i + k)), 1e-9);
    }
  }
  EXPECT_LT((r.covariance - expected).norm(), 1e-6 * expected.norm());
  EXPECT_NEAR(r.covariance.trace(), sigma * sigma * (3 * n - 6), 1e-6 * sigma * sigma);
  // An offset tolerance adds its worst case through the same map: 10 um along one tag's x axis.
  points[2].offset_uncertainty = Eigen::Vector3d(10e-6, 0, 0);
  measured[2].tag.camera_T_board.orientation = Eigen::Vector4d(1, 0, 0, 0);  // the tag's x = S's
  const PointRegistration toleranced = register_points(points, measured, holes, 3.0, "holes");
  Eigen::MatrixXd rotate = Eigen::MatrixXd::Zero(3 * n, 3 * n);  // S -> W, point by point
  for (int i = 0; i < n; ++i) rotate.block<3, 3>(3 * i, 3 * i) = R.transpose();
  const Eigen::MatrixXd to_frame = (Eigen::MatrixXd::Identity(3 * n, 3 * n) - projector) * rotate;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(toleranced.half_widths[static_cast<std::size_t>(i)][k] -
                      r.half_widths[static_cast<std::size_t>(i)][k],
                  10e-6 * std::abs(to_frame(3 * i + k, 6)), 1e-10);
}

// The virtual robot's truth (every A_i and B_i at 0.8 of its 0.1 mm half-widths from the design),
// its base seen from 0.4 m and its platform from 0.35 m at a random pose (as the attachment-point
// test), measured and registered onto the design: each point against the truth registered the
// same way (Eigen's Umeyama fit of the truth onto the design), within its half-widths and within
// chi-square(3)'s 0.99999 quantile of its propagated covariance. A second layout states each
// offset 40 um off along the tag's x (within its 50 um offset_uncertainty): its points stay within
// their half-widths, which now hold the offsets' worst case.
TEST(SpatialVision, AttachmentPointsRegisteredIntoWAndPWithinTheirHalfWidths) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  const int n = nominal.params.num_rods;
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> joint(-0.005, 0.008);
  double worst_d2 = 0, sum_d2 = 0, worst_ratio = 0, worst_toleranced = 0, rms_A = 0, rms_B = 0;
  std::string worst;
  Eigen::Vector3d sum_half_A = Eigen::Vector3d::Zero(), sum_half_B = Eigen::Vector3d::Zero();
  int count = 0;
  constexpr int kTruths = 2;
  for (int truth_seed = 0; truth_seed < kTruths; ++truth_seed) {
    SpatialVirtualRobotOptions options;
    options.seed = 11 + truth_seed;
    options.truth_at_fraction = 0.8;
    SpatialVirtualRobot robot(nominal, options);
    const SpatialRobotParams<double>& truth = robot.truth().params;
    const std::vector<TagPoint> points = attachment_points(truth);
    AttachmentLayout layout, shifted;
    layout.source = shifted.source = "layout";
    layout.holes.assign(points.begin(), points.begin() + n);
    layout.attachments.assign(points.begin() + n, points.end());
    shifted = layout;
    for (std::vector<TagPoint>* group : {&shifted.holes, &shifted.attachments}) {
      for (TagPoint& p : *group) {
        p.offset.x() += 40e-6;
        p.offset_uncertainty = Eigen::Vector3d::Constant(50e-6);
      }
    }
    SpatialJointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = joint(rng);
    const SpatialVirtualMeasurement pose = robot.measure(q);
    ASSERT_TRUE(pose.ok);
    // The images: the tags of `group` in W (`platform` the identity) or on the platform.
    const auto image = [&](const std::vector<TagPoint>& group, const SpatialPose<double>& platform,
                           double height, unsigned seed) {
      Scene scene = platform_scene(platform, height);
      for (const TagPoint& p : group)
        scene.tags_3d.push_back(
            RenderTag3d{p.tag.family, p.tag.id, p.tag.size_m, platform * p.tag.pose});
      RenderOptions opt;
      opt.supersampling = 2;
      opt.blur_sigma_px = 0.8;
      opt.noise_sigma = 0.02;
      opt.white = 0.85;
      opt.seed = seed;
      return render_scene(scene, opt);
    };
    const GrayImage base = image(layout.holes, SpatialPose<double>{}, 0.4, 70 + truth_seed);
    const GrayImage top = image(layout.attachments, pose.platform,
                                pose.platform.position.z() + 0.35, 80 + truth_seed);
    const Scene camera = platform_scene(SpatialPose<double>{});
    const AttachmentMeasurement m = measure_attachment_points(base, "base.png", top, "platform.png",
                                                              layout, camera.camera, nominal);
    const AttachmentMeasurement ms = measure_attachment_points(
        base, "base.png", top, "platform.png", shifted, camera.camera, nominal);
    rms_A += m.A.rms / kTruths;
    rms_B += m.B.rms / kTruths;
    for (int end = 0; end < 2; ++end) {
      const PointRegistration& r = end ? m.B : m.A;
      const PointRegistration& rs = end ? ms.B : ms.A;
      std::vector<Eigen::Vector3d> design, truths;
      for (int i = 0; i < n; ++i) {
        design.push_back(end ? nominal.params.limb(i).B : nominal.params.limb(i).A);
        truths.push_back(end ? truth.limb(i).B : truth.limb(i).A);
      }
      const std::vector<Eigen::Vector3d> reference = pcr::test::umeyama_registered(truths, design);
      for (int i = 0; i < n; ++i) {
        const std::size_t k = static_cast<std::size_t>(i);
        const std::string name = std::string(end ? "B" : "A") + std::to_string(i + 1) + " truth " +
                                 std::to_string(truth_seed);
        const Eigen::Vector3d e = r.points[k] - reference[k];
        const Eigen::Matrix3d S = r.covariance.block<3, 3>(3 * i, 3 * i);
        const double d2 = e.dot(S.ldlt().solve(e));
        EXPECT_LT(d2, kChiSquare3Quantile99999) << name << ": error " << e.transpose();
        worst_d2 = std::max(worst_d2, d2);
        sum_d2 += d2;
        ++count;
        (end ? sum_half_B : sum_half_A) += r.half_widths[k] / (kTruths * n);
        for (int a = 0; a < 3; ++a) {
          EXPECT_LE(std::abs(e[a]), r.half_widths[k][a]) << name << " axis " << a;
          if (std::abs(e[a]) / r.half_widths[k][a] > worst_ratio) {
            worst_ratio = std::abs(e[a]) / r.half_widths[k][a];
            worst = name + " axis " + "xyz"[a];
          }
          const double es = rs.points[k][a] - reference[k][a];
          EXPECT_LE(std::abs(es), rs.half_widths[k][a]) << name << " (shifted) axis " << a;
          worst_toleranced = std::max(worst_toleranced, std::abs(es) / rs.half_widths[k][a]);
        }
      }
    }
  }
  std::printf(
      "%d points: mean d2 %.2f (chi-square 3: 3), worst %.2f; worst |error| / half-width %.2f "
      "(%s; %.2f with the offsets' tolerances); registration rms A %.1f um, B %.1f um\n"
      "mean half-widths A %.0f %.0f %.0f um, B %.0f %.0f %.0f um\n",
      count, sum_d2 / count, worst_d2, worst_ratio, worst.c_str(), worst_toleranced, rms_A * 1e6,
      rms_B * 1e6, sum_half_A.x() * 1e6, sum_half_A.y() * 1e6, sum_half_A.z() * 1e6,
      sum_half_B.x() * 1e6, sum_half_B.y() * 1e6, sum_half_B.z() * 1e6);
}

// The message names the image (or the board) and the value.
void expect_input_error(const std::function<void()>& call, const std::vector<std::string>& named) {
  try {
    call();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    for (const std::string& word : named)
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
  }
}

TEST(SpatialVision, BadBoardsAndImagesAreNamed) {
  const TagBoard board = platform_board();
  Scene scene = platform_scene(
      SpatialPose<double>{Eigen::Vector3d(0, 0, 0.4), quaternion(Eigen::Matrix3d::Identity())});
  scene.tags_3d = board_tags(board, SpatialPose<double>{Eigen::Vector3d(0, 0, 0.4),
                                                        quaternion(Eigen::Matrix3d::Identity())});
  RenderOptions opt;
  opt.supersampling = 2;
  const GrayImage im = render_scene(scene, opt);
  EXPECT_EQ(measure_board_pose(im, "board.png", board, scene.camera).detections.size(),
            board.tags.size());

  // An id the family does not have, a family and id twice, a size that is not positive.
  TagBoard unknown = board;
  unknown.tags[2].id = 9999;
  expect_input_error([&] { measure_board_pose(im, "board.png", unknown, scene.camera); },
                     {"board.png", "9999", "board tag 2"});
  TagBoard twice = board;
  twice.tags[3].id = twice.tags[1].id;
  expect_input_error([&] { measure_board_pose(im, "board.png", twice, scene.camera); },
                     {"board.png", "id 11", "twice"});
  TagBoard flat = board;
  flat.tags[0].size_m = 0;
  expect_input_error([&] { measure_board_pose(im, "board.png", flat, scene.camera); },
                     {"board.png", "size 0"});
  // No tag of the board in view: the image, the board's ids and those detected are named.
  TagBoard other = board;
  for (BoardTag& t : other.tags) t.id += 100;
  expect_input_error([&] { measure_board_pose(im, "board.png", other, scene.camera); },
                     {"board.png", "no tag of the board", "id 110", "detected: tag36h11 id 10"});
  // A board tag twice in the image.
  Scene doubled = scene;
  RenderTag3d copy = doubled.tags_3d[4];
  copy.pose.position.x() += 0.02;
  copy.pose.position.y() += 0.06;
  doubled.tags_3d.push_back(copy);
  expect_input_error(
      [&] { measure_board_pose(render_scene(doubled, opt), "doubled.png", board, scene.camera); },
      {"doubled.png", "id 14", "2 times"});
  // A point whose tag is not in view.
  TagPoint missing;
  missing.name = "A4";
  missing.tag.id = 77;
  expect_input_error([&] { measure_tag_points(im, "board.png", {missing}, scene.camera); },
                     {"board.png", "point A4", "id 77", "not found"});
  // Too few corners for a pose.
  expect_input_error([&] { fit_board_pose({}, {}, board, scene.camera, "none.png"); },
                     {"none.png", "0 tag corners"});
}

// The attachment layout file's errors name the file, the field and the value; the measurement's
// name the layout file and the design (a rod count that differs) or the image and the point (a tag
// not in view).
TEST(SpatialVision, BadAttachmentLayoutsAndImagesAreNamed) {
  const auto layout_text = [](const std::string& rods) {
    return "{\"format\": \"pcr-attachment-points\", \"tag_size\": 0.04, \"rods\": [" + rods + "]}";
  };
  const auto rod = [](int a, int b, const std::string& extra = "") {
    return "{\"A\": {\"id\": " + std::to_string(a) + ", \"offset\": [0.025, 0, 0]" + extra +
           "}, \"B\": {\"id\": " + std::to_string(b) +
           ", \"tag_size\": 0.03, \"offset\": [0, -0.02, 0]}}";
  };
  const AttachmentLayout good = parse_attachment_layout(
      layout_text(rod(20, 30, ", \"offset_uncertainty\": [1e-5, 1e-5, 0]") + "," + rod(21, 31)),
      "points.json");
  ASSERT_EQ(good.num_rods(), 2);
  EXPECT_EQ(good.holes[1].name, "A2");
  EXPECT_EQ(good.attachments[0].tag.id, 30);
  EXPECT_DOUBLE_EQ(good.attachments[0].tag.size_m, 0.03);
  EXPECT_DOUBLE_EQ(good.holes[0].tag.size_m, 0.04);
  EXPECT_DOUBLE_EQ(good.holes[0].offset_uncertainty.x(), 1e-5);
  EXPECT_DOUBLE_EQ(good.attachments[0].offset.y(), -0.02);
  const auto bad = [&](const std::string& text, const std::vector<std::string>& named) {
    expect_input_error([&] { parse_attachment_layout(text, "points.json"); }, named);
  };
  bad(layout_text(rod(20, 30) + "," + rod(21, 31, ", \"ofset\": 1")),
      {"points.json", "rods[1].A.ofset", "unknown field"});
  bad(layout_text(rod(20, 30) + "," + rod(21, 20)),
      {"points.json", "rods[1].B.id", "twice", "rods[0].A.id"});
  bad(layout_text(rod(20, 5000)), {"points.json", "rods[0].B.id", "5000"});
  bad(layout_text(rod(20, 30, ", \"offset_uncertainty\": [1e-5, -1e-5, 0]")),
      {"points.json", "rods[0].A.offset_uncertainty[1]", "-1e-05"});
  bad(layout_text(rod(20, 30, ", \"family\": \"tag99h9\"")),
      {"points.json", "rods[0].A.family", "tag99h9"});
  bad("{\"rods\": [{\"A\": {\"id\": 1, \"offset\": [0, 0, 0]}, \"B\": {\"id\": 2, "
      "\"offset\": [0, 0, 0]}}]}",
      {"points.json", "rods[0].A.tag_size", "missing"});
  bad(layout_text("{\"A\": {\"id\": 1, \"offset\": [0, 0, 0]}}"),
      {"points.json", "rods[0].B", "missing"});
  bad(layout_text(""), {"points.json", "rods", "non-empty"});

  // The measurement: a layout of 2 rods for the 6-rod design; a hole whose tag is not in view.
  const SpatialRobotDescription design = continuum_stewart_gough_description();
  const std::vector<TagPoint> points = attachment_points(design.params);
  AttachmentLayout layout;
  layout.source = "points.json";
  layout.holes.assign(points.begin(), points.begin() + 6);
  layout.attachments.assign(points.begin() + 6, points.end());
  Scene scene = platform_scene(SpatialPose<double>{}, 0.4);
  for (const TagPoint& p : layout.holes)
    scene.tags_3d.push_back(RenderTag3d{p.tag.family, p.tag.id, p.tag.size_m, p.tag.pose});
  RenderOptions opt;
  opt.supersampling = 2;
  const GrayImage base = render_scene(scene, opt);
  expect_input_error(
      [&] {
        measure_attachment_points(base, "base.png", base, "top.png", good, scene.camera, design);
      },
      {"points.json", "2 rods", "continuum-stewart-gough", "has 6"});
  AttachmentLayout hidden = layout;
  hidden.holes[3].tag.id = 77;
  expect_input_error(
      [&] {
        measure_attachment_points(base, "base.png", base, "top.png", hidden, scene.camera, design);
      },
      {"base.png", "point A4", "id 77", "not found"});
  // The base's tags are not the platform's: the platform image is named with its first point.
  expect_input_error(
      [&] {
        measure_attachment_points(base, "base.png", base, "top.png", layout, scene.camera, design);
      },
      {"top.png", "point B1", "not found"});
}

}  // namespace
}  // namespace pcr::vision
