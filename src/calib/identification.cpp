// The residuals the stages see: Identification's values, equilibria, Jacobian, Huber scale.

#include "identification.hpp"

#include <ceres/ceres.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr {
namespace calib_internal {
namespace {

/// The scale of the load parameters (their "half-widths"; they carry no bound): for each
/// component, the load that moves the nominal platform (in Eq. 6's metric, root mean square over
/// the rows) as far as a clamp's position tolerance (the mean half-width of A and B) does, so that
/// its columns weigh like the geometry's. The platform is stiff (inextensible rods, and at home
/// nearly rigid): a millinewton moves it by about 0.1 um on the paper's robot, where EI / L^2 is a
/// millinewton. Where no row solves: the load that bends a rod by the tolerance.
std::array<double, kLoadParameters> load_scales(const RobotParams<double>& robot,
                                                const std::vector<double>& half_widths,
                                                const std::vector<CalibrationSample>& rows,
                                                const CalibrationOptions& options) {
  double tolerance = 0;
  int terms = 0;
  for (std::size_t k = 0; k < half_widths.size(); ++k) {
    const ParameterKind kind = parameter_id(static_cast<int>(k), robot.num_limbs).kind;
    const bool position = kind == ParameterKind::kAx || kind == ParameterKind::kAy ||
                          kind == ParameterKind::kBx || kind == ParameterKind::kBy;
    if (position && half_widths[k] > 0) {
      tolerance += half_widths[k];
      ++terms;
    }
  }
  const ShootingScale scale = shooting_scale(robot);
  tolerance = terms > 0 ? tolerance / terms : 1e-3 * scale.length;
  const double bend = tolerance / scale.length;
  std::array<double, kLoadParameters> out = {bend * scale.force, bend * scale.force,
                                             bend * scale.moment()};
  double square[kLoadParameters] = {0, 0, 0};
  int solved = 0;
  ForwardSequence sequence(robot, options.fk);
  for (const CalibrationSample& row : rows) {
    const ForwardSolution& solution = sequence.solve(row.q);
    double dpose[3 * kMaxParameters], dload[3 * kLoadParameters];
    if (!is_equilibrium(solution.summary) ||
        !platform_pose_jacobian(robot, PlatformLoad<double>(), solution, options.fk, dpose,
                                dload)) {
      continue;
    }
    for (int j = 0; j < kLoadParameters; ++j) {  // per N or N m
      const double w = options.orientation_weight * dload[6 + j];
      square[j] += dload[j] * dload[j] + dload[3 + j] * dload[3 + j] + w * w;
    }
    ++solved;
  }
  for (int j = 0; j < kLoadParameters && solved > 0; ++j) {
    const double moved = std::sqrt(square[j] / solved);
    if (moved > 0 && std::isfinite(moved)) out[static_cast<std::size_t>(j)] = tolerance / moved;
  }
  return out;
}

}  // namespace

Identification::Identification(const RobotDescription& nominal,
                               const std::vector<CalibrationSample>& data,
                               const CalibrationOptions& options)
    : nominal_(nominal.params),
      data_(data),
      options_(options),
      n_(nominal.params.num_limbs),
      count_(num_parameters(n_)),
      identify_load_(frees_load(options.stages)),
      block_(count_ + (identify_load_ ? kLoadParameters : 0)),
      values_(static_cast<std::size_t>(block_)),
      nominal_values_(static_cast<std::size_t>(block_), 0.0),
      caches_(data.size()),
      gross_(data.size(), false),
      lost_(data.size(), false) {
  half_widths_ = parameter_half_widths(*nominal.uncertainty, n_);
  if (identify_load_) {
    const auto scales = load_scales(nominal_, half_widths_, data_, options);
    half_widths_.insert(half_widths_.end(), scales.begin(), scales.end());
  }
  get_parameters(nominal_, nominal_values_.data());  // the nominal load is zero
  values_ = nominal_values_;
}

void Identification::move(const GaugeMotion& m) {
  const PlatformLoad<double> moved = move_load_along_gauge(load(), m.G, m.H, m.stiffness_scale);
  set_robot(move_along_gauge(robot(), m.G, m.H, m.stiffness_scale));
  if (identify_load_) {
    values_[static_cast<std::size_t>(count_)] = moved.force.x();
    values_[static_cast<std::size_t>(count_) + 1] = moved.force.y();
    values_[static_cast<std::size_t>(count_) + 2] = moved.moment;
  }
  for (FkCache& c : caches_) {
    if (!c.valid || !c.anchored) continue;
    c.anchor = move_equilibrium_along_gauge(c.anchor, m.G, m.H, m.stiffness_scale);
    std::copy(values_.begin(), values_.end(), c.anchor_parameters.begin());
  }
  settle();
}

void Identification::start_on_measured_branches() {
  const RobotParams<double> robot_now = robot();
  std::vector<double> nearest(data_.size(), HUGE_VAL);
  for (const auto& [options, mode] : dataset_readings(options_.fk)) {
    const std::vector<ForwardSolution> reached =
        solve_rows(robot_now, data_, options, mode, load());
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if (!is_equilibrium(reached[j].summary)) continue;
      const Pose2<double> measured =
          robot_now.extrinsics.platform_from_measurement(data_[j].measured);
      const double distance = pose_distance(reached[j].pose, measured, options_.orientation_weight);
      if (!(distance < nearest[j])) continue;  // a tie keeps the equilibrium connected to home
      nearest[j] = distance;
      FkCache& c = caches_[j];
      c.solution = reached[j];
      c.valid = true;
      std::copy(values_.begin(), values_.end(), c.parameters.begin());
      c.accept();
    }
  }
}

