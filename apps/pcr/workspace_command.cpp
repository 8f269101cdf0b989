// pcr workspace: FK and IK over a random sample of the stroke box, with round-trip errors.
// The interim main job: it exercises the whole kinematics on the robot and summarises.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <random>

#include "commands.hpp"

namespace {

struct WorkspaceArguments {
  std::string robot, output;
  int samples = 200;
  unsigned seed = 1;
  int steps = pcr::SolverOptions().rod_steps;
};

void run_workspace(const WorkspaceArguments& args) {
  using namespace pcr;
  const RobotDescription robot = load_robot_or_default(args.robot);
  const RobotParams<double>& params = robot.params;
  const int n = params.num_limbs;
  const bool has_ik = n <= 3;
  SolverOptions options;
  options.rod_steps = args.steps;
  std::mt19937_64 rng(args.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  OutputFile out(args.output);
  std::vector<std::string> header = cli::joint_names(n);
  for (const char* c : {"x", "y", "theta", "fk_status", "fk_iterations", "max_strain", "ik_status",
                        "ik_iterations", "ik_start", "q_error", "pose_error"}) {
    header.emplace_back(c);
  }
  out.stream() << csv_line(header);

  int fk_converged = 0, fk_singular = 0, fk_other = 0, ik_converged = 0, ik_failed = 0,
      ik_cold_failed = 0;
  double max_q_error = 0, max_pose_error = 0, max_strain = 0;
  const auto start = std::chrono::steady_clock::now();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < args.samples; ++k) {
    JointVector q(n);
    for (int i = 0; i < n; ++i) {
      const LimbParams<double>& limb = params.limb(i);
      q(i) = limb.q_min + (limb.q_max - limb.q_min) * unit(rng);
    }
    const ForwardSolution fk = forward_kinematics(params, q, options);
    std::vector<std::string> fields;
    for (int i = 0; i < n; ++i) fields.push_back(format_double(q(i)));
    const bool ok = fk.summary.converged();
    fields.push_back(format_double(ok ? fk.pose.x : nan));
    fields.push_back(format_double(ok ? fk.pose.y : nan));
    fields.push_back(format_double(ok ? fk.pose.theta : nan));
    fields.push_back(to_string(fk.summary.status));
    fields.push_back(std::to_string(fk.summary.iterations));
    fields.push_back(format_double(ok ? fk.summary.max_strain : nan));
    if (ok) {
      ++fk_converged;
      max_strain = std::max(max_strain, fk.summary.max_strain);
    } else if (fk.summary.status == SolveStatus::kSingular) {
      ++fk_singular;
    } else {
      ++fk_other;
    }
    std::string ik_status = "-", ik_iterations = "-", ik_start = "-";
    double q_error = nan, pose_error = nan;
    if (ok && has_ik) {
      // IK of the FK pose cold from home (what a user does), warm-started from the FK solution
      // when that fails (another branch); then FK of the IK joints, warm from the IK solution.
      InverseSolution ik = inverse_kinematics(params, fk.pose, options);
      ik_start = "cold";
      if (!ik.summary.converged()) {
        ++ik_cold_failed;
        ik = inverse_kinematics(params, fk.pose, as_inverse_warm_start(fk), options);
        ik_start = "warm";
      }
      ik_status = to_string(ik.summary.status);
      ik_iterations = std::to_string(ik.summary.iterations);
      if (ik.summary.converged()) {
        ++ik_converged;
        q_error = (ik.q - q).lpNorm<Eigen::Infinity>();
        ForwardSolution warm;
        warm.q = ik.q;
        warm.pose = ik.pose;
        warm.wrenches = ik.wrenches;
        const ForwardSolution back = forward_kinematics(params, ik.q, warm, options);
        if (back.summary.converged()) {
          pose_error = std::hypot(back.pose.x - fk.pose.x, back.pose.y - fk.pose.y);
          max_pose_error = std::max(max_pose_error, pose_error);
        }
        max_q_error = std::max(max_q_error, q_error);
      } else {
        ++ik_failed;
      }
    }
    fields.push_back(ik_status);
    fields.push_back(ik_iterations);
    fields.push_back(ik_start);
    fields.push_back(format_double(q_error));
    fields.push_back(format_double(pose_error));
    out.stream() << csv_line(fields);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::ostream& s = out.stream();
  s << "# robot '" << robot.name << "', " << n << " limbs, " << args.samples
    << " random joint vectors in the stroke box (seed " << args.seed << ")\n";
  s << "# FK (cold from home): " << fk_converged << " converged, " << fk_singular
    << " singular (beyond reach on this branch), " << fk_other << " other failures\n";
  s << "# max bending strain of the converged configurations: " << format_double(max_strain)
    << "\n";
  if (has_ik) {
    s << "# IK of the converged poses: " << ik_converged << " converged (" << ik_cold_failed
      << " of them needed the warm start from the FK solution after a cold start from home "
         "failed), "
      << ik_failed << " failed\n";
    s << "# max round-trip error: |IK(FK(q)) - q| = " << format_double(max_q_error)
      << " m, |FK(IK(pose)) - pose| = " << format_double(max_pose_error) << " m\n";
  } else {
    s << "# IK skipped: it is supported for 2 and 3 limbs only\n";
  }
  s << "# time: " << format_double(seconds) << " s\n";
  out.commit();
  if (ik_failed > 0) cli::exit_status() = 1;
}

}  // namespace

void register_workspace_command(CLI::App& app) {
  auto args = std::make_shared<WorkspaceArguments>();
  CLI::App* cmd = app.add_subcommand(
      "workspace",
      "Sample random joint vectors in the stroke box, solve FK (cold), then IK of each converged "
      "pose (cold from home; warm from the FK solution if that fails) and FK of the IK joints; "
      "print a CSV table and a '#' summary with the round-trip errors. Exit status 1 if the IK "
      "of a reachable pose fails.");
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option("--samples", args->samples, "number of random joint vectors")
      ->check(pcr::cli::within(pcr::kWorkspaceSamplesRange))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "random seed")->capture_default_str();
  cmd->add_option("--steps", args->steps,
                  "RK4 steps per rod (0: chosen from the solution's error estimate, 1 nm / 1 urad)")
      ->check(pcr::cli::within(pcr::SolverOptions::kRodSteps))
      ->capture_default_str();
  cmd->add_option("--output", args->output, "output CSV (default: stdout)");
  cmd->callback([args] { run_workspace(*args); });
}
