#pragma once
// The calibration report (the paper's Section 5): the paper's Table 3 for the nominal and the
// identified model on the calibration and validation sets, the stages, the identified values with
// their standard deviations, the parameters at a bound and the gauge directions. One writer for
// pcr_calibrate, pcr demo and the Python bindings.

#include <string>
#include <vector>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/dataset.hpp"

namespace pcr {

struct ModelSelection;  // pcr/calib/model_selection.hpp

/// The dataset's rows as calibration samples; `source` (the file) names them in messages as
/// "source:line".
std::vector<CalibrationSample> calibration_samples(const Dataset& data,
                                                   const std::string& source = "");

/// Table 3: e_p (Eq. 8) and e_theta (Eq. 9) of the nominal model (nominal geometry with the
/// identified extrinsics, as the paper reports it) and of the identified model.
struct CalibrationTable {
  PoseErrorStats nominal_calibration, identified_calibration;
  PoseErrorStats nominal_validation, identified_validation;
  /// The per-configuration errors behind each statistic (the paper's Figures 8 and 9).
  ConfigurationErrors nominal_calibration_errors, identified_calibration_errors;
  ConfigurationErrors nominal_validation_errors, identified_validation_errors;
  bool has_validation = false;
  /// What makes the validation doubtful, in words: configurations whose nominal FK fails, a
  /// nominal error far beyond the calibration set's (another robot's or another unit's data).
  std::vector<std::string> warnings;
};

/// Evaluates both models on both sets (`validation` may be empty), and warns of a validation set
/// unlike the calibration set: the nominal model's mean e_p on it beyond 5 times that on the
/// calibration set (both sets come from one workspace, where the nominal model's errors are
/// alike), or configurations whose FK fails.
CalibrationTable calibration_table(const CalibrationResult& result,
                                   const std::vector<CalibrationSample>& calibration,
                                   const std::vector<CalibrationSample>& validation,
                                   const SolverOptions& fk = SolverOptions());

/// Every warning of a calibration: the result's, then the table's.
std::vector<std::string> calibration_warnings(const CalibrationResult& result,
                                              const CalibrationTable& table);

/// Table 3 as text (um and mrad), one line per model and set.
std::string calibration_table_text(const CalibrationTable& table);

/// The whole report as text: Table 3, stages, free parameters (value, nominal, std), parameters at
/// a bound, gauge directions, residual variance, the result's and the table's warnings.
std::string calibration_report_text(const CalibrationResult& result, const CalibrationTable& table);

/// Each row's whitened pose error, the norm of its residual of Eq. 6 in declared-noise units:
/// sqrt(e_p^2 + (w e_theta)^2) / residual_scale (rigid transforms keep e_p, so the norm follows
/// from e_p and e_theta); NaN where FK failed.
std::vector<double> whitened_error_norms(const ConfigurationErrors& errors,
                                         const CalibrationOptions& options);

/// The per-configuration residuals of the identified model on the calibration set, as CSV:
/// `row,line,q1..qn,e_p,e_theta,residual_norm,outlier` (row: 1-based in the dataset; line: in its
/// file, 0 if unknown; e_p in m, e_theta in rad, NaN where FK failed; residual_norm: the whitened
/// residual of Eq. 6 in declared-noise units; outlier: 1 beyond result.outlier_threshold).
std::string residuals_csv(const CalibrationResult& result, const CalibrationTable& table,
                          const std::vector<CalibrationSample>& calibration,
                          const CalibrationOptions& options = CalibrationOptions());

/// The whole report as JSON text (SI units, field names carry them: e_p_m, e_theta_rad, ...).
std::string calibration_report_json(const CalibrationResult& result, const CalibrationTable& table);

/// A model selection (pcr/calib/model_selection.hpp) as JSON text: the decision and its numbers
/// and, when the load model was fitted, the fit not chosen as calibration_report_json on the same
/// sets ("other_fit").
std::string model_selection_json(const ModelSelection& selection);

}  // namespace pcr
