#include "pcr/vision/measure.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <set>
#include <stdexcept>

#include "pcr/files.hpp"

namespace pcr::vision {

namespace {

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

std::array<Eigen::Vector2d, 4> tag_points(double size) {
  const double h = 0.5 * size;
  return {Eigen::Vector2d(-h, -h), Eigen::Vector2d(h, -h), Eigen::Vector2d(h, h),
          Eigen::Vector2d(-h, h)};
}

// Residuals (pixels) of every corner for plane (R, t) and marker states x (3 per marker).
Eigen::VectorXd corner_residuals(const std::vector<TagDetection>& dets,
                                 const std::vector<double>& sizes, const Eigen::Matrix3d& R,
                                 const Eigen::Vector3d& t, const Eigen::VectorXd& x, double f) {
  Eigen::VectorXd r(8 * dets.size());
  for (std::size_t j = 0; j < dets.size(); ++j) {
    const Pose2<double> pose{x[3 * j], x[3 * j + 1], x[3 * j + 2]};
    const auto pts = tag_points(sizes[j]);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d p = pose.transform(pts[k]);
      const Eigen::Vector3d c = R.col(0) * p.x() + R.col(1) * p.y() + t;
      r.segment<2>(8 * j + 2 * k) =
          f * (Eigen::Vector2d(c.x() / c.z(), c.y() / c.z()) - dets[j].corners_normalized[k]);
    }
  }
  return r;
}

double wrap_near(double angle, double reference) {
  return reference + wrap_angle(angle - reference);
}

}  // namespace

Pose2<double> rigid_fit(const std::vector<Eigen::Vector2d>& from,
                        const std::vector<Eigen::Vector2d>& to) {
  if (from.size() != to.size() || from.size() < 2)
    throw std::invalid_argument("rigid_fit: need >= 2 pairs");
  Eigen::Vector2d mf = Eigen::Vector2d::Zero(), mt = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) {
    mf += from[i];
    mt += to[i];
  }
  mf /= static_cast<double>(from.size());
  mt /= static_cast<double>(to.size());
  double sc = 0, cc = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const Eigen::Vector2d a = from[i] - mf, b = to[i] - mt;
    cc += a.dot(b);
    sc += a.x() * b.y() - a.y() * b.x();
  }
  Pose2<double> T{0, 0, std::atan2(sc, cc)};
  const Eigen::Vector2d t = mt - T.rotate(mf);
  T.x = t.x();
  T.y = t.y();
  return T;
}

