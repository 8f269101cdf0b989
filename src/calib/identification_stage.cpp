// One stage of the identification: bounded Levenberg-Marquardt in rounds, with an active set.

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "calibration_internal.hpp"
#include "identification.hpp"

namespace pcr::calib_internal {

/// Accepts the caches at every point Ceres keeps (the start and each successful step): the
/// solves of the next trial points start from there (FkCache::anchor). Needs
/// update_state_every_iteration.
class Identification::AcceptCallback : public ceres::IterationCallback {
 public:
  explicit AcceptCallback(Identification* id) : id_(id) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (s.iteration == 0 || s.step_is_successful) id_->accept_evaluated();
    return ceres::SOLVER_CONTINUE;
  }

 private:
  Identification* id_;
};

/// Ends a solve (successfully: the values are the last accepted step's) when `stop` says so
/// after an accepted step.
class Identification::BoundCallback : public ceres::IterationCallback {
 public:
  explicit BoundCallback(std::function<bool()> stop) : stop_(std::move(stop)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    return s.iteration > 0 && s.step_is_successful && stop_() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                                              : ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<bool()> stop_;
};

/// Writes each iteration's cost (m^2) on the progress stream.
class Identification::ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(std::string stage, double to_m2,
                   const std::function<void(const std::string&)>& sink)
      : stage_(std::move(stage)), to_m2_(to_m2), sink_(sink) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (sink_) {
      sink_("stage " + stage_ + ": iteration " + std::to_string(s.iteration) + ", cost " +
            format_number(s.cost * to_m2_) + " m^2");
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::string stage_;
  double to_m2_;
  const std::function<void(const std::string&)>& sink_;
};

template <class AtBound>
bool Identification::update_active_set(const std::vector<int>& free, const AtBound& at_bound,
                                       bool stopped_at_bound, std::vector<bool>* is_free) {
  if (stopped_at_bound) {
    bool changed = false;
    for (int k : free) {
      if ((*is_free)[static_cast<std::size_t>(k)] && at_bound(k)) {
        (*is_free)[static_cast<std::size_t>(k)] = false;
        changed = true;
      }
    }
    return changed;
  }
  ceres::Problem problem;
  add_residuals(problem);
  double c = 0;
  std::vector<double> gradient;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, nullptr, &gradient, nullptr)) {
    return false;
  }
  bool changed = false;
  for (int k : free) {
    const std::size_t uk = static_cast<std::size_t>(k);
    if (!at_bound(k)) continue;
    const bool pulled_inside = gradient[uk] * (values_[uk] - nominal_values_[uk]) > 0;
    if ((*is_free)[uk] != pulled_inside) {
      (*is_free)[uk] = pulled_inside;
      changed = true;
    }
  }
  return changed;
}

ceres::Solver::Options Identification::solver_options(double function_tolerance) const {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options_.max_iterations;
  solver.num_threads = 1;
  solver.function_tolerance = function_tolerance;
  solver.gradient_tolerance = 1e-12;
  // Off: Ceres compares the step with |x|, which E (~7e10 Pa) dominates, so any step would
  // look negligible. The function and gradient tolerances (whitened residuals) decide.
  solver.parameter_tolerance = 0.0;
  solver.logging_type = ceres::SILENT;
  // With bounds, Ceres runs an Armijo line search on every step; cubic interpolation (its
  // default) asks for the gradient at each trial point, a whole Jacobian evaluation of the
  // rows. Quadratic interpolation needs the trial costs only.
  solver.line_search_interpolation_type = ceres::QUADRATIC;
  return solver;
}

