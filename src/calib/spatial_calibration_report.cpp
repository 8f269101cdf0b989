// The spatial calibration's report (see spatial_calibration_report.hpp), in the planar report's
// layout (report_internal.hpp).

#include "pcr/calib/spatial_calibration_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "pcr/calib/configuration_errors.hpp"
#include "report_internal.hpp"

namespace pcr {
namespace {

using report_internal::ordered_json;

/// Table 3's statistics of one robot on one set (rows without FK counted apart).
PoseErrorStats statistics(const SpatialPredictionErrors& errors) {
  ConfigurationErrors rows;
  rows.e_p = errors.position;
  rows.e_theta = errors.angle;
  return error_statistics(rows);
}

}  // namespace

SpatialCalibrationTable spatial_calibration_table(const SpatialCalibrationResult& result,
                                                  const SpatialDataset& calibration,
                                                  const SpatialDataset& validation,
                                                  const SolverOptions& fk) {
  SpatialCalibrationTable table;
  const SpatialRobotParams<double>& nominal = result.extrinsics_only;
  table.nominal_calibration = spatial_prediction_errors(nominal, calibration, fk);
  table.identified_calibration = spatial_prediction_errors(result.identified, calibration, fk);
  table.has_validation = validation.size() > 0;
  if (!table.has_validation) return table;
  table.nominal_validation = spatial_prediction_errors(nominal, validation, fk);
  table.identified_validation = spatial_prediction_errors(result.identified, validation, fk);
  const double calibration_mean = statistics(table.nominal_calibration).mean_p;
  const double validation_mean = statistics(table.nominal_validation).mean_p;
  if (validation_mean > 5 * calibration_mean) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "the nominal model's mean e_p on the validation set (%.3g um) is %.3g times "
                  "that on the calibration set (%.3g um): another robot's data, another unit or "
                  "another frame?",
                  validation_mean * 1e6, validation_mean / calibration_mean,
                  calibration_mean * 1e6);
    table.warnings.push_back(text);
  }
  const int failed =
      std::max(table.nominal_validation.failures, table.identified_validation.failures);
  if (failed > 0) {
    table.warnings.push_back(std::to_string(failed) + " of " + std::to_string(validation.size()) +
                             " validation configurations have no FK solution on the nominal or "
                             "the identified model (left out of the pose errors)");
  }
  return table;
}

std::vector<std::string> spatial_calibration_warnings(const SpatialCalibrationResult& result,
                                                      const SpatialCalibrationTable& table) {
  std::vector<std::string> all = result.warnings;
  all.insert(all.end(), table.warnings.begin(), table.warnings.end());
  return all;
}

std::string spatial_calibration_report_text(const SpatialCalibrationResult& result,
                                            const SpatialCalibrationTable& table) {
  using report_internal::stats_line;
  std::ostringstream out;
  out << "pose errors                        e_p (um): max      mean       min | e_angle (mrad): "
         "max      mean       min\n";
  out << stats_line("nominal model, calibration set", statistics(table.nominal_calibration));
  if (table.has_validation)
    out << stats_line("nominal model, validation set", statistics(table.nominal_validation));
  out << stats_line("identified model, calibration set", statistics(table.identified_calibration));
  if (table.has_validation) {
    out << stats_line("identified model, validation set", statistics(table.identified_validation));
  }
  out << "(nominal model: the nominal geometry with the identified extrinsics)\n\nstages:\n";
  for (const SpatialStageReport& s : result.stages) {
    out << report_internal::stage_line(s, " (whitened)") << "  " << s.unseen_directions
        << " unseen directions\n    " << s.termination << "\n";
  }
  out << "\nparameters (free: deviation from nominal, std, half-width; in the kind's display "
         "unit):\n";
  std::vector<std::string> at_bound;
  for (const SpatialParameterEstimate& p : result.parameters) {
    if (p.free) {
      const SpatialParameterKindInfo& unit = spatial_parameter_kind_info(p.id.kind);
      char std_text[48] = "not identifiable";
      if (p.identifiable) {
        std::snprintf(std_text, sizeof std_text, "std %9.3f", p.std_dev * unit.display_factor);
      }
      char buf[320];
      std::snprintf(buf, sizeof buf, "  %-14s %+10.3f %-4s  %-16s  half-width %9.3f%s\n",
                    p.name.c_str(), p.deviation * unit.display_factor, unit.display_unit, std_text,
                    p.half_width * unit.display_factor, p.at_bound ? "  AT BOUND" : "");
      out << buf;
    }
    if (p.at_bound) at_bound.push_back(p.name);
  }
  out << "parameters at a bound:";
  for (const std::string& name : at_bound) out << " " << name;
  out << (at_bound.empty() ? " none\n" : "\n");
  out << "(rank " << result.jacobian_rank << " of " << result.free_count << " free parameters)\n";
  if (!result.unidentifiable.empty()) {
    out << "\nnot identifiable from these data (combinations in half-widths, the gauge "
           "included):\n";
    for (const std::string& combination : result.unidentifiable) out << "  " << combination << "\n";
  }
  char buf[320];
  if (result.load_identified) {
    std::snprintf(buf, sizeof buf,
                  "\nplatform load (identified; in W, about the platform origin): f = (%.4g, %.4g, "
                  "%.4g) N, m = (%.4g, %.4g, %.4g) N m\n",
                  result.load_force.x(), result.load_force.y(), result.load_force.z(),
                  result.load_moment.x(), result.load_moment.y(), result.load_moment.z());
    out << buf;
  }
  std::snprintf(buf, sizeof buf,
                "\nresidual variance (whitened): %.6g\nrms on the calibration set: %.4g um, "
                "%.4g mrad (orientation weight %.4g m/rad, residual scale %.4g m)\n",
                result.residual_variance, result.rms_position * 1e6, result.rms_angle * 1e3,
                result.orientation_weight, result.residual_scale);
  out << buf;
  if (table.has_validation) {
    std::snprintf(buf, sizeof buf, "rms on the validation set: %.4g um, %.4g mrad\n",
                  table.identified_validation.rms_position * 1e6,
                  table.identified_validation.rms_angle * 1e3);
    out << buf;
  }
  for (const std::string& warning : spatial_calibration_warnings(result, table))
    out << "warning: " << warning << "\n";
  return out.str();
}

