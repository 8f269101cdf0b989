#pragma once
// AprilTag detection (the AprilRobotics C library, hidden behind this header) with sub-pixel
// corners in OpenCV's pixel convention.
//
// Tag frame: origin at the tag centre, x towards the right of the tag's bitmap, y towards its top
// (as printed and seen from above). `size_m` is the edge of the black border square, as in the
// AprilTag papers; the bitmap with its white quiet zone is total_width / width_at_border larger.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "pcr/option_range.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"

namespace pcr::vision {

/// The family of a tag that names none (mount layouts, detection, rendering).
inline constexpr const char* kDefaultTagFamily = "tag36h11";

/// The supported families: tag36h11 (default), tag25h9, tag16h5, tagStandard41h12.
bool is_known_family(const std::string& family);
/// Their names, comma-separated, for messages: "tag36h11, tag25h9, tag16h5, tagStandard41h12".
std::string known_families();
/// Bitmap of one code, total_width x total_width cells, row 0 at the top; true = white.
/// Throws InputError for an unknown family or an id out of range.
std::vector<bool> tag_bitmap(const std::string& family, int id, int* total_width,
                             int* width_at_border);

struct DetectorOptions {
  std::string family{kDefaultTagFamily};
  double min_decision_margin{30.0};  ///< reject weaker detections
  int max_hamming{0};                ///< reject detections with more corrected bits
  double quad_decimate{2.0};         ///< AprilTag's quad detection decimation (refined after)
  double quad_sigma{0.0};
  int threads{1};
  bool refine{true};  ///< sub-pixel edge refinement (below)

  // Named as pcr measure and Python spell them. More than 3 corrected bits makes AprilTag's
  // decoding tables grow beyond use.
  static constexpr OptionRange kMinDecisionMargin{"min_margin", 0, 1000};
  static constexpr OptionRange kMaxHamming{"max_hamming", 0, 3};
};

struct TagDetection {
  std::string family;
  int id{-1};
  int hamming{0};
  double decision_margin{0};
  /// Corners in OpenCV pixel coordinates, at the tag-frame points (-s/2,-s/2), (s/2,-s/2),
  /// (s/2,s/2), (-s/2,s/2) (s = size): bottom-left, bottom-right, top-right, top-left.
  std::array<Eigen::Vector2d, 4> corners;
  /// The same corners in normalised (undistorted) camera coordinates, when a camera was given.
  std::array<Eigen::Vector2d, 4> corners_normalized;
  double edge_rms_px{0};  ///< scatter of the refined edge points about their fitted lines
  /// Fraction of the points along the four border edges whose light side, within the reach of
  /// the edge refinement, holds a pixel at full scale (clipped highlights; see kFullScale).
  double clipped_fraction{0};
};

/// A pixel at or above this value is taken as clipped: the full scale of the image file (an 8- or
/// 16-bit image's largest code, 1 for a float image). Where the light side of an edge clips, the
/// edge profile loses its top and the refined edge moves towards the dark side.
inline constexpr float kFullScale = 1.0f - 1e-6f;

/// Detects the tags of `options.family`. With `camera`, the refinement fits the four border edges
/// as straight lines in undistorted coordinates (sub-pixel edge points along each edge's normal)
/// and intersects them; without it, lines are fitted in pixel coordinates.
std::vector<TagDetection> detect_tags(const GrayImage& image, const DetectorOptions& options,
                                      const CameraModel* camera = nullptr);

}  // namespace pcr::vision
