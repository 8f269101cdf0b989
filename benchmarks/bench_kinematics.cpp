// Speed of the header-only core on the default robot at the default accuracy.
//   build/benchmarks/bench_kinematics [--benchmark_repetitions=5
//   --benchmark_report_aggregates_only]
// Configured with -DPCR_BENCHMARK_NATIVE=ON, the benchmarks are compiled with -march=native (the
// vector code then uses AVX2/FMA where the machine has them); the default is the plain x86-64
// flags that the library, tests and tools are built with.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/stability.hpp"
#include "random_robots.hpp"

namespace {

using namespace pcr;

JointVector random_joints(std::mt19937& rng, const RobotParams<double>& robot) {
  JointVector q(robot.num_limbs);
  for (int i = 0; i < robot.num_limbs; ++i) {
    std::uniform_real_distribution<double> u(robot.limb(i).q_min, robot.limb(i).q_max);
    q(i) = u(rng);
  }
  return q;
}

/// Converged solutions spread over the central part of the stroke box.
std::vector<ForwardSolution> reachable_solutions(int count) {
  const RobotParams<double> robot = femto_3pf();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-0.004, 0.004);
  std::vector<ForwardSolution> out;
  while (static_cast<int>(out.size()) < count) {
    JointVector q(3);
    q << u(rng), u(rng), u(rng);
    ForwardSolution fk = forward_kinematics(robot, q);
    if (fk.summary.converged() && fk.summary.max_strain < 0.01) out.push_back(fk);
  }
  return out;
}

/// The default robot with rods stepped by each law (the argument): 0 straight and uniform (the
/// paper's), 1 pre-curved (u* = 5 1/m), 2 also tapered (tips 0.8 times as thick). The point's
/// cost, not its equilibrium, is measured.
RobotParams<double> robot_with_rod_law(int law) {
  RobotParams<double> robot = femto_3pf();
  for (int i = 0; i < robot.num_limbs; ++i) {
    Rod<double>& rod = robot.limb(i).rod;
    if (law >= 1) rod.precurvature = 5.0;
    if (law >= 2) rod.diameter_slope = -0.2 * rod.diameter / rod.length;
  }
  return robot;
}

void BM_ResidualOnly(benchmark::State& state) {
  const RobotParams<double> robot = robot_with_rod_law(static_cast<int>(state.range(0)));
  const ForwardSolution fk = reachable_solutions(1)[0];
  ShootingPoint<double> point;
  point.pose = fk.pose;
  for (int i = 0; i < 3; ++i) {
    point.q[i] = fk.q(i);
    point.wrenches[i] = fk.wrenches[i];
  }
  const ShootingScale scale = shooting_scale(robot);
  ResidualVector<double> r;
  state.counters["rod_steps"] = fk.summary.rod_steps;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        shooting_residual(robot, point, PlatformLoad<double>(), scale, fk.summary.rod_steps, r));
  }
}
BENCHMARK(BM_ResidualOnly)->Arg(0)->Arg(1)->Arg(2);

void BM_ResidualAndJacobian(benchmark::State& state) {
  const RobotParams<double> robot = robot_with_rod_law(static_cast<int>(state.range(0)));
  const ForwardSolution fk = reachable_solutions(1)[0];
  ShootingPoint<double> point;
  point.pose = fk.pose;
  for (int i = 0; i < 3; ++i) {
    point.q[i] = fk.q(i);
    point.wrenches[i] = fk.wrenches[i];
  }
  const ShootingScale scale = shooting_scale(robot);
  ResidualVector<double> r;
  ShootingMatrix partials;
  state.counters["rod_steps"] = fk.summary.rod_steps;
  for (auto _ : state) {
    benchmark::DoNotOptimize(shooting_residual(robot, point, PlatformLoad<double>(), scale,
                                               fk.summary.rod_steps, r, &partials));
  }
}
BENCHMARK(BM_ResidualAndJacobian)->Arg(0)->Arg(1)->Arg(2);