StageReport Identification::run_stage(const CalibrationStage& stage, bool last, int rescale) {
  StageReport report;
  report.name = stage.name;
  const std::vector<int> free = free_indices(stage);
  for (int k : free) report.free_parameters.push_back(parameter_name(parameter_id(k, n_)));
  const double to_m2 = options_.residual_scale * options_.residual_scale;
  if (free.empty()) {
    report.initial_cost = report.final_cost = cost() * to_m2;
    report.termination = "no free parameter";
    report.usable = true;
    return report;
  }
  std::vector<bool> stage_free(static_cast<std::size_t>(block_), false);
  for (int k : free) stage_free[static_cast<std::size_t>(k)] = true;
  const bool subspace = options_.stage_gauge == StageGauge::kSubspace;
  const auto at_bound = [&](int k) {
    const std::size_t uk = static_cast<std::size_t>(k);
    return bounded(k) && std::abs(values_[uk] - nominal_values_[uk]) >=
                             stage.bounds_scale * half_widths_[uk] * (1 - 1e-9);
  };

  ceres::Solver::Options solver =
      solver_options(last ? options_.function_tolerance : options_.intermediate_function_tolerance);
  ProgressCallback callback(stage.name, to_m2, options_.progress);
  if (options_.progress) solver.callbacks.push_back(&callback);
  // Ceres projects the unconstrained step onto the box: once a step has put a free parameter
  // on its bound, the following ones keep a fraction of the decrease their model predicts and
  // crawl. The solve stops there instead, and the parameter is held at the bound (below).
  std::vector<bool> is_free;
  BoundCallback stop_at_bound([&] {
    for (int k : free) {
      if (is_free[static_cast<std::size_t>(k)] && at_bound(k)) return true;
    }
    return false;
  });
  AcceptCallback accept(this);
  solver.callbacks.push_back(&accept);
  solver.callbacks.push_back(&stop_at_bound);
  solver.update_state_every_iteration = true;  // the callbacks read values_
  ceres::Solver::Summary summary;
  const auto start = std::chrono::steady_clock::now();
  for (FkCache& c : caches_) c.evaluations = c.warm_start_failures = c.newton_iterations = 0;

  // Rounds: each starts from the representative of the gauge orbit deepest inside the box
  // (recentre_in_gauge) with every parameter of the stage free. A round that ends with
  // parameters at a bound is followed by another while the rounds still lower the cost by 1%:
  // a bound met in the gauge a round started in may not be met in the next one's, and a
  // parameter held at a bound is released. A truth inside the box has a representative inside
  // it, which the rounds reach (the sweep in tests/test_calibration.cpp).
  // A round whose start (recentred, clamped) the model cannot evaluate, a row past a fold
  // there, goes on from the last values it evaluated instead: the stage's start, or the end
  // of the last round.
  constexpr int kMaxRounds = 4;
  std::vector<double> last_evaluated = values_;
  std::vector<FkCache> caches_evaluated = caches_;  // the equilibria at last_evaluated
  ceres::Solver::Summary last_summary;
  bool solved = false, restored = false;
  recentre_in_gauge(stage_free, stage.bounds_scale);
  double previous_round_cost = std::numeric_limits<double>::infinity();
  for (int round = 0; round < kMaxRounds; ++round) {
    for (int k : free) {  // a previous stage with wider bounds may have left a value outside
      if (!bounded(k)) continue;
      const double h = stage.bounds_scale * half_widths_[static_cast<std::size_t>(k)];
      const double c = nominal_values_[static_cast<std::size_t>(k)];
      double& v = values_[static_cast<std::size_t>(k)];
      v = std::min(std::max(v, c - h), c + h);
    }
    settle();
    if (round == 0) {
      update_loss_scale();
      exclude_gross_outliers();
    }
    ceres::Problem problem;
    add_residuals(problem);
    is_free = stage_free;
    problem.SetManifold(values_.data(), make_manifold(is_free, subspace));
    if (!subspace && options_.gauge_prior_weight > 0) {
      // Weak pull towards the nominal values, in half-width units: it only matters along the
      // gauge directions (where the data says nothing), which it fixes to the representative
      // closest to the nominal, away from the bounds.
      Eigen::MatrixXd a = Eigen::MatrixXd::Zero(block_, block_);
      for (int k : free) {
        a(k, k) = options_.gauge_prior_weight / half_widths_[static_cast<std::size_t>(k)];
      }
      const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(nominal_values_.data(), block_);
      problem.AddResidualBlock(new ceres::NormalPrior(a, b), nullptr, values_.data());
    }
    for (int k : free) {
      if (!bounded(k)) continue;
      const double h = stage.bounds_scale * half_widths_[static_cast<std::size_t>(k)];
      const double c = nominal_values_[static_cast<std::size_t>(k)];
      problem.SetParameterLowerBound(values_.data(), k, c - h);
      problem.SetParameterUpperBound(values_.data(), k, c + h);
    }
    solve(solver, &problem, &summary, stage.name);
    const bool failed_at_start = summary.termination_type == ceres::FAILURE &&
                                 (summary.iterations.empty() || summary.initial_cost < 0);
    if (failed_at_start && !restored) {
      values_ = last_evaluated;
      for (std::size_t j = 0; j < caches_.size(); ++j) {  // the counters go on counting
        caches_[j].solution = caches_evaluated[j].solution;
        caches_[j].valid = caches_evaluated[j].valid;
        caches_[j].parameters = caches_evaluated[j].parameters;
      }
      restored = true;
      if (solved) {
        summary = last_summary;
        break;
      }
      --round;  // round 0 again, from the stage's own start
      continue;
    }
    if (round == 0) report.initial_cost = summary.initial_cost * to_m2;
    report.iterations += static_cast<int>(summary.iterations.size()) - 1;
    add_counters(summary, &report);
    // Active set: hold the free parameters at a bound the cost pushes against, release the
    // held ones it pulls back inside, solve again; until neither changes.
    constexpr int kMaxPasses = 12;
    for (int pass = 0; pass < kMaxPasses &&
                       update_active_set(free, at_bound,
                                         summary.termination_type == ceres::USER_SUCCESS, &is_free);
         ++pass) {
      if (std::none_of(free.begin(), free.end(),
                       [&](int k) { return is_free[static_cast<std::size_t>(k)]; })) {
        break;
      }
      problem.SetManifold(values_.data(), make_manifold(is_free, subspace));
      solve(solver, &problem, &summary, stage.name + " (active set)");
      report.iterations += static_cast<int>(summary.iterations.size()) - 1;
      add_counters(summary, &report);
    }
    const bool any_at_bound = std::any_of(free.begin(), free.end(), at_bound);
    if (!any_at_bound || !(summary.final_cost < (1 - 1e-2) * previous_round_cost)) break;
    previous_round_cost = summary.final_cost;
    last_evaluated = values_;
    caches_evaluated = caches_;
    last_summary = summary;
    solved = summary.IsSolutionUsable();
    recentre_in_gauge(stage_free, stage.bounds_scale);
  }
  report.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const FkCache& c : caches_) {
    report.fk_solves += c.evaluations;
    report.fk_warm_start_failures += c.warm_start_failures;
    report.fk_newton_iterations += c.newton_iterations;
  }
  report.final_cost = summary.final_cost * to_m2;
  report.termination = summary.BriefReport();
  report.usable = summary.IsSolutionUsable();
  last_free_ = free;
  last_bounds_scale_ = stage.bounds_scale;
  // The Huber scale follows the residuals down (a stage that starts far from the data first
  // fits with a wide one): while it shrinks by half, the stage is solved again with it
  // (solve_stage_again).
  const double used = loss_scale_;
  if (rescale < 8 && used > 0) {
    update_loss_scale();
    if (solve_stage_again(used, loss_scale_, row_norms_,
                          gross_outliers(row_norms_, loss_scale_, options_.robust_scale, 3))) {
      const StageReport again = run_stage(stage, last, rescale + 1);
      report.final_cost = again.final_cost;
      report.termination = again.termination;
      report.usable = again.usable;
      report.iterations += again.iterations;
      report.time_s += again.time_s;
      report.residual_evaluations += again.residual_evaluations;
      report.jacobian_evaluations += again.jacobian_evaluations;
      report.residual_time_s += again.residual_time_s;
      report.jacobian_time_s += again.jacobian_time_s;
      report.linear_solver_time_s += again.linear_solver_time_s;
      report.fk_solves += again.fk_solves;
      report.fk_warm_start_failures += again.fk_warm_start_failures;
      report.fk_newton_iterations += again.fk_newton_iterations;
    }
  }
  return report;
}

