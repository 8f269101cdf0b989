// The floor of `pcr fk` and `pcr ik`, for benchmarks/bench_cli.py: the library's FK of the default
// robot along the joint path of a CSV file (columns q1,q2,q3), solved as pcr fk solves its rows
// (ForwardSequence) and by forward_kinematics_or_cold row after row; its IK along the pose path of
// another (columns x,y,theta), as pcr ik solves them (InverseSequence); and, as a yardstick of the
// machine, a plain three-rod RK4 residual of 64 steps (plain_rk4_residual.cpp).
//   build/benchmarks/bench_fk_path PATH.csv [REPEAT [POSES.csv]]
// Prints one "name microseconds" line per measurement: the best of REPEAT (default 3) runs.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

#include "pcr/csv_io.hpp"
#include "pcr/kinematics.hpp"
#include "plain_rk4_residual.hpp"

namespace {

using Clock = std::chrono::steady_clock;

/// The best of `repeat` runs of `run` (which returns a count of failures, to be 0), in us per
/// item.
template <class Run>
double best_us_per_item(int repeat, std::size_t items, Run&& run) {
  double best = 1e300;
  for (int r = 0; r < repeat; ++r) {
    const Clock::time_point start = Clock::now();
    const int failures = run();
    const double us = std::chrono::duration<double, std::micro>(Clock::now() - start).count();
    if (failures > 0) std::fprintf(stderr, "bench_fk_path: %d rows did not converge\n", failures);
    best = std::min(best, us / static_cast<double>(items));
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) try {
  using namespace pcr;
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_fk_path PATH.csv [REPEAT]\n");
    return 2;
  }
  const int repeat = argc > 2 ? std::atoi(argv[2]) : 3;
  const RobotParams<double> robot = femto_3pf();
  CsvReadOptions csv;
  csv.columns = {"q1", "q2", "q3"};
  const CsvTable table = read_csv(argv[1], csv);
  std::vector<JointVector> path;
  for (const CsvRow row : table.rows) {
    path.emplace_back(JointVector::Map(row.data(), 3));
  }

  const double sequence_us = best_us_per_item(repeat, path.size(), [&] {
    ForwardSequence sequence(robot, SolverOptions(), PlatformLoad<double>(), SequenceMode::kPath);
    int failures = 0;
    for (const JointVector& q : path) failures += !sequence.solve(q).summary.converged();
    return failures;
  });
  const double or_cold_us = best_us_per_item(repeat, path.size(), [&] {
    ForwardSolution previous;
    bool have_previous = false;
    int failures = 0;
    for (const JointVector& q : path) {
      const ForwardSolution solution =
          forward_kinematics_or_cold(robot, q, have_previous ? &previous : nullptr);
      have_previous = solution.summary.converged();
      if (have_previous) previous = solution;
      failures += !have_previous;
    }
    return failures;
  });

  double ik_sequence_us = 0;
  if (argc > 3) {
    CsvReadOptions pose_columns;
    pose_columns.columns = {"x", "y", "theta"};
    const CsvTable poses_table = read_csv(argv[3], pose_columns);
    std::vector<Pose2<double>> poses;
    for (const CsvRow row : poses_table.rows) poses.push_back({row[0], row[1], row[2]});
    ik_sequence_us = best_us_per_item(repeat, poses.size(), [&] {
      InverseSequence sequence(robot, SolverOptions(), PlatformLoad<double>(), SequenceMode::kPath);
      int failures = 0;
      for (const Pose2<double>& pose : poses) failures += !sequence.solve(pose).summary.converged();
      return failures;
    });
  }

  // The default robot's rods, near home: the unknowns change a little from call to call.
  bench::PlainRod rods[3];
  for (int i = 0; i < 3; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    rods[i] = {limb.A.x(), limb.A.y(), limb.alpha,      limb.B.x(),
               limb.B.y(), limb.beta,  limb.rod.length, limb.rod.bending_stiffness()};
  }
  volatile double sink = 0;  // keeps the residuals computed
  const double residual_us = best_us_per_item(repeat, path.size(), [&] {
    double unknowns[12] = {1e-3, -2e-3, 1e-5, -1e-3, 2e-3, -1e-5, 0, 0, 0, 1e-4, -1e-4, 1e-3};
    double residual[12];
    for (std::size_t k = 0; k < path.size(); ++k) {
      unknowns[2] = 1e-5 + 1e-9 * static_cast<double>(k);
      bench::plain_rk4_residual(rods, unknowns, residual);
      sink = residual[0] + residual[11];
    }
    return 0;
  });

  std::printf("rows %zu\n", path.size());
  std::printf("fk_sequence_us %.4f\n", sequence_us);
  std::printf("fk_or_cold_us %.4f\n", or_cold_us);
  std::printf("plain_rk4_64_residual_us %.4f\n", residual_us);
  if (argc > 3) std::printf("ik_sequence_us %.4f\n", ik_sequence_us);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_fk_path: %s\n", e.what());
  return 2;
}
