#include "pcr/vision/tags.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>

extern "C" {
#include <apriltag.h>
#include <common/image_u8.h>
#include <common/zarray.h>
#include <tag16h5.h>
#include <tag25h9.h>
#include <tag36h11.h>
#include <tagStandard41h12.h>
}

#include "pcr/robot_io.hpp"

namespace pcr::vision {

namespace {

struct FamilyEntry {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

const FamilyEntry kFamilies[] = {
    {"tag36h11", tag36h11_create, tag36h11_destroy},
    {"tag25h9", tag25h9_create, tag25h9_destroy},
    {"tag16h5", tag16h5_create, tag16h5_destroy},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
};

const FamilyEntry* find_family(const std::string& name) {
  for (const FamilyEntry& f : kFamilies)
    if (name == f.name) return &f;
  return nullptr;
}

using FamilyPtr = std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)>;

FamilyPtr make_family(const std::string& name) {
  const FamilyEntry* entry = find_family(name);
  if (!entry)
    throw InputError("unknown tag family '" + name + "' (known: " + known_families() + ")");
  return FamilyPtr(entry->create(), entry->destroy);
}

double bilinear(const GrayImage& im, double x, double y) {
  x = std::clamp(x, 0.0, im.width - 1.001);
  y = std::clamp(y, 0.0, im.height - 1.001);
  const int u = static_cast<int>(x), v = static_cast<int>(y);
  const double fx = x - u, fy = y - v;
  return (1 - fy) * ((1 - fx) * im.at(u, v) + fx * im.at(u + 1, v)) +
         fy * ((1 - fx) * im.at(u, v + 1) + fx * im.at(u + 1, v + 1));
}

// Total-least-squares line through points: n . p = d with |n| = 1. Returns the rms residual.
double fit_line(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d* n, double* d) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (const auto& p : pts) S += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(S);
  *n = es.eigenvectors().col(0);
  *d = n->dot(mean);
  return std::sqrt(std::max(0.0, es.eigenvalues()[0]) / static_cast<double>(pts.size()));
}

// The reach of the edge refinement along an edge's normal (px): within the black border on the
// dark side and the white ring on the light side.
double edge_reach(const std::array<Eigen::Vector2d, 4>& px, double cells) {
  const double side = 0.25 * ((px[1] - px[0]).norm() + (px[2] - px[1]).norm() +
                              (px[3] - px[2]).norm() + (px[0] - px[3]).norm());
  return std::min(0.45 * side / cells, 8.0);
}

// Fraction of the edge points (as refine_quad samples them) whose light side, out to the
// refinement's reach, holds a pixel at full scale.
double clipped_edge_fraction(const GrayImage& im, const std::array<Eigen::Vector2d, 4>& px,
                             double cells) {
  const double reach = edge_reach(px, cells);
  const Eigen::Vector2d centre = 0.25 * (px[0] + px[1] + px[2] + px[3]);
  int points = 0, clipped = 0;
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d a = px[e], b = px[(e + 1) % 4];
    const Eigen::Vector2d t = (b - a).normalized();
    Eigen::Vector2d n(-t.y(), t.x());
    if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;  // towards the light outside
    const int samples = std::max(8, static_cast<int>((b - a).norm()));
    for (int k = 0; k < samples; ++k) {
      const Eigen::Vector2d p0 = a + (0.1 + 0.8 * (k + 0.5) / samples) * (b - a);
      bool hit = false;
      for (double j = 0.5; j <= reach + 0.5 && !hit; j += 0.5) {
        const Eigen::Vector2d p = p0 + j * n;
        const long u = std::lround(p.x()), v = std::lround(p.y());
        if (u < 0 || v < 0 || u >= im.width || v >= im.height) continue;
        hit = im.at(static_cast<int>(u), static_cast<int>(v)) >= kFullScale;
      }
      clipped += hit;
      ++points;
    }
  }
  return points ? static_cast<double>(clipped) / points : 0.0;
}

