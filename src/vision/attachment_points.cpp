#include "pcr/vision/attachment_points.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include "pcr/input_error.hpp"
#include "pcr/spatial/rigid_fit.hpp"

namespace pcr::vision {

namespace {

// The points `camera` (3 per point, in S) mapped into F by their least-squares fit onto `design`
// (in F); the fit ^F T_S in `frame_T_camera` when given.
Eigen::VectorXd registered(const Eigen::VectorXd& camera,
                           const std::vector<Eigen::Vector3d>& design,
                           SpatialPose<double>* frame_T_camera) {
  const int n = static_cast<int>(design.size());
  std::vector<Eigen::Vector3d> from(design.size());
  for (int i = 0; i < n; ++i) from[static_cast<std::size_t>(i)] = camera.segment<3>(3 * i);
  const SpatialPose<double> T = fit_rigid_motion(from.data(), design.data(), n);
  if (frame_T_camera) *frame_T_camera = T;
  const Eigen::Matrix3d R = T.rotation();
  Eigen::VectorXd out(3 * n);
  for (int i = 0; i < n; ++i)
    out.segment<3>(3 * i) = T.position + R * from[static_cast<std::size_t>(i)];
  return out;
}

}  // namespace

PointRegistration register_points(const std::vector<TagPoint>& points,
                                  const std::vector<TagPointMeasurement>& measured,
                                  const std::vector<Eigen::Vector3d>& design,
                                  double coverage_factor, const std::string& what) {
  const int n = static_cast<int>(design.size());
  if (points.size() != design.size() || measured.size() != design.size())
    throw std::invalid_argument("register_points: one point and one measurement per design point");
  if (n < 3) {
    throw InputError(what + ": " + std::to_string(n) +
                     " points cannot define a frame (a rigid registration needs at least 3 that "
                     "are not collinear)");
  }
  // The frame's rotation about a line through collinear points is undetermined (fit_rigid_motion
  // would keep it the identity, silently).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : design) centroid += p / n;
  Eigen::MatrixXd centred(3, n);
  for (int i = 0; i < n; ++i) centred.col(i) = design[static_cast<std::size_t>(i)] - centroid;
  const Eigen::Vector3d spread = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  if (!(spread[1] > 1e-6 * spread[0])) {
    throw InputError(what +
                     ": the design's points are collinear, so a rigid registration onto them "
                     "leaves the frame's rotation about their line undetermined");
  }

  Eigen::VectorXd camera(3 * n), tolerances(3 * n);
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Eigen::MatrixXd offset_jacobian = Eigen::MatrixXd::Zero(3 * n, 3 * n);  // d camera / d offsets
  for (int i = 0; i < n; ++i) {
    const TagPointMeasurement& m = measured[static_cast<std::size_t>(i)];
    camera.segment<3>(3 * i) = m.position;
    covariance.block<3, 3>(3 * i, 3 * i) = m.covariance;  // each point from its own tag
    offset_jacobian.block<3, 3>(3 * i, 3 * i) = m.tag.camera_T_board.rotation();  // p = t + R o
    tolerances.segment<3>(3 * i) = points[static_cast<std::size_t>(i)].offset_uncertainty;
  }
  PointRegistration out;
  SpatialPose<double> frame_T_camera;
  const Eigen::VectorXd y = registered(camera, design, &frame_T_camera);
  out.camera_T_frame = frame_T_camera.inverse();
  // d y / d camera by central differences, the fit moving with the points: the frame is defined
  // by these very points, so their noise moves it too, and the registered points' covariance
  // includes the fit's own uncertainty (it absorbs the rigid part of the noise: rank 3n - 6, each
  // point a little surer than in S). The truth registered the same way differs from y by J e for
  // the image error e, so this is the covariance the registered points are checked against.
  Eigen::MatrixXd J(3 * n, 3 * n);
  constexpr double h = 1e-7;  // m, against points about 0.1-1 m from the camera
  for (int c = 0; c < 3 * n; ++c) {
    Eigen::VectorXd plus = camera, minus = camera;
    plus[c] += h;
    minus[c] -= h;
    J.col(c) = (registered(plus, design, nullptr) - registered(minus, design, nullptr)) / (2 * h);
  }
  out.covariance = J * covariance * J.transpose();
  const Eigen::VectorXd half =
      measured_half_widths(out.covariance, J * offset_jacobian, tolerances, coverage_factor);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    out.points.push_back(y.segment<3>(3 * i));
    out.half_widths.push_back(half.segment<3>(3 * i));
    sum += (out.points.back() - design[static_cast<std::size_t>(i)]).squaredNorm();
  }
  out.rms = std::sqrt(sum / n);
  return out;
}

AttachmentMeasurement measure_attachment_points(
    const GrayImage& base_image, const std::string& base_source, const GrayImage& platform_image,
    const std::string& platform_source, const AttachmentLayout& layout, const CameraModel& camera,
    const SpatialRobotDescription& design, const MeasureOptions& options) {
  const int n = design.params.num_rods;
  if (layout.num_rods() != n) {
    throw InputError(layout.source + ": rods: " + std::to_string(layout.num_rods()) +
                     " rods, but the design '" + design.name + "' has " + std::to_string(n));
  }
  check_image_size(camera, base_image.width, base_image.height, "(camera)", base_source);
  check_image_size(camera, platform_image.width, platform_image.height, "(camera)",
                   platform_source);
  AttachmentMeasurement out;
  out.holes = measure_tag_points(base_image, base_source, layout.holes, camera, options);
  out.attachments =
      measure_tag_points(platform_image, platform_source, layout.attachments, camera, options);
  std::vector<Eigen::Vector3d> A, B;
  for (int i = 0; i < n; ++i) {
    A.push_back(design.params.limb(i).A);
    B.push_back(design.params.limb(i).B);
  }
  out.A = register_points(layout.holes, out.holes, A, options.coverage_factor,
                          "design '" + design.name + "', the holes A_i");
  out.B = register_points(layout.attachments, out.attachments, B, options.coverage_factor,
                          "design '" + design.name + "', the attachment points B_i");
  return out;
}

SpatialRobotDescription measured_spatial_description(const SpatialRobotDescription& design,
                                                     const AttachmentMeasurement& measurement) {
  SpatialRobotDescription out = design;
  const int n = design.params.num_rods;
  SpatialUncertainty u =
      design.uncertainty ? *design.uncertainty : continuum_stewart_gough_uncertainty(n);
  if (static_cast<int>(u.rods.size()) != n) u.rods.assign(static_cast<std::size_t>(n), u.global);
  for (int i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    out.params.limb(i).A = measurement.A.points.at(k);
    out.params.limb(i).B = measurement.B.points.at(k);
    u.rods[k].A = measurement.A.half_widths.at(k);
    u.rods[k].B = measurement.B.half_widths.at(k);
  }
  out.uncertainty = u;
  return out;
}

}  // namespace pcr::vision
