#pragma once
// Trajectories through inverse kinematics and their ISO 9283 accuracy (Mauze et al. 2021,
// Section 6). The allocating side of pcr/trajectory.hpp: paths as vectors,
// paths and measurements from CSV, IK along a whole path with errors naming the pose, the ISO 9283
// statistics, and runs against the virtual robot.
//
// ISO 9283, per commanded pose c and its n attained poses j (n >= 30 in the standard):
//   barycentre  x_bar = mean(x_j), y_bar = mean(y_j), theta_bar = theta_c + mean(wrap(theta_j -
//   theta_c)) AP_p     = sqrt((x_bar - x_c)^2 + (y_bar - y_c)^2)                       (Eq. 10)
//   AP_theta = theta_bar - theta_c                                            (Eq. 11)
//   l_j = |(x_j, y_j) - (x_bar, y_bar)|,  S_l = sqrt(sum (l_j - l_bar)^2 / (n - 1)),
//   RP_l = l_bar + 3 S_l;  S_theta = sqrt(sum (theta_j - theta_bar)^2 / (n - 1)), RP_theta = +-3
//   S_theta.
// Table 4 of the paper is the max, mean and min over the path of AP_p and |AP_theta|.

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "pcr/calib/virtual_robot.hpp"
#include "pcr/input_error.hpp"
#include "pcr/trajectory.hpp"

namespace pcr {

/// The poses of any path with num_poses and pose(k) (pcr/trajectory.hpp,
/// pcr/spatial/trajectory.hpp) as a vector; InputError "`what`: <is_valid's message>" when the
/// path lies out of its ranges.
template <class Path>
auto path_poses(const Path& spec, const std::string& what) {
  require_valid(spec, what);
  std::vector<decltype(spec.pose(0))> out(static_cast<std::size_t>(spec.num_poses));
  fill_path(spec, out.data(), spec.num_poses);
  return out;
}

/// The poses of a path as a vector (SquarePath / CirclePath in pcr/trajectory.hpp).
std::vector<Pose2<double>> square_path(const SquarePath& spec = SquarePath());
std::vector<Pose2<double>> circle_path(const CirclePath& spec = CirclePath());

/// A path from CSV with columns `x,y,theta` (m, m, rad; header optional, '#' comments allowed).
/// Throws InputError naming the file and line on bad input, or when it has no pose.
std::vector<Pose2<double>> load_path_csv(const std::string& path);

/// IK along a path, warm-started pose to pose from the home solution.
struct PathCommandOptions {
  PathStepOptions step;  ///< strain limit, solver options, platform load, cold-start fallback
  bool is_valid(std::string* error = nullptr) const { return step.is_valid(error); }
};

struct PathCommand {
  std::vector<JointVector> q;        ///< commanded joints of each pose (m)
  std::vector<Pose2<double>> poses;  ///< the poses solved for (theta solved when n = 2)
  std::vector<double> max_strain;    ///< largest bending strain at each pose
  std::vector<int> iterations;       ///< Newton iterations spent on each pose
};

/// Throws InputError "pose k (x, y, theta): <reason>" (k 0-based) at the first pose that has no
/// IK solution, leaves a stroke, or exceeds the strain limit; and on an empty path or a robot
/// whose IK is not square (n > 3).
PathCommand command_path(const RobotParams<double>& model, const std::vector<Pose2<double>>& path,
                         const PathCommandOptions& options = PathCommandOptions());

/// ISO 9283 statistics of one commanded pose.
struct Iso9283Pose {
  Pose2<double> commanded;
  Pose2<double> barycentre;   ///< (x_bar, y_bar, theta_bar)
  int cycles = 0;             ///< n attained poses
  double ap_x = 0, ap_y = 0;  ///< x_bar - x_c, y_bar - y_c (m)
  double ap_p = 0;            ///< Eq. 10 (m)
  double ap_theta = 0;        ///< Eq. 11, signed (rad)
  double l_bar = 0, s_l = 0;  ///< m
  double rp_l = 0;            ///< l_bar + 3 S_l (m)
  double s_theta = 0;         ///< rad
  double rp_theta = 0;        ///< 3 S_theta: the repeatability is +-rp_theta (rad)
};

struct Iso9283Stats {
  double max = 0, mean = 0, min = 0;
};

/// The max, mean and min of value(item) over a path's per-pose statistics (zeros when empty).
template <class Item, class Value>
Iso9283Stats iso9283_stats(const std::vector<Item>& items, Value&& value) {
  Iso9283Stats s;
  if (items.empty()) return s;
  s.max = -INFINITY;
  s.min = INFINITY;
  double sum = 0;
  for (const Item& item : items) {
    const double v = value(item);
    s.max = std::max(s.max, v);
    s.min = std::min(s.min, v);
    sum += v;
  }
  s.mean = sum / static_cast<double>(items.size());
  return s;
}

struct Iso9283Result {
  std::vector<Iso9283Pose> poses;
  Iso9283Stats ap_p;          ///< m (Table 4)
  Iso9283Stats ap_theta_abs;  ///< rad, of |AP_theta| (Table 4)
  Iso9283Stats rp_l;          ///< m
  Iso9283Stats rp_theta;      ///< rad
};

/// attained[k] holds the attained poses of commanded[k] (all in the same frame, W). Throws
/// InputError when the sizes differ, a pose has fewer than 2 attained poses, or a value is NaN.
Iso9283Result iso9283(const std::vector<Pose2<double>>& commanded,
                      const std::vector<std::vector<Pose2<double>>>& attained);

/// How the virtual robot's camera measurements ^Se T_M are mapped to platform poses in W.
///
/// Identification recovers a robot only up to a gauge: a rigid change of W (all A_i, alpha_i and
/// the camera pose together) and of P (all B_i, beta_i and the pattern offset together) leaves
/// every camera measurement unchanged. An identified model therefore commands poses of its own P
/// in its own W, and only its own extrinsics tie those frames to the physical camera and pattern.
enum class AttainedFrame {
  /// With the commanding model's extrinsics, as the paper does with the identified ones: the
  /// poses are compared in the model's frames, whatever its gauge (default). For a nominal model
  /// this includes the error of its nominal extrinsics.
  kModelExtrinsics,
  /// With the virtual robot's true extrinsics: the error of the model's robot parameters alone,
  /// meaningful only when the model shares the truth's frames (the nominal description the truth
  /// was drawn from), not for an identified model.
  kTrueExtrinsics,
};
struct AccuracyOptions {
  int repeat = 30;  ///< ISO 9283 cycles per pose (>= 2; the standard asks for >= 30)
  PathCommandOptions command;
  AttainedFrame frame = AttainedFrame::kModelExtrinsics;

