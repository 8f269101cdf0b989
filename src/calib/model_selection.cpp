// Model selection between the calibration's stages and the load model (see the header): one rule
// for planar and spatial robots.
#include "pcr/calib/model_selection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <tuple>
#include <utility>

#include "report_internal.hpp"

namespace pcr {
namespace {

std::string fixed(const char* format, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

/// Whitened pose error of each validation row in `table`; NaN where FK fails or the row meets a
/// branch mismatch.
std::vector<double> validation_errors(const CalibrationTable& table,
                                      const CalibrationOptions& options) {
  const ConfigurationErrors& errors = table.identified_validation_errors;
  std::vector<double> out = whitened_error_norms(errors, options);
  for (std::size_t j = 0; j < out.size(); ++j) {
    if (errors.branch_mismatch[j]) out[j] = std::nan("");
  }
  return out;
}

/// The same for a spatial robot (NaN where FK fails), at the stages' resolved weight and scale.
std::vector<double> validation_errors(const SpatialCalibrationTable& table,
                                      const SpatialCalibrationResult& stages) {
  const SpatialPredictionErrors& errors = table.identified_validation;
  return report_internal::whitened_norms(errors.position, errors.angle, stages.orientation_weight,
                                         stages.residual_scale);
}

/// The rule of the header, for either kind of robot: `fit(options)` calibrates and tabulates
/// (Result, Table), `errors(table)` gives each validation row's whitened error.
template <class Selection, class Options, class Fit, class Errors>
Selection select_model(const Options& options, std::size_t validation_rows, const Fit& fit,
                       const Errors& errors) {
  Selection out;
  std::tie(out.stages, out.stages_table) = fit(options);
  // A fit the model cannot evaluate at its result (residual variance NaN) has not shown that it
  // explains the data either.
  const bool unexplained =
      out.stages.residuals_exceed_noise || !std::isfinite(out.stages.residual_variance);
  if (!unexplained) {
    out.decision = "the residuals are consistent with the declared noise: the stages' model";
    return out;
  }
  if (frees_load(options.stages)) {
    out.decision = "the stages free the load already: their model";
    return out;
  }
  if (validation_rows == 0) {
    out.decision =
        "the stages' model does not explain the data, but without a validation set the load "
        "model cannot be tested: the stages' model";
    return out;
  }
  Options with_load = options;
  with_load.stages = with_load_stage(options.stages);
  try {
    std::tie(out.load, out.load_table) = fit(with_load);
  } catch (const std::exception& e) {
    out.decision =
        std::string("the load model could not be fitted (") + e.what() + "): the stages' model";
    return out;
  }
  out.tried_load = true;

  const std::vector<double> a = errors(out.stages_table, out.stages);
  const std::vector<double> b = errors(out.load_table, out.stages);
  double sum = 0, sum_squares = 0;
  for (std::size_t j = 0; j < a.size() && j < b.size(); ++j) {
    if (!std::isfinite(a[j]) || !std::isfinite(b[j])) continue;
    const double d = a[j] * a[j] - b[j] * b[j];
    sum += d;
    sum_squares += d * d;
    ++out.rows;
  }
  if (out.rows < 2) {
    out.decision = "fewer than two validation rows both models predict: the stages' model";
    return out;
  }
  const double n = out.rows;
  out.mean_difference = sum / n;
  const double variance =
      std::max(0.0, (sum_squares - n * out.mean_difference * out.mean_difference) / (n - 1));
  const double standard_error = std::sqrt(variance / n);
  out.t = standard_error > 0 ? out.mean_difference / standard_error
                             : (out.mean_difference > 0 ? INFINITY : 0.0);
  out.load_chosen = out.t > kModelSelectionT;
  out.decision = std::string(out.stages.residuals_exceed_noise
                                 ? "the residuals exceed the noise"
                                 : "the stages' model cannot be evaluated at its result") +
                 "; on " + std::to_string(out.rows) +
                 " validation rows the load model lowers the squared whitened error by " +
                 fixed("%.4g", out.mean_difference) +
                 " per row (paired t = " + fixed("%.3g", out.t) + ", threshold " +
                 fixed("%.3g", kModelSelectionT) +
                 " one-sided 1 %): " + (out.load_chosen ? "the load model" : "the stages' model");
  return out;
}

}  // namespace

ModelSelection calibrate_selecting_model(const RobotDescription& nominal,
                                         const std::vector<CalibrationSample>& calibration,
                                         const std::vector<CalibrationSample>& validation,
                                         const CalibrationOptions& options) {
  return select_model<ModelSelection>(
      options, validation.size(),
      [&](const CalibrationOptions& o) {
        CalibrationResult result = calibrate(nominal, calibration, o);
        CalibrationTable table = calibration_table(result, calibration, validation);
        return std::make_pair(std::move(result), std::move(table));
      },
      [&](const CalibrationTable& table, const CalibrationResult&) {
        return validation_errors(table, options);
      });
}

SpatialModelSelection calibrate_selecting_model(const SpatialRobotDescription& nominal,
                                                const SpatialDataset& calibration,
                                                const SpatialDataset& validation,
                                                const SpatialCalibrationOptions& options) {
  return select_model<SpatialModelSelection>(
      options, validation.size(),
      [&](const SpatialCalibrationOptions& o) {
        SpatialCalibrationResult result = calibrate_spatial(nominal, calibration, o);
        SpatialCalibrationTable table =
            spatial_calibration_table(result, calibration, validation, o.fk);
        return std::make_pair(std::move(result), std::move(table));
      },
      [](const SpatialCalibrationTable& table, const SpatialCalibrationResult& stages) {
        return validation_errors(table, stages);
      });
}

}  // namespace pcr
