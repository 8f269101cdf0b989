// Slices through a spatial robot's workspace (pcr/spatial/workspace_map.hpp), flooded as the planar
// maps are (map_flood.hpp).
#include <chrono>
#include <cmath>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>

#include "map_flood.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/input_error.hpp"
#include "pcr/spatial/workspace_map.hpp"

namespace pcr {
namespace {

constexpr std::array<const char*, 6> kCoordinateNames = {"x", "y", "z", "rx", "ry", "rz"};

/// The range a pose coordinate must lie in: kPosition for x, y, z (m), kRotation for rx, ry, rz.
OptionRange coordinate_range(int c, const char* name) {
  const OptionRange& r =
      c < 3 ? SpatialWorkspaceMapOptions::kPosition : SpatialWorkspaceMapOptions::kRotation;
  return OptionRange{name, r.lo, r.hi, r.unit};
}

std::string numbers_text(const double* values, int count) {
  std::string text;
  for (int k = 0; k < count; ++k) text += (k > 0 ? "," : "") + OptionRange::text(values[k]);
  return text;
}

SpatialPose<double> pose_of(const SpatialPoseCoordinates& c) {
  SpatialPose<double> pose;
  pose.position = Vector3<double>(c[0], c[1], c[2]);
  pose.orientation = quaternion_exp<double>(Vector3<double>(c[3], c[4], c[5]));
  return pose;
}

/// The spatial map's points for map_internal::GridFlood: IK at the slice's poses, cold from the
/// home solution or warm from a neighbour, each recorded into its SpatialWorkspaceMapPoint.
class SpatialMapPoints {
 public:
  using Solution = SpatialInverseSolution;

  SpatialMapPoints(const SpatialRobotParams<double>& robot,
                   const SpatialWorkspaceMapOptions& options, const SpatialForwardSolution& home,
                   SpatialWorkspaceMap& map)
      : robot_(robot), options_(options), home_(home), map_(map) {
    // The map follows its branch, as the planar map: where it turns unstable the point says so
    // (stable false), and the flood goes on along it.
    cold_options_ = options.solver;
    cold_options_.stable_inverse = false;
    neighbour_options_ = map_internal::neighbour_solver_options(cold_options_);
  }

  SpatialInverseSolution cold(std::size_t k) const {
    return spatial_inverse_kinematics_from_home(robot_, pose_of(map_.points[k].pose), home_,
                                                cold_options_);
  }
  SpatialInverseSolution warm(std::size_t k, const SpatialInverseSolution& from) const {
    return spatial_inverse_kinematics(robot_, pose_of(map_.points[k].pose), from,
                                      neighbour_options_);
  }

  void record(std::size_t k, const SpatialInverseSolution& s) {
    SpatialWorkspaceMapPoint& p = map_.points[k];
    p.visited = true;
    p.status = s.summary.status;
    if (!is_equilibrium(s.summary)) return;
    p.q = s.q;
    p.reachable = within_stroke(s.q);
    if (p.status == SolveStatus::kConverged && !p.reachable) p.status = SolveStatus::kOutOfRange;
    p.stable = s.summary.stability == Stability::kStable;
    p.max_strain = s.summary.max_strain;
    p.stability_margin = s.summary.stability_margin;
    p.singularity = s.summary.singularity;
  }

 private:
  bool within_stroke(const SpatialJointVector& q) const {
    if (!options_.stroke) return true;
    const auto [lo, hi] = *options_.stroke;
    return (q.array() >= lo).all() && (q.array() <= hi).all();
  }

