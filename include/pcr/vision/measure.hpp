#pragma once
// From tag detections to the robot's geometric parameters (Mauze et al. 2021, Section 4).
//
// 1. Marker poses. All tags lie in one plane. One least-squares fit (Gauss-Newton) estimates the
//    plane's pose in the camera (2 tilts and a distance: its in-plane position and rotation are a
//    free gauge, fixed by the initial guess) together with every tag's planar pose (x, y, theta),
//    minimising the reprojection error of all tag corners in undistorted coordinates (scaled to
//    pixels). The covariance of the poses is sigma^2 (J^T J)^-1, with sigma the corner noise
//    estimated from the residuals times `corner_sigma_scale` (never below `corner_sigma_floor_px`).
//    It includes the plane's uncertainty (scale, tilt). When the plane pose is known it is held
//    fixed.
// 2. Clamps. A = c + R(theta) o and alpha = theta + phi for each mount (o, phi from the layout).
// 3. Frames. W is the least-squares rigid registration of the measured A_i onto the design's A_i,
//    P the one of the measured B_i onto the design's B_i (the usual metrology best fit), so the
//    results are in the design's frames and directly comparable with it.
// 4. Half-widths: k sigma of the linearly propagated marker covariance (k = `coverage_factor`)
//    plus the worst case of the linearly propagated layout half-widths (offsets, rod angles).
// 5. Actuator direction: the proximal tag centres over a sweep of one actuator, a total
//    least-squares line (direction from the first image to the last, images in name order);
//    gamma = its angle - alpha, with the line's and alpha's uncertainties.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/robot_description.hpp"
#include "pcr/se2.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/mounts.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {

struct PoseOptions {
  double corner_sigma_floor_px{0.02};
  /// The corners of one tag come from four fitted edges, so their errors are correlated and the
  /// fit residuals understate them; measured on rendered images (tests/test_vision_measure.cpp),
  /// the true corner scatter is about 1.4 times the residual estimate.
  double corner_sigma_scale{1.5};
  int max_iterations{50};
};

struct MarkerPose {
  std::string family;
  int id{-1};
  Pose2<double> pose;                                   ///< tag frame in the plane frame (m, rad)
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Zero()};  ///< on (x, y, theta)
};

struct PlaneFit {
  PlanePose plane;
  std::vector<MarkerPose> markers;
  Eigen::MatrixXd covariance;  ///< joint, 3 per marker in order
  double corner_rms_px{0};     ///< reprojection residual rms
  double corner_sigma_px{0};   ///< the sigma used for the covariance
};

/// `sizes` maps each detection (by index) to its tag size (m). If `known_plane` is given it is held
/// fixed. Throws std::runtime_error when there are no detections.
PlaneFit fit_planar_markers(const std::vector<TagDetection>& detections,
                            const std::vector<double>& sizes, const CameraModel& camera,
                            const std::optional<PlanePose>& known_plane = std::nullopt,
                            const PoseOptions& options = {});

struct MeasureOptions {
  DetectorOptions detector;
  PoseOptions pose;
  double coverage_factor{3.0};
};

/// Per limb: measured values (in W / P of the design) and half-widths.
struct LimbMeasurement {
  Eigen::Vector2d A{0, 0}, A_halfwidth{0, 0};
  double alpha{0}, alpha_halfwidth{0};
  Eigen::Vector2d B{0, 0}, B_halfwidth{0, 0};
  double beta{0}, beta_halfwidth{0};
  std::optional<double> gamma, gamma_halfwidth;  ///< from a sweep
  Eigen::Vector2d A_plane{0, 0};                 ///< A in the plane frame (before registration)
  double alpha_plane{0};
  Eigen::Vector2d B_plane{0, 0};
  double beta_plane{0};
};

