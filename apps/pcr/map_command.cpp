// pcr map: where the robot can work at one platform orientation: reachability, elastic
// stability, singularity (and predicted accuracy) over a grid of positions; for a spatial robot,
// the same over a slice of its 6-D workspace (a plane of positions or of rotation vectors).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/predicted_accuracy.hpp"
#include "pcr/calib/workspace_map.hpp"
#include "pcr/files.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/spatial/workspace_map.hpp"

namespace {

struct MapArguments {
  std::string robot, output, range;
  double theta = 0;
  int grid = 0;  ///< 0: the library's default for the robot's kind
  int threads = 0;
  std::string rotation_at, covariance, frame = "measurement";
  bool worst_case = false;
  std::string plane = "xy", pose, stroke;  ///< spatial robots
  pcr::cli::SolveArguments solve;
  const CLI::App* command = nullptr;  ///< which options were given
};

/// Options of one kind of robot only: those given for the other kind are refused by name.
const std::vector<std::string> kPlanarOnly = {"--theta",      "--rotation-range", "--covariance",
                                              "--worst-case", "--frame",          "--force",
                                              "--moment"};
const std::vector<std::string> kSpatialOnly = {"--plane", "--pose", "--stroke"};

std::vector<std::string> spatial_map_plane_names() {
  std::vector<std::string> names;
  for (pcr::SpatialMapPlane plane : pcr::kSpatialMapPlanes) names.emplace_back(to_string(plane));
  return names;
}

void refuse_options(const MapArguments& args, const std::vector<std::string>& names,
                    const std::string& why) {
  for (const std::string& name : names) {
    if (args.command->count(name) > 0) {
      throw pcr::InputError(name + ": " + (args.robot.empty() ? "<default robot>" : args.robot) +
                            " is " + why);
    }
  }
}

/// A spatial robot: IK over a slice of its 6-D workspace, CSV out, counts and areas on stderr.
void run_spatial_map(const MapArguments& args) {
  using namespace pcr;
  refuse_options(args, kPlanarOnly,
                 "a spatial robot: its map is a slice through the pose (--plane, --pose), its file "
                 "carries its load, and it has no calibration");
  const SpatialRobotDescription robot = load_spatial_robot(args.robot);
  SpatialWorkspaceMapOptions options;
  spatial_map_plane_from_string(args.plane, options.plane);  // CLI11 checked the name
  if (args.grid > 0) options.grid = args.grid;
  options.threads = args.threads;
  options.solver = args.solve.options();
  if (!args.pose.empty()) {
    const std::vector<double> p = cli::parse_list(args.pose, cli::spatial_pose_columns(), "--pose");
    options.pose = SpatialPoseCoordinates{p[0], p[1], p[2], p[3], p[4], p[5]};
  }
  const std::array<int, 2> axes = spatial_map_axes(options.plane);
  if (!args.range.empty()) {
    std::vector<std::string> names;
    for (int a : axes) {
      for (const char* end : {"_min", "_max"})
        names.push_back(cli::spatial_pose_columns()[a] + end);
    }
    const std::vector<double> r = cli::parse_list(args.range, names, "--range");
    options.range = std::array<double, 4>{r[0], r[1], r[2], r[3]};
  }
  if (!args.stroke.empty()) {
    const std::vector<double> s = cli::parse_list(args.stroke, {"q_min", "q_max"}, "--stroke");
    options.stroke = std::array<double, 2>{s[0], s[1]};
  }
  const SpatialWorkspaceMap map = spatial_workspace_map(robot.params, options);
  OutputFile file(args.output);
  write_spatial_workspace_map_csv(map, file.stream());
  file.commit();

  const bool turns = is_orientation_plane(map.plane);
  const std::string unit = turns ? "rad" : "m";
  const std::vector<std::string>& names = cli::spatial_pose_columns();
  std::string held;
  for (int c = 0; c < 6; ++c) {
    if (c == axes[0] || c == axes[1]) continue;
    held += (held.empty() ? "" : ", ") + names[c] + " " + format_double(map.pose[c]) +
            (c < 3 ? " m" : " rad");
  }
  int unstable = 0;  // reachable, not stable
  for (const SpatialWorkspaceMapPoint& p : map.points) unstable += p.reachable && !p.stable ? 1 : 0;
  std::cerr << "pcr map: robot '" << robot.name << "', plane " << to_string(map.plane) << " at "
            << held << "; " << map.nu << " x " << map.nv << " points over " << names[axes[0]]
            << " [" << format_double(map.u_min) << ", " << format_double(map.u_max) << "], "
            << names[axes[1]] << " [" << format_double(map.v_min) << ", "
            << format_double(map.v_max) << "] " << unit << " in " << format_double(map.seconds)
            << " s\n"
            << "pcr map: " << map.reachable_count << " reachable ("
            << format_double(map.reachable_area) << " " << unit << "^2), " << map.stable_count
            << " of them stable (" << format_double(map.stable_area) << " " << unit << "^2), "
            << unstable << " of them on an unstable equilibrium of the branch the map follows; "
            << map.visited_count << " of " << map.points.size() << " points solved\n";
}

/// "a,b,c,d" -> numbers, or InputError naming the option and the text.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const char* option) {
  std::vector<double> values;
  std::size_t begin = 0;
  const std::string bad = std::string(option) + ": expected " + std::to_string(count) +
                          " comma-separated numbers, got '" + text + "'";
  while (begin <= text.size()) {
    const std::size_t comma = std::min(text.find(',', begin), text.size());
    const std::string field = text.substr(begin, comma - begin);
    char* end = nullptr;
    const double value = std::strtod(field.c_str(), &end);
    if (field.empty() || *end != '\0' || !std::isfinite(value)) throw pcr::InputError(bad);
    values.push_back(value);
    begin = comma + 1;
  }
  if (values.size() != count) throw pcr::InputError(bad);
  return values;
}