// Sub-pixel refinement of the quad: for each border edge, edge points found along the edge's normal
// (centroid of the intensity derivative), a straight line through them (in undistorted coordinates
// when the camera is known), the corners where adjacent lines meet.
bool refine_quad(const GrayImage& im, const CameraModel* camera, double cells,
                 std::array<Eigen::Vector2d, 4>& px, std::array<Eigen::Vector2d, 4>& norm,
                 double* rms_px) {
  const double side = 0.25 * ((px[1] - px[0]).norm() + (px[2] - px[1]).norm() +
                              (px[3] - px[2]).norm() + (px[0] - px[3]).norm());
  const double cell = side / cells;
  const double reach = edge_reach(px, cells);
  if (reach < 1.5) return false;
  const double f = camera ? camera->focal_px() : 1.0;
  std::array<Eigen::Vector2d, 4> normals;
  std::array<double, 4> offsets;
  double sum_sq = 0;
  int count = 0;
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d a = px[e], b = px[(e + 1) % 4];
    const Eigen::Vector2d t = (b - a).normalized();
    Eigen::Vector2d n(-t.y(), t.x());
    // Orient n from the inside (dark) to the outside (light) of the quad.
    const Eigen::Vector2d centre = 0.25 * (px[0] + px[1] + px[2] + px[3]);
    if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
    const int samples = std::max(8, static_cast<int>((b - a).norm() / 1.0));
    std::vector<Eigen::Vector2d> pts;
    for (int k = 0; k < samples; ++k) {
      const double s = 0.1 + 0.8 * (k + 0.5) / samples;  // keep away from the corners
      const Eigen::Vector2d p0 = a + s * (b - a);
      // Derivative along the normal at 0.25 px steps; centroid of its positive part.
      constexpr double step = 0.25;
      const int m = static_cast<int>(reach / step);
      double prev = bilinear(im, p0.x() - (m + 1) * step * n.x(), p0.y() - (m + 1) * step * n.y());
      double w_sum = 0, wx_sum = 0, w_max = 0;
      std::vector<std::pair<double, double>> deriv;
      for (int j = -m; j <= m; ++j) {
        const double cur = bilinear(im, p0.x() + j * step * n.x(), p0.y() + j * step * n.y());
        deriv.emplace_back((j - 0.5) * step, cur - prev);
        w_max = std::max(w_max, cur - prev);
        prev = cur;
      }
      if (w_max <= 0) continue;
      for (const auto& [x, w] : deriv) {
        if (w > 0.1 * w_max) {
          w_sum += w;
          wx_sum += w * x;
        }
      }
      const Eigen::Vector2d edge = p0 + (wx_sum / w_sum) * n;
      pts.push_back(camera ? camera->normalize(edge) : edge);
    }
    if (pts.size() < 4) return false;
    const double rms = fit_line(pts, &normals[e], &offsets[e]);
    sum_sq += rms * rms * static_cast<double>(pts.size());
    count += static_cast<int>(pts.size());
  }
  for (int k = 0; k < 4; ++k) {
    const int e0 = (k + 3) % 4, e1 = k;  // corner k is between edge k-1 and edge k
    Eigen::Matrix2d A;
    A.row(0) = normals[e0].transpose();
    A.row(1) = normals[e1].transpose();
    if (std::abs(A.determinant()) < 1e-6) return false;
    const Eigen::Vector2d c = A.partialPivLu().solve(Eigen::Vector2d(offsets[e0], offsets[e1]));
    const Eigen::Vector2d pixel = camera ? camera->project_normalized(c) : c;
    if ((pixel - px[k]).norm() > 0.3 * cell + 2.0) return false;  // refinement went astray
    norm[k] = c;
    px[k] = pixel;
  }
  *rms_px = std::sqrt(sum_sq / count) * f;
  return true;
}

}  // namespace

