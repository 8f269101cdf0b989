// Predicted accuracy per configuration (pcr/calib/predicted_accuracy.hpp), for workspace maps:
// the cost of one prediction at a solved configuration (pose covariance from a dense covariance
// of the 30 limb parameters and the extrinsics, and the worst case over the default robot's
// intervals), of its Jacobian alone, and of FK plus the prediction along the rows of a joint grid
// (warm-started, as a map would be computed). Default robot, 20 x 20 grid of q1, q2 over
// +-5 mm (q3 = 0); items are configurations: "time / item" is the cost per grid point.

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "pcr/calib/predicted_accuracy.hpp"

namespace {

struct Scenario {
  pcr::RobotDescription robot = pcr::default_robot();
  pcr::ParameterCovariance covariance;
  pcr::PredictedAccuracyOptions options;
  std::vector<pcr::JointVector> grid;
  std::vector<pcr::ForwardSolution> solutions;

  Scenario() {
    const int n = robot.params.num_limbs;
    const int count = pcr::num_parameters(n);
    options.half_widths = pcr::parameter_half_widths(*robot.uncertainty, n);
    // A dense, positive definite covariance: (A A^T) scaled by a tenth of the half-widths.
    std::mt19937_64 rng(1);
    std::normal_distribution<double> normal;
    Eigen::MatrixXd A(count, count);
    for (int r = 0; r < count; ++r) {
      for (int c = 0; c < count; ++c) A(r, c) = normal(rng);
    }
    Eigen::VectorXd scale(count);
    for (int k = 0; k < count; ++k) scale(k) = 0.1 * options.half_widths[k] / std::sqrt(count);
    covariance.matrix = scale.asDiagonal() * (A * A.transpose()) * scale.asDiagonal();
    for (int k = 0; k < count; ++k) {
      covariance.names.push_back(pcr::parameter_name(pcr::parameter_id(k, n)));
    }
    pcr::validate_parameter_covariance(covariance, "benchmark", n);
    constexpr int kSide = 20;
    pcr::ForwardSequence sequence(robot.params);
    for (int a = 0; a < kSide; ++a) {
      for (int b = 0; b < kSide; ++b) {
        pcr::JointVector q(3);
        q << -5e-3 + 10e-3 * a / (kSide - 1), -5e-3 + 10e-3 * b / (kSide - 1), 0.0;
        const pcr::ForwardSolution& s = sequence.solve(q);
        if (!s.summary.converged()) continue;
        grid.push_back(q);
        solutions.push_back(s);
      }
    }
  }
};

const Scenario& scenario() {
  static const Scenario s;
  return s;
}

void BM_PredictedAccuracy(benchmark::State& state) {
  const Scenario& s = scenario();
  std::size_t k = 0;
  for (auto _ : state) {
    const pcr::PredictedAccuracy a =
        pcr::predicted_accuracy(s.robot.params, s.solutions[k], s.covariance, s.options);
    benchmark::DoNotOptimize(a);
    k = (k + 1) % s.solutions.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PredictedAccuracy)->Unit(benchmark::kMicrosecond);

void BM_PoseParameterJacobian(benchmark::State& state) {
  const Scenario& s = scenario();
  std::size_t k = 0;
  pcr::PoseParameterJacobian J;
  for (auto _ : state) {
    benchmark::DoNotOptimize(pcr::pose_parameter_jacobian(s.robot.params, s.solutions[k], &J));
    k = (k + 1) % s.solutions.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PoseParameterJacobian)->Unit(benchmark::kMicrosecond);

/// FK warm-started along the grid, then the prediction at each point.
void BM_ForwardThenPredictedAccuracy(benchmark::State& state) {
  const Scenario& s = scenario();
  pcr::ForwardSequence sequence(s.robot.params);
  std::size_t k = 0;
  for (auto _ : state) {
    const pcr::ForwardSolution& solution = sequence.solve(s.grid[k]);
    const pcr::PredictedAccuracy a =
        pcr::predicted_accuracy(s.robot.params, solution, s.covariance, s.options);
    benchmark::DoNotOptimize(a);
    k = (k + 1) % s.grid.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardThenPredictedAccuracy)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
