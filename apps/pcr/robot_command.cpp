// pcr robot: validate a pcr-robot description and print it in canonical form.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace {

struct RobotArguments {
  std::string robot, output, home_pose;
};

/// A spatial robot file: validated and written in canonical form (every field).
void run_spatial_robot(const RobotArguments& args) {
  using namespace pcr;
  if (!args.home_pose.empty()) {
    throw InputError("--home-pose: " + args.robot +
                     " is a spatial robot, whose home is unique (no home_bow)");
  }
  const SpatialRobotDescription robot = load_spatial_robot(args.robot);
  if (args.output.empty() || args.output == "-") {
    std::cout << spatial_robot_to_json(robot);
  } else {
    save_spatial_robot(robot, args.output);
  }
  std::cerr << args.robot << ": '" << robot.name << "', spatial, " << robot.params.num_rods
            << " rods: valid\n";
}

void run_robot(const RobotArguments& args) {
  using namespace pcr;
  if (cli::is_spatial_robot(args.robot)) {
    run_spatial_robot(args);
    return;
  }
  RobotDescription robot = load_robot_or_default(args.robot);
  if (!args.home_pose.empty()) {
    const std::vector<double> pose =
        cli::parse_list(args.home_pose, {"x", "y", "theta"}, "--home-pose");
    RobotParams<double> chosen;
    if (!choose_home(robot.params, Pose2<double>{pose[0], pose[1], pose[2]}, chosen)) {
      throw InputError("--home-pose: no home of the robot solves");
    }
    robot.params = chosen;
  }
  if (args.output.empty() || args.output == "-") {
    std::cout << robot_to_json(robot);
  } else {
    save_robot(robot, args.output);
  }
  const RobotParams<double>& p = robot.params;
  double l_min = p.limb(0).rod.length, l_max = l_min;
  for (int i = 1; i < p.num_limbs; ++i) {
    l_min = std::min(l_min, p.limb(i).rod.length);
    l_max = std::max(l_max, p.limb(i).rod.length);
  }
  std::cerr << (args.robot.empty() ? "<default robot>" : args.robot) << ": '" << robot.name << "', "
            << p.num_limbs << " limbs, E = " << format_double(robot.young_modulus)
            << " Pa, l = " << format_double(l_min)
            << (l_max != l_min ? " to " + format_double(l_max) : std::string()) << " m, "
            << (robot.uncertainty ? "with" : "without") << " uncertainty: valid\n";
  std::string bows;
  for (int i = 0; i < p.num_limbs; ++i) {
    if (p.limb(i).home_bow != 0) {
      bows += (bows.empty() ? "" : ", ") + std::string("limbs[") + std::to_string(i) + "] " +
              (p.limb(i).home_bow > 0 ? "left" : "right");
    }
  }
  if (!bows.empty()) std::cerr << "home: rods bowed " << bows << "\n";
}

}  // namespace

void register_robot_command(CLI::App& app) {
  auto args = std::make_shared<RobotArguments>();
  CLI::App* cmd =
      app.add_subcommand("robot",
                         "Validate a pcr-robot description, planar or spatial, and write it in "
                         "canonical form (full precision; a summary goes to stderr).");
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option("--output", args->output, "output JSON file (default: stdout)");
  cmd->add_option("--home-pose", args->home_pose,
                  "the robot's measured home pose x,y,theta (m, m, rad: ^W T_P at q = 0): writes "
                  "it with each limb's home_bow, the home nearest that pose (a pre-stressed "
                  "robot, n >= 4, has several)");
  cmd->callback([args] { run_robot(*args); });
}
