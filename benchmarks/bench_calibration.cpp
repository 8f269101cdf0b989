// The whole three-stage identification on the paper's 99 configurations (virtual robot drawn in
// the paper's intervals, paper noise): exact derivatives side by side with central finite
// differences (what the paper's lsqnonlin did), same data. Exact derivatives come in two
// implementations: the per-limb analytic assembly (the default) and one auto-diff Jet through the
// whole residual (the cross-check, ~10x dearer per Jacobian).
// Counters: final cost (m^2, 1/2 sum F^T F), LM iterations, Jacobian and residual evaluations,
// double FK solves and Newton iterations, failed warm starts, per-stage iterations and times
// (s), mean e_p (m) of the identified model on the calibration set.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

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

void identify(benchmark::State& state, pcr::DerivativeMode mode,
              pcr::StageGauge gauge = pcr::StageGauge::kSubspace) {
  const Scenario& s = scenario();
  pcr::CalibrationOptions options;
  options.derivatives = mode;
  options.stage_gauge = gauge;
  options.compute_covariance = false;
  pcr::CalibrationResult result;
  for (auto _ : state) {
    result = pcr::calibrate(s.nominal, s.data, options);
    benchmark::DoNotOptimize(result);
  }
  int iterations = 0, jacobians = 0, residuals = 0, fk = 0, newton = 0, warm_failures = 0;
  for (std::size_t k = 0; k < result.stages.size(); ++k) {
    const pcr::StageReport& stage = result.stages[k];
    iterations += stage.iterations;
    jacobians += stage.jacobian_evaluations;
    residuals += stage.residual_evaluations;
    fk += stage.fk_solves;
    newton += stage.fk_newton_iterations;
    warm_failures += stage.fk_warm_start_failures;
    const std::string prefix = "s" + std::to_string(k + 1) + "_";
    state.counters[prefix + "iter"] = stage.iterations;
    state.counters[prefix + "time_s"] = stage.time_s;
    state.counters[prefix + "jac_time_s"] = stage.jacobian_time_s;
  }
  state.counters["final_cost_m2"] = result.stages.back().final_cost;
  state.counters["lm_iterations"] = iterations;
  state.counters["jacobian_evals"] = jacobians;
  state.counters["residual_evals"] = residuals;
  state.counters["fk_solves"] = fk;
  state.counters["fk_newton_iter"] = newton;
  state.counters["fk_warm_fail"] = warm_failures;
  state.counters["mean_e_p_m"] = pcr::pose_errors(result.identified, s.data).mean_p;
}

void BM_ThreeStages_Implicit(benchmark::State& state) {
  identify(state, pcr::DerivativeMode::kImplicit);
}
void BM_ThreeStages_AutoDiff(benchmark::State& state) {
  identify(state, pcr::DerivativeMode::kAutoDiff);
}
void BM_ThreeStages_CentralDifferences(benchmark::State& state) {
  identify(state, pcr::DerivativeMode::kNumericCentral);
}
// The former gauge handling (weak prior towards the nominal values), for the iteration count.
void BM_ThreeStages_Implicit_GaugePrior(benchmark::State& state) {
  identify(state, pcr::DerivativeMode::kImplicit, pcr::StageGauge::kPrior);
}
BENCHMARK(BM_ThreeStages_Implicit)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_ThreeStages_AutoDiff)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ThreeStages_CentralDifferences)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ThreeStages_Implicit_GaugePrior)->Unit(benchmark::kMillisecond)->Iterations(1);

// The sweep over truths (VirtualRobotOptions::truth_at_fraction: 0 uniform inside the intervals,
// 90 for every parameter at +-0.9 half-widths, 100 exactly on the bounds), 99 + 56
// configurations (each set measured from home), 8 truths per run:
// validation e_p mean (worst truth and truths above 0.05 um), parameters at a bound, and the
// median and largest time of the three stages (s).
//   build/benchmarks/bench_calibration --benchmark_filter=Sweep
void BM_Sweep(benchmark::State& state) {
  const pcr::RobotDescription nominal = pcr::default_robot();
  pcr::SamplingOptions so;
  so.count = 155;
  so.seed = 7;
  const std::vector<pcr::JointVector> q =
      pcr::poisson_disc_sample(nominal.params, so).configurations;
  if (q.size() != 155) {
    state.SkipWithError("the sampling found fewer than 155 configurations");
    return;
  }
  std::vector<double> times;
  double worst = 0;
  int above = 0, at_bound = 0, truths = 0;
  for (auto _ : state) {
    for (std::uint64_t seed = 1; truths < 8 && seed < 100; ++seed) {
      pcr::VirtualRobotOptions vo;
      vo.seed = seed;
      vo.truth_at_fraction = static_cast<double>(state.range(0)) / 100.0;
      pcr::VirtualRobot robot(nominal, vo);
      bool reachable = true;
      const auto measure = [&](std::size_t from, std::size_t to) {  // each set from home
        const std::vector<pcr::JointVector> rows(q.begin() + from, q.begin() + to);
        const std::vector<pcr::VirtualMeasurement> measured = robot.measure_dataset(rows);
        std::vector<pcr::CalibrationSample> out;
        for (std::size_t k = 0; k < rows.size(); ++k) {
          reachable = reachable && measured[k].ok;
          out.push_back({rows[k], measured[k].measured});
        }
        return out;
      };
      const std::vector<pcr::CalibrationSample> calibration = measure(0, 99);
      const std::vector<pcr::CalibrationSample> validation = measure(99, q.size());
      if (!reachable) continue;  // the truth cannot reach a configuration of the set
      ++truths;
      pcr::CalibrationOptions options;
      options.compute_covariance = false;
      const auto t0 = std::chrono::steady_clock::now();
      const pcr::CalibrationResult result = pcr::calibrate(nominal, calibration, options);
      times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      const double mean = pcr::pose_errors(result.identified, validation).mean_p;
      worst = std::max(worst, mean);
      above += mean > 0.05e-6;
      for (const pcr::ParameterEstimate& p : result.parameters) at_bound += p.at_bound;
    }
  }
  std::sort(times.begin(), times.end());
  state.counters["truths"] = truths;
  state.counters["worst_val_mean_e_p_m"] = worst;
  state.counters["truths_above_0.05um"] = above;
  state.counters["params_at_bound"] = at_bound;
  state.counters["median_time_s"] = times.empty() ? 0.0 : times[times.size() / 2];
  state.counters["max_time_s"] = times.empty() ? 0.0 : times.back();
}
BENCHMARK(BM_Sweep)->Arg(0)->Arg(90)->Arg(100)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
