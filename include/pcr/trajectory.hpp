#pragma once
// Cartesian paths at constant platform orientation (Mauze et al. 2021, Section 6.1: a square of
// side 2 mm and a circle of diameter 3 mm, theta = 0) and inverse kinematics along a path,
// warm-started pose to pose.
//
// Real-time safe like kinematics.hpp: no heap, no exceptions. Paths are pose generators (pose(k),
// at(fraction)) or fill a caller-provided buffer; the allocating conveniences (std::vector, CSV)
// live in pcr/calib/accuracy.hpp.

#include <cmath>
#include <string>

#include "pcr/kinematics.hpp"

namespace pcr {

inline constexpr double kPaperSquareSide = 2e-3;      ///< m
inline constexpr double kPaperCircleDiameter = 3e-3;  ///< m
/// Bending strain a commanded pose (PathStepOptions) and a sampled configuration
/// (SamplingOptions) may reach, |kappa| d / 2: its default and its range.
inline constexpr double kDefaultStrainLimit = 0.01;
inline constexpr OptionRange kStrainLimitRange{"strain_limit", 1e-6, 0.1};

/// A square traversed counter-clockwise from its corner (-side/2, -side/2) (before `rotation`),
/// at the constant platform orientation `theta`. With num_poses a multiple of 4 the corners are
/// poses; the path is closed: pose(num_poses) == pose(0), which is not repeated.
struct SquarePath {
  Vector2<double> centre{0.0, 0.0};  ///< m, in W
  double side = kPaperSquareSide;    ///< m
  double rotation = 0.0;             ///< rad, of the square's sides with respect to W
  double theta = 0.0;                ///< rad, constant platform orientation
  int num_poses = 40;

  // The documented ranges of the fields (is_valid), as pcr accuracy takes them: a path beyond a
  // decimetre is a unit typo (mm typed as m) no robot of this scale reaches.
  static constexpr OptionRange kSide{"side", 1e-6, 0.1, "m"};
  static constexpr OptionRange kCentre{"centre", -0.1, 0.1, "m"};  ///< each of x and y
  static constexpr OptionRange kTheta{"theta", -M_PI, M_PI, "rad"};
  static constexpr OptionRange kNumPoses{"num_poses", 1, 100000};
  /// As SolverOptions::is_valid, naming the field with `prefix` ("square." when nested).
  bool is_valid(std::string* error = nullptr, const char* prefix = "") const {
    return kSide.check(side, error, prefix) && kCentre.check(centre.x(), error, prefix) &&
           kCentre.check(centre.y(), error, prefix) && kTheta.check(theta, error, prefix) &&
           kNumPoses.check(num_poses, error, prefix);
  }

  /// The pose at `fraction` of the perimeter (wrapped into [0, 1)).
  Pose2<double> at(double fraction) const noexcept {
    double f = fraction - std::floor(fraction);
    const double s = 4.0 * f;  // sides travelled
    const int edge = static_cast<int>(s) & 3;
    const double u = s - std::floor(s);
    // Corners of the unit square (-1/2 .. 1/2), counter-clockwise from bottom-left.
    static constexpr double kCx[5] = {-0.5, 0.5, 0.5, -0.5, -0.5};
    static constexpr double kCy[5] = {-0.5, -0.5, 0.5, 0.5, -0.5};
    const double lx = side * (kCx[edge] + u * (kCx[edge + 1] - kCx[edge]));
    const double ly = side * (kCy[edge] + u * (kCy[edge + 1] - kCy[edge]));
    const double c = std::cos(rotation), sn = std::sin(rotation);
    return Pose2<double>{centre.x() + c * lx - sn * ly, centre.y() + sn * lx + c * ly, theta};
  }
  Pose2<double> pose(int k) const noexcept {
    return at(num_poses > 0 ? static_cast<double>(k) / num_poses : 0.0);
  }
  int size() const noexcept { return num_poses; }
};

/// A circle traversed counter-clockwise from the polar angle `start_angle`, at the constant
/// platform orientation `theta`; closed like SquarePath.
struct CirclePath {
  Vector2<double> centre{0.0, 0.0};        ///< m, in W
  double diameter = kPaperCircleDiameter;  ///< m
  double start_angle = 0.0;                ///< rad, polar angle of the first pose about the centre
  double theta = 0.0;                      ///< rad, constant platform orientation
  int num_poses = 36;

  /// The square's ranges: pcr accuracy's --size is a side or a diameter.
  static constexpr OptionRange kDiameter{"diameter", SquarePath::kSide.lo, SquarePath::kSide.hi,
                                         "m"};
  static constexpr OptionRange kCentre = SquarePath::kCentre;
  static constexpr OptionRange kTheta = SquarePath::kTheta;
  static constexpr OptionRange kNumPoses = SquarePath::kNumPoses;
  /// As SquarePath::is_valid.
  bool is_valid(std::string* error = nullptr, const char* prefix = "") const {
    return kDiameter.check(diameter, error, prefix) && kCentre.check(centre.x(), error, prefix) &&
           kCentre.check(centre.y(), error, prefix) && kTheta.check(theta, error, prefix) &&
           kNumPoses.check(num_poses, error, prefix);
  }

