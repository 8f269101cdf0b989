#include "pcr/vision/tag_board.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <set>
#include <utility>

#include "pcr/input_error.hpp"

namespace pcr::vision {

namespace {

std::string tag_name(const BoardTag& t) { return t.family + " id " + std::to_string(t.id); }

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity() + skew(w);
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

// Reprojection residuals (undistorted coordinates times the focal length, px) of the corners
// `points` (in M) seen at `observed` (normalised), for the pose (R, t) of M in the camera, and
// their Jacobian with respect to (dp, dtheta): t + dp, R exp([dtheta]x).
void residuals(const std::vector<Eigen::Vector3d>& points,
               const std::vector<Eigen::Vector2d>& observed, const Eigen::Matrix3d& R,
               const Eigen::Vector3d& t, double f, Eigen::VectorXd* r, Eigen::MatrixXd* J) {
  const int m = static_cast<int>(points.size());
  r->resize(2 * m);
  if (J) J->resize(2 * m, 6);
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector3d c = R * points[k] + t;
    const double iz = 1.0 / c.z();
    r->segment<2>(2 * k) = f * (Eigen::Vector2d(c.x() * iz, c.y() * iz) - observed[k]);
    if (!J) continue;
    Eigen::Matrix<double, 2, 3> dproj;
    dproj << iz, 0, -c.x() * iz * iz, 0, iz, -c.y() * iz * iz;
    J->block<2, 3>(2 * k, 0) = f * dproj;
    J->block<2, 3>(2 * k, 3) = -f * dproj * R * skew(points[k]);
  }
}

// The corners where adjacent lines of a tag's border meet (corner k between line k - 1 and line
// k), the lines given by their points `mid` and directions `dir`.
Eigen::Matrix<double, 8, 1> intersections(const std::array<Eigen::Vector2d, 4>& mid,
                                          const std::array<Eigen::Vector2d, 4>& dir) {
  Eigen::Matrix<double, 8, 1> out;
  for (int k = 0; k < 4; ++k) {
    const int a = (k + 3) % 4, b = k;
    Eigen::Matrix2d A;
    A << dir[a], -dir[b];
    const Eigen::Vector2d s = A.partialPivLu().solve(mid[b] - mid[a]);
    out.segment<2>(2 * k) = mid[a] + s[0] * dir[a];
  }
  return out;
}

// The covariance of a tag's four corners (px^2, per unit variance of the edge points about their
// lines), as the detector makes them (pcr/vision/tags.cpp, refine_quad): each border edge is a
// line fitted to about one point per pixel of its length L spread over its middle 80 %, so the
// line's offset at its middle has variance 1 / N and its angle 12 / (N (0.8 L)^2); the corners
// are the intersections of adjacent lines. Adjacent corners share a line, so their errors are
// correlated: a line's offset moves both alike, its angle moves them apart, and the tag's centre
// is known better than four independent corners would say.
Eigen::Matrix<double, 8, 8> corner_covariance(const std::array<Eigen::Vector2d, 4>& corners) {
  std::array<Eigen::Vector2d, 4> mid, dir;
  Eigen::Matrix<double, 8, 1> variance;
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d d = corners[(e + 1) % 4] - corners[e];
    const double L = d.norm(), n = std::max(8.0, std::floor(L));
    mid[e] = corners[e] + 0.5 * d;
    dir[e] = d / L;
    variance[2 * e] = 1.0 / n;
    variance[2 * e + 1] = 12.0 / (n * 0.64 * L * L);
  }
  // d corners / d (offset, angle) of each line, by central differences (exactly linear in the
  // offsets; the angles' step is far below any curvature that matters).
  Eigen::Matrix<double, 8, 8> G;
  for (int e = 0; e < 4; ++e) {
    for (int which = 0; which < 2; ++which) {
      const double h = which == 0 ? 1e-4 : 1e-6;
      std::array<Eigen::Vector2d, 4> mp = mid, mm = mid, dp = dir, dm = dir;
      if (which == 0) {
        const Eigen::Vector2d normal(-dir[e].y(), dir[e].x());
        mp[e] += h * normal;
        mm[e] -= h * normal;
      } else {
        dp[e] = Eigen::Rotation2Dd(h) * dir[e];
        dm[e] = Eigen::Rotation2Dd(-h) * dir[e];
      }
      G.col(2 * e + which) = (intersections(mp, dp) - intersections(mm, dm)) / (2 * h);
    }
  }
  return G * variance.asDiagonal() * G.transpose();
}

}  // namespace

std::array<Eigen::Vector3d, 4> BoardTag::corners() const {
  const double h = 0.5 * size_m;
  const Eigen::Matrix3d R = pose.rotation();
  std::array<Eigen::Vector3d, 4> out;
  const Eigen::Vector2d c[4] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
  for (int k = 0; k < 4; ++k) out[k] = pose.position + R * Eigen::Vector3d(c[k].x(), c[k].y(), 0);
  return out;
}

