#pragma once
// Model selection: when the residual test says the calibrated model does not explain its data
// (CalibrationResult::residuals_exceed_noise, SpatialCalibrationResult's for a spatial robot, or a
// result the model cannot evaluate), the calibration is run again with the load model (the last
// stage also frees a constant platform load: a cable, air-bearing drag, an unknown payload), and
// the load model is kept only when the validation set, which neither fit saw, supports it. One
// home for pcr demo, pcr_calibrate --select-load and Python, planar and spatial robots alike.
//
// The test is a paired one-sided t-test on the validation rows: d_j = r_j(stages)^2 -
// r_j(load)^2, r_j the row's whitened pose error sqrt(e_p^2 + (w e_theta)^2) / residual_scale
// (Eqs. 6, 8, 9). The load model is kept when mean(d) > kModelSelectionT * sd(d) / sqrt(N): its
// extra parameters (three planar, six spatial) predict configurations they were not fitted to
// better than chance (one-sided 1 %). Rows where either model's FK fails or meets a branch
// mismatch are left out.

#include <string>
#include <vector>

#include "pcr/calib/calibration_report.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/spatial_calibration_report.hpp"
#include "pcr/calib/spatial_calibrator.hpp"

namespace pcr {

/// One-sided 1 % quantile of the normal distribution: the t statistic the load model must pass.
inline constexpr double kModelSelectionT = 2.326;

/// The two fits and the choice, for a calibration's Result and its Table 3 (Table).
template <class Result, class Table>
struct BasicModelSelection {
  Result stages;       ///< the options' stages
  Table stages_table;  ///< its Table 3 on the calibration and validation sets
  /// The stages' residuals exceed the noise (or cannot be evaluated), the stages did not free the
  /// load already, and a validation set was given: the load model was fitted.
  bool tried_load = false;
  Result load;                 ///< the stages with the load (with_load_stage), when tried_load
  Table load_table;            ///< its Table 3, when tried_load
  bool load_chosen = false;    ///< the test kept the load model
  int rows = 0;                ///< validation rows in the test
  double mean_difference = 0;  ///< mean of d_j (whitened units squared)
  double t = 0;                ///< mean(d) / (sd(d) / sqrt(rows))
  std::string decision;        ///< in words, with the numbers
  const Result& chosen() const { return load_chosen ? load : stages; }
  const Table& chosen_table() const { return load_chosen ? load_table : stages_table; }
  /// The fit not chosen (meaningful when tried_load).
  const Result& other() const { return load_chosen ? stages : load; }
  const Table& other_table() const { return load_chosen ? stages_table : load_table; }
};

struct ModelSelection : BasicModelSelection<CalibrationResult, CalibrationTable> {};
struct SpatialModelSelection
    : BasicModelSelection<SpatialCalibrationResult, SpatialCalibrationTable> {};

/// Calibrates `nominal` on `calibration` with `options` and, when its residuals exceed the noise,
/// with the load model too, choosing between them on `validation` (see above), with each fit's
/// Table 3 (calibration_table). Throws as calibrate() does.
ModelSelection calibrate_selecting_model(const RobotDescription& nominal,
                                         const std::vector<CalibrationSample>& calibration,
                                         const std::vector<CalibrationSample>& validation,
                                         const CalibrationOptions& options = CalibrationOptions());

/// The same for a spatial robot (calibrate_spatial, spatial_calibration_table; the load model's
/// last stage frees the platform wrench's six values). Throws as calibrate_spatial() does.
SpatialModelSelection calibrate_selecting_model(const SpatialRobotDescription& nominal,
                                                const SpatialDataset& calibration,
                                                const SpatialDataset& validation,
                                                const SpatialCalibrationOptions& options = {});

}  // namespace pcr