void run_map(const MapArguments& args) {
  using namespace pcr;
  if (cli::is_spatial_robot(args.robot)) {
    run_spatial_map(args);
    return;
  }
  refuse_options(args, kSpatialOnly, "a planar robot: its map is at --theta over x and y");
  const RobotDescription robot = cli::load_robot_for_inverse(args.robot, "pcr map");
  const int n = robot.params.num_limbs;
  WorkspaceMapOptions options;
  options.theta = args.theta;
  if (args.grid > 0) options.grid = args.grid;
  options.threads = args.threads;
  options.solver = args.solve.options();
  options.load = args.solve.load();
  if (!args.range.empty()) {
    const std::vector<double> r = parse_numbers(args.range, 4, "--range");
    for (double v : r) {
      if (!(std::abs(v) <= 1.0)) {  // as pcr ik's poses: no robot of this kind reaches further
        throw InputError("--range: " + format_double(v) + " m is outside [-1, 1] m");
      }
    }
    if (!(r[0] < r[1] && r[2] < r[3])) {
      throw InputError("--range: expected x_min < x_max and y_min < y_max (m), got '" + args.range +
                       "'");
    }
    options.range = std::array<double, 4>{r[0], r[1], r[2], r[3]};
  }
  // Predicted accuracy: from the calibration's covariance, and the worst case over the robot's
  // uncertainty intervals.
  ParameterCovariance covariance;
  PredictedAccuracyOptions accuracy;
  accuracy.frame = args.frame == "platform" ? PoseFrame::kPlatform : PoseFrame::kMeasurement;
  accuracy.load = options.load;
  if (!args.covariance.empty()) covariance = read_parameter_covariance(args.covariance, n);
  if (args.worst_case || !args.covariance.empty()) {
    if (!robot.uncertainty) {
      if (args.worst_case) {
        throw InputError((args.robot.empty() ? std::string("<default robot>") : args.robot) +
                         ": --worst-case needs the description's uncertainty section");
      }
    } else {
      accuracy.half_widths = parameter_half_widths(*robot.uncertainty, n);
    }
  }
  if (!covariance.names.empty() || !accuracy.half_widths.empty()) {
    options.accuracy = predicted_accuracy_of_points(robot.params, covariance, accuracy);
  }
  if (!args.rotation_at.empty()) {
    const std::vector<double> at = parse_numbers(args.rotation_at, 2, "--rotation-range");
    const RotationRange range =
        rotation_range(robot.params, at[0], at[1], args.theta, options.solver, options.load);
    std::cout << "x,y,theta,reachable,theta_min,theta_max\n"
              << csv_line({format_double(at[0]), format_double(at[1]), format_double(args.theta),
                           range.reachable ? "1" : "0", format_double(range.theta_min),
                           format_double(range.theta_max)});
    return;
  }
  const WorkspaceMap map = workspace_map(robot.params, options);
  OutputFile file(args.output);
  write_workspace_map_csv(map, n, file.stream());
  file.commit();
  int reachable = 0, unstable = 0, stable = 0;  // unstable: reachable, not stable
  for (const WorkspaceMapPoint& p : map.points) {
    reachable += p.reachable ? 1 : 0;
    stable += p.reachable && p.stable ? 1 : 0;
    unstable += p.reachable && !p.stable ? 1 : 0;
  }
  std::cerr << "pcr map: robot '" << robot.name << "', theta " << format_double(map.theta)
            << " rad, " << map.nx << " x " << map.ny << " points over x ["
            << format_double(map.x_min) << ", " << format_double(map.x_max) << "], y ["
            << format_double(map.y_min) << ", " << format_double(map.y_max) << "] m in "
            << format_double(map.seconds) << " s\n"
            << "pcr map: " << reachable << " reachable (" << format_double(map.reachable_area * 1e6)
            << " mm^2), " << stable << " of them stable (" << format_double(map.stable_area * 1e6)
            << " mm^2), " << unstable
            << " of them on an unstable equilibrium of the branch the map follows\n";
}

}  // namespace

