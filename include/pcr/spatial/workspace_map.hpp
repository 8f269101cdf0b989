#pragma once
// Slices through a six-rod spatial robot's 6-D workspace: IK over a grid of two of the platform
// pose's six coordinates (x, y, z in m; rx, ry, rz the rotation vector in rad), the other four
// held: a plane of positions at one orientation, or a plane of rotation vectors at one position.
// The spatial counterpart of pcr/calib/workspace_map.hpp, solved by the same flood (warm starts
// from solved neighbours, outward from seeds). Compiled in pcr::calib (threads, std::vector): not
// part of the header-only core.

#include <array>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "pcr/option_range.hpp"
#include "pcr/solver.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace pcr {

/// The pose as a map writes it: x, y, z (m, in W), then the rotation vector rx, ry, rz (rad) of
/// the platform's orientation P -> W (quaternion_exp turns it into the quaternion).
using SpatialPoseCoordinates = std::array<double, 6>;

/// The two pose coordinates a slice spans: three planes of positions, three of rotation vectors.
enum class SpatialMapPlane { kXY, kXZ, kYZ, kRxRy, kRxRz, kRyRz };
inline constexpr std::array<SpatialMapPlane, 6> kSpatialMapPlanes = {
    SpatialMapPlane::kXY,   SpatialMapPlane::kXZ,   SpatialMapPlane::kYZ,
    SpatialMapPlane::kRxRy, SpatialMapPlane::kRxRz, SpatialMapPlane::kRyRz};

/// "xy", "xz", "yz", "rxry", "rxrz", "ryrz".
const char* to_string(SpatialMapPlane plane);
/// The plane named `text` (as to_string writes it); false when there is none.
bool spatial_map_plane_from_string(const std::string& text, SpatialMapPlane& plane);
/// The indices in SpatialPoseCoordinates of the plane's two axes (u, then v).
std::array<int, 2> spatial_map_axes(SpatialMapPlane plane);
/// Whether the plane spans rotation-vector components (rad) rather than positions (m).
bool is_orientation_plane(SpatialMapPlane plane);

struct SpatialWorkspaceMapOptions {
  SpatialMapPlane plane = SpatialMapPlane::kXY;
  /// The pose whose four coordinates off the plane the slice holds, and the centre of the default
  /// range; default: the home pose (FK at q = 0).
  std::optional<SpatialPoseCoordinates> pose;
  /// Points per side (>= 2). 40 x 40 over the default range of the reference robot's x-y plane
  /// is about 30 s of one core: a point far from home bends the rods hard (more RK4 steps, more
  /// Newton steps a cell away) and the border's failed solves cost most.
  int grid = 40;
  /// u_min, u_max, v_min, v_max along the plane's axes (m or rad); default: centred on the pose,
  /// kPositionHalfWidth times the mean rod length either way for positions, kRotationHalfWidth
  /// for rotations.
  std::optional<std::array<double, 4>> range;
  /// The actuators' stroke q_min, q_max (m), the same for every rod; a spatial robot's file has
  /// none: default, every joint value is within it.
  std::optional<std::array<double, 2>> stroke;
  SolverOptions solver;
  /// Threads that solve the map (0: one per core); the map is the same whatever their number.
  int threads = 0;

  /// The default range: half the mean rod length either way holds the reference robot's stable
  /// positions at its home height, and 0.75 rad its reachable rotation vectors at home.
  static constexpr double kPositionHalfWidth = 0.5;   ///< of the mean rod length
  static constexpr double kRotationHalfWidth = 0.75;  ///< rad
  /// A spatial IK costs about 0.6 ms warm: 500 x 500 points is minutes on one core; beyond, a typo.
  static constexpr OptionRange kGrid{"grid", 2, 500};
  static constexpr OptionRange kThreads{"threads", 0, 1024};
  /// As pcr ik's poses: no robot of this kind reaches further.
  static constexpr OptionRange kPosition{"position", -1, 1, "m"};
  static constexpr OptionRange kRotation{"rotation", -2 * M_PI, 2 * M_PI, "rad"};
  static constexpr OptionRange kStroke{"stroke", -1, 1, "m"};