PlaneFit fit_planar_markers(const std::vector<TagDetection>& dets, const std::vector<double>& sizes,
                            const CameraModel& camera, const std::optional<PlanePose>& known_plane,
                            const PoseOptions& options) {
  if (dets.empty()) throw std::runtime_error("fit_planar_markers: no markers");
  if (sizes.size() != dets.size())
    throw std::invalid_argument("fit_planar_markers: one size per detection");
  const int n = static_cast<int>(dets.size());
  const double f = camera.focal_px();

  // Initial guess: each tag's pose by IPPE (square planar PnP) in normalised coordinates.
  std::vector<Eigen::Matrix3d> Rs(n);
  std::vector<Eigen::Vector3d> ts(n);
  for (int j = 0; j < n; ++j) {
    const double h = 0.5 * sizes[j];
    // IPPE_SQUARE's order: (-h, h), (h, h), (h, -h), (-h, -h) = our corners 3, 2, 1, 0.
    std::vector<cv::Point3d> obj{{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
    std::vector<cv::Point2d> img;
    for (int k : {3, 2, 1, 0})
      img.emplace_back(dets[j].corners_normalized[k].x(), dets[j].corners_normalized[k].y());
    cv::Mat rvec, tvec;
    cv::solvePnP(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                 cv::SOLVEPNP_IPPE_SQUARE);
    cv::Mat Rm;
    cv::Rodrigues(rvec, Rm);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) Rs[j](r, c) = Rm.at<double>(r, c);
      ts[j][r] = tvec.at<double>(r);
    }
  }
  PlanePose plane;
  if (known_plane) {
    plane = *known_plane;
  } else {
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(), origin = Eigen::Vector3d::Zero();
    for (int j = 0; j < n; ++j) {
      normal += Rs[j].col(2);
      origin += ts[j];
    }
    normal.normalize();
    origin /= n;
    Eigen::Vector3d x = Rs[0].col(0) - Rs[0].col(0).dot(normal) * normal;
    x.normalize();
    plane.rotation.col(0) = x;
    plane.rotation.col(1) = normal.cross(x);
    plane.rotation.col(2) = normal;
    // Move the origin along the normal so the markers' mean lies in the plane.
    plane.translation = origin;
  }
  Eigen::VectorXd x(3 * n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d d = plane.rotation.transpose() * (ts[j] - plane.translation);
    const Eigen::Vector3d ax = plane.rotation.transpose() * Rs[j].col(0);
    x.segment<3>(3 * j) << d.x(), d.y(), std::atan2(ax.y(), ax.x());
  }

  // Gauss-Newton: marker states, and the plane's two tilts and its distance unless it is known.
  const int np = known_plane ? 0 : 3;
  const int m = 8 * n, p = 3 * n + np;
  Eigen::MatrixXd J(m, p);
  Eigen::VectorXd r;
  const auto evaluate = [&](const Eigen::VectorXd& delta, const PlanePose& base,
                            const Eigen::VectorXd& xs) {
    Eigen::Matrix3d R = base.rotation;
    Eigen::Vector3d t = base.translation;
    if (np) {
      R = base.rotation * exp_so3(Eigen::Vector3d(delta[0], delta[1], 0));
      t = base.translation + base.rotation.col(2) * delta[2];
    }
    return corner_residuals(dets, sizes, R, t, xs + delta.tail(3 * n), f);
  };
  const auto jacobian = [&]() {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(p);
    r = evaluate(zero, plane, x);
    for (int k = 0; k < p; ++k) {
      const bool angle = (k < np && k < 2) || (k >= np && (k - np) % 3 == 2);
      const double h = angle ? 1e-7 : 1e-8;
      Eigen::VectorXd d = zero;
      d[k] = h;
      const Eigen::VectorXd rp = evaluate(d, plane, x);
      d[k] = -h;
      J.col(k) = (rp - evaluate(d, plane, x)) / (2 * h);
    }
  };
  for (int it = 0; it < options.max_iterations; ++it) {
    jacobian();
    const Eigen::VectorXd delta = -(J.transpose() * J).ldlt().solve(J.transpose() * r);
    if (np) {
      plane.rotation = plane.rotation * exp_so3(Eigen::Vector3d(delta[0], delta[1], 0));
      plane.translation += plane.rotation.col(2) * delta[2];
    }
    x += delta.tail(3 * n);
    if (delta.tail(3 * n).cwiseAbs().maxCoeff() < 1e-13) break;
  }
  jacobian();

  PlaneFit fit;
  fit.plane = plane;
  fit.corner_rms_px = std::sqrt(r.squaredNorm() / m);
  const double sigma_hat = m > p ? std::sqrt(r.squaredNorm() / (m - p)) : 0.0;
  fit.corner_sigma_px =
      std::max(sigma_hat * options.corner_sigma_scale, options.corner_sigma_floor_px);
  const Eigen::MatrixXd cov = fit.corner_sigma_px * fit.corner_sigma_px *
                              (J.transpose() * J).ldlt().solve(Eigen::MatrixXd::Identity(p, p));
  fit.covariance = cov.bottomRightCorner(3 * n, 3 * n);
  for (int j = 0; j < n; ++j) {
    MarkerPose mp;
    mp.family = dets[j].family;
    mp.id = dets[j].id;
    mp.pose = Pose2<double>{x[3 * j], x[3 * j + 1], wrap_angle(x[3 * j + 2])};
    mp.covariance = fit.covariance.block<3, 3>(3 * j, 3 * j);
    fit.markers.push_back(mp);
  }
  return fit;
}

