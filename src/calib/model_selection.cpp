// Model selection between the calibration's stages and the load model (see the header).
#include "pcr/calib/model_selection.hpp"

#include <cmath>
#include <cstdio>
#include <exception>

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

}  // namespace

ModelSelection calibrate_selecting_model(const RobotDescription& nominal,
                                         const std::vector<CalibrationSample>& calibration,
                                         const std::vector<CalibrationSample>& validation,
                                         const CalibrationOptions& options) {
  ModelSelection out;
  out.stages = calibrate(nominal, calibration, options);
  out.stages_table = calibration_table(out.stages, calibration, validation);
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
  if (validation.empty()) {
    out.decision =
        "the stages' model does not explain the data, but without a validation set the load "
        "model cannot be tested: the stages' model";
    return out;
  }
  CalibrationOptions with_load = options;
  with_load.stages = with_load_stage(options.stages);
  try {
    out.load = calibrate(nominal, calibration, with_load);
    out.load_table = calibration_table(out.load, calibration, validation);
  } catch (const std::exception& e) {
    out.decision =
        std::string("the load model could not be fitted (") + e.what() + "): the stages' model";
    return out;
  }
  out.tried_load = true;

  const std::vector<double> a = validation_errors(out.stages_table, options);
  const std::vector<double> b = validation_errors(out.load_table, options);
  double sum = 0, sum_squares = 0;
  for (std::size_t j = 0; j < validation.size(); ++j) {
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

}  // namespace pcr