  /// As SolverOptions::is_valid: the grid, the threads, the solver's options, and the pose, range
  /// and stroke when given (finite, within kPosition / kRotation / kStroke, in order).
  bool is_valid(std::string* error = nullptr) const;
};

/// One grid point of a spatial map. NaN fields where the value does not apply.
struct SpatialWorkspaceMapPoint {
  double u = 0, v = 0;          ///< the point's coordinates along the plane's axes (m or rad)
  SpatialPoseCoordinates pose;  ///< the whole pose of the point
  /// IK was run here: false where the flood from the seeds never came (beyond the border of the
  /// equilibria found; reachable and stable false, status meaningless).
  bool visited = false;
  /// IK found an equilibrium at this pose with the joints inside the stroke.
  bool reachable = false;
  /// That equilibrium (or, outside the stroke, the one IK found) holds with the joints held.
  bool stable = false;
  /// The IK status; kOutOfRange for an equilibrium whose joints lie outside the stroke.
  SolveStatus status = SolveStatus::kMaxIterations;
  SpatialJointVector q;  ///< joints of the equilibrium (m), NaN when IK found none
  double max_strain = std::numeric_limits<double>::quiet_NaN();
  double stability_margin = std::numeric_limits<double>::quiet_NaN();
  double singularity = std::numeric_limits<double>::quiet_NaN();
};

struct SpatialWorkspaceMap {
  SpatialMapPlane plane = SpatialMapPlane::kXY;
  SpatialPoseCoordinates pose{};  ///< the held coordinates (the plane's two: the range's centre)
  int nu = 0, nv = 0;
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0;
  std::vector<SpatialWorkspaceMapPoint> points;  ///< point (i, j) at j * nu + i, v_j rising
  double reachable_area = 0;  ///< m^2 or rad^2: the reachable points times a cell's area
  double stable_area = 0;     ///< the points reachable and stable
  int reachable_count = 0, stable_count = 0, visited_count = 0;
  double seconds = 0;  ///< wall time of the solves
  double cell_area() const { return (u_max - u_min) / (nu - 1) * (v_max - v_min) / (nv - 1); }
  double u(int i) const { return u_min + (u_max - u_min) * i / (nu - 1); }
  double v(int j) const { return v_min + (v_max - v_min) * j / (nv - 1); }
};

/// The platform pose of `solution` as SpatialPoseCoordinates (quaternion_log of its orientation).
SpatialPoseCoordinates spatial_pose_coordinates(const SpatialPose<double>& pose);

/// IK over the slice's grid, flooded outward from seeds as workspace_map floods a planar map
/// (the same code): each point warm-started from a neighbour (of its four) solved in the wave
/// before, with a small budget; seeds solved cold (from the home solution, FK at q = 0): first the
/// grid point nearest the home pose, then the kSeedLattice x kSeedLattice lattice points the
/// flood left unvisited. Each point gets the equilibrium of the branch the flood follows, stable
/// or not (SolverOptions::stable_inverse is not used: where the branch turns unstable the point
/// says so, as on a planar map). The result does not depend on the number of threads.
///
/// Six-rod robots only (their IK imposes the whole pose; with 3 or 5 rods it solves part of the
/// orientation, spatial_inverse_free_angles); throws InputError on another rod count, on options
/// is_valid refuses (naming the field and the value), and when the home solution fails (no
/// default pose, no seed).
SpatialWorkspaceMap spatial_workspace_map(const SpatialRobotParams<double>& robot,
                                          const SpatialWorkspaceMapOptions& options);

/// The map as CSV: u, v, x, y, z, rx, ry, rz, reachable, stable, status, q1..q6, max_strain,
/// stability_margin, singularity; status `unvisited` where no IK ran.
void write_spatial_workspace_map_csv(const SpatialWorkspaceMap& map, std::ostream& out);

}  // namespace pcr