  static constexpr OptionRange kRepeat{"repeat", 2, 100000};
  /// As SolverOptions::is_valid, for the repeat and the command's options.
  bool is_valid(std::string* error = nullptr) const {
    return kRepeat.check(repeat, error) && command.is_valid(error);
  }
};

struct AccuracyEvaluation {
  std::vector<Pose2<double>> commanded;
  PathCommand command;
  std::vector<std::vector<Pose2<double>>> attained;  ///< [pose][cycle], platform poses in W
  Iso9283Result iso;
};

/// Commands the path with `model` (nominal or identified), then runs `repeat` cycles on the
/// virtual robot: each cycle visits every pose in path order, so every pose is approached from
/// the same direction (from the previous pose) in every cycle, as ISO 9283 asks. The robot moves
/// on its true parameters and load; the camera adds its repeatability noise.
AccuracyEvaluation evaluate_on_virtual_robot(const RobotParams<double>& model, VirtualRobot& robot,
                                             const std::vector<Pose2<double>>& path,
                                             const AccuracyOptions& options = AccuracyOptions());

/// Measured poses of a real robot: CSV columns `pose,x_c,y_c,theta_c,x,y,theta`, one row per
/// attained pose: the 0-based pose index, the commanded pose, the attained pose (m, m, rad, in W).
/// Rows of one pose need not be contiguous; every pose index from 0 to the largest must occur,
/// with the same commanded pose on all its rows.
struct MeasuredPath {
  std::vector<Pose2<double>> commanded;
  std::vector<std::vector<Pose2<double>>> attained;
};
MeasuredPath load_measured_csv(const std::string& path);
std::string measured_to_csv(const std::vector<Pose2<double>>& commanded,
                            const std::vector<std::vector<Pose2<double>>>& attained);

/// Table 4 (AP_p in um, |AP_theta| in mrad: max, mean, min) plus RP, one row per named result, as
/// Markdown; and the per-pose statistics as CSV (SI units) and everything as JSON (SI units).
std::string iso9283_table_markdown(
    const std::vector<std::pair<std::string, const Iso9283Result*>>& rows);
std::string iso9283_poses_csv(const Iso9283Result& result);
std::string iso9283_json(const std::vector<std::pair<std::string, const Iso9283Result*>>& rows);

}  // namespace pcr
