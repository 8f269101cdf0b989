#pragma once
// A spatial robot's platform measured by a camera: a rigid board of AprilTags fixed to the
// platform (the marker frame M of pcr::SpatialExtrinsics; M = P when the board's coordinates are
// given in P), whose pose ^S T_M in the camera frame S one image gives (Mauze et al. 2021, Section
// 4, in 3-D: the planar method's tags lie in one work plane, a board's tags may face any way).
//
// Measurement: the board's tags are detected (pcr/vision/tags.hpp: sub-pixel corners fitted in
// undistorted coordinates), matched to the board by family and id, and the pose is the
// perspective-n-point solution on all their corners at once: an initial pose by OpenCV's SQPnP,
// then Gauss-Newton on the reprojection error in undistorted coordinates scaled to pixels (as
// fit_planar_markers), each tag's four corners weighted by their covariance as the detector makes
// them (each corner is where two fitted edge lines meet, so adjacent corners share a line and
// their errors are correlated: generalised least squares). Covariance sigma^2 (J^T W J)^-1, J the
// Jacobian of the reprojection residuals with respect to the pose, W the corners' inverse
// covariance per unit sigma^2, sigma the scatter of the edge points about their lines estimated
// from the weighted residuals (so it holds the detector's systematic corner errors as well as the
// image noise), never below a floor: the scatter the detector measured along the tags' edges
// (TagDetection::edge_rms_px, from many more points: one tag leaves its residuals 2 degrees of
// freedom) plus what raises each corner's variance by PoseOptions::corner_sigma_floor_px^2 (the
// detector's systematic corner error: 0.016 px per coordinate on renders without noise), averaged
// over the tags. With independent corners (the planar fit's model) the predicted sigma came out 3
// times the spread measured over noise seeds (tests/test_spatial_vision.cpp).
//
// The pose's perturbation, for its covariance: position + dp (in S), rotation R exp([dtheta]x)
// (dtheta in M, composed on the right), as pcr::SpatialVirtualRobot's measurement noise.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "pcr/spatial/robot.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {

/// One tag of a board. Tag frame as in pcr/vision/tags.hpp (centre, x to the bitmap's right, y
/// to its top), z out of its printed face.
struct BoardTag {
  std::string family{kDefaultTagFamily};
  int id{0};
  double size_m{0.01};       ///< black border edge
  SpatialPose<double> pose;  ///< the tag frame in the board frame M

  /// Its corners in M, in TagDetection::corners' order (bottom-left, bottom-right, top-right,
  /// top-left of the bitmap).
  std::array<Eigen::Vector3d, 4> corners() const;
};

struct TagBoard {
  std::vector<BoardTag> tags;
  /// ^M T_P, the platform frame in the board frame (the robot file's extrinsics.marker): the
  /// identity when the tags are given in P (M = P).
  SpatialPose<double> marker_T_platform;
};

/// The tag board file (JSON, SI units; docs/vision.md, "The tag board file"):
///   {
///     "format": "pcr-tag-board", "version": 1,   // both optional
///     "family": "tag36h11", "tag_size": 0.024,   // defaults for the tags (optional)
///     "marker": {"position": [x, y, z], "orientation": [w, x, y, z]},  // ^M T_P (optional)
///     "tags": [ {"id": 10, "family": ..., "tag_size": ..., "comment": ...,
///                "pose": {"position": [...], "orientation": [...]}} ]  // the tag in P
///   }
/// The tags' poses are read in P and kept in M (^M T_P pose). Every error names `source`, the
/// field and the value (an unknown field, a quaternion not of unit norm, an id that is not an
/// integer, and what check_board refuses).
TagBoard parse_tag_board(const std::string& json_text, const std::string& source);
TagBoard load_tag_board(const std::string& path);

/// Throws InputError naming `source` and the tag for a board without tags, an unknown family, an
/// id the family does not have, a size that is not positive, or a family and id given twice.
void check_board(const TagBoard& board, const std::string& source);

struct BoardPose {
  SpatialPose<double> camera_T_board;  ///< ^S T_M
  Eigen::Matrix<double, 6, 6> covariance{
      Eigen::Matrix<double, 6, 6>::Zero()};  ///< of (dp in S, dtheta in M), m and rad
  double corner_rms_px{0};                   ///< reprojection residual rms
  double edge_sigma_px{0};  ///< sigma: the edge points' scatter used for the covariance
  std::vector<TagDetection> detections;  ///< the board's tags seen, in board order
  std::vector<int> board_index;          ///< of each detection, into board.tags
  int iterations{0};                     ///< Gauss-Newton steps taken
};

/// The pose of the board from its matched detections (corners_normalized must be set: detect_tags
/// with the camera). `board_index[k]` is the board tag of `detections[k]`. Throws InputError
/// naming `source` when there are fewer than 4 corners.
BoardPose fit_board_pose(const std::vector<TagDetection>& detections,
                         const std::vector<int>& board_index, const TagBoard& board,
                         const CameraModel& camera, const std::string& source,
                         const PoseOptions& options = {});

/// Detects the board's tags in `image` (every family the board uses), matches them to the board
/// and fits its pose. Tags of ids not on the board are left out (other tags may be in view);
/// board tags not seen are left out too. Throws InputError naming `image_source` when no tag of
/// the board is seen (naming the board's ids and those detected), when a board tag appears twice,
/// is cut by the image border or sees clipped highlights (check_detection), and for an invalid
/// board (check_board).
BoardPose measure_board_pose(const GrayImage& image, const std::string& image_source,
                             const TagBoard& board, const CameraModel& camera,
                             const MeasureOptions& options = {});

/// A point fixed next to a tag (a base hole, a platform attachment point), known in the tag's
/// frame: measured from that tag's pose alone.
struct TagPoint {
  std::string name;                 ///< for messages ("A1", "B3")
  BoardTag tag;                     ///< its pose is not used (the tag's own frame)
  Eigen::Vector3d offset{0, 0, 0};  ///< the point in the tag frame (m)
  /// The offset's half-widths along the tag's axes (m): how well the point is known next to its
  /// tag (registration adds them worst case, as the planar clamp_offset_uncertainty).
  Eigen::Vector3d offset_uncertainty{0, 0, 0};
};

struct TagPointMeasurement {
  Eigen::Vector3d position{0, 0, 0};                    ///< in the camera frame S (m)
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Zero()};  ///< from the image (m^2)
  BoardPose tag;                                        ///< the tag's pose ^S T_tag
};

/// Each point from its own tag's pose (fit_board_pose on that tag alone): p = t + R offset, its
/// covariance propagated linearly from the tag pose's. Throws InputError naming `image_source` and
/// the point when its tag is not seen, as measure_board_pose otherwise.
std::vector<TagPointMeasurement> measure_tag_points(const GrayImage& image,
                                                    const std::string& image_source,
                                                    const std::vector<TagPoint>& points,
                                                    const CameraModel& camera,
                                                    const MeasureOptions& options = {});

}  // namespace pcr::vision
