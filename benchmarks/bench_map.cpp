// Workspace maps (pcr/calib/workspace_map.hpp) as `pcr map` solves them (the default range: the
// stroke box's FK scan, a tenth wider): the default robot and the same with a +-60 mm stroke
// (robots/femto-3pf-long-stroke.json, where most of the map lies beyond the branch's folds), on
// 1 and 2 threads; the default robot without the stability check (timed on its own in
// bench_kinematics). Arguments: grid, stability check, long stroke, threads.
#include <benchmark/benchmark.h>

#include "pcr/calib/workspace_map.hpp"

namespace {

void BM_WorkspaceMap(benchmark::State& state) {
  pcr::RobotParams<double> robot = pcr::femto_3pf();
  for (int i = 0; state.range(2) != 0 && i < robot.num_limbs; ++i) {
    robot.limb(i).q_min = -0.06;
    robot.limb(i).q_max = 0.06;
  }
  pcr::WorkspaceMapOptions options;
  options.grid = static_cast<int>(state.range(0));
  options.solver.check_stability = state.range(1) != 0;
  options.threads = static_cast<int>(state.range(3));
  pcr::WorkspaceMap map;
  for (auto _ : state) {
    map = pcr::workspace_map(robot, options);
    benchmark::DoNotOptimize(map.points.data());
  }
  state.counters["points"] = static_cast<double>(options.grid) * options.grid;
  state.counters["reachable_mm2"] = map.reachable_area * 1e6;
  state.counters["us_per_point"] = benchmark::Counter(
      static_cast<double>(options.grid) * options.grid,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_WorkspaceMap)
    ->ArgNames({"grid", "stability", "long_stroke", "threads"})
    ->Args({200, 1, 0, 1})
    ->Args({200, 1, 0, 2})
    ->Args({200, 0, 0, 2})
    ->Args({50, 1, 0, 2})
    ->Args({50, 1, 1, 2})
    ->Args({200, 1, 1, 1})
    ->Args({200, 1, 1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
