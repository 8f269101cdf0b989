// Workspace maps and rotation ranges (pcr/calib/workspace_map.hpp), and slices through a spatial
// robot's workspace (pcr/spatial/workspace_map.hpp).
#include "calibration_bindings.hpp"
#include "pcr/calib/workspace_map.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/spatial/workspace_map.hpp"

namespace pcr::python {

py::dict workspace_map_dict(const WorkspaceMap& map, int n) {
  const auto nx = static_cast<py::ssize_t>(map.nx), ny = static_cast<py::ssize_t>(map.ny);
  py::array_t<double> xs(nx), ys(ny), q({ny, nx, static_cast<py::ssize_t>(n)});
  py::array_t<bool> visited({ny, nx}), reachable({ny, nx}), stable({ny, nx});
  py::array_t<int> status({ny, nx});
  const char* names[] = {"max_strain",       "stability_margin",   "singularity",
                         "position_3sigma",  "orientation_3sigma", "worst_position",
                         "worst_orientation"};
  std::vector<py::array_t<double>> fields;
  for (std::size_t f = 0; f < 7; ++f) fields.emplace_back(std::vector<py::ssize_t>{ny, nx});
  for (py::ssize_t i = 0; i < nx; ++i) xs.mutable_at(i) = map.points[i].x;
  for (py::ssize_t j = 0; j < ny; ++j) ys.mutable_at(j) = map.points[j * nx].y;
  for (py::ssize_t j = 0; j < ny; ++j) {
    for (py::ssize_t i = 0; i < nx; ++i) {
      const WorkspaceMapPoint& p = map.points[static_cast<std::size_t>(j * nx + i)];
      visited.mutable_at(j, i) = p.visited;
      reachable.mutable_at(j, i) = p.reachable;
      stable.mutable_at(j, i) = p.stable;
      status.mutable_at(j, i) = p.visited ? static_cast<int>(p.status) : -1;
      for (int k = 0; k < n; ++k) q.mutable_at(j, i, k) = p.q(k);
      const double values[] = {p.max_strain,       p.stability_margin,   p.singularity,
                               p.position_3sigma,  p.orientation_3sigma, p.worst_position,
                               p.worst_orientation};
      for (std::size_t f = 0; f < 7; ++f) fields[f].mutable_at(j, i) = values[f];
    }
  }
  py::dict d;
  d["x"] = xs;
  d["y"] = ys;
  d["theta"] = map.theta;
  d["visited"] = visited;
  d["reachable"] = reachable;
  d["stable"] = stable;
  d["status_code"] = status;
  d["q"] = q;
  for (std::size_t f = 0; f < 7; ++f) d[names[f]] = fields[f];
  d["reachable_area"] = map.reachable_area;
  d["stable_area"] = map.stable_area;
  d["seconds"] = map.seconds;
  return d;
}

py::dict spatial_workspace_map_dict(const SpatialWorkspaceMap& map, int n) {
  const auto nu = static_cast<py::ssize_t>(map.nu), nv = static_cast<py::ssize_t>(map.nv);
  py::array_t<double> us(nu), vs(nv), q({nv, nu, static_cast<py::ssize_t>(n)}),
      poses({nv, nu, py::ssize_t{6}}), held(py::ssize_t{6});
  py::array_t<bool> visited({nv, nu}), reachable({nv, nu}), stable({nv, nu});
  py::array_t<int> status({nv, nu});
  py::array_t<double> max_strain({nv, nu}), margin({nv, nu}), singularity({nv, nu});
  for (py::ssize_t i = 0; i < nu; ++i) us.mutable_at(i) = map.u(static_cast<int>(i));
  for (py::ssize_t j = 0; j < nv; ++j) vs.mutable_at(j) = map.v(static_cast<int>(j));
  for (py::ssize_t k = 0; k < 6; ++k) held.mutable_at(k) = map.pose[static_cast<std::size_t>(k)];
  for (py::ssize_t j = 0; j < nv; ++j) {
    for (py::ssize_t i = 0; i < nu; ++i) {
      const SpatialWorkspaceMapPoint& p = map.points[static_cast<std::size_t>(j * nu + i)];
      visited.mutable_at(j, i) = p.visited;
      reachable.mutable_at(j, i) = p.reachable;
      stable.mutable_at(j, i) = p.stable;
      status.mutable_at(j, i) = p.visited ? static_cast<int>(p.status) : -1;
      for (int k = 0; k < n; ++k) {
        q.mutable_at(j, i, k) = p.q(k);  // NaN where IK found no equilibrium
      }
      for (int k = 0; k < 6; ++k) poses.mutable_at(j, i, k) = p.pose[static_cast<std::size_t>(k)];
      max_strain.mutable_at(j, i) = p.max_strain;
      margin.mutable_at(j, i) = p.stability_margin;
      singularity.mutable_at(j, i) = p.singularity;
    }
  }
  py::dict d;
  d["plane"] = to_string(map.plane);
  d["u"] = us;
  d["v"] = vs;
  d["pose"] = held;
  d["poses"] = poses;
  d["visited"] = visited;
  d["reachable"] = reachable;
  d["stable"] = stable;
  d["status_code"] = status;
  d["q"] = q;
  d["max_strain"] = max_strain;
  d["stability_margin"] = margin;
  d["singularity"] = singularity;
  d["reachable_area"] = map.reachable_area;
  d["stable_area"] = map.stable_area;
  d["seconds"] = map.seconds;
  return d;
}

void wrap_workspace_map(py::module_& m) {
  m.def(
      "workspace_map",
      [](const RobotDescription& robot, double theta, int grid,
         const std::optional<std::array<double, 4>>& range, const py::object& force, double moment,
         const std::optional<SolverOptions>& solver, int threads) {
        WorkspaceMapOptions o;
        o.threads = threads;
        o.theta = theta;
        o.grid = grid;
        o.range = range;
        o.load = make_load(force, moment);
        o.solver = options_or_default(solver);
        checked_options(o);
        WorkspaceMap map;
        {
          py::gil_scoped_release release;
          map = workspace_map(robot.params, o);
        }
        return workspace_map_dict(map, robot.params.num_limbs);
      },
      py::arg("robot"), py::kw_only(), py::arg("theta") = 0.0, py::arg("grid") = 200,
      py::arg("range") = py::none(), py::arg("force") = no_force(), py::arg("moment") = 0.0,
      py::arg("options") = py::none(), py::arg("threads") = 0,
      "Workspace map at orientation theta (rad): IK over a grid x grid of platform positions "
      "(range = (x_min, x_max, y_min, y_max) m; default: the positions an FK scan of the stroke "
      "box reaches, a tenth wider), each warm-started from a solved neighbour, outward from home, "
      "on `threads` threads (0: one per core; the map does not depend on them). Returns a dict: "
      "x (grid,), y (grid,), theta, and (grid, grid) arrays indexed [iy, ix]: visited (IK was "
      "run there; not where no solved neighbour led), reachable (an equilibrium within the "
      "stroke), stable, status_code (a SolveStatus value, -1 where not visited), q (grid, grid, "
      "n) m, max_strain, stability_margin, "
      "singularity, position_3sigma, orientation_3sigma, worst_position, worst_orientation (NaN "
      "without a covariance); reachable_area, stable_area (m^2), seconds. Releases the GIL.");

  m.def(
      "workspace_map",
      [](const SpatialRobotDescription& robot, const std::string& plane,
         const std::optional<std::array<double, 6>>& pose,
         const std::optional<std::array<double, 4>>& range, int grid,
         const std::optional<std::array<double, 2>>& stroke,
         const std::optional<SolverOptions>& solver, int threads) {
        SpatialWorkspaceMapOptions o;
        if (!spatial_map_plane_from_string(plane, o.plane)) {
          throw std::invalid_argument("plane: expected xy, xz, yz, rxry, rxrz or ryrz, got '" +
                                      plane + "'");
        }
        o.pose = pose;
        o.range = range;
        o.grid = grid;
        o.stroke = stroke;
        o.solver = options_or_default(solver);
        o.threads = threads;
        checked_options(o);
        SpatialWorkspaceMap map;
        {
          py::gil_scoped_release release;
          map = spatial_workspace_map(robot.params, o);
        }
        return spatial_workspace_map_dict(map, robot.params.num_rods);
      },
      py::arg("robot"), py::kw_only(), py::arg("plane") = "xy", py::arg("pose") = py::none(),
      py::arg("range") = py::none(), py::arg("grid") = SpatialWorkspaceMapOptions().grid,
      py::arg("stroke") = py::none(), py::arg("options") = py::none(), py::arg("threads") = 0,
      "A spatial robot's workspace slice (six rods), as `pcr map` maps a spatial file: IK over a "
      "grid x grid of two pose coordinates, plane 'xy', 'xz', 'yz' (positions, m) or 'rxry', "
      "'rxrz', 'ryrz' (rotation vector, rad), the other four held at pose (x, y, z, rx, ry, rz; "
      "default: the home pose); range (u_min, u_max, v_min, v_max), default centred on the pose; "
      "stroke (q_min, q_max) m for every rod, default none. Each point warm-started from a solved "
      "neighbour, outward from home, on `threads` threads (the map does not depend on them). "
      "Returns a dict: plane, u (grid,), v (grid,), pose (6,) the held coordinates, and (grid, "
      "grid) arrays indexed [iv, iu]: visited, reachable, stable, status_code (-1 where not "
      "visited), q (grid, grid, n) m, poses (grid, grid, 6), max_strain, stability_margin, "
      "singularity; reachable_area, stable_area (m^2 or rad^2), seconds. Releases the GIL.");

  m.def(
      "rotation_range",
      [](const RobotDescription& robot, double x, double y, double theta, const py::object& force,
         double moment, const std::optional<SolverOptions>& solver) {
        const PlatformLoad<double> load = make_load(force, moment);
        RotationRange r;
        {
          py::gil_scoped_release release;
          r = rotation_range(robot.params, checked_number(x, "x", "m"), checked_number(y, "y", "m"),
                             checked_number(theta, "theta", "rad"), options_or_default(solver),
                             load);
        }
        return py::make_tuple(r.reachable, r.theta_min, r.theta_max);
      },
      py::arg("robot"), py::arg("x"), py::arg("y"), py::kw_only(), py::arg("theta") = 0.0,
      py::arg("force") = no_force(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
      "The interval of platform orientations reachable (an equilibrium within the stroke, and "
      "stable) at the position (x, y) (m), searched from theta both ways: (reachable, theta_min, "
      "theta_max) in rad. Releases the GIL.");
}

}  // namespace pcr::python