void check_detection(const TagDetection& d, const GrayImage& image, const std::string& source,
                     const std::string& who) {
  // The tag's white quiet zone (one cell) must lie inside the image too.
  const double side =
      0.25 * ((d.corners[1] - d.corners[0]).norm() + (d.corners[2] - d.corners[1]).norm() +
              (d.corners[3] - d.corners[2]).norm() + (d.corners[0] - d.corners[3]).norm());
  const double margin = side / 8.0 + 1.0;
  for (const Eigen::Vector2d& c : d.corners) {
    if (c.x() < margin || c.y() < margin || c.x() > image.width - 1 - margin ||
        c.y() > image.height - 1 - margin) {
      throw InputError(source + ": " + who + " is cut by the image border (corner at " +
                       std::to_string(c.x()) + ", " + std::to_string(c.y()) + " px)");
    }
  }
  // Clipped highlights along the border bias every edge towards the dark side (0.09 px at 5 %
  // over-exposure): the tag looks smaller, and its size is the image's only scale. No interval
  // accounts for that, so the tag is refused. A few noise peaks at full scale move each edge
  // line by far less than the noise itself.
  constexpr double kMaxClippedFraction = 0.01;
  if (d.clipped_fraction > kMaxClippedFraction) {
    char percent[32];
    std::snprintf(percent, sizeof percent, "%.1f", 100.0 * d.clipped_fraction);
    throw InputError(source + ": " + who + ": " + percent +
                     " % of the points along its edges see clipped highlights (pixels at full "
                     "scale), which shrink the tag and bias the scale; reduce the exposure or "
                     "the lighting");
  }
}

std::vector<TagDetection> match_mounts(const std::vector<TagDetection>& detections,
                                       const MountLayout& layout, const GrayImage& image,
                                       const std::string& source) {
  std::vector<TagDetection> out;
  for (const Mount& mount : layout.mounts) {
    const std::string who =
        "mount " + mount.name + " (" + mount.family + " id " + std::to_string(mount.id) + ")";
    std::vector<const TagDetection*> hits;
    for (const TagDetection& d : detections)
      if (d.family == mount.family && d.id == mount.id) hits.push_back(&d);
    if (hits.empty()) {
      std::string seen;
      for (const TagDetection& d : detections) seen += " " + d.family + ":" + std::to_string(d.id);
      throw InputError(source + ": " + who + " not found in the image (detected:" +
                       (seen.empty() ? std::string(" none") : seen) +
                       "); is it hidden, cut by the image border, or of another family?");
    }
    if (hits.size() > 1) {
      throw InputError(source + ": tag id " + std::to_string(mount.id) + " (" + mount.family +
                       ") appears " + std::to_string(hits.size()) + " times in the image; " + who +
                       " is ambiguous");
    }
    check_detection(*hits.front(), image, source, who);
    out.push_back(*hits.front());
  }
  return out;
}

std::vector<TagDetection> detect_families(const GrayImage& image,
                                          const std::set<std::string>& families,
                                          const CameraModel& camera, const DetectorOptions& base) {
  std::vector<TagDetection> all;
  for (const std::string& family : families) {
    DetectorOptions opt = base;
    opt.family = family;
    const auto d = detect_tags(image, opt, &camera);
    all.insert(all.end(), d.begin(), d.end());
  }
  return all;
}

