#pragma once
// The pieces the planar and the spatial calibration reports share (calibration_report.cpp,
// spatial_calibration_report.cpp), not part of the API: one wording and one layout for both.

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pcr/calib/configuration_errors.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/csv_io.hpp"

namespace pcr::report_internal {

using nlohmann::ordered_json;

/// Table 3's statistics as JSON; `angle_key`: "e_theta_rad" (planar) or "e_angle_rad" (spatial).
ordered_json stats_json(const PoseErrorStats& s, const char* angle_key = "e_theta_rad");

/// The identified parameters' covariance as JSON: {"parameters": names, "units": "SI, flat
/// order", "matrix": rows} (NaN entries are written null; read_parameter_covariance,
/// pcr/calib/predicted_accuracy.hpp, reads it).
ordered_json covariance_json(const std::vector<std::string>& names, const Eigen::MatrixXd& matrix);

/// A model selection as JSON text (model_selection_json): the decision and its numbers and, when
/// the load model was fitted, the fit not chosen, `report(result, table)` ("other_fit").
template <class Result, class Table, class Report>
std::string model_selection_json(const BasicModelSelection<Result, Table>& selection,
                                 const Report& report) {
  ordered_json out{{"decision", selection.decision},
                   {"load_tried", selection.tried_load},
                   {"load_chosen", selection.load_chosen},
                   {"validation_rows", selection.rows},
                   {"mean_difference", selection.mean_difference},
                   {"t", selection.t},
                   {"threshold_t", kModelSelectionT}};
  if (selection.tried_load) {
    out["other_fit"] = ordered_json::parse(report(selection.other(), selection.other_table()));
  }
  return out.dump();
}

/// One line of Table 3 as text (um and mrad).
std::string stats_line(const char* label, const PoseErrorStats& s);

/// Each row's whitened pose error, the norm of its residual of Eq. 6 in declared-noise units:
/// sqrt(e_p^2 + (w e_angle)^2) / scale (NaN where FK failed).
std::vector<double> whitened_norms(const std::vector<double>& e_p,
                                   const std::vector<double>& e_angle, double weight, double scale);

/// A stage's line of the text report: name, free parameters, cost (in `cost_unit`), iterations,
/// time.
template <class Stage>
std::string stage_line(const Stage& s, const char* cost_unit) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "  %-12s %2zu free  cost %.4e -> %.4e%s  %3d iterations  %.2f s",
                s.name.c_str(), s.free_parameters.size(), s.initial_cost, s.final_cost, cost_unit,
                s.iterations, s.time_s);
  return buf;
}

/// A residuals CSV: `row,line,q1..qn,e_p,<angle_column>,residual_norm,outlier` (row: 1-based in
/// the dataset; line: in its file, 0 if unknown; outlier: 1 beyond `threshold` when it is > 0).
template <class Joints>
std::string residuals_csv_text(const std::vector<Joints>& q, const std::vector<int>& lines,
                               const std::vector<double>& e_p, const std::vector<double>& e_angle,
                               const std::vector<double>& norms, double threshold,
                               const char* angle_column) {
  const int n = q.empty() ? 0 : static_cast<int>(q.front().size());
  std::string out = "row,line";
  for (int i = 1; i <= n; ++i) out += ",q" + std::to_string(i);
  out += std::string(",e_p,") + angle_column + ",residual_norm,outlier\n";
  for (std::size_t j = 0; j < q.size() && j < e_p.size(); ++j) {
    const double norm = norms[j];
    out += std::to_string(j + 1) + "," + std::to_string(j < lines.size() ? lines[j] : 0);
    for (int i = 0; i < n; ++i) out += "," + format_double(q[j][i]);
    out += "," + format_double(e_p[j]) + "," + format_double(e_angle[j]) + "," +
           format_double(norm) + "," + (threshold > 0 && norm > threshold ? "1" : "0") + "\n";
  }
  return out;
}

}  // namespace pcr::report_internal
