// Workspace maps (pcr/calib/workspace_map.hpp): the default robot's 200 x 200 map at theta = 0,
// with and without the stability check (timed on its own in bench_kinematics).
#include <benchmark/benchmark.h>

#include "pcr/calib/workspace_map.hpp"

namespace {

void BM_WorkspaceMap(benchmark::State& state) {
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  pcr::WorkspaceMapOptions options;
  options.grid = static_cast<int>(state.range(0));
  options.solver.check_stability = state.range(1) != 0;
  options.range = pcr::stroke_pose_box(robot);  // fixed, so that only the map is timed
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
    ->Args({200, 1})
    ->Args({200, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