namespace {

std::vector<TagDetection> detect_layout_families(const GrayImage& image, const MountLayout& layout,
                                                 const CameraModel& camera,
                                                 const DetectorOptions& base) {
  std::set<std::string> families;
  for (const Mount& m : layout.mounts) families.insert(m.family);
  return detect_families(image, families, camera, base);
}

// Outputs per limb (Ax, Ay, alpha, Bx, By, beta) in the design frames, from marker states m
// (3 per mount, layout order) and layout parameters o (offset x, y, rod angle per mount).
Eigen::VectorXd clamp_outputs(const MountLayout& layout, const RobotParams<double>& design,
                              const Eigen::VectorXd& m, const Eigen::VectorXd& o, Pose2<double>* W,
                              Pose2<double>* P, std::vector<LimbMeasurement>* limbs) {
  const int n = layout.num_limbs();
  std::vector<Eigen::Vector2d> A(n), B(n), Ad(n), Bd(n);
  std::vector<double> alpha(n), beta(n);
  for (std::size_t i = 0; i < layout.mounts.size(); ++i) {
    const Mount& mount = layout.mounts[i];
    const Pose2<double> tag{m[3 * i], m[3 * i + 1], m[3 * i + 2]};
    const Eigen::Vector2d clamp = tag.transform(o.segment<2>(3 * i));
    const double angle = tag.theta + o[3 * i + 2];
    if (mount.role == MountRole::kProximal) {
      A[mount.limb] = clamp;
      alpha[mount.limb] = angle;
    } else {
      B[mount.limb] = clamp;
      beta[mount.limb] = angle;
    }
  }
  for (int i = 0; i < n; ++i) {
    Ad[i] = design.limb(i).A;
    Bd[i] = design.limb(i).B;
  }
  const Pose2<double> Tw = rigid_fit(A, Ad), Tp = rigid_fit(B, Bd);
  if (W) *W = Tw.inverse();
  if (P) *P = Tp.inverse();
  Eigen::VectorXd out(6 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d a = Tw.transform(A[i]), b = Tp.transform(B[i]);
    out.segment<6>(6 * i) << a.x(), a.y(), wrap_near(alpha[i] + Tw.theta, design.limb(i).alpha),
        b.x(), b.y(), wrap_near(beta[i] + Tp.theta, design.limb(i).beta);
    if (limbs) {
      LimbMeasurement& l = (*limbs)[i];
      l.A_plane = A[i];
      l.alpha_plane = alpha[i];
      l.B_plane = B[i];
      l.beta_plane = beta[i];
    }
  }
  return out;
}

}  // namespace

Eigen::VectorXd measured_half_widths(const Eigen::MatrixXd& covariance,
                                     const Eigen::MatrixXd& tolerance_jacobian,
                                     const Eigen::VectorXd& tolerances, double coverage_factor) {
  return coverage_factor * covariance.diagonal().cwiseMax(0).cwiseSqrt() +
         tolerance_jacobian.cwiseAbs() * tolerances;
}

RobotMeasurement measure_robot(const GrayImage& image, const std::string& source,
                               const MountLayout& layout, const CameraModel& camera,
                               const RobotParams<double>& design, const MeasureOptions& options) {
  const int n = layout.num_limbs();
  if (n != design.num_limbs) {
    throw InputError("the mount layout describes " + std::to_string(n) +
                     " limbs but the design has " + std::to_string(design.num_limbs));
  }
  if (n < 2) throw InputError("the mount layout needs at least 2 limbs to define W and P");
  check_image_size(camera, image.width, image.height, "(camera)", source);
  RobotMeasurement result;
  result.detections = match_mounts(detect_layout_families(image, layout, camera, options.detector),
                                   layout, image, source);
  std::vector<double> sizes;
  for (const Mount& mnt : layout.mounts) sizes.push_back(mnt.tag_size);
  result.fit = fit_planar_markers(result.detections, sizes, camera, std::nullopt, options.pose);

  const int k = static_cast<int>(layout.mounts.size());
  Eigen::VectorXd m(3 * k), o(3 * k), oh(3 * k);
  for (int i = 0; i < k; ++i) {
    const MarkerPose& mp = result.fit.markers[i];
    m.segment<3>(3 * i) << mp.pose.x, mp.pose.y, mp.pose.theta;
    const Mount& mnt = layout.mounts[i];
    o.segment<3>(3 * i) << mnt.clamp_offset.x(), mnt.clamp_offset.y(), mnt.rod_angle;
    oh.segment<3>(3 * i) << mnt.clamp_offset_uncertainty.x(), mnt.clamp_offset_uncertainty.y(),
        mnt.rod_angle_uncertainty;
  }
  result.limbs.resize(n);
  const Eigen::VectorXd y = clamp_outputs(layout, design, m, o, &result.world_in_plane,
                                          &result.platform_in_plane, &result.limbs);
  // Linear propagation, by central differences.
  const auto jac = [&](bool of_markers) {
    Eigen::MatrixXd J(y.size(), 3 * k);
    for (int c = 0; c < 3 * k; ++c) {
      const double h = (c % 3 == 2) ? 1e-7 : 1e-8;
      Eigen::VectorXd mp = m, mm = m, op = o, om = o;
      (of_markers ? mp : op)[c] += h;
      (of_markers ? mm : om)[c] -= h;
      J.col(c) = (clamp_outputs(layout, design, mp, op, nullptr, nullptr, nullptr) -
                  clamp_outputs(layout, design, mm, om, nullptr, nullptr, nullptr)) /
                 (2 * h);
    }
    return J;
  };
  const Eigen::MatrixXd Jm = jac(true), Jo = jac(false);
  const Eigen::VectorXd half = measured_half_widths(Jm * result.fit.covariance * Jm.transpose(), Jo,
                                                    oh, options.coverage_factor);
  for (int i = 0; i < n; ++i) {
    LimbMeasurement& l = result.limbs[i];
    l.A = y.segment<2>(6 * i);
    l.alpha = y[6 * i + 2];
    l.B = y.segment<2>(6 * i + 3);
    l.beta = y[6 * i + 5];
    l.A_halfwidth = half.segment<2>(6 * i);
    l.alpha_halfwidth = half[6 * i + 2];
    l.B_halfwidth = half.segment<2>(6 * i + 3);
    l.beta_halfwidth = half[6 * i + 5];
  }
  std::vector<Eigen::Vector2d> a, b;
  double sa = 0, sb = 0;
  for (int i = 0; i < n; ++i) {
    sa += (result.limbs[i].A - design.limb(i).A).squaredNorm();
    sb += (result.limbs[i].B - design.limb(i).B).squaredNorm();
  }
  result.registration_rms_A = std::sqrt(sa / n);
  result.registration_rms_B = std::sqrt(sb / n);
  return result;
}

