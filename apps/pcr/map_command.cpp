// pcr map: where the robot can work at one platform orientation: reachability, elastic
// stability, singularity (and predicted accuracy) over a grid of positions.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/predicted_accuracy.hpp"
#include "pcr/calib/workspace_map.hpp"
#include "pcr/files.hpp"

namespace {

struct MapArguments {
  std::string robot, output, range;
  double theta = 0;
  int grid = 200;
  int threads = 0;
  std::string rotation_at, covariance, frame = "measurement";
  bool worst_case = false;
  pcr::cli::SolveArguments solve;
};

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
  const RobotDescription robot = cli::load_robot_for_inverse(args.robot, "pcr map");
  const int n = robot.params.num_limbs;
  WorkspaceMapOptions options;
  options.theta = args.theta;
  options.grid = args.grid;
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
      "reachable (stable, within the stroke) at one position instead.");
  pcr::cli::add_robot_option(*map, args->robot);
  map->add_option("--theta", args->theta, "platform orientation (rad)")
      ->check(pcr::cli::within(pcr::WorkspaceMapOptions::kTheta));
  map->add_option("--grid", args->grid, "points per side")
      ->check(pcr::cli::within(pcr::WorkspaceMapOptions::kGrid))
      ->capture_default_str();
  map->add_option("--range", args->range,
                  "x_min,x_max,y_min,y_max (m); default: the positions an FK scan of the stroke "
                  "box reaches, a tenth wider");
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
  map->callback([args] { run_map(*args); });
}