/// A converged solution of the n-limb variant of the default robot (tests/random_robots.hpp),
/// its joints up to 2 mm from home, and the shooting point of it, for the paired benchmarks below.
struct CheckedPoint {
  RobotParams<double> robot;
  ForwardSolution fk;
  ShootingPoint<double> point;

  explicit CheckedPoint(int n) : robot(testing::regular_robot(n)) {
    JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = 0.002 * std::cos(1.0 + 2.0 * i);
    fk = forward_kinematics(robot, q);
    point.pose = fk.pose;
    for (int i = 0; i < n; ++i) {
      point.q[i] = fk.q(i);
      point.wrenches[i] = fk.wrenches[i];
    }
  }
};

// The stability check of a solution of (limbs, RK4 steps) as the solvers run it
// (stability_rod_steps), and the residual-plus-Jacobian evaluation of that solution, to compare.
void BM_StabilityCheck(benchmark::State& state) {
  const CheckedPoint p(static_cast<int>(state.range(0)));
  const int steps = stability_rod_steps(static_cast<int>(state.range(1)));
  for (auto _ : state) {
    const EquilibriumStability s =
        equilibrium_stability(p.robot, p.fk.q, p.fk.pose, p.fk.wrenches, steps);
    benchmark::DoNotOptimize(s.margin);
  }
  state.counters["check_rod_steps"] = steps;
}
void BM_EvaluationOfTheCheckedSolution(benchmark::State& state) {
  const CheckedPoint p(static_cast<int>(state.range(0)));
  const ShootingScale scale = shooting_scale(p.robot);
  ResidualVector<double> r;
  ShootingMatrix partials;
  for (auto _ : state) {
    benchmark::DoNotOptimize(shooting_residual(p.robot, p.point, PlatformLoad<double>(), scale,
                                               static_cast<int>(state.range(1)), r, &partials));
  }
}
// The solvers' least step count (SolverOptions::min_rod_steps), the default robot's usual ones,
// and a fine one; 2 to 6 limbs (2, 4 and 8 SIMD lanes).
#define PCR_CHECK_ARGS ArgsProduct({{2, 3, 4, 6}, {16, 24, 32, 64}})
BENCHMARK(BM_StabilityCheck)->PCR_CHECK_ARGS;
BENCHMARK(BM_EvaluationOfTheCheckedSolution)->PCR_CHECK_ARGS;
#undef PCR_CHECK_ARGS

/// Times each solve of a warm-start benchmark: the target is on the median solve, which the
/// mean Google Benchmark reports is not (a rare slow solve moves the mean, not the median).
class SolveTimer {
 public:
  /// Times `solve()`, which returns a solution (by value or reference) with a summary.
  template <class Solve>
  void time(Solve&& solve) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto& solution = solve();
    benchmark::DoNotOptimize(&solution);
    const SolverSummary summary = solution.summary;
    times_us_.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    iterations_ += summary.iterations;
    evaluations_ += summary.residual_evaluations;
    failures_ += summary.converged() ? 0 : 1;
  }
  void report(benchmark::State& state) {
    const auto per_solve = [&](double total) {
      return benchmark::Counter(total, benchmark::Counter::kAvgIterations);
    };
    state.counters["newton_iterations"] = per_solve(static_cast<double>(iterations_));
    state.counters["residual_evaluations"] = per_solve(static_cast<double>(evaluations_));
    state.counters["failures"] = static_cast<double>(failures_);
    std::nth_element(times_us_.begin(), times_us_.begin() + times_us_.size() / 2, times_us_.end());
    state.counters["median_solve_us"] = times_us_[times_us_.size() / 2];
  }

 private:
  std::vector<double> times_us_;
  long iterations_ = 0, evaluations_ = 0, failures_ = 0;
};

/// The solver's default options, with the stability check (pcr/stability.hpp) on (argument 1) or
/// off (0): the warm-start benchmarks time both.
SolverOptions with_stability(const benchmark::State& state) {
  SolverOptions options;
  options.check_stability = state.range(0) != 0;
  return options;
}

