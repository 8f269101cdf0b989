#pragma once
// Pinhole camera with OpenCV's distortion model, read from / written to OpenCV's YAML format
// (cv::FileStorage keys camera_matrix, distortion_coefficients, image_width, image_height, the
// format written by OpenCV's calibration sample and by `pcr camera`).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <utility>
#include <vector>

#include "pcr/option_range.hpp"

namespace pcr::vision {

struct CameraModel {
  int width{0};   ///< px
  int height{0};  ///< px
  Eigen::Matrix3d K{Eigen::Matrix3d::Identity()};
  /// OpenCV order: k1 k2 p1 p2 [k3 [k4 k5 k6]] (0, 4, 5 or 8 coefficients).
  Eigen::VectorXd distortion{Eigen::VectorXd::Zero(5)};

  double focal_px() const { return 0.5 * (K(0, 0) + K(1, 1)); }
  /// Normalised image coordinates (x/z, y/z) -> distorted pixel coordinates.
  Eigen::Vector2d project_normalized(const Eigen::Vector2d& xn) const;
  /// Pixel -> normalised coordinates (inverse of project_normalized, Newton to 1e-12).
  Eigen::Vector2d normalize(const Eigen::Vector2d& pixel) const;
  /// A camera-frame point -> pixel.
  Eigen::Vector2d project(const Eigen::Vector3d& point_camera) const;
};

/// Throws pcr::InputError naming the file and the field on a missing or invalid field.
CameraModel load_camera(const std::string& path);
void save_camera(const CameraModel& camera, const std::string& path, double rms_px = -1.0);
/// Checks that an image of width x height px fits this camera (names `image_source` otherwise).
void check_image_size(const CameraModel& camera, int width, int height,
                      const std::string& camera_source, const std::string& image_source);

/// Pose of the work plane in the camera frame: a plane point (x, y) maps to R [x y 0]^T + t.
struct PlanePose {
  Eigen::Matrix3d rotation{Eigen::Matrix3d::Identity()};
  Eigen::Vector3d translation{0, 0, 1};

  Eigen::Vector3d to_camera(const Eigen::Vector2d& p) const {
    return rotation.col(0) * p.x() + rotation.col(1) * p.y() + translation;
  }
  /// A camera looking straight down at the plane from `height_m`, the plane's y axis pointing to
  /// the image's top and its origin on the optical axis; tilted by `tilt_x`, `tilt_y` (rad).
  static PlanePose looking_down(double height_m, double tilt_x = 0.0, double tilt_y = 0.0);

  // A rendered view's placement. Beyond about 60 degrees of tilt the plane is seen too obliquely
  // to measure.
  static constexpr OptionRange kHeight{"height", 0.01, 100, "m"};
  static constexpr OptionRange kTiltX{"tilt_x", -1, 1, "rad"};
  static constexpr OptionRange kTiltY{"tilt_y", -1, 1, "rad"};
};

/// The chessboard used by `pcr camera`: `cols` x `rows` inner corners, square edge `square_m`.
/// (A printed OpenCV chessboard; the inner corners are found with cv::findChessboardCorners and
/// refined with cv::cornerSubPix.)
struct ChessboardSpec {
  int cols{9};
  int rows{6};
  double square_m{0.005};

  static constexpr OptionRange kSquare{"square", 1e-4, 1, "m"};  ///< as pcr camera spells it
};

/// `option`'s text "COLSxROWS" as cols and rows of ChessboardSpec: digits, 'x', digits and nothing
/// else, 2 to 100 each ("9x6"); InputError naming the option and the text otherwise ("9x6x",
/// "9x", " 9x6", "+9x6").
std::pair<int, int> parse_board_size(const std::string& text, const std::string& option);

struct CalibrationResult {
  CameraModel camera;
  double rms_px{0};                   ///< reprojection error
  std::vector<std::string> used;      ///< images whose board was found
  std::vector<std::string> rejected;  ///< images without a board
};

/// cv::calibrateCamera over the images in which the board is found (at least 3 are needed).
CalibrationResult calibrate_camera(const std::vector<std::string>& image_paths,
                                   const ChessboardSpec& board);

}  // namespace pcr::vision