bool is_known_family(const std::string& family) { return find_family(family) != nullptr; }

std::string known_families() {
  std::string names;
  for (const FamilyEntry& f : kFamilies) names += (names.empty() ? "" : ", ") + std::string(f.name);
  return names;
}

std::vector<bool> tag_bitmap(const std::string& family, int id, int* total_width,
                             int* width_at_border) {
  FamilyPtr fam = make_family(family);
  if (id < 0 || static_cast<uint32_t>(id) >= fam->ncodes) {
    throw InputError("tag id " + std::to_string(id) + " does not exist in family " + family +
                     " (0.." + std::to_string(fam->ncodes - 1) + ")");
  }
  image_u8_t* im = apriltag_to_image(fam.get(), id);
  std::vector<bool> bits(static_cast<std::size_t>(im->width * im->height));
  for (int y = 0; y < im->height; ++y)
    for (int x = 0; x < im->width; ++x) bits[y * im->width + x] = im->buf[y * im->stride + x] > 127;
  *total_width = im->width;
  *width_at_border = fam->width_at_border;
  image_u8_destroy(im);
  return bits;
}

std::vector<TagDetection> detect_tags(const GrayImage& image, const DetectorOptions& options,
                                      const CameraModel* camera) {
  FamilyPtr fam = make_family(options.family);
  std::unique_ptr<apriltag_detector_t, void (*)(apriltag_detector_t*)> td(
      apriltag_detector_create(), apriltag_detector_destroy);
  apriltag_detector_add_family_bits(td.get(), fam.get(),
                                    std::max(0, std::min(options.max_hamming, 3)));
  td->quad_decimate = static_cast<float>(options.quad_decimate);
  td->quad_sigma = static_cast<float>(options.quad_sigma);
  td->nthreads = std::max(1, options.threads);
  td->refine_edges = true;

  // 8-bit copy for the detector, stretched to the full range.
  float lo = 1.f, hi = 0.f;
  for (float p : image.pixels) {
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  const float scale = hi > lo ? 255.f / (hi - lo) : 0.f;
  std::vector<uint8_t> buf(image.pixels.size());
  for (std::size_t i = 0; i < buf.size(); ++i)
    buf[i] = static_cast<uint8_t>(std::clamp((image.pixels[i] - lo) * scale + 0.5f, 0.f, 255.f));
  image_u8_t im{image.width, image.height, image.width, buf.data()};
  zarray_t* found = apriltag_detector_detect(td.get(), &im);

  std::vector<TagDetection> out;
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(found, i, &det);
    if (det->hamming > options.max_hamming || det->decision_margin < options.min_decision_margin)
      continue;
    TagDetection d;
    d.family = options.family;
    d.id = det->id;
    d.hamming = det->hamming;
    d.decision_margin = det->decision_margin;
    // AprilTag puts pixel centres at +0.5; p[0..3] are the tag points (-1,1), (1,1), (1,-1),
    // (-1,-1) with the tag's y pointing down its bitmap, i.e. our bottom-left, bottom-right,
    // top-right, top-left.
    for (int k = 0; k < 4; ++k)
      d.corners[k] = Eigen::Vector2d(det->p[k][0] - 0.5, det->p[k][1] - 0.5);
    const double cells = fam->width_at_border;
    d.clipped_fraction = clipped_edge_fraction(image, d.corners, cells);
    bool ok = false;
    if (options.refine)
      ok = refine_quad(image, camera, cells, d.corners, d.corners_normalized, &d.edge_rms_px);
    if (!ok && camera) {
      for (int k = 0; k < 4; ++k) d.corners_normalized[k] = camera->normalize(d.corners[k]);
    }
    out.push_back(d);
  }
  apriltag_detections_destroy(found);
  std::sort(out.begin(), out.end(),
            [](const TagDetection& a, const TagDetection& b) { return a.id < b.id; });
  return out;
}

}  // namespace pcr::vision
