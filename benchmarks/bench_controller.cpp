// The embedded controller (pcr_controller): IK time per tick of the 1 kHz circle follower over
// 1e5 ticks (50 turns of the paper's 3 mm circle), reported as worst-case and median counters in
// seconds. Wall-clock times include preemption by other processes; the thread's CPU time
// (CLOCK_THREAD_CPUTIME_ID) does not, so its worst case is the solver's own.
//   build/benchmarks/bench_controller
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "pcr/controller.hpp"

namespace {

using namespace pcr;

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void BM_CircleFollowerTicks(benchmark::State& state) {
  const long ticks = state.range(0);
  const RobotParams<double> robot = femto_3pf();
  std::vector<double> wall(static_cast<std::size_t>(ticks)), cpu(wall.size());
  long failures = 0, max_iterations = 0;
  for (auto _ : state) {
    PathFollower<CirclePath> follower(robot, CirclePath(), 2.0);  // one turn per 2000 ticks
    for (long k = 0; k < ticks; ++k) {
      const double c0 = thread_cpu_seconds();
      const auto t0 = std::chrono::steady_clock::now();
      const ControllerTick tick = follower.step(1e-3 * static_cast<double>(k));
      const auto t1 = std::chrono::steady_clock::now();
      const double c1 = thread_cpu_seconds();
      wall[static_cast<std::size_t>(k)] = std::chrono::duration<double>(t1 - t0).count();
      cpu[static_cast<std::size_t>(k)] = c1 - c0;
      benchmark::DoNotOptimize(tick.q.data());
      if (!tick.ok()) ++failures;
      max_iterations = std::max<long>(max_iterations, tick.iterations);
    }
  }
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  state.counters["median_s"] = wall[wall.size() / 2];
  state.counters["worst_s"] = wall.back();
  state.counters["median_cpu_s"] = cpu[cpu.size() / 2];
  state.counters["worst_cpu_s"] = cpu.back();
  state.counters["p999_s"] = wall[wall.size() * 999 / 1000];
  state.counters["p999_cpu_s"] = cpu[cpu.size() * 999 / 1000];
  state.counters["max_newton_iterations"] = static_cast<double>(max_iterations);
  state.counters["failures"] = static_cast<double>(failures);
  state.counters["ticks"] = static_cast<double>(ticks);
}
BENCHMARK(BM_CircleFollowerTicks)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
