// pcr sensitivity: the paper's Table 2 for a robot, and the ranking of the parameters by the pose
// error their uncertainty can cause. See pcr/calib/sensitivity.hpp; for a spatial robot file,
// pcr/calib/spatial_sensitivity.hpp.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/calib/spatial_sensitivity.hpp"

namespace {

struct SensitivityArguments {
  std::string robot, csv, json;
  double step = 1e-3;
  bool measured = false;
  pcr::cli::SolveArguments solve;
};

void run_spatial_sensitivity(const SensitivityArguments& args) {
  using namespace pcr;
  args.solve.require_no_planar_load(args.robot);
  const SpatialRobotDescription robot = load_spatial_robot(args.robot);
  SpatialSensitivityOptions options;
  options.step = args.step;
  options.pose =
      args.measured ? SpatialSensitivityPose::kMeasured : SpatialSensitivityPose::kPlatform;
  options.solver = args.solve.options();
  options.solver.check_stability = false;  // the derivatives do not need it
  const SpatialSensitivityReport report = spatial_sensitivity(robot, options);
  std::cout << spatial_sensitivity_table_text(report);
  OutputTransaction outputs;  // all or none
  if (!args.csv.empty()) write_file_atomically(args.csv, spatial_sensitivity_csv(report));
  if (!args.json.empty()) write_file_atomically(args.json, spatial_sensitivity_json(report));
  outputs.commit();
}

void run_sensitivity(const SensitivityArguments& args) {
  using namespace pcr;
  check_distinct_outputs({{"--csv", args.csv}, {"--json", args.json}});
  if (cli::is_spatial_robot(args.robot)) {
    run_spatial_sensitivity(args);
    return;
  }
  if (args.measured) {
    throw InputError(
        "--measured: for a spatial robot file only (the planar table is of the "
        "platform pose)");
  }
  const RobotDescription robot = load_robot_or_default(args.robot);
  SensitivityOptions options;
  options.step = args.step;
  options.load = args.solve.load();
  options.solver = args.solve.options();
  const SensitivityReport report = sensitivity_analysis(robot, options);
  std::cout << sensitivity_table_text(report);
  OutputTransaction outputs;  // all or none
  if (!args.csv.empty()) write_file_atomically(args.csv, sensitivity_csv(report));
  if (!args.json.empty()) write_file_atomically(args.json, sensitivity_json(report));
  outputs.commit();
}

}  // namespace

void register_sensitivity_command(CLI::App& app) {
  auto args = std::make_shared<SensitivityArguments>();
  CLI::App* cmd = app.add_subcommand(
      "sensitivity", "Table 2: platform pose sensitivity to each kind of parameter, and ranking");
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option("--csv", args->csv, "also write the table as CSV");
  cmd->add_option("--json", args->json, "also write the table as JSON");
  cmd->add_flag("--measured", args->measured,
                "spatial robot: differentiate the measured marker pose ^S T_M (the extrinsics "
                "get rows) instead of the platform pose ^W T_P");
  cmd->add_option("--step", args->step,
                  "grid step around the centre of the strokes (m; spatial: around 5 mm per rod)")
      ->check(pcr::cli::within(pcr::SensitivityOptions::kStep))
      ->capture_default_str();
  args->solve.add_to(*cmd);
  cmd->callback([args] { run_sensitivity(*args); });
}
