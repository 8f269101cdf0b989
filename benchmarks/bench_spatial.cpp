// Speed of the spatial Cosserat rod (pcr/spatial/cosserat_rod.hpp): the rods of one shooting
// residual of a continuum Stewart-Gough robot (six rods), with and without the sensitivity a
// Newton step needs, at the default step count and at half of it; and warm FK and IK of the
// reference robot (pcr/spatial/kinematics.hpp) along 1 mm joint steps.
//   build/benchmarks/bench_spatial [--benchmark_repetitions=5 --benchmark_report_aggregates_only]
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <vector>

#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace {

using namespace pcr;

/// Six rods of a continuum Stewart-Gough robot in a bent configuration: 0.4 m of 1 mm NiTi-like
/// rod each, in pairs around a 0.1 m base circle, each with its own proximal wrench (up to about
/// 2 EI / L^2 and 2 EI / L), under gravity.
struct SixRods {
  SpatialRod<double> rod;
  std::array<SpatialRodState<double>, 6> bases;
  Vector3<double> gravity{0, 0, -9.81};

  SixRods() {
    rod.length = 0.4;
    rod.diameter = 1e-3;
    rod.young_modulus = 60e9;
    rod.shear_modulus = 60e9 / (2 * 1.33);
    rod.density = 6450;
    const double ei = rod.bending_stiffness(), L = rod.length;
    for (int i = 0; i < 6; ++i) {
      const double angle = 2 * M_PI * (i / 2) / 3 + (i % 2 ? 0.2 : -0.2);
      SpatialRodState<double>& base = bases[i];
      base.position = 0.1 * Vector3<double>(std::cos(angle), std::sin(angle), 0);
      base.orientation = identity_quaternion<double>();
      base.force = ei / (L * L) * Vector3<double>(std::cos(3.0 * i), std::sin(2.0 * i), -1.5);
      base.moment = ei / L * Vector3<double>(std::sin(1.0 + i), std::cos(2.0 + i), 0.3);
    }
  }
};

void BM_SixRods(benchmark::State& state) {
  const SixRods robot;
  const int steps = static_cast<int>(state.range(0));
  for (auto _ : state) {
    for (const SpatialRodState<double>& base : robot.bases) {
      benchmark::DoNotOptimize(integrate_spatial_rod(base, robot.rod, robot.gravity, steps));
    }
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_SixRods)->Arg(kDefaultSpatialRodSteps)->Arg(kDefaultSpatialRodSteps / 2);

void BM_SixRodsInLanes(benchmark::State& state) {
  const SixRods robot;
  const int steps = static_cast<int>(state.range(0));
  const std::array<SpatialRod<double>, 6> rods{robot.rod, robot.rod, robot.rod,
                                               robot.rod, robot.rod, robot.rod};
  std::array<SpatialRodState<double>, 6> tips;
  for (auto _ : state) {
    integrate_spatial_rods(robot.bases.data(), rods.data(), 6, robot.gravity, steps, tips.data());
    benchmark::DoNotOptimize(tips.data());
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_SixRodsInLanes)->Arg(kDefaultSpatialRodSteps)->Arg(kDefaultSpatialRodSteps / 2);

void BM_SixRodsWithSensitivity(benchmark::State& state) {
  const SixRods robot;
  const int steps = static_cast<int>(state.range(0));
  for (auto _ : state) {
    for (const SpatialRodState<double>& base : robot.bases) {
      benchmark::DoNotOptimize(
          integrate_spatial_rod_with_sensitivity(base, robot.rod, robot.gravity, steps));
    }
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_SixRodsWithSensitivity)
    ->Arg(kDefaultSpatialRodSteps)
    ->Arg(kDefaultSpatialRodSteps / 2);

/// A closed path of the reference continuum Stewart-Gough robot in 1 mm joint steps: each rod's
/// length q0 + 5 mm sin(2 pi k / 32 + phase_i) (5 mm x 2 pi / 32 = 0.98 mm per step) around the
/// equal length that holds the platform 0.4 m up, with its FK solutions.
struct SpatialPath {
  static constexpr int kPoints = 32;
  SpatialRobotParams<double> robot = continuum_stewart_gough();
  std::vector<SpatialJointVector> q;
  std::vector<SpatialForwardSolution> fk;

  SpatialPath() {
    const double q0 = 0.005285;
    for (int k = 0; k < kPoints; ++k) {
      SpatialJointVector joints(6);
      for (int i = 0; i < 6; ++i) joints(i) = q0 + 0.005 * std::sin(2 * M_PI * k / kPoints + i);
      q.push_back(joints);
    }
    fk.push_back(spatial_forward_kinematics(robot, q[0]));
    for (int k = 1; k < kPoints; ++k)
      fk.push_back(spatial_forward_kinematics(robot, q[k], fk.back()));
  }
};

const SpatialPath& spatial_path() {
  static const SpatialPath path;
  return path;
}

/// Warm FK along the path, each solve from the previous solution.
void BM_SpatialForwardWarm(benchmark::State& state) {
  const SpatialPath& path = spatial_path();
  SpatialForwardSolution previous = path.fk.back();
  int k = 0;
  long evaluations = 0, solves = 0, failures = 0;
  for (auto _ : state) {
    SpatialForwardSolution next = spatial_forward_kinematics(path.robot, path.q[k], previous);
    benchmark::DoNotOptimize(next.pose.position.data());
    evaluations += next.summary.residual_evaluations;
    failures += next.summary.converged() ? 0 : 1;
    ++solves;
    previous = std::move(next);
    k = (k + 1) % SpatialPath::kPoints;
  }
  state.counters["evaluations"] = static_cast<double>(evaluations) / solves;
  state.counters["failures"] = static_cast<double>(failures);
}
BENCHMARK(BM_SpatialForwardWarm)->Unit(benchmark::kMicrosecond);

/// Warm IK along the path's poses, each solve from the previous solution.
void BM_SpatialInverseWarm(benchmark::State& state) {
  const SpatialPath& path = spatial_path();
  SpatialInverseSolution previous =
      spatial_inverse_kinematics(path.robot, path.fk.back().pose, path.fk.back());
  int k = 0;
  long evaluations = 0, solves = 0, failures = 0;
  for (auto _ : state) {
    SpatialInverseSolution next = spatial_inverse_kinematics(path.robot, path.fk[k].pose, previous);
    benchmark::DoNotOptimize(next.q.data());
    evaluations += next.summary.residual_evaluations;
    failures += next.summary.converged() ? 0 : 1;
    ++solves;
    previous = std::move(next);
    k = (k + 1) % SpatialPath::kPoints;
  }
  state.counters["evaluations"] = static_cast<double>(evaluations) / solves;
  state.counters["failures"] = static_cast<double>(failures);
}
BENCHMARK(BM_SpatialInverseWarm)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
