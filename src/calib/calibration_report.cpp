// The calibration report: Table 3, stages, identified values, gauge (see calibration_report.hpp).

#include "pcr/calib/calibration_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "pcr/calib/model_selection.hpp"
#include "pcr/csv_io.hpp"
#include "report_internal.hpp"

namespace pcr {
namespace report_internal {

ordered_json stats_json(const PoseErrorStats& s, const char* angle_key) {
  return ordered_json{
      {"e_p_m", {{"max", s.max_p}, {"mean", s.mean_p}, {"min", s.min_p}}},
      {angle_key, {{"max", s.max_theta}, {"mean", s.mean_theta}, {"min", s.min_theta}}},
      {"configurations", s.count},
      {"failed", s.failed},
      {"branch_mismatches", s.branch_mismatches}};
}

ordered_json covariance_json(const std::vector<std::string>& names, const Eigen::MatrixXd& matrix) {
  ordered_json rows = ordered_json::array();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    ordered_json row = ordered_json::array();
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) row.push_back(matrix(r, c));
    rows.push_back(row);
  }
  return {{"parameters", names}, {"units", "SI, flat order"}, {"matrix", rows}};
}

std::string stats_line(const char* label, const PoseErrorStats& s) {
  std::string left_out;
  if (s.failed) left_out += ", " + std::to_string(s.failed) + " FK failures";
  if (s.branch_mismatches) {
    left_out += ", " + std::to_string(s.branch_mismatches) + " on another equilibrium";
  }
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "%-34s %9.4f %9.4f %9.4f | %9.5f %9.5f %9.5f  (%d configurations%s)\n", label,
                s.max_p * 1e6, s.mean_p * 1e6, s.min_p * 1e6, s.max_theta * 1e3, s.mean_theta * 1e3,
                s.min_theta * 1e3, s.count, left_out.c_str());
  return buf;
}

std::vector<double> whitened_norms(const std::vector<double>& e_p,
                                   const std::vector<double>& e_angle, double weight,
                                   double scale) {
  std::vector<double> out(e_p.size());
  for (std::size_t j = 0; j < out.size(); ++j) {
    const double weighted = weight * e_angle[j];
    out[j] = std::sqrt(e_p[j] * e_p[j] + weighted * weighted) / scale;
  }
  return out;
}

}  // namespace report_internal

using report_internal::ordered_json;
using report_internal::stats_json;
using report_internal::stats_line;

std::vector<CalibrationSample> calibration_samples(const Dataset& data, const std::string& source) {
  std::vector<CalibrationSample> out;
  out.reserve(data.size());
  for (std::size_t j = 0; j < data.size(); ++j) {
    std::string origin;
    if (!source.empty() && j < data.line_numbers.size())
      origin = source + ":" + std::to_string(data.line_numbers[j]);
    const int line = j < data.line_numbers.size() ? data.line_numbers[j] : 0;
    out.push_back({data.q[j], data.poses[j], origin, line});
  }
  return out;
}

CalibrationTable calibration_table(const CalibrationResult& result,
                                   const std::vector<CalibrationSample>& calibration,
                                   const std::vector<CalibrationSample>& validation,
                                   const SolverOptions& fk) {
  CalibrationTable table;
  // The identified model predicts under the identified platform load (zero unless identified);
  // the nominal model carries none.
  const auto evaluate = [&](const RobotParams<double>& model, const PlatformLoad<double>& load,
                            const std::vector<CalibrationSample>& data, ConfigurationErrors& errors,
                            PoseErrorStats& stats) {
    errors = configuration_errors(model, data, fk, load);
    stats = error_statistics(errors);
  };
  const PlatformLoad<double> none;
  evaluate(result.extrinsics_only, none, calibration, table.nominal_calibration_errors,
           table.nominal_calibration);
  evaluate(result.identified, result.load, calibration, table.identified_calibration_errors,
           table.identified_calibration);
  table.has_validation = !validation.empty();
  if (table.has_validation) {
    evaluate(result.extrinsics_only, none, validation, table.nominal_validation_errors,
             table.nominal_validation);
    evaluate(result.identified, result.load, validation, table.identified_validation_errors,
             table.identified_validation);
    const double calibration_mean = table.nominal_calibration.mean_p;
    const double validation_mean = table.nominal_validation.mean_p;
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
    const int mismatched = std::max(table.nominal_validation.branch_mismatches,
                                    table.identified_validation.branch_mismatches);
    if (mismatched > 0) {
      table.warnings.push_back(
          std::to_string(mismatched) + " of " + std::to_string(validation.size()) +
          " validation configurations were measured next to another equilibrium of the model at "
          "the same joints than the one it predicts there (a branch mismatch: the robot came to "
          "them along another path; left out of Table 3, see the per-configuration errors)");
    }
    const int failed =
        std::max(table.nominal_validation.failed, table.identified_validation.failed);
    if (failed > 0) {
      table.warnings.push_back(std::to_string(failed) + " of " + std::to_string(validation.size()) +
                               " validation configurations have no FK solution on the nominal or "
                               "the identified model (left out of Table 3)");
    }
  }
  return table;
}

