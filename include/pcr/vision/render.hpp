#pragma once
// Synthetic camera images of AprilTags (and rods, outlines, chessboards) lying in the work plane,
// or of tags with any 3-D pose (on a spatial robot's platform), seen through a pinhole camera
// with OpenCV distortion. For tests and the end-to-end demo. Anti-aliased by supersampling (each
// pixel averages s x s samples, every sample's ray is traced exactly through the distortion to
// the plane of each tag and of the work plane), then an illumination gradient, a Gaussian blur and
// Gaussian noise. The tag bitmaps are the AprilTag library's own (apriltag_to_image).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "pcr/option_range.hpp"
#include "pcr/se2.hpp"
#include "pcr/spatial/robot.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {

struct RenderTag {
  std::string family{kDefaultTagFamily};
  int id{0};
  double size_m{0.01};  ///< black border edge
  Pose2<double> pose;   ///< tag frame in the plane frame
};

/// A tag with a 3-D pose, e.g. on a spatial robot's platform. Its frame: x to the right of its
/// bitmap, y to its top, z out of its printed face; only that face is seen (a tag is printed on
/// an opaque board). A planar RenderTag is the special case position (x, y, 0), a turn theta
/// about z.
struct RenderTag3d {
  std::string family{kDefaultTagFamily};
  int id{0};
  double size_m{0.01};       ///< black border edge
  SpatialPose<double> pose;  ///< tag frame in the plane frame (a spatial robot's W)
};

/// A dark straight band (a rod, an outline edge) of `width_m`, drawn under the tags.
struct RenderSegment {
  Eigen::Vector2d a{0, 0};
  Eigen::Vector2d b{0, 0};
  double width_m{125e-6};
  float intensity{0.15f};
};

/// A dark circle outline (the platform's 100 mm wafer, for a person looking at the image): a band
/// of `width_m` centred on the circle of `radius_m`, drawn under the tags.
struct RenderCircle {
  Eigen::Vector2d centre{0, 0};
  double radius_m{0.05};
  double width_m{300e-6};
  float intensity{0.25f};

  /// Of the circle, 2 radius_m (pcr render --wafer-diameter, where 0 draws none): a metre covers
  /// any platform; beyond, a unit typo (mm typed as m).
  static constexpr OptionRange kDiameter{"diameter", 0, 1, "m"};
  /// As pcr::SolverOptions::is_valid.
  bool is_valid(std::string* error = nullptr) const { return kDiameter.check(2 * radius_m, error); }
};

/// A chessboard with `cols` x `rows` inner corners; its corner (0, 0) at `pose`, squares along +x,
/// +y, with a one-square white margin.
struct RenderChessboard {
  int cols{9};
  int rows{6};
  double square_m{0.005};
  Pose2<double> pose;

  /// The board whose centre is at `centre` (the pose `pcr render --board-pose` takes).
  static RenderChessboard centred(int cols, int rows, double square_m,
                                  const Pose2<double>& centre) {
    return {
        cols, rows, square_m,
        centre * Pose2<double>{-0.5 * (cols - 1) * square_m, -0.5 * (rows - 1) * square_m, 0.0}};
  }
};

/// What the camera sees. Where tags overlap along a ray the nearest is drawn; tags are drawn over
/// the work plane's content (segments, circles, chessboard), which is the background.
struct Scene {
  CameraModel camera;
  PlanePose plane;  ///< the plane frame in the camera (a spatial robot's ^C T_W)
  std::vector<RenderTag> tags;
  std::vector<RenderTag3d> tags_3d;
  std::vector<RenderSegment> segments;
  std::optional<RenderChessboard> chessboard;
  std::vector<RenderCircle> circles;
};

struct RenderOptions {
  int supersampling{4};        ///< s x s samples per pixel
  double blur_sigma_px{0.0};   ///< Gaussian blur (optics), px
  double noise_sigma{0.0};     ///< additive Gaussian noise, in units of full scale
  double gradient{0.0};        ///< illumination: relative change from one image side to the other
  double gradient_angle{0.5};  ///< direction of the gradient in the image (rad)
  float background{0.45f};
  float white{0.92f};
  float black{0.06f};
  unsigned seed{1};

  // Named as pcr render and Python spell them. The work grows with the square of the
  // supersampling: 16 x 16 samples per pixel is already a minute's render.
  static constexpr OptionRange kSupersampling{"supersampling", 1, 16};
  static constexpr OptionRange kBlur{"blur", 0, 50, "px"};
  static constexpr OptionRange kNoise{"noise", 0, 1, "fraction of full scale"};
  static constexpr OptionRange kGradient{"gradient", 0, 1};
  /// As pcr::SolverOptions::is_valid: the message names the first field out of its range.
  bool is_valid(std::string* error = nullptr) const {
    return kSupersampling.check(supersampling, error) && kBlur.check(blur_sigma_px, error) &&
           kNoise.check(noise_sigma, error) && kGradient.check(gradient, error);
  }
};

/// Throws InputError for options or circles out of their ranges.
GrayImage render_scene(const Scene& scene, const RenderOptions& options);

/// Ground-truth pixel coordinates of a tag's corners (same order as TagDetection::corners).
std::vector<Eigen::Vector2d> tag_corner_pixels(const Scene& scene, const RenderTag& tag);
std::vector<Eigen::Vector2d> tag_corner_pixels(const Scene& scene, const RenderTag3d& tag);

}  // namespace pcr::vision

#include "pcr/robot.hpp"
#include "pcr/vision/mounts.hpp"

namespace pcr::vision {

/// The tags of `layout` placed on `robot`, with the plane frame = W: proximal tags at A_i + q_i
/// along the actuator direction (q empty = all 0), distal tags on the platform at `platform` (^W
/// T_P). Each tag is placed so that its clamp point and rod angle (the layout's offsets) fall on
/// the robot's A_i, alpha_i or B_i, beta_i. Also adds the rods (straight A-B segments, for a person
/// looking at the image) to `segments` when it is non-null.
std::vector<RenderTag> mount_tags(const MountLayout& layout, const RobotParams<double>& robot,
                                  const Pose2<double>& platform, const std::vector<double>& q = {},
                                  std::vector<RenderSegment>* segments = nullptr);

}  // namespace pcr::vision

#include "pcr/vision/tag_board.hpp"

namespace pcr::vision {

/// The tags of `board` placed in the plane frame, the board frame M at `plane_T_board` (for a
/// spatial robot whose board is given in P: ^W T_P).
std::vector<RenderTag3d> board_tags(const TagBoard& board,
                                    const SpatialPose<double>& plane_T_board);

}  // namespace pcr::vision
