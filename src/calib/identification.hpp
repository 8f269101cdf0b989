#pragma once
// Identification: the state the stages of the identification share and fit.

#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "calibration_internal.hpp"
#include "outlier_rule.hpp"
#include "pcr/calib/calibrator.hpp"

namespace pcr::calib_internal {

/// Everything the stages share: current values, warm-start caches, data.
class Identification {
 public:
  Identification(const RobotDescription& nominal, const std::vector<CalibrationSample>& data,
                 const CalibrationOptions& options);

  /// The flat parameters.
  int count() const { return count_; }
  /// The values Ceres sees: the flat parameters, then the load when a stage frees it.
  int block() const { return block_; }
  /// The geometry is bounded (Eq. 7); the extrinsics and the load are not: the extrinsics start
  /// from the registration of the data (registered_extrinsics), whatever the guess, and the
  /// report says when they end outside the declared interval.
  bool bounded(int k) const { return k < count_ && parameter_id(k, n_).limb >= 0; }
  const std::vector<double>& values() const { return values_; }
  void set_values(const std::vector<double>& v) { values_ = v; }
  const std::vector<double>& half_widths() const { return half_widths_; }
  const std::vector<double>& nominal_values() const { return nominal_values_; }
  RobotParams<double> robot() const { return with_parameters(nominal_, values_.data()); }
  void set_robot(const RobotParams<double>& robot) { get_parameters(robot, values_.data()); }
  PlatformLoad<double> load() const {
    if (!identify_load_) return PlatformLoad<double>();
    const double* l = values_.data() + count_;
    return PlatformLoad<double>{Vector2<double>(l[0], l[1]), l[2]};
  }
  /// Moves the values along the gauge orbit, the load with them (move_load_along_gauge), and
  /// each row's anchored equilibrium with them by the model's symmetry
  /// (move_equilibrium_along_gauge), then settles there: every robot on the orbit predicts the
  /// same poses, and no continuation is needed to find the same equilibrium (one through robots
  /// off the orbit can fail near a fold).
  void move(const GaugeMotion& m);
  /// Starts each row on the equilibrium its experiment reached: of those the rows reach at the
  /// current values in the dataset's readings (dataset_readings: on its own from home, along the
  /// rows' path, through folds), the one whose platform pose lies nearest the row's measurement
  /// (Eq. 6's metric). Rows are measured in their order from home (the formats page), and a robot
  /// that came to a row along its path may hold it on another equilibrium than the one a cold
  /// start from home gives: fitted there, the row would look like a gross outlier, and the model
  /// would be fitted without it. At the start values the model is within its intervals of the
  /// robot, and equilibria at the same joints are millimetres apart.
  void start_on_measured_branches();
  /// Moves each row that the model's equilibrium at the current values misses by far onto the
  /// equilibrium at its joints that its measurement names (equilibria_measured_instead): one the
  /// robot came to in a way the readings at the start values did not follow (a fold the nominal
  /// geometry places elsewhere). The rows moved, by name.
  std::vector<std::string> move_to_measured_equilibria();
  /// Continues every valid cache to the current values and accepts them there (a row that cannot
  /// follow keeps its anchor, and the cost continues it from there when evaluated).
  void settle();
  /// The rows whose residuals add_residuals(problem, false) adds, in its order: all but the lost.
  std::vector<std::size_t> evaluated_rows() const;
  /// The rows left out because their equilibrium does not follow the current values.
  std::vector<std::string> lost_rows() const;
  /// Accepts the caches solved at the current values (a point Ceres kept).
  void accept_evaluated();
  /// Whether `is_free` (over the block) frees a load parameter.
  bool load_free(const std::vector<bool>& is_free) const;

  /// The gauge generators at the current values, over the block (with the load's components when
  /// it is identified).
  std::vector<GaugeGenerator> generators() const {
    return identify_load_ ? gauge_generators(robot(), load()) : gauge_generators(robot());
  }
  /// Which of `generators` are gauges of a problem whose free parameters are `is_free`: every
  /// parameter they move is free, and, with the load free, not a distal translation (under a
  /// force it changes the predictions, by the arm that turns with the platform).
  std::vector<bool> gauges(const std::vector<GaugeGenerator>& generators,
                           const std::vector<bool>& is_free) const {
    std::vector<bool> present = present_generators(generators, is_free);
    if (load_free(is_free)) present[kDistalX] = present[kDistalY] = false;
    return present;
  }

  /// Free flat indices of a stage (stage_free_indices).
  std::vector<int> free_indices(const CalibrationStage& stage) const {
    return stage_free_indices(stage, half_widths_, n_);
  }

  /// Adds every residual block on values_.data(). With `robust`, each configuration's block goes
  /// through the Huber loss at loss_scale_ (whitened units); the problem owns it.
  /// With `robust`, the gross outliers of the stage (exclude_gross_outliers) are left out.
  void add_residuals(ceres::Problem& problem, bool robust = true);