// FK from the solution of joints 10 um away (each joint), as in a control loop.
void BM_ForwardWarm(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  const SolverOptions options = with_stability(state);
  const std::vector<ForwardSolution> solutions = reachable_solutions(64);
  std::size_t k = 0;
  SolveTimer timer;
  for (auto _ : state) {
    const ForwardSolution& warm = solutions[k++ % solutions.size()];
    JointVector q = warm.q;
    q.array() += 10e-6;
    timer.time([&] { return forward_kinematics(robot, q, warm, options); });
  }
  timer.report(state);
}
BENCHMARK(BM_ForwardWarm)->Arg(0)->Arg(1);

// IK from the solution of the pose 10 um / 1 mrad away. The warm starts are IK solutions, as in a
// control loop (each carries its IK Jacobian for the first, chord, step).
void BM_InverseWarm(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  const SolverOptions options = with_stability(state);
  std::vector<InverseSolution> warm;
  for (const ForwardSolution& fk : reachable_solutions(64)) {
    warm.push_back(inverse_kinematics(robot, fk.pose, as_inverse_warm_start(fk)));
  }
  std::size_t k = 0;
  SolveTimer timer;
  for (auto _ : state) {
    const InverseSolution& start = warm[k++ % warm.size()];
    const Pose2<double> target{start.pose.x + 7.07e-6, start.pose.y + 7.07e-6,
                               start.pose.theta + 1e-3};
    timer.time([&] { return inverse_kinematics(robot, target, start, options); });
  }
  timer.report(state);
}
BENCHMARK(BM_InverseWarm)->Arg(0)->Arg(1);

// The same steps along a path, as a control loop solves them (ForwardSequence, InverseSequence):
// each solve starts from the previous one with the chord matrix it carries, already corrected by
// the previous secant steps. BM_ForwardWarm and BM_InverseWarm start each solve from one of 64
// stored solutions instead, whose carried matrix is a bare factorisation: their first chord
// correction forms its inverse (about 0.5 us of an IK solve). A circle of 1 mm radius, 10 um from
// solve to solve (the joints for FK; the position for IK, with theta = 0.02 sin(0.05 k), steps up
// to 1 mrad).
void BM_ForwardSequence(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  ForwardSequence sequence(robot, with_stability(state), PlatformLoad<double>(),
                           SequenceMode::kPath);
  SolveTimer timer;
  long k = 0;
  for (auto _ : state) {
    const double phi = 0.01 * static_cast<double>(k++) / std::sqrt(1.5);  // |dq| = 10 um
    JointVector q(3);
    for (int i = 0; i < 3; ++i) q(i) = 1e-3 * std::cos(phi - 2 * M_PI * i / 3);
    timer.time([&]() -> const ForwardSolution& { return sequence.solve(q); });
  }
  timer.report(state);
}
BENCHMARK(BM_ForwardSequence)->Arg(0)->Arg(1);

void BM_InverseSequence(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  InverseSequence sequence(robot, with_stability(state), PlatformLoad<double>(),
                           SequenceMode::kPath);
  SolveTimer timer;
  long k = 0;
  for (auto _ : state) {
    const double phi = 0.01 * static_cast<double>(k);
    const Pose2<double> target{1e-3 * std::cos(phi), 1e-3 * std::sin(phi),
                               0.02 * std::sin(0.05 * static_cast<double>(k))};
    ++k;
    timer.time([&]() -> const InverseSolution& { return sequence.solve(target); });
  }
  timer.report(state);
}
BENCHMARK(BM_InverseSequence)->Arg(0)->Arg(1);

