#include "pcr/vision/render.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "pcr/input_error.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {

namespace {

// A plane seen by the camera: its frame's pose in the camera (R, t). The ray of normalised
// coordinates (x, y) meets it at the plane point (q_x, q_y) / q_z, q = to_plane (x, y, 1), at the
// depth 1 / q_z (the inverse of the homography [r1 r2 t]); q_z <= 0: behind the camera. Every ray
// of the renderer, to the work plane and to each tag, is traced here.
struct RayToPlane {
  Eigen::Matrix3d to_plane;
  bool facing{true};  ///< the camera is on the side of the plane's +z (its printed face)

  RayToPlane(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
    Eigen::Matrix3d H;
    H << R.col(0), R.col(1), t;
    to_plane = H.inverse();
    facing = R.col(2).dot(t) < 0;
  }
  /// The plane point hit by `ray` (normalised coordinates, 1) and its depth; false when behind.
  bool hit(const Eigen::Vector3d& ray, Eigen::Vector2d* point, double* depth) const {
    const Eigen::Vector3d q = to_plane * ray;
    if (q.z() <= 0) return false;
    *point = q.head<2>() / q.z();
    *depth = 1.0 / q.z();
    return true;
  }
};

// A tag's pose in the camera frame: the plane frame's pose composed with the tag's.
RayToPlane tag_in_camera(const PlanePose& plane, const SpatialPose<double>& pose) {
  return RayToPlane(plane.rotation * pose.rotation(),
                    plane.rotation * pose.position + plane.translation);
}

SpatialPose<double> lifted(const Pose2<double>& p) {
  return SpatialPose<double>{
      Eigen::Vector3d(p.x, p.y, 0),
      Eigen::Vector4d(std::cos(0.5 * p.theta), 0, 0, std::sin(0.5 * p.theta))};
}

RenderTag3d lifted(const RenderTag& t) {
  return RenderTag3d{t.family, t.id, t.size_m, lifted(t.pose)};
}

struct TagPaint {
  RayToPlane ray;
  double cell{0};
  int total{0};
  std::vector<bool> bits;
  double half{0};  // half extent of the bitmap, m
};

struct Painter {
  const Scene& scene;
  const RenderOptions& opt;
  RayToPlane plane;
  std::vector<TagPaint> tags;