void register_map_command(CLI::App& app) {
  auto args = std::make_shared<MapArguments>();
  CLI::App* map = app.add_subcommand(
      "map",
      "Workspace map at a fixed orientation: IK over a grid of platform positions (each "
      "warm-started "
      "from a solved neighbour, outward from home) -> CSV "
      "x,y,theta,reachable,stable,status,q1..qn,max_strain,stability_margin,"
      "singularity,position_3sigma,orientation_3sigma,worst_position,worst_orientation; the "
      "reachable and stable areas on stderr. --rotation-range x,y prints the interval of theta "
      "reachable (stable, within the stroke) at one position instead. A spatial robot file (six "
      "rods) maps a slice of its 6-D workspace: --plane xy|xz|yz (positions, m) or rxry|rxrz|ryrz "
      "(rotation vectors, rad) through --pose -> CSV u,v,x,y,z,rx,ry,rz,reachable,stable,status,"
      "q1..q6,max_strain,stability_margin,singularity; areas in m^2 or rad^2 on stderr.");
  pcr::cli::add_robot_option(*map, args->robot);
  map->add_option("--theta", args->theta, "platform orientation (rad)")
      ->check(pcr::cli::within(pcr::WorkspaceMapOptions::kTheta));
  map->add_option("--grid", args->grid,
                  "points per side (default " + std::to_string(pcr::WorkspaceMapOptions().grid) +
                      "; " + std::to_string(pcr::SpatialWorkspaceMapOptions().grid) +
                      " for a spatial robot, at most " +
                      pcr::OptionRange::text(pcr::SpatialWorkspaceMapOptions::kGrid.hi) + ")")
      ->check(pcr::cli::within(pcr::WorkspaceMapOptions::kGrid));
  map->add_option("--range", args->range,
                  "x_min,x_max,y_min,y_max (m); default: the positions an FK scan of the stroke "
                  "box reaches, a tenth wider. Spatial: u_min,u_max,v_min,v_max along --plane's "
                  "axes (m or rad); default: centred on --pose, half the mean rod length either "
                  "way (positions) or 0.75 rad (rotations)");
  map->add_option("--plane", args->plane,
                  "spatial robots: the two pose coordinates the grid spans: xy, xz, yz "
                  "(positions) or rxry, rxrz, ryrz (rotation-vector components)")
      ->check(CLI::IsMember(spatial_map_plane_names()))
      ->capture_default_str();
  map->add_option("--pose", args->pose,
                  "spatial robots: x,y,z,rx,ry,rz (m, rad): the pose whose other four coordinates "
                  "the slice holds, and the centre of the default range; default: the home pose "
                  "(FK at q = 0)");
  map->add_option("--stroke", args->stroke,
                  "spatial robots: q_min,q_max (m), every rod's stroke: joints outside it are not "
                  "reachable (default: no limit, the file has none)");
  map->add_option("--rotation-range", args->rotation_at,
                  "x,y (m): print the rotation range at this position and stop");
  map->add_option("--covariance", args->covariance,
                  "calibration report (pcr_calibrate's REPORT.json) whose covariance gives the "
                  "predicted 3-sigma errors per point (and the worst case over the robot's "
                  "uncertainty intervals)");
  map->add_option("--frame", args->frame,
                  "pose whose error is predicted: measurement (what the camera measures, "
                  "^Se T_M, default) or platform (^W T_P in the limb-0 frames)")
      ->check(CLI::IsMember({"measurement", "platform"}));
  map->add_flag("--worst-case", args->worst_case,
                "worst-case errors over the robot's uncertainty intervals (no covariance needed)");
  map->add_option("--threads", args->threads,
                  "threads that solve the map (0: one per core); the map is the same whatever "
                  "their number")
      ->check(pcr::cli::within(pcr::WorkspaceMapOptions::kThreads))
      ->capture_default_str();
  map->add_option("--output", args->output, "output CSV (default: stdout)");
  args->solve.add_to(*map);
  args->command = map;
  map->callback([args] { run_map(*args); });
}