// A set of 99 configurations in random order across the central +-4 mm of the stroke box (a
// sampler's calibration set): as independent rows (arg 0: from the home solution the sequence
// keeps), as a path through them in that order (arg 1: each continued from the last, on its
// branch), and cold one by one (arg 2: forward_kinematics(robot, q)). Time per row.
void BM_ScatteredRows(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.004, 0.004);
  std::vector<JointVector> rows;
  for (int k = 0; k < 99; ++k) {
    JointVector q(3);
    q << u(rng), u(rng), u(rng);
    rows.push_back(q);
  }
  const int how = static_cast<int>(state.range(0));
  for (auto _ : state) {
    if (how == 2) {
      for (const JointVector& q : rows) {
        const ForwardSolution fk = forward_kinematics(robot, q);
        benchmark::DoNotOptimize(fk.pose.x);
      }
      continue;
    }
    ForwardSequence sequence(robot, SolverOptions(), PlatformLoad<double>(),
                             how == 0 ? SequenceMode::kIndependent : SequenceMode::kPath);
    for (const JointVector& q : rows) benchmark::DoNotOptimize(sequence.solve(q).pose.x);
  }
  state.counters["us_per_row"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * rows.size() * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_ScatteredRows)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_ForwardCold(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  std::mt19937 rng(1);
  for (auto _ : state) {
    const ForwardSolution fk = forward_kinematics(robot, random_joints(rng, robot));
    benchmark::DoNotOptimize(fk.pose.x);
  }
}
BENCHMARK(BM_ForwardCold);

void BM_InverseCold(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  const std::vector<ForwardSolution> solutions = reachable_solutions(64);
  std::size_t k = 0;
  for (auto _ : state) {
    const InverseSolution ik = inverse_kinematics(robot, solutions[k++ % solutions.size()].pose);
    benchmark::DoNotOptimize(ik.q(0));
  }
}
BENCHMARK(BM_InverseCold);

// Outcome of cold FK over 1000 random configurations of the whole stroke box. A failure is
// accounted for when the path stopped at a singularity (the Jacobian's conditioning extrapolates
// to zero ahead) or when its last solved point already bends a rod beyond the 1% strain limit of
// fused silica; `unexplained_failures` counts the rest (target: 0).
void BM_ColdSurvey(benchmark::State& state) {
  const RobotParams<double> robot = femto_3pf();
  constexpr double kStrainLimit = 0.01;
  double direct = 0, continued = 0, over_strain = 0, singular = 0, singular_over_strain = 0,
         failed_over_strain = 0, unexplained = 0;
  std::vector<double> solve_us;  // wall time of each solve (the median is what the target is on)
  for (auto _ : state) {
    std::mt19937 rng(2021);
    direct = continued = over_strain = singular = singular_over_strain = failed_over_strain =
        unexplained = 0;
    solve_us.clear();
    for (int k = 0; k < 1000; ++k) {
      const JointVector q = random_joints(rng, robot);
      const auto t0 = std::chrono::steady_clock::now();
      const ForwardSolution fk = forward_kinematics(robot, q);
      solve_us.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      const bool beyond_strain_limit = fk.summary.max_strain > kStrainLimit;
      if (fk.summary.converged()) {
        (fk.summary.continuation_steps == 0 ? direct : continued) += 1;
        over_strain += beyond_strain_limit;
      } else if (fk.summary.status == SolveStatus::kSingular) {
        singular += 1;
        singular_over_strain += beyond_strain_limit;
      } else {
        (beyond_strain_limit ? failed_over_strain : unexplained) += 1;
      }
    }
  }
  state.counters["direct"] = direct;
  state.counters["continuation"] = continued;
  state.counters["converged_over_1pct_strain"] = over_strain;
  state.counters["singular"] = singular;
  state.counters["singular_past_1pct_strain"] = singular_over_strain;
  state.counters["failed_past_1pct_strain"] = failed_over_strain;
  state.counters["unexplained_failures"] = unexplained;
  std::nth_element(solve_us.begin(), solve_us.begin() + 500, solve_us.end());
  state.counters["median_solve_us"] = solve_us[500];
}
BENCHMARK(BM_ColdSurvey)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