  const SpatialRobotParams<double>& robot_;
  const SpatialWorkspaceMapOptions& options_;
  const SpatialForwardSolution& home_;
  SpatialWorkspaceMap& map_;
  SolverOptions cold_options_, neighbour_options_;
};

}  // namespace

const char* to_string(SpatialMapPlane plane) {
  switch (plane) {
    case SpatialMapPlane::kXY:
      return "xy";
    case SpatialMapPlane::kXZ:
      return "xz";
    case SpatialMapPlane::kYZ:
      return "yz";
    case SpatialMapPlane::kRxRy:
      return "rxry";
    case SpatialMapPlane::kRxRz:
      return "rxrz";
    case SpatialMapPlane::kRyRz:
      return "ryrz";
  }
  return "?";
}

bool spatial_map_plane_from_string(const std::string& text, SpatialMapPlane& plane) {
  for (SpatialMapPlane p : kSpatialMapPlanes) {
    if (text == to_string(p)) {
      plane = p;
      return true;
    }
  }
  return false;
}

std::array<int, 2> spatial_map_axes(SpatialMapPlane plane) {
  switch (plane) {
    case SpatialMapPlane::kXY:
      return {0, 1};
    case SpatialMapPlane::kXZ:
      return {0, 2};
    case SpatialMapPlane::kYZ:
      return {1, 2};
    case SpatialMapPlane::kRxRy:
      return {3, 4};
    case SpatialMapPlane::kRxRz:
      return {3, 5};
    case SpatialMapPlane::kRyRz:
      return {4, 5};
  }
  return {0, 1};
}

bool is_orientation_plane(SpatialMapPlane plane) { return spatial_map_axes(plane)[0] >= 3; }

bool SpatialWorkspaceMapOptions::is_valid(std::string* error) const {
  if (!kGrid.check(grid, error) || !kThreads.check(threads, error) || !solver.is_valid(error)) {
    return false;
  }
  if (pose) {
    for (int c = 0; c < 6; ++c) {
      if (!coordinate_range(c, kCoordinateNames[c]).check((*pose)[c], error, "pose.")) return false;
    }
  }
  if (range) {
    const std::array<int, 2> axes = spatial_map_axes(plane);
    const std::array<double, 4>& r = *range;
    for (int k = 0; k < 4; ++k) {
      const int c = axes[static_cast<std::size_t>(k / 2)];
      const std::string name = std::string(kCoordinateNames[c]) + (k % 2 == 0 ? "_min" : "_max");
      if (!coordinate_range(c, name.c_str()).check(r[k], error, "range.")) return false;
    }
    if (!(r[0] < r[1] && r[2] < r[3])) {
      if (error != nullptr) {
        const std::string u = kCoordinateNames[axes[0]], v = kCoordinateNames[axes[1]];
        *error = "range: expected " + u + "_min < " + u + "_max and " + v + "_min < " + v +
                 "_max for the plane " + to_string(plane) + ", got " + numbers_text(r.data(), 4);
      }
      return false;
    }
  }
  if (stroke) {
    const std::array<double, 2>& s = *stroke;
    if (!OptionRange{"q_min", kStroke.lo, kStroke.hi, kStroke.unit}.check(s[0], error, "stroke.") ||
        !OptionRange{"q_max", kStroke.lo, kStroke.hi, kStroke.unit}.check(s[1], error, "stroke.")) {
      return false;
    }
    if (!(s[0] <= s[1])) {
      if (error != nullptr) {
        *error = "stroke: expected q_min <= q_max (m), got " + numbers_text(s.data(), 2);
      }
      return false;
    }
  }
  return true;
}

SpatialPoseCoordinates spatial_pose_coordinates(const SpatialPose<double>& pose) {
  const Vector3<double> r = quaternion_log(pose.orientation);
  return {pose.position.x(), pose.position.y(), pose.position.z(), r.x(), r.y(), r.z()};
}

SpatialWorkspaceMap spatial_workspace_map(const SpatialRobotParams<double>& robot,
                                          const SpatialWorkspaceMapOptions& options) {
  if (robot.num_rods != 6) {
    // With 3 or 5 rods IK solves part of the orientation (spatial_inverse_free_angles): the
    // slice's coordinates would not all be imposed.
    throw InputError(
        "spatial_workspace_map: maps robots of 6 rods, whose IK imposes the whole pose; the robot "
        "has " +
        std::to_string(robot.num_rods));
  }
  require_valid(options, "spatial_workspace_map");
  const SpatialForwardSolution home =
      spatial_forward_kinematics(robot, SpatialJointVector::Zero(6), options.solver);
  if (!options.pose && !home.summary.converged()) {
    throw std::runtime_error(
        std::string("spatial_workspace_map: the home solution (FK at q = 0) did not converge (") +
        to_string(home.summary.status) + "): no default pose; give one");
  }
  SpatialWorkspaceMap map;
  map.plane = options.plane;
  map.pose = options.pose ? *options.pose : spatial_pose_coordinates(home.pose);
  const std::array<int, 2> axes = spatial_map_axes(options.plane);
  std::array<double, 4> range;
  if (options.range) {
    range = *options.range;
  } else {
    double half = SpatialWorkspaceMapOptions::kRotationHalfWidth;
    if (!is_orientation_plane(options.plane)) {
      double length = 0;
      for (int i = 0; i < robot.num_rods; ++i) length += robot.limb(i).rod.length;
      half = SpatialWorkspaceMapOptions::kPositionHalfWidth * length / robot.num_rods;
    }
    const double u = map.pose[axes[0]], v = map.pose[axes[1]];
    range = {u - half, u + half, v - half, v + half};
  }
  map.nu = map.nv = options.grid;
  map.u_min = range[0];
  map.u_max = range[1];
  map.v_min = range[2];
  map.v_max = range[3];
  map.points.resize(static_cast<std::size_t>(map.nu) * static_cast<std::size_t>(map.nv));
  for (std::size_t k = 0; k < map.points.size(); ++k) {
    SpatialWorkspaceMapPoint& p = map.points[k];
    p.u = map.u(static_cast<int>(k % static_cast<std::size_t>(map.nu)));
    p.v = map.v(static_cast<int>(k / static_cast<std::size_t>(map.nu)));
    p.pose = map.pose;
    p.pose[axes[0]] = p.u;
    p.pose[axes[1]] = p.v;
    p.q = SpatialJointVector::Constant(6, std::numeric_limits<double>::quiet_NaN());
  }
  const auto start = std::chrono::steady_clock::now();
  SpatialMapPoints points(robot, options, home, map);
  map_internal::GridFlood<SpatialMapPoints> flood(points, map.nu, map.nv, options.threads);
  std::optional<std::size_t> first;
  if (home.summary.converged()) {  // the grid point nearest the home pose
    const SpatialPoseCoordinates at = spatial_pose_coordinates(home.pose);
    using map_internal::nearest_grid_index;
    first = flood.index(nearest_grid_index(at[axes[0]], map.u_min, map.u_max, map.nu),
                        nearest_grid_index(at[axes[1]], map.v_min, map.v_max, map.nv));
  }
  flood.run(first);
  map.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const SpatialWorkspaceMapPoint& p : map.points) {
    map.visited_count += p.visited ? 1 : 0;
    map.reachable_count += p.reachable ? 1 : 0;
    map.stable_count += p.reachable && p.stable ? 1 : 0;
  }
  map.reachable_area = map.reachable_count * map.cell_area();
  map.stable_area = map.stable_count * map.cell_area();
  return map;
}

void write_spatial_workspace_map_csv(const SpatialWorkspaceMap& map, std::ostream& out) {
  CsvWriter csv(out);
  for (const char* c : {"u", "v"}) csv.add(c);
  for (const char* c : kCoordinateNames) csv.add(c);
  for (const char* c : {"reachable", "stable", "status"}) csv.add(c);
  for (int i = 0; i < 6; ++i) csv.add("q" + std::to_string(i + 1));
  for (const char* c : {"max_strain", "stability_margin", "singularity"}) csv.add(c);
  csv.end_row();
  for (const SpatialWorkspaceMapPoint& p : map.points) {
    csv.add(p.u);
    csv.add(p.v);
    for (double c : p.pose) csv.add(c);
    csv.add(p.reachable ? 1 : 0);
    csv.add(p.stable ? 1 : 0);
    csv.add(p.visited ? to_string(p.status) : "unvisited");
    for (int i = 0; i < 6; ++i) csv.add(p.q(i));
    csv.add(p.max_strain);
    csv.add(p.stability_margin);
    csv.add(p.singularity);
    csv.end_row();
  }
  csv.flush();
}

}  // namespace pcr
