// Speed of the spatial Cosserat rod (pcr/spatial/cosserat_rod.hpp): the rods of one shooting
// residual of a continuum Stewart-Gough robot (six rods), with and without the sensitivity a
// Newton step needs, at the default step count and at half of it.
//   build/benchmarks/bench_spatial [--benchmark_repetitions=5 --benchmark_report_aggregates_only]
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>

#include "pcr/spatial/cosserat_rod.hpp"

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

}  // namespace

BENCHMARK_MAIN();
