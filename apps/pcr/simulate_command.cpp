// pcr simulate: a dataset measured on a virtual robot (truth drawn in the nominal description's
// uncertainty intervals, Eq. 5 measurements with the paper's noise). See
// pcr/calib/virtual_robot.hpp.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/calib/named_effects.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace {

struct SimulateArguments {
  std::string robot, configs, output, truth;
  std::uint64_t seed = 1;
  double noise_position = pcr::kDefaultNoisePosition;
  double noise_angle = pcr::kDefaultNoiseAngle;
  std::vector<std::string> effects;
  double misalignment = pcr::UnmodelledEffects().misalignment_half_width;
  double diameter_spread = pcr::UnmodelledEffects().diameter_half_width;
  pcr::cli::SolveArguments solve;
};

void run_simulate(const SimulateArguments& args) {
  using namespace pcr;
  check_distinct_outputs({{"--output", args.output}, {"--truth", args.truth}});
  const RobotDescription nominal = load_robot_or_default(args.robot);
  VirtualRobotOptions options;
  options.seed = args.seed;
  options.noise_position = args.noise_position;
  options.noise_angle = args.noise_angle;
  options.solver = args.solve.options();
  UnmodelledEffects& fx = options.effects;
  fx = planar_effects_named(args.effects, "--effects");
  fx.misalignment_half_width = args.misalignment;
  fx.diameter_half_width = args.diameter_spread;
  if (!args.solve.force.empty() || args.solve.moment != 0) {
    fx.external_load = true;
    fx.load = args.solve.load();
  }
  const std::vector<JointVector> configs =
      read_configurations(args.configs, nominal.params.num_limbs);
  VirtualRobot robot(nominal, options);
  Dataset data;
  data.num_joints = nominal.params.num_limbs;
  const std::vector<VirtualMeasurement> measured = robot.measure_dataset(configs);
  for (std::size_t k = 0; k < configs.size(); ++k) {
    const VirtualMeasurement& m = measured[k];
    if (!m.ok) {
      throw std::runtime_error(args.configs + ": configuration " + std::to_string(k + 1) +
                               ": the virtual robot holds no equilibrium there (" +
                               to_string(m.summary.status) + ")");
    }
    data.add(configs[k], m.measured);
  }
  OutputTransaction outputs;  // all or none
  write_dataset(data, args.output);
  if (!args.truth.empty()) save_robot(robot.truth(), args.truth);
  outputs.commit();
  std::cerr << "pcr simulate: " << data.size() << " measurements of robot '" << nominal.name
            << "' (seed " << args.seed << ") written to " << args.output;
  if (fx.external_load) {
    std::cerr << "; external load (" << robot.load().force.x() << ", " << robot.load().force.y()
              << ") N, " << robot.load().moment << " N m";
  }
  std::cerr << "\n";
}

}  // namespace

void register_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArguments>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "measure joint configurations on a virtual robot drawn from a nominal description");
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option("--seed", args->seed, "seed of the truth draw and of the noise")
      ->capture_default_str();
  cmd->add_option("--configs", args->configs, "joint configurations CSV (q1,...,qn)")->required();
  cmd->add_option("--output", args->output, "dataset CSV to write (q1,...,qn,x,y,theta)")
      ->required();
  cmd->add_option("--truth", args->truth, "also write the true robot description (JSON)");
  using pcr::cli::within;
  cmd->add_option("--noise-position", args->noise_position, "std of x and y (m)")
      ->check(within(pcr::VirtualRobotOptions::kNoisePosition))
      ->capture_default_str();
  cmd->add_option("--noise-angle", args->noise_angle, "std of theta (rad)")
      ->check(within(pcr::VirtualRobotOptions::kNoiseAngle))
      ->capture_default_str();
  cmd->add_option("--effects", args->effects,
                  "unmodelled effects to switch on: misalignments, diameters, load, all "
                  "(pcr/calib/named_effects.hpp)")
      ->delimiter(',');
  cmd->add_option("--misalignment", args->misalignment,
                  "extra half-width on beta_i and gamma_i with 'misalignments' (rad)")
      ->check(within(pcr::UnmodelledEffects::kMisalignmentHalfWidth))
      ->capture_default_str();
  cmd->add_option("--diameter-spread", args->diameter_spread,
                  "independent half-width on each d_i with 'diameters' (m)")
      ->check(within(pcr::UnmodelledEffects::kDiameterHalfWidth))
      ->capture_default_str();
  args->solve.add_to(*cmd);
  cmd->callback([args] { run_simulate(*args); });
}