void Identification::solve(const ceres::Solver::Options& solver, ceres::Problem* problem,
                           ceres::Solver::Summary* summary, const std::string& what) {
  std::vector<int> failures_before(caches_.size());
  for (std::size_t j = 0; j < caches_.size(); ++j) failures_before[j] = caches_[j].failures;
  ceres::Solve(solver, problem, summary);
  settle();
  if (summary->termination_type != ceres::FAILURE || !options_.progress) return;
  std::vector<std::string> rows;
  for (std::size_t j = 0; j < caches_.size(); ++j) {
    if (caches_[j].failures > failures_before[j]) rows.push_back(origin(j));
  }
  options_.progress("stage " + what + ": " + summary->message + " FK failed on " +
                    std::to_string(rows.size()) + " rows" +
                    (rows.empty() ? std::string() : ": " + listing(rows, 5)));
}

void Identification::add_counters(const ceres::Solver::Summary& summary, StageReport* report) {
  report->residual_evaluations += summary.num_residual_evaluations;
  report->jacobian_evaluations += summary.num_jacobian_evaluations;
  report->residual_time_s += summary.residual_evaluation_time_in_seconds;
  report->jacobian_time_s += summary.jacobian_evaluation_time_in_seconds;
  report->linear_solver_time_s += summary.linear_solver_time_in_seconds;
}

void Identification::refit_holding(const std::vector<int>& held) {
  std::vector<bool> is_free(static_cast<std::size_t>(block_), false);
  for (int k : last_free_) is_free[static_cast<std::size_t>(k)] = true;
  for (int k : held) is_free[static_cast<std::size_t>(k)] = false;
  ceres::Problem problem;
  add_residuals(problem);
  problem.SetManifold(values_.data(), make_manifold(is_free, false));
  const ceres::Solver::Options solver = solver_options(options_.function_tolerance);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  settle();
}

}  // namespace pcr::calib_internal