std::vector<std::string> Identification::move_to_measured_equilibria() {
  settle();
  std::vector<const ForwardSolution*> predicted(data_.size(), nullptr);
  for (std::size_t j = 0; j < data_.size(); ++j) {
    if (caches_[j].valid && !lost_[j]) predicted[j] = &caches_[j].solution;
  }
  const std::vector<std::optional<ForwardSolution>> measured =
      equilibria_measured_instead(robot(), data_, predicted, options_.fk, load(), std::nullopt);
  std::vector<std::string> moved;
  for (std::size_t j = 0; j < data_.size(); ++j) {
    if (!measured[j]) continue;
    caches_[j].solution = *measured[j];
    caches_[j].accept();
    moved.push_back(origin(j));
  }
  return moved;
}

void Identification::settle() {
  const double* values = values_.data();
  double residuals[3];
  for (std::size_t j = 0; j < data_.size(); ++j) {
    if (!caches_[j].valid) continue;
    const std::unique_ptr<ceres::CostFunction> cost(PoseMeasurementError::Create(
        nominal_, data_[j].q, data_[j].measured, options_.orientation_weight,
        options_.residual_scale, &caches_[j], options_.fk, options_.derivatives, identify_load_));
    cost->Evaluate(&values, residuals, nullptr);
  }
  accept_evaluated();
  for (std::size_t j = 0; j < data_.size(); ++j) {
    lost_[j] = caches_[j].valid &&
               !std::equal(values_.begin(), values_.end(), caches_[j].parameters.begin());
  }
}

std::vector<std::size_t> Identification::evaluated_rows() const {
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < data_.size(); ++j) {
    if (!lost_[j]) out.push_back(j);
  }
  return out;
}

std::vector<std::string> Identification::lost_rows() const {
  std::vector<std::string> out;
  for (std::size_t j = 0; j < data_.size(); ++j) {
    if (lost_[j]) out.push_back(origin(j));
  }
  return out;
}

void Identification::accept_evaluated() {
  for (FkCache& c : caches_) {
    if (c.valid && std::equal(values_.begin(), values_.end(), c.parameters.begin())) c.accept();
  }
}

bool Identification::load_free(const std::vector<bool>& is_free) const {
  for (int k = count_; k < block_; ++k) {
    if (is_free[static_cast<std::size_t>(k)]) return true;
  }
  return false;
}

