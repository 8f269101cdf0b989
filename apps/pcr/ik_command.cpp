// pcr ik: platform poses -> joint values, one CSV row per input row: each on its own, or a path
// (--path).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/spatial/sequence.hpp"

namespace {

struct IkArguments {
  std::string robot, input, output;
  pcr::cli::SolveArguments solve;
  pcr::cli::RowsArguments rows;
  bool allow_unstable = false;
};

/// A spatial robot of six rods: rows x, y, z, rx, ry, rz -> the same, q1..q6 and the summary
/// columns.
void run_spatial_ik(const IkArguments& args) {
  using namespace pcr;
  args.solve.require_no_planar_load(args.robot);
  const SpatialRobotDescription robot = load_spatial_robot(args.robot);
  const int n = robot.params.num_rods;
  const int free_angles = spatial_inverse_free_angles(n);
  if (free_angles < 0) {
    throw InputError(args.robot + ": robot '" + robot.name + "' has " + std::to_string(n) +
                     " rods; the inverse kinematics of a spatial robot is square for 3, 5 and 6 "
                     "rods only");
  }
  CsvReadOptions csv;
  csv.columns = cli::spatial_pose_columns();
  const CsvTable table = cli::read_table(args.input, csv);
  for (std::size_t c = 0; c < 3; ++c) cli::check_column_range(table, c, -1.0, 1.0, "m");
  for (std::size_t c = 3; c < 6; ++c) cli::check_column_range(table, c, -2 * M_PI, 2 * M_PI, "rad");

  std::vector<std::string> header = csv.columns;
  for (const std::string& q : cli::joint_names(n)) header.push_back(q);
  for (const std::string& c : cli::summary_columns()) header.push_back(c);

  SolverOptions options = args.solve.options();
  args.rows.apply(options);
  SpatialInverseSequence sequence(robot.params, options, args.rows.mode());
  const auto solve_row = [&](const CsvRow row, CsvWriter& out) {
    SpatialPose<double> pose;
    pose.position = Vector3<double>(row[0], row[1], row[2]);
    pose.orientation = quaternion_exp(Vector3<double>(row[3], row[4], row[5]));
    const SpatialInverseSolution& solution = sequence.solve(pose);
    const SolverSummary& s = solution.summary;
    const bool valid = is_equilibrium(s);  // maybe unstable
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // The position as requested; the rotation as requested, or as solved where the rod count
    // leaves some of it free.
    for (std::size_t c = 0; c < 3; ++c) out.add(row[c]);
    const Vector3<double> rotation = free_angles == 0 ? Vector3<double>(row[3], row[4], row[5])
                                     : valid          ? quaternion_log(solution.pose.orientation)
                                                      : Vector3<double>::Constant(nan);
    for (int c = 0; c < 3; ++c) out.add(rotation(c));
    for (int i = 0; i < n; ++i) out.add(valid ? solution.q(i) : nan);
    cli::add_summary_fields(s, valid, out);
    return s;
  };
  cli::solve_rows("pcr ik", table, args.output, header, solve_row, args.allow_unstable);
}

void run_ik(const IkArguments& args) {
  using namespace pcr;
  if (cli::is_spatial_robot(args.robot)) {
    run_spatial_ik(args);
    return;
  }
  const RobotDescription robot = cli::load_robot_for_inverse(args.robot, "pcr ik");
  const int n = robot.params.num_limbs;
  SolverOptions options = args.solve.options();
  args.rows.apply(options);
  const PlatformLoad<double> load = args.solve.load();
  CsvReadOptions csv;
  csv.columns = {"x", "y", "theta"};
  const CsvTable table = cli::read_table(args.input, csv);
  for (std::size_t c = 0; c < 2; ++c) cli::check_column_range(table, c, -1.0, 1.0, "m");
  cli::check_column_range(table, 2, -2 * M_PI, 2 * M_PI, "rad");

  std::vector<std::string> header = {"x", "y", "theta"};
  for (const std::string& q : cli::joint_names(n)) header.push_back(q);
  for (const std::string& c : cli::summary_columns()) header.push_back(c);

  InverseSequence sequence(robot.params, options, load, args.rows.mode());
  const auto solve_row = [&](const CsvRow row, CsvWriter& out) {
    const Pose2<double> pose{row[0], row[1], row[2]};
    const InverseSolution& solution = sequence.solve(pose);
    const SolverSummary& s = solution.summary;
    // A valid equilibrium, maybe out of range or unstable.
    const bool valid = is_equilibrium(s);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // For n = 2 theta is solved for: report the solved value.
    out.add(pose.x);
    out.add(pose.y);
    out.add(n == 2 ? (valid ? solution.pose.theta : nan) : pose.theta);
    for (int i = 0; i < n; ++i) out.add(valid ? solution.q(i) : nan);
    cli::add_summary_fields(s, valid, out);
    return s;
  };
  cli::solve_rows("pcr ik", table, args.output, header, solve_row, args.allow_unstable);
}

}  // namespace

void register_ik_command(CLI::App& app) {
  auto args = std::make_shared<IkArguments>();
  CLI::App* ik = app.add_subcommand(
      "ik",
      "Inverse kinematics: rows x,y,theta (m, m, rad) -> x,y,theta,q1,...,qn,converged,"
      "iterations,residual,status,max_strain,stable,stability_margin,singularity. Joints "
      "outside q_range give converged=0, status out_of_range; an estimated error above the "
      "accuracy targets, status inaccurate (near a singularity). An equilibrium that would not "
      "hold (stable=0) is replaced by a stable one at the same pose when one is found, else "
      "status unstable. With 2 limbs theta is solved for (the input theta is ignored). Exit "
      "status 1 if a row did not converge or is unstable (unless --allow-unstable). A spatial "
      "robot file (\"kind\": \"spatial\") takes rows x,y,z,rx,ry,rz (m, rad: the "
      "platform's orientation as a rotation vector) -> x,y,z,rx,ry,rz,q1,...,qn and the same "
      "summary columns: six rods impose the whole pose; five the position and the platform's "
      "normal, three the position, and the rotation written is the solved one.");
  pcr::cli::add_robot_option(*ik, args->robot);
  ik->add_option("--input", args->input, "CSV of poses (default: stdin)");
  ik->add_option("--output", args->output, "output CSV (default: stdout)");
  ik->add_flag("--allow-unstable", args->allow_unstable,
               "accept rows where only an unstable equilibrium was found (exit status 0)");
  args->solve.add_to(*ik);
  args->rows.add_to(*ik);
  ik->callback([args] { run_ik(*args); });
}