  float plane_shade(const Eigen::Vector2d& p) const {
    float value = opt.background;
    if (scene.chessboard) {
      const RenderChessboard& b = *scene.chessboard;
      const Eigen::Vector2d q = b.pose.inverse().transform(p) / b.square_m;
      // Squares -1..cols (so the inner corners are 0..cols-1), then a one-square white margin.
      if (q.x() >= -2 && q.x() < b.cols + 2 && q.y() >= -2 && q.y() < b.rows + 2) {
        value = opt.white;
        const int i = static_cast<int>(std::floor(q.x())), j = static_cast<int>(std::floor(q.y()));
        if (i >= -1 && i <= b.cols - 1 && j >= -1 && j <= b.rows - 1 && ((i + j) & 1) == 0)
          value = opt.black;
      }
    }
    for (const RenderCircle& c : scene.circles) {
      if (std::abs((p - c.centre).norm() - c.radius_m) <= 0.5 * c.width_m) value = c.intensity;
    }
    for (const RenderSegment& s : scene.segments) {
      const Eigen::Vector2d ab = s.b - s.a;
      const double t = std::clamp((p - s.a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      if ((p - s.a - t * ab).norm() <= 0.5 * s.width_m) value = s.intensity;
    }
    return value;
  }

  /// The intensity seen along `ray` (normalised coordinates, 1).
  float shade(const Eigen::Vector3d& ray) const {
    double nearest = std::numeric_limits<double>::infinity();
    float value = 0;
    Eigen::Vector2d p;
    double depth;
    for (const TagPaint& t : tags) {
      // At equal depths (tags in one plane) the later tag is drawn over the earlier.
      if (!t.ray.hit(ray, &p, &depth) || depth > nearest * (1 + 1e-9)) continue;
      const double gx = p.x() / t.cell + 0.5 * t.total, gy = 0.5 * t.total - p.y() / t.cell;
      if (gx >= 0 && gx < t.total && gy >= 0 && gy < t.total) {
        nearest = depth;
        value =
            t.bits[static_cast<std::size_t>(static_cast<int>(gy) * t.total + static_cast<int>(gx))]
                ? opt.white
                : opt.black;
      }
    }
    if (nearest < std::numeric_limits<double>::infinity()) return value;
    return plane.hit(ray, &p, &depth) ? plane_shade(p) : opt.background;
  }
};

// Pixel bounding box of a polygon in the camera frame (sampled along its edges), with a margin.
cv::Rect pixel_box(const CameraModel& camera, const std::vector<Eigen::Vector3d>& polygon) {
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const Eigen::Vector3d a = polygon[k], b = polygon[(k + 1) % polygon.size()];
    for (int j = 0; j <= 32; ++j) {
      const Eigen::Vector3d pc = a + (b - a) * (j / 32.0);
      if (pc.z() <= 0) continue;
      const Eigen::Vector2d px = camera.project(pc);
      u0 = std::min(u0, px.x());
      v0 = std::min(v0, px.y());
      u1 = std::max(u1, px.x());
      v1 = std::max(v1, px.y());
    }
  }
  if (u0 > u1) return {};
  const int x0 = std::max(0, static_cast<int>(std::floor(u0)) - 3);
  const int y0 = std::max(0, static_cast<int>(std::floor(v0)) - 3);
  const int x1 = std::min(camera.width, static_cast<int>(std::ceil(u1)) + 4);
  const int y1 = std::min(camera.height, static_cast<int>(std::ceil(v1)) + 4);
  if (x1 <= x0 || y1 <= y0) return {};
  return {x0, y0, x1 - x0, y1 - y0};
}

// The same for a polygon in the work plane.
cv::Rect pixel_box(const Scene& scene, const std::vector<Eigen::Vector2d>& polygon) {
  std::vector<Eigen::Vector3d> camera;
  for (const Eigen::Vector2d& p : polygon) camera.push_back(scene.plane.to_camera(p));
  return pixel_box(scene.camera, camera);
}

// A square of half edge `half` centred on a tag, in the camera frame (corners in
// TagDetection::corners' order).
std::vector<Eigen::Vector3d> square(const Scene& scene, const RenderTag3d& tag, double half) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector2d& c : {Eigen::Vector2d(-half, -half), Eigen::Vector2d(half, -half),
                                   Eigen::Vector2d(half, half), Eigen::Vector2d(-half, half)}) {
    const Eigen::Vector3d w =
        tag.pose.position + tag.pose.rotation() * Eigen::Vector3d(c.x(), c.y(), 0);
    out.push_back(scene.plane.rotation * w + scene.plane.translation);
  }
  return out;
}

}  // namespace

std::vector<Eigen::Vector2d> tag_corner_pixels(const Scene& scene, const RenderTag3d& tag) {
  std::vector<Eigen::Vector2d> out;
  for (const Eigen::Vector3d& p : square(scene, tag, 0.5 * tag.size_m))
    out.push_back(scene.camera.project(p));
  return out;
}

std::vector<Eigen::Vector2d> tag_corner_pixels(const Scene& scene, const RenderTag& tag) {
  return tag_corner_pixels(scene, lifted(tag));
}

