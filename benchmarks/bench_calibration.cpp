// The whole three-stage identification on the paper's 99 configurations (virtual robot drawn in
// the paper's intervals, paper noise): exact derivatives (auto-diff + implicit function theorem)
// side by side with central finite differences (what the paper's lsqnonlin did), same data.
// Counters: final cost (m^2, 1/2 sum F^T F), total LM iterations, validation-free mean e_p (m).

#include <benchmark/benchmark.h>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace {

struct Scenario {
  pcr::RobotDescription nominal = pcr::default_robot();
  std::vector<pcr::CalibrationSample> data;
  Scenario() {
    pcr::VirtualRobotOptions vo;
    vo.seed = 11;
    pcr::VirtualRobot robot(nominal, vo);
    pcr::SamplingOptions so;
    so.count = 99;
    so.seed = 11;
    for (const pcr::JointVector& q : pcr::poisson_disc_sample(nominal.params, so).configurations) {
      data.push_back({q, robot.measure_or_throw(q)});
    }
  }
};

const Scenario& scenario() {
  static const Scenario s;
  return s;
}

void identify(benchmark::State& state, pcr::DerivativeMode mode) {
  const Scenario& s = scenario();
  pcr::CalibrationOptions options;
  options.derivatives = mode;
  options.compute_covariance = false;
  pcr::CalibrationResult result;
  for (auto _ : state) {
    result = pcr::calibrate(s.nominal, s.data, options);
    benchmark::DoNotOptimize(result);
  }
  int iterations = 0;
  for (const pcr::StageReport& stage : result.stages) iterations += stage.iterations;
  state.counters["final_cost_m2"] = result.stages.back().final_cost;
  state.counters["lm_iterations"] = iterations;
  state.counters["mean_e_p_m"] = pcr::pose_errors(result.identified, s.data).mean_p;
}

void BM_ThreeStages_Implicit(benchmark::State& state) {
  identify(state, pcr::DerivativeMode::kImplicit);
}
void BM_ThreeStages_CentralDifferences(benchmark::State& state) {
  identify(state, pcr::DerivativeMode::kNumericCentral);
}
BENCHMARK(BM_ThreeStages_Implicit)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_ThreeStages_CentralDifferences)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