void check_board(const TagBoard& board, const std::string& source) {
  if (board.tags.empty()) throw InputError(source + ": the tag board has no tags");
  std::set<std::pair<std::string, int>> seen;
  for (std::size_t i = 0; i < board.tags.size(); ++i) {
    const BoardTag& t = board.tags[i];
    const std::string who = source + ": board tag " + std::to_string(i) + " (" + tag_name(t) + ")";
    if (!is_known_family(t.family))
      throw InputError(who + ": unknown family (known: " + known_families() + ")");
    int total = 0, border = 0;
    try {
      tag_bitmap(t.family, t.id, &total, &border);
    } catch (const InputError& e) {
      throw InputError(who + ": " + e.what());
    }
    if (!(t.size_m > 0 && t.size_m < 10))
      throw InputError(who + ": size " + std::to_string(t.size_m) + " m is not in (0, 10) m");
    if (!seen.insert({t.family, t.id}).second)
      throw InputError(who + ": the board has this family and id twice");
  }
}

BoardPose fit_board_pose(const std::vector<TagDetection>& detections,
                         const std::vector<int>& board_index, const TagBoard& board,
                         const CameraModel& camera, const std::string& source,
                         const PoseOptions& options) {
  if (board_index.size() != detections.size())
    throw std::invalid_argument("fit_board_pose: one board index per detection");
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> observed;
  for (std::size_t k = 0; k < detections.size(); ++k) {
    const auto corners = board.tags.at(static_cast<std::size_t>(board_index[k])).corners();
    for (int c = 0; c < 4; ++c) {
      points.push_back(corners[c]);
      observed.push_back(detections[k].corners_normalized[c]);
    }
  }
  const int m = static_cast<int>(points.size());
  if (m < 4)
    throw InputError(source + ": " + std::to_string(m) +
                     " tag corners are too few for the board's pose (at least 4: one tag)");

  // Initial pose: SQPnP (any point set, planar or not) in normalised coordinates.
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (int k = 0; k < m; ++k) {
    obj.emplace_back(points[k].x(), points[k].y(), points[k].z());
    img.emplace_back(observed[k].x(), observed[k].y());
  }
  cv::Mat rvec, tvec;
  if (!cv::solvePnP(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                    cv::SOLVEPNP_SQPNP))
    throw InputError(source + ": no pose of the board fits its " + std::to_string(m) +
                     " tag corners");
  cv::Mat Rm;
  cv::Rodrigues(rvec, Rm);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R(i, j) = Rm.at<double>(i, j);
    t[i] = tvec.at<double>(i);
  }

  // Each tag's residuals are whitened by its corner covariance's Cholesky factor (generalised
  // least squares): r_w = L^-1 r, J_w = L^-1 J.
  const double f = camera.focal_px();
  std::vector<Eigen::Matrix<double, 8, 8>> whiten;
  double floor_sq = 0;
  for (const TagDetection& d : detections) {
    std::array<Eigen::Vector2d, 4> px;
    for (int c = 0; c < 4; ++c) px[c] = f * d.corners_normalized[c];
    const Eigen::Matrix<double, 8, 8> C = corner_covariance(px);
    // The least sigma for this tag: the detector's own edge scatter, plus what makes its corners'
    // variance reach corner_sigma_floor_px^2 more (the systematic corner error).
    floor_sq += d.edge_rms_px * d.edge_rms_px +
                options.corner_sigma_floor_px * options.corner_sigma_floor_px / (C.trace() / 8);
    const Eigen::Matrix<double, 8, 8> L = C.llt().matrixL();
    whiten.push_back(L.inverse());
  }
  const auto evaluate = [&](const Eigen::Matrix3d& Rc, const Eigen::Vector3d& tc,
                            Eigen::VectorXd* r, Eigen::MatrixXd* J) {
    residuals(points, observed, Rc, tc, f, r, J);
    for (std::size_t k = 0; k < whiten.size(); ++k) {
      r->segment<8>(8 * k) = whiten[k] * r->segment<8>(8 * k);
      if (J) J->middleRows<8>(8 * k) = whiten[k] * J->middleRows<8>(8 * k);
    }
  };

  // Gauss-Newton; a step that does not lower the cost is halved (at most 30 times).
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  evaluate(R, t, &r, &J);
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    const Eigen::Matrix<double, 6, 1> delta = -(J.transpose() * J).ldlt().solve(J.transpose() * r);
    double scale = 1.0;
    bool lowered = false;
    for (int half = 0; half < 30 && !lowered; ++half, scale *= 0.5) {
      const Eigen::Matrix3d Rn = R * exp_so3(scale * delta.tail<3>());
      const Eigen::Vector3d tn = t + scale * delta.head<3>();
      Eigen::VectorXd rn;
      evaluate(Rn, tn, &rn, nullptr);
      if (rn.squaredNorm() <= r.squaredNorm()) {
        R = Rn;
        t = tn;
        lowered = true;
      }
    }
    evaluate(R, t, &r, &J);
    if (!lowered || scale * delta.norm() < 1e-14) break;
  }

  BoardPose out;
  out.camera_T_board = SpatialPose<double>{t, Eigen::Vector4d::Zero()};
  const Eigen::Quaterniond q(R);
  out.camera_T_board.orientation << q.w(), q.x(), q.y(), q.z();
  Eigen::VectorXd raw;
  residuals(points, observed, R, t, f, &raw, nullptr);
  out.corner_rms_px = std::sqrt(raw.squaredNorm() / m);
  const double sigma_hat = 2 * m > 6 ? std::sqrt(r.squaredNorm() / (2 * m - 6)) : 0.0;
  double edge_rms_sq = 0;  // the detector's own edge-point scatter, mean over the tags
  for (const TagDetection& d : detections) edge_rms_sq += d.edge_rms_px * d.edge_rms_px;
  edge_rms_sq /= static_cast<double>(detections.size());
  out.edge_sigma_px = std::max({sigma_hat, std::sqrt(edge_rms_sq), options.corner_sigma_floor_px});
  out.covariance = out.edge_sigma_px * out.edge_sigma_px *
                   (J.transpose() * J).ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
  out.detections = detections;
  out.board_index = board_index;
  out.iterations = it;
  return out;
}

