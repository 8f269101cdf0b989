// The C++ side of python/benchmarks/bench_batch.py: the same batched, warm-started FK loop that
// Robot.forward runs (python/src/solve.hpp), on the same trajectory, timed with steady_clock.
//   bench_batch_cpp [N]   prints "<N> <seconds> <converged>"
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "../src/solve.hpp"

int main(int argc, char** argv) {
  const long rows = argc > 1 ? std::atol(argv[1]) : 100000;
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  const int n = robot.num_limbs;
  // Trajectory shared with bench_batch.py: q_i(k) = 3 mm sin(2 pi (i + 1) k / N + i).
  std::vector<double> q(static_cast<std::size_t>(rows * n));
  for (long k = 0; k < rows; ++k) {
    for (int i = 0; i < n; ++i) {
      q[static_cast<std::size_t>(k * n + i)] =
          0.003 * std::sin(2.0 * M_PI * (i + 1) * static_cast<double>(k) / rows + i);
    }
  }
  std::vector<double> qo(q.size()), pose(static_cast<std::size_t>(rows * 3)),
      wrenches(static_cast<std::size_t>(rows * n * 3)), residual(rows), strain(rows), margin(rows),
      singularity(rows);
  std::vector<int> status(rows), iterations(rows), steps(rows);
  std::unique_ptr<bool[]> converged(new bool[static_cast<std::size_t>(rows)]);
  std::unique_ptr<bool[]> stable(new bool[static_cast<std::size_t>(rows)]);
  const pcr::python::BatchBuffers out{qo.data(),       pose.data(),   wrenches.data(),
                                      converged.get(), status.data(), iterations.data(),
                                      residual.data(), strain.data(), steps.data(),
                                      stable.get(),    margin.data(), singularity.data()};
  const auto start = std::chrono::steady_clock::now();
  pcr::python::forward_batch(robot, q.data(), rows, pcr::SolverOptions(), {}, out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  long ok = 0;
  for (long k = 0; k < rows; ++k) ok += converged[static_cast<std::size_t>(k)] ? 1 : 0;
  std::printf("%ld %.6f %ld\n", rows, seconds, ok);
  return ok == rows ? 0 : 1;
}
