// pcr fk: joint values -> platform pose, one CSV row per input row: each on its own, or a path
// (--path).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/spatial/sequence.hpp"

namespace {

struct FkArguments {
  std::string robot, input, output;
  pcr::cli::SolveArguments solve;
  pcr::cli::RowsArguments rows;
};

/// A spatial robot: rows q1..qn -> q1..qn, x, y, z, rx, ry, rz and the summary columns.
void run_spatial_fk(const FkArguments& args) {
  using namespace pcr;
  args.solve.require_no_planar_load(args.robot);
  const SpatialRobotDescription robot = load_spatial_robot(args.robot);
  const int n = robot.params.num_rods;
  const CsvTable table = cli::read_joint_table(args.input, n);

  std::vector<std::string> header = cli::joint_names(n);
  for (const std::string& c : cli::spatial_pose_columns()) header.push_back(c);
  for (const std::string& c : cli::summary_columns()) header.push_back(c);

  SolverOptions options = args.solve.options();
  args.rows.apply(options);
  SpatialForwardSequence sequence(robot.params, options, args.rows.mode());
  const auto solve_row = [&](const CsvRow row, CsvWriter& out) {
    SpatialJointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = row[static_cast<std::size_t>(i)];
    const SpatialForwardSolution& solution = sequence.solve(q);
    const SolverSummary& s = solution.summary;
    const bool valid = usable_as_warm_start(s);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const Vector3<double> r = quaternion_log(solution.pose.orientation);
    for (int i = 0; i < n; ++i) out.add(q(i));
    for (int k = 0; k < 3; ++k) out.add(valid ? solution.pose.position(k) : nan);
    for (int k = 0; k < 3; ++k) out.add(valid ? r(k) : nan);
    cli::add_summary_fields(s, valid, out);
    return s;
  };
  cli::solve_rows("pcr fk", table, args.output, header, solve_row);
}

void run_fk(const FkArguments& args) {
  using namespace pcr;
  if (cli::is_spatial_robot(args.robot)) {
    run_spatial_fk(args);
    return;
  }
  const RobotDescription robot = load_robot_or_default(args.robot);
  const int n = robot.params.num_limbs;
  SolverOptions options = args.solve.options();
  args.rows.apply(options);
  const PlatformLoad<double> load = args.solve.load();
  const CsvTable table = cli::read_joint_table(args.input, n);

  std::vector<std::string> header = cli::joint_names(n);
  for (const char* c : {"x", "y", "theta"}) header.emplace_back(c);
  for (const std::string& c : cli::summary_columns()) header.push_back(c);

  ForwardSequence sequence(robot.params, options, load, args.rows.mode());
  const auto solve_row = [&](const CsvRow row, CsvWriter& out) {
    JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = row[static_cast<std::size_t>(i)];
    const ForwardSolution& solution = sequence.solve(q);
    const SolverSummary& s = solution.summary;
    const bool valid = usable_as_warm_start(s);  // a valid equilibrium, maybe out of range
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (int i = 0; i < n; ++i) out.add(q(i));
    out.add(valid ? solution.pose.x : nan);
    out.add(valid ? solution.pose.y : nan);
    out.add(valid ? solution.pose.theta : nan);
    cli::add_summary_fields(s, valid, out);
    return s;
  };
  cli::solve_rows("pcr fk", table, args.output, header, solve_row);
}

}  // namespace

void register_fk_command(CLI::App& app) {
  auto args = std::make_shared<FkArguments>();
  CLI::App* fk = app.add_subcommand(
      "fk",
      "Forward kinematics: rows q1,...,qn (m) -> q1,...,qn,x,y,theta,converged,"
      "iterations,residual,status,max_strain,stable,stability_margin,singularity. Joints "
      "outside q_range give converged=0, status out_of_range (the pose of that equilibrium is "
      "still given); status inaccurate: its estimated error exceeds the accuracy targets (near a "
      "singularity; the pose is still given). stable=0: the equilibrium would not hold. A spatial "
      "robot file (\"kind\": "
      "\"spatial\") gives q1,...,qn,x,y,z,rx,ry,rz (m, rad: the platform's orientation as a "
      "rotation vector) and the same summary columns. Exit status 1 if a row did not "
      "converge.");
  pcr::cli::add_robot_option(*fk, args->robot);
  fk->add_option("--input", args->input, "CSV of joint values (default: stdin)");
  fk->add_option("--output", args->output, "output CSV (default: stdout)");
  args->solve.add_to(*fk);
  args->rows.add_to(*fk);
  fk->callback([args] { run_fk(*args); });
}