SweepResult measure_sweep(const std::vector<GrayImage>& images,
                          const std::vector<std::string>& sources, int limb,
                          const MountLayout& layout, const CameraModel& camera,
                          RobotMeasurement& home, const MeasureOptions& options) {
  const int idx = layout.find(limb, MountRole::kProximal);
  if (idx < 0 || limb >= static_cast<int>(home.limbs.size())) {
    throw InputError("sweep: limb " + std::to_string(limb) +
                     " has no proximal mount in the layout");
  }
  if (images.size() < 3) {
    throw InputError("sweep of limb " + std::to_string(limb) + ": need at least 3 images, got " +
                     std::to_string(images.size()));
  }
  const Mount& mount = layout.mounts[idx];
  MountLayout single;
  single.mounts.push_back(mount);
  SweepResult result;
  double var_perp = 0;
  std::vector<Eigen::Matrix2d> covs;
  for (std::size_t s = 0; s < images.size(); ++s) {
    check_image_size(camera, images[s].width, images[s].height, "(camera)", sources[s]);
    DetectorOptions opt = options.detector;
    opt.family = mount.family;
    const auto dets =
        match_mounts(detect_tags(images[s], opt, &camera), single, images[s], sources[s]);
    const PlaneFit fit =
        fit_planar_markers(dets, {mount.tag_size}, camera, home.fit.plane, options.pose);
    result.centres.emplace_back(fit.markers[0].pose.x, fit.markers[0].pose.y);
    covs.push_back(fit.markers[0].covariance.topLeftCorner<2, 2>());
  }
  // Total least squares line through the centres.
  const int n = static_cast<int>(result.centres.size());
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& c : result.centres) mean += c;
  mean /= n;
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (const auto& c : result.centres) S += (c - mean) * (c - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(S);
  Eigen::Vector2d dir = es.eigenvectors().col(1);
  if (dir.dot(result.centres.back() - result.centres.front()) < 0) dir = -dir;
  const Eigen::Vector2d normal(-dir.y(), dir.x());
  double ss = 0, res = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d d = result.centres[i] - mean;
    ss += d.dot(dir) * d.dot(dir);
    res += d.dot(normal) * d.dot(normal);
    var_perp += normal.dot(covs[i] * normal);
  }
  if (ss <= 0)
    throw InputError("sweep of limb " + std::to_string(limb) + ": the marker did not move");
  result.line_rms = std::sqrt(res / n);
  // The perpendicular scatter: the larger of the residuals' and the markers' own covariance.
  const double sigma_perp = std::sqrt(std::max(res / std::max(1, n - 2), var_perp / n));
  result.direction_plane = std::atan2(dir.y(), dir.x());
  result.direction_sigma = sigma_perp / std::sqrt(ss);
  LimbMeasurement& l = home.limbs[limb];
  const double sigma_theta = std::sqrt(std::max(0.0, home.fit.markers[idx].covariance(2, 2)));
  result.gamma = wrap_angle(result.direction_plane - l.alpha_plane);
  result.gamma_halfwidth =
      options.coverage_factor * std::hypot(result.direction_sigma, sigma_theta) +
      mount.rod_angle_uncertainty;
  l.gamma = result.gamma;
  l.gamma_halfwidth = result.gamma_halfwidth;
  return result;
}