void Identification::add_residuals(ceres::Problem& problem, bool robust) {
  ceres::LossFunction* loss =
      robust && loss_scale_ > 0 ? new ceres::HuberLoss(loss_scale_) : nullptr;
  for (std::size_t j = 0; j < data_.size(); ++j) {
    if ((robust && gross_[j]) || lost_[j]) continue;
    problem.AddResidualBlock(PoseMeasurementError::Create(
                                 nominal_, data_[j].q, data_[j].measured,
                                 options_.orientation_weight, options_.residual_scale, &caches_[j],
                                 options_.fk, options_.derivatives, identify_load_),
                             loss, values_.data());
  }
}

double Identification::smallest_singular_value(const std::vector<int>& columns) {
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  if (columns.empty() || !jacobian(&J, &r) || !J.allFinite()) return kNaN;
  Eigen::MatrixXd Js(J.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) {
    Js.col(static_cast<Eigen::Index>(c)) =
        J.col(columns[c]) * half_widths_[static_cast<std::size_t>(columns[c])];
  }
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(Js).singularValues();
  if (sv.size() < static_cast<Eigen::Index>(columns.size())) return 0.0;  // fewer rows
  return sv(sv.size() - 1) / sv(0);
}

double Identification::cost() {
  ceres::Problem problem;
  add_residuals(problem);
  double c = 0;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, nullptr, nullptr, nullptr);
  return c;
}

bool Identification::jacobian(Eigen::MatrixXd* J, Eigen::VectorXd* r) {
  ceres::Problem problem;
  add_residuals(problem, false);  // raw residuals: the loss is the stages' business
  double c = 0;
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, &residuals, nullptr, &crs)) {
    return false;
  }
  J->setZero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int p = crs.rows[static_cast<std::size_t>(row)];
         p < crs.rows[static_cast<std::size_t>(row) + 1]; ++p) {
      (*J)(row, crs.cols[static_cast<std::size_t>(p)]) = crs.values[static_cast<std::size_t>(p)];
    }
  }
  *r = Eigen::Map<Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
  return true;
}

void Identification::update_loss_scale() {
  loss_scale_ = options_.robust_scale;
  row_norms_.clear();
  if (!(loss_scale_ > 0)) return;
  ceres::Problem problem;
  add_residuals(problem, false);
  double c = 0;
  std::vector<double> r;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, &r, nullptr, nullptr)) return;
  // Per data row; a lost row has no residual (NaN), and exclude_gross_outliers leaves it out.
  const std::vector<std::size_t> in = evaluated_rows();
  if (r.size() != 3 * in.size() || in.empty()) return;
  row_norms_.assign(data_.size(), kNaN);
  for (std::size_t b = 0; b < in.size(); ++b) {
    row_norms_[in[b]] =
        std::sqrt(r[3 * b] * r[3 * b] + r[3 * b + 1] * r[3 * b + 1] + r[3 * b + 2] * r[3 * b + 2]);
  }
  loss_scale_ = huber_scale(options_.robust_scale, row_norms_, 3);
}

void Identification::exclude_gross_outliers() {
  std::fill(gross_.begin(), gross_.end(), false);
  if (row_norms_.size() == gross_.size())
    gross_ = gross_outliers(row_norms_, loss_scale_, options_.robust_scale, 3);
}

}  // namespace calib_internal

bool measurement_jacobian(const RobotParams<double>& robot, const JointVector& q,
                          double orientation_weight, double residual_scale,
                          Eigen::MatrixXd* jacobian, const SolverOptions& fk) {
  const int count = num_parameters(robot.num_limbs);
  FkCache cache;
  const std::unique_ptr<ceres::CostFunction> cost(
      PoseMeasurementError::Create(robot, q, Pose2<double>(), orientation_weight, residual_scale,
                                   &cache, fk, DerivativeMode::kImplicit));
  std::vector<double> values(static_cast<std::size_t>(count));
  get_parameters(robot, values.data());
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> J(3, count);
  double residuals[3];
  const double* parameters[] = {values.data()};
  double* jacobians[] = {J.data()};
  if (!cost->Evaluate(parameters, residuals, jacobians)) return false;
  *jacobian = J;
  return true;
}

}  // namespace pcr
