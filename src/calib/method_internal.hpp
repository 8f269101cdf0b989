#pragma once
// What the planar and spatial methods share (src/calib/method.cpp, src/calib/spatial_method.cpp),
// not part of the API: how a stage runs, and how the virtual robot measures a set.

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "pcr/calib/experiment_design.hpp"  // visiting_order
#include "pcr/calib/method.hpp"             // MethodStage

namespace pcr::calib_internal {

/// Runs one stage of a method: its callbacks (Options::on_stage_begin, on_stage_end) and its wall
/// time (Result::seconds).
template <class Options, class Result>
class StageRunner {
 public:
  StageRunner(const Options& options, Result& result) : options_(options), result_(result) {}

  template <typename F>
  void run(MethodStage stage, F&& body) {
    if (options_.on_stage_begin) options_.on_stage_begin(stage);
    const auto start = std::chrono::steady_clock::now();
    body();
    result_.seconds[static_cast<int>(stage)] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (options_.on_stage_end) options_.on_stage_end(stage, result_);
  }

 private:
  const Options& options_;
  Result& result_;
};

/// The rows the virtual robot measured, visited in the order an experiment would take them; the
/// configurations it measures no equilibrium at are counted in `unmeasured`.
template <class Data, class Robot, class Joints>
Data measured_rows(Robot& robot, const std::vector<Joints>& configurations, int num_joints,
                   const char* set, int* unmeasured) {
  std::vector<Joints> visits;
  for (std::size_t k : visiting_order(configurations)) visits.push_back(configurations[k]);
  const auto measured = robot.measure_dataset(visits);
  Data data;
  data.num_joints = num_joints;
  for (std::size_t k = 0; k < visits.size(); ++k) {
    if (measured[k].ok) {
      data.add(visits[k], measured[k].measured);
    } else {
      ++*unmeasured;
    }
  }
  if (data.size() == 0) {
    throw std::runtime_error("none of the " + std::to_string(visits.size()) + " " + set +
                             " configurations is measured: the true robot holds no stable "
                             "equilibrium at any");
  }
  return data;
}

}  // namespace pcr::calib_internal