  Pose2<double> at(double fraction) const noexcept {
    const double phi = start_angle + 2.0 * M_PI * (fraction - std::floor(fraction));
    const double r = 0.5 * diameter;
    return Pose2<double>{centre.x() + r * std::cos(phi), centre.y() + r * std::sin(phi), theta};
  }
  Pose2<double> pose(int k) const noexcept {
    return at(num_poses > 0 ? static_cast<double>(k) / num_poses : 0.0);
  }
  int size() const noexcept { return num_poses; }
};

/// Writes min(path.size(), capacity) poses into `out`; returns how many were written. Any path
/// with size() and pose(k): Pose2<double> for the planar ones, SpatialPose<double> for those of
/// pcr/spatial/trajectory.hpp.
template <class Path, class Pose>
int fill_path(const Path& path, Pose* out, int capacity) noexcept {
  const int count = path.size() < capacity ? path.size() : capacity;
  for (int k = 0; k < count; ++k) out[k] = path.pose(k);
  return count < 0 ? 0 : count;
}

/// Outcome of one pose of a path.
enum class PathPoseStatus {
  kOk,              ///< IK converged, q inside the strokes, strain below the limit
  kNoSolution,      ///< IK did not converge (outside the workspace, or a singularity on the way)
  kOutOfRange,      ///< a joint lies outside [q_min, q_max]
  kStrainExceeded,  ///< the largest bending strain exceeds the limit
  kInaccurate,      ///< IK converged short of the accuracy targets (SolveStatus::kInaccurate)
};

inline const char* to_string(PathPoseStatus status) noexcept {
  switch (status) {
    case PathPoseStatus::kOk:
      return "ok";
    case PathPoseStatus::kNoSolution:
      return "no_solution";
    case PathPoseStatus::kOutOfRange:
      return "out_of_range";
    case PathPoseStatus::kStrainExceeded:
      return "strain_exceeded";
    case PathPoseStatus::kInaccurate:
      return "inaccurate";
  }
  return "unknown";
}

struct PathStepOptions {
  double strain_limit = kDefaultStrainLimit;
  SolverOptions solver;
  PlatformLoad<double> load;
  /// When the warm-started solve fails, try a cold start from home (the reference branch).
  bool cold_start_fallback = true;

  /// As SolverOptions::is_valid, for these fields, the solver's and the load's.
  bool is_valid(std::string* error = nullptr) const {
    return kStrainLimitRange.check(strain_limit, error) && solver.is_valid(error) &&
           load.is_valid(error);
  }
};

struct PathStep {
  InverseSolution solution;  ///< q, the wrenches (the next warm start) and the solver summary
  PathPoseStatus status = PathPoseStatus::kNoSolution;
  int iterations = 0;  ///< Newton iterations, fallback included
  bool ok() const noexcept { return status == PathPoseStatus::kOk; }
};

/// Classifies a solved pose: convergence, strokes, strain.
inline PathPoseStatus classify_pose(const InverseSolution& solution, double strain_limit) noexcept {
  const SolveStatus s = solution.summary.status;
  if (s == SolveStatus::kOutOfRange) return PathPoseStatus::kOutOfRange;
  if (s == SolveStatus::kInaccurate) return PathPoseStatus::kInaccurate;
  if (s != SolveStatus::kConverged) return PathPoseStatus::kNoSolution;
  if (!(solution.summary.max_strain <= strain_limit)) return PathPoseStatus::kStrainExceeded;
  return PathPoseStatus::kOk;
}

/// One step of IK along a path: from the previous pose's solution to `pose`.
inline PathStep path_ik_step(const RobotParams<double>& robot, const Pose2<double>& pose,
                             const InverseSolution& previous,
                             const PathStepOptions& options = PathStepOptions()) noexcept {
  PathStep step;
  step.solution =
      options.cold_start_fallback
          ? inverse_kinematics_or_cold(robot, pose, &previous, options.solver, options.load)
          : inverse_kinematics(robot, pose, previous, options.solver, options.load);
  step.iterations = step.solution.summary.iterations;
  step.status = classify_pose(step.solution, options.strain_limit);
  return step;
}

/// The first pose of a path: IK from home (a cold start).
inline PathStep path_ik_start(const RobotParams<double>& robot, const Pose2<double>& pose,
                              const PathStepOptions& options = PathStepOptions()) noexcept {
  PathStep step;
  step.solution = inverse_kinematics(robot, pose, options.solver, options.load);
  step.iterations = step.solution.summary.iterations;
  step.status = classify_pose(step.solution, options.strain_limit);
  return step;
}

}  // namespace pcr