namespace {

// The board's tags among `all`, with their indices into board.tags; InputError for a board tag
// seen twice or that check_detection refuses.
void match_board(const std::vector<TagDetection>& all, const TagBoard& board,
                 const GrayImage& image, const std::string& source,
                 std::vector<TagDetection>* matched, std::vector<int>* index) {
  for (std::size_t i = 0; i < board.tags.size(); ++i) {
    const BoardTag& t = board.tags[i];
    const std::string who = "board tag " + std::to_string(i) + " (" + tag_name(t) + ")";
    std::vector<const TagDetection*> hits;
    for (const TagDetection& d : all)
      if (d.family == t.family && d.id == t.id) hits.push_back(&d);
    if (hits.empty()) continue;
    if (hits.size() > 1)
      throw InputError(source + ": " + who + " appears " + std::to_string(hits.size()) +
                       " times in the image");
    check_detection(*hits.front(), image, source, who);
    matched->push_back(*hits.front());
    index->push_back(static_cast<int>(i));
  }
}

std::vector<TagDetection> detect_board(const GrayImage& image, const TagBoard& board,
                                       const CameraModel& camera, const DetectorOptions& options) {
  std::set<std::string> families;
  for (const BoardTag& t : board.tags) families.insert(t.family);
  return detect_families(image, families, camera, options);
}

}  // namespace

BoardPose measure_board_pose(const GrayImage& image, const std::string& source,
                             const TagBoard& board, const CameraModel& camera,
                             const MeasureOptions& options) {
  check_board(board, source + ": tag board");
  const std::vector<TagDetection> all = detect_board(image, board, camera, options.detector);
  std::vector<TagDetection> matched;
  std::vector<int> index;
  match_board(all, board, image, source, &matched, &index);
  if (matched.empty()) {
    std::string ids, seen;
    for (const BoardTag& t : board.tags) ids += (ids.empty() ? "" : ", ") + tag_name(t);
    for (const TagDetection& d : all)
      seen += (seen.empty() ? "" : ", ") + d.family + " id " + std::to_string(d.id);
    throw InputError(source + ": no tag of the board (" + ids + ") found in the image (detected: " +
                     (seen.empty() ? std::string("none") : seen) +
                     "); is the board hidden, out of view, or of another family?");
  }
  return fit_board_pose(matched, index, board, camera, source, options.pose);
}

std::vector<TagPointMeasurement> measure_tag_points(const GrayImage& image,
                                                    const std::string& source,
                                                    const std::vector<TagPoint>& points,
                                                    const CameraModel& camera,
                                                    const MeasureOptions& options) {
  TagBoard tags;  // each point's tag at the identity: its own frame
  for (const TagPoint& p : points) tags.tags.push_back(p.tag);
  for (BoardTag& t : tags.tags) t.pose = SpatialPose<double>{};
  check_board(tags, source + ": tag points");
  const std::vector<TagDetection> all = detect_board(image, tags, camera, options.detector);
  std::vector<TagDetection> matched;
  std::vector<int> index;
  match_board(all, tags, image, source, &matched, &index);
  std::vector<TagPointMeasurement> out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const TagPoint& p = points[i];
    const auto found = std::find(index.begin(), index.end(), static_cast<int>(i));
    if (found == index.end())
      throw InputError(source + ": point " + p.name + ": its tag (" + tag_name(p.tag) +
                       ") is not found in the image; is it hidden, out of view, or of another "
                       "family?");
    const std::size_t k = static_cast<std::size_t>(found - index.begin());
    TagPointMeasurement m;
    m.tag = fit_board_pose({matched[k]}, {static_cast<int>(i)}, tags, camera,
                           source + ": point " + p.name, options.pose);
    // p = t + R o; d p / d (dp, dtheta) = [I, -R [o]x].
    const Eigen::Matrix3d R = m.tag.camera_T_board.rotation();
    m.position = m.tag.camera_T_board.position + R * p.offset;
    Eigen::Matrix<double, 3, 6> D;
    D << Eigen::Matrix3d::Identity(), -R * skew(p.offset);
    m.covariance = D * m.tag.covariance * D.transpose();
    out.push_back(m);
  }
  return out;
}

}  // namespace pcr::vision