RobotDescription measured_description(const RobotDescription& design,
                                      const RobotMeasurement& measurement) {
  RobotDescription out = design;
  const int n = design.params.num_limbs;
  RobotUncertainty unc = design.uncertainty ? *design.uncertainty : *default_robot().uncertainty;
  if (static_cast<int>(unc.limbs.size()) != n)
    unc.limbs.assign(static_cast<std::size_t>(n), unc.global);
  for (int i = 0; i < n && i < static_cast<int>(measurement.limbs.size()); ++i) {
    const LimbMeasurement& l = measurement.limbs[i];
    LimbParams<double>& p = out.params.limb(i);
    LimbUncertainty& u = unc.limbs[i];
    p.A = l.A;
    p.alpha = l.alpha;
    p.B = l.B;
    p.beta = l.beta;
    u.A = l.A_halfwidth;
    u.alpha = l.alpha_halfwidth;
    u.B = l.B_halfwidth;
    u.beta = l.beta_halfwidth;
    if (l.gamma) {
      p.gamma = *l.gamma;
      u.gamma = *l.gamma_halfwidth;
    }
  }
  out.uncertainty = unc;
  return out;
}

}  // namespace pcr::vision

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace pcr::vision {

void write_annotated(const GrayImage& image, const RobotMeasurement& m, const MountLayout& layout,
                     const CameraModel& camera, const std::string& path) {
  cv::Mat f(image.height, image.width, CV_32F, const_cast<float*>(image.pixels.data())), u8, bgr;
  f.convertTo(u8, CV_8U, 255.0);
  cv::cvtColor(u8, bgr, cv::COLOR_GRAY2BGR);
  const int thick = std::max(1, image.width / 800);
  const auto px = [&](const Eigen::Vector2d& plane_point) {
    const Eigen::Vector2d p = camera.project(m.fit.plane.to_camera(plane_point));
    return cv::Point(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
  };
  for (std::size_t i = 0; i < m.detections.size(); ++i) {
    const TagDetection& d = m.detections[i];
    for (int k = 0; k < 4; ++k) {
      cv::line(bgr, cv::Point2d(d.corners[k].x(), d.corners[k].y()),
               cv::Point2d(d.corners[(k + 1) % 4].x(), d.corners[(k + 1) % 4].y()), {0, 200, 0},
               thick);
    }
    const Eigen::Vector2d c = 0.25 * (d.corners[0] + d.corners[1] + d.corners[2] + d.corners[3]);
    cv::putText(bgr, layout.mounts[i].name + " id " + std::to_string(d.id),
                cv::Point2d(c.x(), c.y()), cv::FONT_HERSHEY_SIMPLEX, 0.6 * thick, {0, 160, 0},
                thick);
  }
  for (const LimbMeasurement& l : m.limbs) {
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector2d p = end ? l.B_plane : l.A_plane;
      const double a = end ? l.beta_plane : l.alpha_plane;
      cv::circle(bgr, px(p), 4 * thick, {0, 0, 255}, thick);
      cv::line(bgr, px(p), px(p + 0.005 * Eigen::Vector2d(std::cos(a), std::sin(a))), {255, 0, 0},
               thick);
    }
  }
  OutputFile file(path, OutputFile::Writer::kExternal, ".png");
  if (!cv::imwrite(file.temp_path(), bgr)) {
    throw std::runtime_error(path + ": cannot write the annotated image");
  }
  file.commit();
}

}  // namespace pcr::vision