GrayImage render_scene(const Scene& scene, const RenderOptions& opt) {
  require_valid(opt, "render_scene");
  for (const RenderCircle& c : scene.circles) require_valid(c, "render_scene: circle");
  const CameraModel& cam = scene.camera;
  if (cam.width <= 0 || cam.height <= 0) throw std::invalid_argument("render_scene: empty camera");
  Painter painter{scene, opt, RayToPlane(scene.plane.rotation, scene.plane.translation), {}};
  std::vector<cv::Rect> boxes;
  std::vector<RenderTag3d> tags = scene.tags_3d;
  for (const RenderTag& t : scene.tags) tags.push_back(lifted(t));
  for (const RenderTag3d& t : tags) {
    int total = 0, wab = 0;
    std::vector<bool> bits = tag_bitmap(t.family, t.id, &total, &wab);
    const double cell = t.size_m / wab, half = 0.5 * total * cell;
    const RayToPlane ray = tag_in_camera(scene.plane, t.pose);
    if (!ray.facing) continue;  // seen from behind: the board hides it
    painter.tags.push_back(TagPaint{ray, cell, total, std::move(bits), half});
    boxes.push_back(pixel_box(cam, square(scene, t, half)));
  }
  for (const RenderSegment& s : scene.segments) {
    const Eigen::Vector2d t = (s.b - s.a).normalized(), n(-t.y(), t.x());
    const double w = 0.5 * s.width_m;
    boxes.push_back(pixel_box(scene, {s.a - w * n - w * t, s.b - w * n + w * t, s.b + w * n + w * t,
                                      s.a + w * n - w * t}));
  }
  for (const RenderCircle& c : scene.circles) {
    // Boxes around short arcs only, so the disc's interior is not supersampled.
    constexpr int kArcs = 72;
    const double h = M_PI / kArcs, r0 = std::max(0.0, c.radius_m - c.width_m),
                 r1 = (c.radius_m + c.width_m) / std::cos(h);
    for (int k = 0; k < kArcs; ++k) {
      const Eigen::Vector2d u0(std::cos(2 * h * k), std::sin(2 * h * k)),
          u1(std::cos(2 * h * (k + 1)), std::sin(2 * h * (k + 1)));
      boxes.push_back(pixel_box(
          scene, {c.centre + r0 * u0, c.centre + r1 * u0, c.centre + r1 * u1, c.centre + r0 * u1}));
    }
  }
  if (scene.chessboard) {
    const RenderChessboard& b = *scene.chessboard;
    const Pose2<double>& P = b.pose;
    const double q = b.square_m;
    boxes.push_back(
        pixel_box(scene, {P.transform({-2 * q, -2 * q}), P.transform({(b.cols + 2) * q, -2 * q}),
                          P.transform({(b.cols + 2) * q, (b.rows + 2) * q}),
                          P.transform({-2 * q, (b.rows + 2) * q})}));
  }

  GrayImage image(cam.width, cam.height, opt.background);
  std::vector<uint8_t> done(image.pixels.size(), 0);
  const int s = std::max(1, opt.supersampling);
  constexpr int kGrid = 4;  // normalised coordinates on a 4 px grid, interpolated (error < 1e-4 px)
  for (const cv::Rect& box : boxes) {
    if (box.area() == 0) continue;
    const int gw = box.width / kGrid + 2, gh = box.height / kGrid + 2;
    std::vector<Eigen::Vector2d> grid(static_cast<std::size_t>(gw * gh));
    for (int j = 0; j < gh; ++j)
      for (int i = 0; i < gw; ++i)
        grid[j * gw + i] =
            cam.normalize(Eigen::Vector2d(box.x - 0.5 + i * kGrid, box.y - 0.5 + j * kGrid));
    for (int v = box.y; v < box.y + box.height; ++v) {
      for (int u = box.x; u < box.x + box.width; ++u) {
        const std::size_t idx = static_cast<std::size_t>(v) * cam.width + u;
        if (done[idx]) continue;
        done[idx] = 1;
        double sum = 0;
        for (int b = 0; b < s; ++b) {
          for (int a = 0; a < s; ++a) {
            const double gx = (u - box.x + (a + 0.5) / s) / kGrid,
                         gy = (v - box.y + (b + 0.5) / s) / kGrid;
            const int i = std::min(static_cast<int>(gx), gw - 2),
                      j = std::min(static_cast<int>(gy), gh - 2);
            const double fx = gx - i, fy = gy - j;
            const Eigen::Vector2d xn =
                (1 - fy) * ((1 - fx) * grid[j * gw + i] + fx * grid[j * gw + i + 1]) +
                fy * ((1 - fx) * grid[(j + 1) * gw + i] + fx * grid[(j + 1) * gw + i + 1]);
            sum += painter.shade(Eigen::Vector3d(xn.x(), xn.y(), 1.0));
          }
        }
        image.pixels[idx] = static_cast<float>(sum / (s * s));
      }
    }
  }

  cv::Mat m(image.height, image.width, CV_32F, image.pixels.data());
  if (opt.gradient != 0.0) {
    const double ca = std::cos(opt.gradient_angle), sa = std::sin(opt.gradient_angle);
    for (int v = 0; v < image.height; ++v) {
      float* row = m.ptr<float>(v);
      for (int u = 0; u < image.width; ++u) {
        row[u] *= static_cast<float>(1.0 + opt.gradient * ((u / double(image.width) - 0.5) * ca +
                                                           (v / double(image.height) - 0.5) * sa));
      }
    }
  }
  if (opt.blur_sigma_px > 0) cv::GaussianBlur(m, m, cv::Size(0, 0), opt.blur_sigma_px);
  if (opt.noise_sigma > 0) {
    std::mt19937 rng(opt.seed);
    std::normal_distribution<float> noise(0.f, static_cast<float>(opt.noise_sigma));
    for (float& p : image.pixels) p += noise(rng);
  }
  for (float& p : image.pixels) p = std::clamp(p, 0.f, 1.f);
  return image;
}

}  // namespace pcr::vision