std::string spatial_calibration_report_json(const SpatialCalibrationResult& result,
                                            const SpatialCalibrationTable& table) {
  using report_internal::stats_json;
  const auto set = [](const SpatialPredictionErrors& e) {
    ordered_json out = stats_json(statistics(e), "e_angle_rad");
    out["rms_position_m"] = e.rms_position;
    out["rms_angle_rad"] = e.rms_angle;
    return out;
  };
  ordered_json errors{{"nominal_model_calibration_set", set(table.nominal_calibration)},
                      {"identified_model_calibration_set", set(table.identified_calibration)}};
  if (table.has_validation) {
    errors["nominal_model_validation_set"] = set(table.nominal_validation);
    errors["identified_model_validation_set"] = set(table.identified_validation);
  }
  ordered_json stages = ordered_json::array();
  for (const SpatialStageReport& s : result.stages) {
    stages.push_back({{"name", s.name},
                      {"free_parameters", s.free_parameters},
                      {"unseen_directions", s.unseen_directions},
                      {"initial_cost", s.initial_cost},
                      {"final_cost", s.final_cost},
                      {"iterations", s.iterations},
                      {"time_s", s.time_s},
                      {"termination", s.termination},
                      {"usable", s.usable}});
  }
  ordered_json parameters = ordered_json::array();
  std::vector<std::string> at_bound;
  for (const SpatialParameterEstimate& p : result.parameters) {
    if (p.at_bound) at_bound.push_back(p.name);
    parameters.push_back({{"name", p.name},
                          {"unit", spatial_parameter_kind_info(p.id.kind).unit},
                          {"deviation", p.deviation},
                          {"std", p.std_dev},
                          {"half_width", p.half_width},
                          {"free", p.free},
                          {"at_bound", p.at_bound},
                          {"identifiable", p.identifiable}});
  }
  ordered_json report{{"kind", "spatial"},
                      {"pose_errors", errors},
                      {"stages", stages},
                      {"parameters", parameters},
                      {"parameters_at_bound", at_bound},
                      {"jacobian_rank", result.jacobian_rank},
                      {"free_parameters", result.free_count},
                      {"unidentifiable_combinations", result.unidentifiable},
                      {"platform_load",
                       {{"identified", result.load_identified},
                        {"f_x_N", result.load_force.x()},
                        {"f_y_N", result.load_force.y()},
                        {"f_z_N", result.load_force.z()},
                        {"m_x_Nm", result.load_moment.x()},
                        {"m_y_Nm", result.load_moment.y()},
                        {"m_z_Nm", result.load_moment.z()}}},
                      {"residual_variance", result.residual_variance},
                      {"residuals_exceed_noise", result.residuals_exceed_noise},
                      {"covariance_ok", result.covariance_ok},
                      {"dropped_rows", result.dropped},
                      {"outlier_rows", result.outliers},
                      {"outlier_threshold", result.outlier_threshold},
                      {"rms_position_m", result.rms_position},
                      {"rms_angle_rad", result.rms_angle},
                      {"orientation_weight_m_per_rad", result.orientation_weight},
                      {"residual_scale_m", result.residual_scale},
                      {"time_s", result.time_s},
                      {"warnings", spatial_calibration_warnings(result, table)}};
  if (result.covariance.size() > 0) {  // the planar report's layout; null where NaN
    std::vector<std::string> names;
    for (const SpatialParameterEstimate& p : result.parameters) names.push_back(p.name);
    report["covariance"] = report_internal::covariance_json(names, result.covariance);
  }
  return report.dump(2) + "\n";  // NaN is not JSON: nlohmann writes null
}

std::string spatial_residuals_csv(const SpatialCalibrationResult& result,
                                  const SpatialCalibrationTable& table,
                                  const SpatialDataset& calibration) {
  const SpatialPredictionErrors& e = table.identified_calibration;
  return report_internal::residuals_csv_text(
      calibration.q, calibration.line_numbers, e.position, e.angle,
      report_internal::whitened_norms(e.position, e.angle, result.orientation_weight,
                                      result.residual_scale),
      result.outlier_threshold, "e_angle");
}

std::string model_selection_json(const SpatialModelSelection& selection) {
  return report_internal::model_selection_json(selection, spatial_calibration_report_json);
}

}  // namespace pcr