std::vector<std::string> calibration_warnings(const CalibrationResult& result,
                                              const CalibrationTable& table) {
  std::vector<std::string> all = result.warnings;
  all.insert(all.end(), table.warnings.begin(), table.warnings.end());
  return all;
}

std::string calibration_table_text(const CalibrationTable& table) {
  std::string out =
      "Table 3                            e_p (um): max      mean       min | e_theta (mrad): max"
      "      mean       min\n";
  out += stats_line("nominal model, calibration set", table.nominal_calibration);
  if (table.has_validation)
    out += stats_line("nominal model, validation set", table.nominal_validation);
  out += stats_line("identified model, calibration set", table.identified_calibration);
  if (table.has_validation) {
    out += stats_line("identified model, validation set", table.identified_validation);
  }
  out += "(nominal model: the nominal geometry with identified extrinsics, as in the paper)\n";
  return out;
}

std::string calibration_report_text(const CalibrationResult& result,
                                    const CalibrationTable& table) {
  std::ostringstream out;
  out << calibration_table_text(table) << "\nstages:\n";
  for (const StageReport& s : result.stages) out << report_internal::stage_line(s, " m^2") << "\n";
  out << "\nparameters (value, nominal, deviation from nominal, std; limb-0 gauge; SI, the "
         "deviation in um, mrad or MPa; box: the deviation in half-widths where the bounds "
         "apply, the stages' frame before the gauge fix, +-1 at a bound):\n";
  std::vector<std::string> at_bound;
  for (const ParameterEstimate& p : result.parameters) {
    if (p.free) {
      const ParameterKindInfo& unit = parameter_kind_info(p.kind);
      char buf[320];
      char std_text[32];
      char box_text[32] = "";
      std::snprintf(std_text, sizeof std_text, "%.3e", p.std_dev);
      if (std::isfinite(p.box_deviation)) {
        std::snprintf(box_text, sizeof box_text, "  box %+.3f", p.box_deviation);
      }
      std::snprintf(buf, sizeof buf, "  %-14s %+.9e  nominal %+.9e  %+9.3f %-4s  std %s%s%s%s\n",
                    p.name.c_str(), p.value, p.nominal, (p.value - p.nominal) * unit.display_factor,
                    unit.display_unit, p.identifiable ? std_text : "not identifiable",
                    p.gauge_reference ? "  (gauge reference)" : "", box_text,
                    p.at_bound ? "  AT BOUND" : "");
      out << buf;
    }
    if (p.at_bound) at_bound.push_back(p.name);
  }
  out << "parameters at a bound:";
  for (const std::string& name : at_bound) out << " " << name;
  out << (at_bound.empty() ? " none\n" : "\n");
  out << "\ngauge directions (rank " << result.jacobian_rank << " of " << result.free_count
      << " free parameters):\n";
  for (const GaugeDirection& g : result.gauge) {
    out << "  " << g.name << " [" << g.combination << "]: ";
    if (g.present) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "present, |J g| / (s_max |g|) = %.2e", g.relative_gain);
      out << buf << "\n";
    } else if (g.free) {
      char buf[96];
      std::snprintf(buf, sizeof buf,
                    "not a gauge under the platform load, |J g| / (s_max |g|) = %.2e",
                    g.relative_gain);
      out << buf << "\n";
    } else {
      out << "not free\n";
    }
  }
  out << "residual variance (whitened): " << result.residual_variance << "\n";
  if (result.load_identified) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "platform load (identified; in W, about the platform origin): f = (%.4g, %.4g) "
                  "N, m = %.4g N m\n",
                  result.load.force.x(), result.load.force.y(), result.load.moment);
    out << buf;
  }
  if (!result.dropped.empty()) {
    out << "\nrows left out (no FK solution on the geometry that tried them):\n";
    for (const std::string& row : result.dropped) out << "  " << row << "\n";
  }
  if (!result.unidentifiable.empty()) {
    out << "\nnot identifiable from these data (combinations in half-widths, beyond the gauge):\n";
    for (const std::string& combination : result.unidentifiable) out << "  " << combination << "\n";
  }
  for (const std::string& warning : calibration_warnings(result, table))
    out << "warning: " << warning << "\n";
  return out.str();
}