namespace pcr::vision {

std::vector<RenderTag> mount_tags(const MountLayout& layout, const RobotParams<double>& robot,
                                  const Pose2<double>& platform, const std::vector<double>& q,
                                  std::vector<RenderSegment>* segments) {
  std::vector<RenderTag> tags;
  const int n = robot.num_limbs;
  std::vector<Eigen::Vector2d> A(n), B(n);
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& l = robot.limb(i);
    A[i] = l.proximal_position(i < static_cast<int>(q.size()) ? q[i] : 0.0);
    B[i] = platform.transform(l.B);
  }
  for (const Mount& m : layout.mounts) {
    if (m.limb >= n)
      throw InputError("mount " + m.name + ": limb " + std::to_string(m.limb) +
                       " is not in the robot");
    const LimbParams<double>& l = robot.limb(m.limb);
    const bool proximal = m.role == MountRole::kProximal;
    const Eigen::Vector2d clamp = proximal ? A[m.limb] : B[m.limb];
    const double rod = proximal ? l.alpha : l.beta + platform.theta;
    RenderTag t;
    t.family = m.family;
    t.id = m.id;
    t.size_m = m.tag_size;
    t.pose.theta = rod - m.rod_angle;
    const Eigen::Vector2d c = clamp - t.pose.rotate(m.clamp_offset);
    t.pose.x = c.x();
    t.pose.y = c.y();
    tags.push_back(t);
  }
  if (segments) {
    for (int i = 0; i < n; ++i) segments->push_back(RenderSegment{A[i], B[i], 125e-6, 0.2f});
  }
  return tags;
}

}  // namespace pcr::vision

namespace pcr::vision {

std::vector<RenderTag3d> board_tags(const TagBoard& board,
                                    const SpatialPose<double>& plane_T_board) {
  std::vector<RenderTag3d> out;
  for (const BoardTag& t : board.tags)
    out.push_back(RenderTag3d{t.family, t.id, t.size_m, plane_T_board * t.pose});
  return out;
}

}  // namespace pcr::vision