struct RobotMeasurement {
  std::vector<LimbMeasurement> limbs;
  PlaneFit fit;                                         ///< the home image's fit
  std::vector<TagDetection> detections;                 ///< matched detections, in layout order
  Pose2<double> world_in_plane;                         ///< W in the plane frame (registration)
  Pose2<double> platform_in_plane;                      ///< P in the plane frame
  double registration_rms_A{0}, registration_rms_B{0};  ///< m
};

/// The tags of every family in `families` (each detected as `base` says, with the camera).
std::vector<TagDetection> detect_families(const GrayImage& image,
                                          const std::set<std::string>& families,
                                          const CameraModel& camera, const DetectorOptions& base);

/// Throws InputError naming `image_source` and `who` (the mount or tag) when a detection cannot be
/// measured: its white quiet zone cut by the image border, or clipped highlights along its edges
/// (more than 1 % of its edge points, see TagDetection::clipped_fraction).
void check_detection(const TagDetection& detection, const GrayImage& image,
                     const std::string& image_source, const std::string& who);

/// Matches detections to the layout's mounts. Throws InputError naming `image_source` and the
/// mount or id for a missing marker, a duplicated id, a marker cut by the image border.
std::vector<TagDetection> match_mounts(const std::vector<TagDetection>& detections,
                                       const MountLayout& layout, const GrayImage& image,
                                       const std::string& image_source);

/// Step 4's half-widths, for every measured value y: k sigma of its linearly propagated
/// covariance (`covariance`, already propagated; k = `coverage_factor`) plus the worst case of the
/// tolerances t propagated linearly (`tolerance_jacobian` = dy / dt): k sqrt(C_jj) + sum |J_jk|
/// t_k. The planar and the spatial registrations both use it.
Eigen::VectorXd measured_half_widths(const Eigen::MatrixXd& covariance,
                                     const Eigen::MatrixXd& tolerance_jacobian,
                                     const Eigen::VectorXd& tolerances, double coverage_factor);

/// Detects, fits and registers onto `design`. `image_source` names the image in messages.
RobotMeasurement measure_robot(const GrayImage& image, const std::string& image_source,
                               const MountLayout& layout, const CameraModel& camera,
                               const RobotParams<double>& design,
                               const MeasureOptions& options = {});

struct SweepResult {
  double direction_plane{0};  ///< angle of the fitted line in the plane frame (rad)
  double direction_sigma{0};  ///< rad
  double gamma{0}, gamma_halfwidth{0};
  std::vector<Eigen::Vector2d> centres;  ///< tag centres in the plane frame
  double line_rms{0};                    ///< m
};

/// Sweep of `limb`: its proximal tag in every image (in order), the plane held at `home.fit.plane`.
/// Also stores gamma in home.limbs[limb].
SweepResult measure_sweep(const std::vector<GrayImage>& images,
                          const std::vector<std::string>& sources, int limb,
                          const MountLayout& layout, const CameraModel& camera,
                          RobotMeasurement& home, const MeasureOptions& options = {});

/// `design` with the measured A, alpha, B, beta (and gamma when swept), and an uncertainty section
/// whose A, alpha, B, beta, gamma half-widths are the measured ones (other fields from the design's
/// uncertainty or the default robot's).
RobotDescription measured_description(const RobotDescription& design,
                                      const RobotMeasurement& measurement);

/// Least-squares rigid transform T (2D) minimising sum |T(from_i) - to_i|^2 (closed form).
Pose2<double> rigid_fit(const std::vector<Eigen::Vector2d>& from,
                        const std::vector<Eigen::Vector2d>& to);

}  // namespace pcr::vision

namespace pcr::vision {

/// A colour PNG for a person to check at a glance: the detected tag outlines and ids (green), the
/// clamp points (red) and the rod directions (blue, 5 mm long) projected back into the image.
void write_annotated(const GrayImage& image, const RobotMeasurement& measurement,
                     const MountLayout& layout, const CameraModel& camera, const std::string& path);

}  // namespace pcr::vision
