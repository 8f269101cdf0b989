// pcr fk: joint values -> platform pose, one CSV row per input row, warm-started row to row.
#include <iostream>
#include <memory>

#include "commands.hpp"

namespace {

struct FkArguments {
  std::string robot, input, output;
  pcr::cli::SolveArguments solve;
};

void run_fk(const FkArguments& args) {
  using namespace pcr;
  const RobotDescription robot = load_robot_or_default(args.robot);
  const int n = robot.params.num_limbs;
  const SolverOptions options = args.solve.options();
  const PlatformLoad<double> load = args.solve.load();
  CsvReadOptions csv;
  csv.columns = cli::joint_names(n);
  const CsvTable table = cli::read_table(args.input, csv);

  OutputFile out(args.output);
  std::vector<std::string> header = csv.columns;
  for (const char* c : {"x", "y", "theta", "converged", "iterations", "residual", "status",
                        "max_strain"}) {
    header.emplace_back(c);
  }
  out.stream() << csv_line(header);

  ForwardSolution previous;
  bool have_previous = false;
  int failures = 0;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = table.rows[r][static_cast<std::size_t>(i)];
    // Warm start from the last converged row; a warm start that fails is retried cold.
    ForwardSolution solution;
    int iterations = 0;
    if (have_previous) {
      solution = forward_kinematics(robot.params, q, previous, options, load);
      iterations += solution.summary.iterations;
    }
    if (!have_previous || !solution.summary.converged()) {
      solution = forward_kinematics(robot.params, q, options, load);
      iterations += solution.summary.iterations;
    }
    const SolverSummary& s = solution.summary;
    have_previous = s.converged();
    if (have_previous) previous = solution;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<std::string> fields;
    for (int i = 0; i < n; ++i) fields.push_back(format_double(q(i)));
    fields.push_back(format_double(s.converged() ? solution.pose.x : nan));
    fields.push_back(format_double(s.converged() ? solution.pose.y : nan));
    fields.push_back(format_double(s.converged() ? solution.pose.theta : nan));
    fields.push_back(s.converged() ? "1" : "0");
    fields.push_back(std::to_string(iterations));
    fields.push_back(format_double(s.final_residual_norm));
    fields.push_back(to_string(s.status));
    fields.push_back(format_double(s.converged() ? s.max_strain : nan));
    out.stream() << csv_line(fields);
    if (!s.converged()) {
      ++failures;
      std::cerr << "pcr fk: " << table.source << ":" << table.line_numbers[r]
                << ": not converged (" << to_string(s.status) << ")\n";
    }
  }
  out.commit();
  if (failures > 0) {
    std::cerr << "pcr fk: " << failures << " of " << table.rows.size()
              << " rows did not converge\n";
    cli::exit_status() = 1;
  }
}

}  // namespace

void register_fk_command(CLI::App& app) {
  auto args = std::make_shared<FkArguments>();
  CLI::App* fk = app.add_subcommand(
      "fk", "Forward kinematics: rows q1,...,qn (m) -> q1,...,qn,x,y,theta,converged,"
            "iterations,residual,status,max_strain. Exit status 1 if a row did not converge.");
  pcr::cli::add_robot_option(*fk, args->robot);
  fk->add_option("--input", args->input, "CSV of joint values (default: stdin)");
  fk->add_option("--output", args->output, "output CSV (default: stdout)");
  args->solve.add_to(*fk);
  fk->callback([args] { run_fk(*args); });
}
