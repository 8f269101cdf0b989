#include "pcr/vision/render.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "pcr/input_error.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {

namespace {

struct TagPaint {
  Pose2<double> pose;
  double cell{0};
  int total{0};
  std::vector<bool> bits;
  double half{0};  // half extent of the bitmap, m
  double c{1}, s{0};
};

struct Painter {
  const Scene& scene;
  const RenderOptions& opt;
  std::vector<TagPaint> tags;

  float shade(const Eigen::Vector2d& p) const {
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
    for (const TagPaint& t : tags) {
      const Eigen::Vector2d d = p - t.pose.translation();
      if (std::abs(d.x()) > 1.5 * t.half || std::abs(d.y()) > 1.5 * t.half) continue;
      const double c = t.c, s = t.s;
      const double lx = c * d.x() + s * d.y(), ly = -s * d.x() + c * d.y();
      const double gx = lx / t.cell + 0.5 * t.total, gy = 0.5 * t.total - ly / t.cell;
      if (gx >= 0 && gx < t.total && gy >= 0 && gy < t.total) {
        value =
            t.bits[static_cast<std::size_t>(static_cast<int>(gy) * t.total + static_cast<int>(gx))]
                ? opt.white
                : opt.black;
      }
    }
    return value;
  }
};

// Pixel bounding box of a plane polygon (sampled along its edges), with a margin.
cv::Rect pixel_box(const Scene& scene, const std::vector<Eigen::Vector2d>& polygon) {
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const Eigen::Vector2d a = polygon[k], b = polygon[(k + 1) % polygon.size()];
    for (int j = 0; j <= 32; ++j) {
      const Eigen::Vector3d pc = scene.plane.to_camera(a + (b - a) * (j / 32.0));
      if (pc.z() <= 0) continue;
      const Eigen::Vector2d px = scene.camera.project(pc);
      u0 = std::min(u0, px.x());
      v0 = std::min(v0, px.y());
      u1 = std::max(u1, px.x());
      v1 = std::max(v1, px.y());
    }
  }
  if (u0 > u1) return {};
  const int x0 = std::max(0, static_cast<int>(std::floor(u0)) - 3);
  const int y0 = std::max(0, static_cast<int>(std::floor(v0)) - 3);
  const int x1 = std::min(scene.camera.width, static_cast<int>(std::ceil(u1)) + 4);
  const int y1 = std::min(scene.camera.height, static_cast<int>(std::ceil(v1)) + 4);
  if (x1 <= x0 || y1 <= y0) return {};
  return {x0, y0, x1 - x0, y1 - y0};
}

std::vector<Eigen::Vector2d> square(const Pose2<double>& pose, double half) {
  return {pose.transform({-half, -half}), pose.transform({half, -half}),
          pose.transform({half, half}), pose.transform({-half, half})};
}

}  // namespace

std::vector<Eigen::Vector2d> tag_corner_pixels(const Scene& scene, const RenderTag& tag) {
  std::vector<Eigen::Vector2d> out;
  for (const Eigen::Vector2d& p : square(tag.pose, 0.5 * tag.size_m))
    out.push_back(scene.camera.project(scene.plane.to_camera(p)));
  return out;
}

GrayImage render_scene(const Scene& scene, const RenderOptions& opt) {
  require_valid(opt, "render_scene");
  for (const RenderCircle& c : scene.circles) require_valid(c, "render_scene: circle");
  const CameraModel& cam = scene.camera;
  if (cam.width <= 0 || cam.height <= 0) throw std::invalid_argument("render_scene: empty camera");
  Painter painter{scene, opt, {}};
  std::vector<cv::Rect> boxes;
  for (const RenderTag& t : scene.tags) {
    TagPaint p;
    int wab = 0;
    p.bits = tag_bitmap(t.family, t.id, &p.total, &wab);
    p.pose = t.pose;
    p.cell = t.size_m / wab;
    p.half = 0.5 * p.total * p.cell;
    p.c = std::cos(t.pose.theta);
    p.s = std::sin(t.pose.theta);
    painter.tags.push_back(std::move(p));
    boxes.push_back(pixel_box(scene, square(t.pose, painter.tags.back().half)));
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

  // Plane point from normalised coordinates: the inverse of [r1 r2 t].
  Eigen::Matrix3d H;
  H.col(0) = scene.plane.rotation.col(0);
  H.col(1) = scene.plane.rotation.col(1);
  H.col(2) = scene.plane.translation;
  const Eigen::Matrix3d Hinv = H.inverse();

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
            const Eigen::Vector3d q = Hinv * Eigen::Vector3d(xn.x(), xn.y(), 1.0);
            sum += painter.shade(Eigen::Vector2d(q.x() / q.z(), q.y() / q.z()));
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
