#pragma once
// The spatial calibration's report (pcr/calib/spatial_calibrator.hpp): the counterpart of
// pcr/calib/calibration_report.hpp, with its layout and wording. The pose errors of the nominal
// and the identified robot on the calibration and validation sets, the stages, each parameter's
// identified deviation with its standard deviation, the combinations the data cannot identify,
// and the warnings. One writer for pcr_calibrate and the Python bindings.

#include <string>
#include <vector>

#include "pcr/calib/spatial_calibrator.hpp"

namespace pcr {

struct SpatialModelSelection;  // pcr/calib/model_selection.hpp

/// The pose errors (position e_p in m, angle e_angle in rad) of the nominal model (the nominal
/// geometry with the identified extrinsics, SpatialCalibrationResult::extrinsics_only, as the
/// planar table's) and of the identified robot on both sets, row by row
/// (spatial_prediction_errors: NaN where FK fails).
struct SpatialCalibrationTable {
  SpatialPredictionErrors nominal_calibration, identified_calibration;
  SpatialPredictionErrors nominal_validation, identified_validation;
  bool has_validation = false;
  /// What makes the validation doubtful, in words (the planar table's rules): the nominal
  /// robot's mean e_p on it beyond 5 times that on the calibration set, rows without FK.
  std::vector<std::string> warnings;
};

/// Evaluates both robots on both sets (`validation` may be empty).
SpatialCalibrationTable spatial_calibration_table(const SpatialCalibrationResult& result,
                                                  const SpatialDataset& calibration,
                                                  const SpatialDataset& validation,
                                                  const SolverOptions& fk = SolverOptions());

/// Every warning of a spatial calibration: the result's, then the table's.
std::vector<std::string> spatial_calibration_warnings(const SpatialCalibrationResult& result,
                                                      const SpatialCalibrationTable& table);

/// The whole report as text: the pose errors (um and mrad), the stages, every free parameter's
/// deviation (display unit), std and half-width, the parameters at a bound, the unidentifiable
/// combinations, the residual variance and rms errors, the warnings.
std::string spatial_calibration_report_text(const SpatialCalibrationResult& result,
                                            const SpatialCalibrationTable& table);

/// The whole report as JSON text (SI units, field names carry them: e_p_m, e_angle_rad, ...;
/// NaN is null).
std::string spatial_calibration_report_json(const SpatialCalibrationResult& result,
                                            const SpatialCalibrationTable& table);

/// The identified robot's per-row residuals on the calibration set, as CSV:
/// `row,line,q1..qn,e_p,e_angle,residual_norm,outlier` (row: 1-based in the dataset; line: in its
/// file, 0 if unknown; e_p in m, e_angle in rad, NaN where FK failed; residual_norm: the whitened
/// residual sqrt(e_p^2 + (w e_angle)^2) / residual_scale at the result's resolved weight and
/// scale; outlier: 1 beyond result.outlier_threshold, as the planar residuals_csv).
std::string spatial_residuals_csv(const SpatialCalibrationResult& result,
                                  const SpatialCalibrationTable& table,
                                  const SpatialDataset& calibration);

/// A spatial model selection (pcr/calib/model_selection.hpp) as JSON text, as the planar
/// model_selection_json: the decision and its numbers and, when the load model was fitted, the
/// fit not chosen as spatial_calibration_report_json on the same sets ("other_fit").
std::string model_selection_json(const SpatialModelSelection& selection);

}  // namespace pcr
