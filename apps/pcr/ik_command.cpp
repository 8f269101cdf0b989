// pcr ik: platform poses -> joint values, one CSV row per input row, warm-started row to row.
#include <iostream>
#include <memory>

#include "commands.hpp"

namespace {

struct IkArguments {
  std::string robot, input, output;
  pcr::cli::SolveArguments solve;
};

/// An IK result that is a valid equilibrium (possibly outside the stroke), usable as a warm start.
bool is_solution(const pcr::SolverSummary& s) {
  return s.converged() || s.status == pcr::SolveStatus::kOutOfRange;
}

void run_ik(const IkArguments& args) {
  using namespace pcr;
  const RobotDescription robot = load_robot_or_default(args.robot);
  const int n = robot.params.num_limbs;
  if (n > 3) {
    throw InputError((args.robot.empty() ? std::string("<default robot>") : args.robot) +
                     ": robot '" + robot.name + "' has " + std::to_string(n) +
                     " limbs; inverse kinematics is a square problem only for 3 limbs (full "
                     "pose) and 2 limbs (x, y imposed, theta solved)");
  }
  const SolverOptions options = args.solve.options();
  const PlatformLoad<double> load = args.solve.load();
  CsvReadOptions csv;
  csv.columns = {"x", "y", "theta"};
  const CsvTable table = cli::read_table(args.input, csv);

  OutputFile out(args.output);
  std::vector<std::string> header = {"x", "y", "theta"};
  for (const std::string& q : cli::joint_names(n)) header.push_back(q);
  for (const char* c : {"converged", "iterations", "residual", "status", "max_strain"}) {
    header.emplace_back(c);
  }
  out.stream() << csv_line(header);

  InverseSolution previous;
  bool have_previous = false;
  int failures = 0;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const std::vector<double>& row = table.rows[r];
    const Pose2<double> pose{row[0], row[1], row[2]};
    InverseSolution solution;
    int iterations = 0;
    if (have_previous) {
      solution = inverse_kinematics(robot.params, pose, previous, options, load);
      iterations += solution.summary.iterations;
    }
    if (!have_previous || !is_solution(solution.summary)) {
      solution = inverse_kinematics(robot.params, pose, options, load);
      iterations += solution.summary.iterations;
    }
    const SolverSummary& s = solution.summary;
    const bool valid = is_solution(s);
    have_previous = valid;
    if (valid) previous = solution;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<std::string> fields;
    // For n = 2 theta is solved for: report the solved value.
    fields.push_back(format_double(pose.x));
    fields.push_back(format_double(pose.y));
    fields.push_back(format_double(n == 2 ? (valid ? solution.pose.theta : nan) : pose.theta));
    for (int i = 0; i < n; ++i) fields.push_back(format_double(valid ? solution.q(i) : nan));
    fields.push_back(s.converged() ? "1" : "0");
    fields.push_back(std::to_string(iterations));
    fields.push_back(format_double(s.final_residual_norm));
    fields.push_back(to_string(s.status));
    fields.push_back(format_double(valid ? s.max_strain : nan));
    out.stream() << csv_line(fields);
    if (!s.converged()) {
      ++failures;
      std::cerr << "pcr ik: " << table.source << ":" << table.line_numbers[r]
                << ": not converged (" << to_string(s.status) << ")\n";
    }
  }
  out.commit();
  if (failures > 0) {
    std::cerr << "pcr ik: " << failures << " of " << table.rows.size()
              << " rows did not converge\n";
    cli::exit_status() = 1;
  }
}

}  // namespace

void register_ik_command(CLI::App& app) {
  auto args = std::make_shared<IkArguments>();
  CLI::App* ik = app.add_subcommand(
      "ik", "Inverse kinematics: rows x,y,theta (m, m, rad) -> x,y,theta,q1,...,qn,converged,"
            "iterations,residual,status,max_strain. Joints outside q_range give converged=0, "
            "status out_of_range. With 2 limbs theta is solved for (the input theta is ignored). "
            "Exit status 1 if a row did not converge.");
  pcr::cli::add_robot_option(*ik, args->robot);
  ik->add_option("--input", args->input, "CSV of poses (default: stdin)");
  ik->add_option("--output", args->output, "output CSV (default: stdout)");
  args->solve.add_to(*ik);
  ik->callback([args] { run_ik(*args); });
}