std::vector<double> whitened_error_norms(const ConfigurationErrors& errors,
                                         const CalibrationOptions& options) {
  return report_internal::whitened_norms(errors.e_p, errors.e_theta, options.orientation_weight,
                                         options.residual_scale);
}

std::string residuals_csv(const CalibrationResult& result, const CalibrationTable& table,
                          const std::vector<CalibrationSample>& calibration,
                          const CalibrationOptions& options) {
  const ConfigurationErrors& errors = table.identified_calibration_errors;
  std::vector<JointVector> q;
  std::vector<int> lines;
  for (const CalibrationSample& sample : calibration) {
    q.push_back(sample.q);
    lines.push_back(sample.line);
  }
  return report_internal::residuals_csv_text(q, lines, errors.e_p, errors.e_theta,
                                             whitened_error_norms(errors, options),
                                             result.outlier_threshold, "e_theta");
}

std::string calibration_report_json(const CalibrationResult& result,
                                    const CalibrationTable& table) {
  ordered_json table3{
      {"nominal_model_calibration_set", stats_json(table.nominal_calibration)},
      {"identified_model_calibration_set", stats_json(table.identified_calibration)}};
  if (table.has_validation) {
    table3["nominal_model_validation_set"] = stats_json(table.nominal_validation);
    table3["identified_model_validation_set"] = stats_json(table.identified_validation);
  }
  ordered_json stages = ordered_json::array();
  for (const StageReport& s : result.stages) {
    stages.push_back({{"name", s.name},
                      {"free_parameters", s.free_parameters},
                      {"initial_cost_m2", s.initial_cost},
                      {"final_cost_m2", s.final_cost},
                      {"iterations", s.iterations},
                      {"time_s", s.time_s},
                      {"termination", s.termination},
                      {"usable", s.usable}});
  }
  ordered_json parameters = ordered_json::array();
  std::vector<std::string> at_bound;
  for (const ParameterEstimate& p : result.parameters) {
    if (p.at_bound) at_bound.push_back(p.name);
    parameters.push_back({{"name", p.name},
                          {"nominal", p.nominal},
                          {"value", p.value},
                          {"std", p.std_dev},
                          {"half_width", p.half_width},
                          {"free", p.free},
                          {"gauge_reference", p.gauge_reference},
                          {"box_deviation", p.box_deviation},
                          {"at_bound", p.at_bound},
                          {"identifiable", p.identifiable}});
  }
  ordered_json gauge = ordered_json::array();
  for (const GaugeDirection& g : result.gauge) {
    gauge.push_back({{"name", g.name},
                     {"combination", g.combination},
                     {"free", g.free},
                     {"present", g.present},
                     {"relative_gain", g.relative_gain}});
  }
  ordered_json report{
      {"table3", table3},
      {"stages", stages},
      {"parameters", parameters},
      {"parameters_at_bound", at_bound},
      {"gauge_directions", gauge},
      {"gauge_fix",
       "limb 0 defines the frames: of A_0, alpha_0, B_0, beta_0 and d_0, those whose gauge "
       "direction is present keep their nominal values (gauge_reference); std are relative to "
       "them"},
      {"platform_load",
       {{"identified", result.load_identified},
        {"f_x_N", result.load.force.x()},
        {"f_y_N", result.load.force.y()},
        {"m_z_Nm", result.load.moment}}},
      {"jacobian_rank", result.jacobian_rank},
      {"free_parameters", result.free_count},
      {"residual_variance", result.residual_variance},
      {"covariance_ok", result.covariance_ok},
      {"dropped_rows", result.dropped},
      {"outlier_rows", result.outliers},
      {"unidentifiable_combinations", result.unidentifiable},
      {"warnings", calibration_warnings(result, table)}};
  if (result.covariance.size() > 0) {
    // Row by row in `parameters` order; null (NaN) for the parameters that are not identifiable,
    // zero for the held ones.
    std::vector<std::string> names;
    for (const ParameterEstimate& p : result.parameters) names.push_back(p.name);
    report["covariance"] = report_internal::covariance_json(names, result.covariance);
  }
  // NaN (a failed covariance, an empty set) is not JSON: nlohmann writes null.
  return report.dump(2) + "\n";
}

std::string model_selection_json(const ModelSelection& selection) {
  return report_internal::model_selection_json(selection, calibration_report_json);
}

}  // namespace pcr