  /// Levenberg-Marquardt with dense QR, stopping on `function_tolerance` (relative) or the
  /// gradient.
  ceres::Solver::Options solver_options(double function_tolerance) const;

  /// Fits the stage's free parameters; `last`: the final stage (the tighter function tolerance);
  /// `rescale`: how many times the stage has been solved again for a smaller Huber scale.
  StageReport run_stage(const CalibrationStage& stage, bool last = true, int rescale = 0);

  /// Solves, accepts the equilibria at the result, and names a failure on the progress stream:
  /// Ceres' message and the rows whose FK failed during the solve.
  void solve(const ceres::Solver::Options& solver, ceres::Problem* problem,
             ceres::Solver::Summary* summary, const std::string& what);
  std::string origin(std::size_t j) const {
    return data_[j].origin.empty() ? "configuration " + std::to_string(j + 1) : data_[j].origin;
  }

  static void add_counters(const ceres::Solver::Summary& summary, StageReport* report);

  /// Moves the values along the gauge orbit (which changes no prediction), by the generators of
  /// `is_free` whose parameters are all free, to the representative that lies deepest inside the
  /// box nominal +- bounds_scale half-widths: the minimum over the motion of
  /// sum_k (dev_k / h_k)^16 on the bounded free parameters, a smooth stand-in for the largest
  /// |dev_k| / h_k (convex: the deviations are affine in the generators' coefficients, then
  /// mapped onto the exact finite motions). A stage restricted to the complement of the gauge
  /// keeps its start's gauge component, so a start near a bound would pin it there; a truth
  /// inside the box has a representative inside it, and this start reaches it.
  void recentre_in_gauge(const std::vector<bool>& is_free, double bounds_scale);

  /// The stage's manifold: the free parameters in half-width units, minus (with `remove_gauge`)
  /// the gauge directions whose parameters are all free, taken at the current values.
  ceres::Manifold* make_manifold(const std::vector<bool>& is_free, bool remove_gauge) const;

  /// Refits the last stage's free parameters with `held` constant: after a gauge fix that changes
  /// the predictions slightly (a distal translation under a load). Holding the gauge references
  /// leaves a full-rank problem, a few iterations from the fixed values. No bounds: the box is
  /// the stages' gauge's, the fixed gauge may put values outside it.
  void refit_holding(const std::vector<int>& held);

  /// The smallest singular value of the scaled Jacobian on `columns` at the current values,
  /// relative to the largest (the rank test of the covariance); NaN when the model cannot be
  /// evaluated.
  double smallest_singular_value(const std::vector<int>& columns);

  /// Ceres cost (whitened) at the current values.
  double cost();

  /// Whitened residuals and the dense Jacobian over every flat parameter at the current values;
  /// their 3-row blocks are those of evaluated_rows().
  bool jacobian(Eigen::MatrixXd* J, Eigen::VectorXd* r);

  /// The Huber scale of the rows' residuals at the current values (huber_scale, outlier_rule.hpp).
  void update_loss_scale();

  /// Leaves out of the stage the gross outliers at its start (gross_outliers, outlier_rule.hpp).
  void exclude_gross_outliers();
  double loss_scale() const { return loss_scale_; }

  const std::vector<int>& last_free() const { return last_free_; }
  std::size_t rows() const { return data_.size(); }
  double last_bounds_scale() const { return last_bounds_scale_; }

 private:
  // The stage's Ceres callbacks (identification_stage.cpp).
  class AcceptCallback;
  class BoundCallback;
  class ProgressCallback;

  /// One update of the active set of the bounds. After a solve stopped by a step onto a bound,
  /// the free parameters at a bound are held. After a solve that ran its course, the sign of the
  /// cost's gradient at a bound (its Lagrange multiplier's) decides: a parameter of `free` the
  /// cost pushes against its bound is held, one it pulls back inside is free. Returns whether
  /// any changed.
  template <class AtBound>
  bool update_active_set(const std::vector<int>& free, const AtBound& at_bound,
                         bool stopped_at_bound, std::vector<bool>* is_free);

  RobotParams<double> nominal_;
  const std::vector<CalibrationSample>& data_;
  const CalibrationOptions& options_;
  int n_;
  int count_;
  bool identify_load_;
  int block_;
  std::vector<double> values_;
  std::vector<double> nominal_values_;
  std::vector<double> half_widths_;
  std::vector<FkCache> caches_;
  std::vector<int> last_free_;
  double last_bounds_scale_ = 1.0;
  double loss_scale_ = 0;          ///< Huber scale of the current stage (whitened units; 0: none)
  std::vector<double> row_norms_;  ///< whitened residual norms at the last update_loss_scale
  std::vector<bool> gross_;        ///< rows left out of the stage (exclude_gross_outliers)
  /// Rows whose equilibrium did not follow the values (settle): left out of the solves until it
  /// does, so that one row past a fold of the current geometry does not end a solve at its start.
  std::vector<bool> lost_;
};

}  // namespace pcr::calib_internal
