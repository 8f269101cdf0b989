// pcr_calibrate: staged, bounded identification of a robot description from measured poses
// (the paper's Section 5). Thin: parse arguments, call pcr::calibrate (a planar robot) or
// pcr::calibrate_spatial (a spatial one), print and write the report.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "pcr/calib/calibration_report.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/calib/spatial_calibration_report.hpp"
#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/commands.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/parameters.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace {

using json = nlohmann::ordered_json;

struct Arguments {
  std::string robot_path, data_path, validation_path, stages_path, output_path, report_path,
      residuals_path;
  double weight = pcr::kDefaultOrientationWeight;
  bool weight_given = false;
  double robust_scale = pcr::CalibrationOptions().robust_scale;
  bool quiet = false, drop_unreachable = false, strict = false, identify_load = false,
       select_load = false;
};

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) {
    return std::filesystem::equivalent(a, b, ec);
  }
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

/// Refuses outputs that coincide with each other or with an input.
void check_outputs(const Arguments& a) {
  pcr::check_distinct_outputs({{"--output", a.output_path},
                               {"--report", a.report_path},
                               {"--residuals", a.residuals_path}});
  for (const std::string& input : {a.robot_path, a.data_path, a.validation_path, a.stages_path}) {
    if (input.empty()) continue;
    if (same_file(input, a.output_path) ||
        (!a.report_path.empty() && same_file(input, a.report_path)) ||
        (!a.residuals_path.empty() && same_file(input, a.residuals_path))) {
      throw pcr::InputError("refusing to overwrite the input " + input);
    }
  }
}

/// The report's record of the inputs.
json inputs_json(const Arguments& a, double weight) {
  return {{"robot", a.robot_path},
          {"data", a.data_path},
          {"validation", a.validation_path},
          {"stages", a.stages_path},
          {"orientation_weight_m_per_rad", weight}};
}

/// Prints the warnings; the exit status (3 with --strict and a warning).
int finish(const Arguments& a, const std::vector<std::string>& warnings) {
  std::cout.flush();
  if (!std::cout) throw std::runtime_error("<stdout>: write error");
  for (const std::string& warning : warnings)
    std::cerr << "pcr_calibrate: warning: " << warning << "\n";
  return a.strict && !warnings.empty() ? 3 : 0;
}

int calibrate_planar(const Arguments& a) {
  const pcr::RobotDescription nominal = pcr::load_robot(a.robot_path);
  const int n = nominal.params.num_limbs;
  const std::vector<pcr::CalibrationSample> calibration =
      pcr::calibration_samples(pcr::read_dataset(a.data_path, n), a.data_path);
  if (calibration.empty()) {
    throw pcr::InputError(a.data_path + ": no calibration configuration (no data rows)");
  }
  std::vector<pcr::CalibrationSample> validation;
  if (!a.validation_path.empty()) {
    validation =
        pcr::calibration_samples(pcr::read_dataset(a.validation_path, n), a.validation_path);
    if (validation.empty()) {
      throw pcr::InputError(a.validation_path + ": no validation configuration (no data rows)");
    }
  }

  pcr::CalibrationOptions options;
  if (!a.stages_path.empty()) options.stages = pcr::load_calibration_stages(a.stages_path);
  if (a.identify_load) options.stages = pcr::with_load_stage(options.stages);
  pcr::check_enough_measurements(options.stages, nominal, calibration.size(), a.data_path);
  options.orientation_weight = a.weight;
  options.drop_unreachable = a.drop_unreachable;
  options.robust_scale = a.robust_scale;
  if (!a.quiet) options.progress = [](const std::string& line) { std::cerr << line << "\n"; };

  // With --select-load the stages' model and, when tried, the load model; `result` is chosen.
  pcr::ModelSelection selection;
  if (a.select_load) {
    selection = pcr::calibrate_selecting_model(nominal, calibration, validation, options);
  } else {
    selection.stages = pcr::calibrate(nominal, calibration, options);
    selection.stages_table = pcr::calibration_table(selection.stages, calibration, validation);
  }
  const pcr::CalibrationResult& result = selection.chosen();

  pcr::OutputTransaction outputs;              // the robot and the report: all or none
  pcr::RobotDescription identified = nominal;  // uncertainty section kept from the nominal
  identified.params = result.identified;
  pcr::save_robot(identified, a.output_path);

  const pcr::CalibrationTable& table = selection.chosen_table();
  std::cout << pcr::calibration_report_text(result, table);
  if (a.select_load) std::cout << "\nModel selection: " << selection.decision << "\n";
  if (!a.report_path.empty()) {
    json report = json::parse(pcr::calibration_report_json(result, table));
    if (a.select_load) {
      report["model_selection"] = json::parse(pcr::model_selection_json(selection));
    }
    report["inputs"] = inputs_json(a, a.weight);
    pcr::write_file_atomically(a.report_path, report.dump(2) + "\n");
  }
  if (!a.residuals_path.empty()) {
    pcr::write_file_atomically(a.residuals_path,
                               pcr::residuals_csv(result, table, calibration, options));
  }
  outputs.commit();
  return finish(a, pcr::calibration_warnings(result, table));
}

/// A spatial robot's dataset (its rod count), refused when it has no row.
pcr::SpatialDataset spatial_rows(const std::string& path, int rods, const char* what) {
  pcr::SpatialDataset data = pcr::read_spatial_dataset(path, rods);
  if (data.size() == 0) {
    throw pcr::InputError(path + ": no " + what + " configuration (no data rows)");
  }
  return data;
}

int calibrate_spatial_robot(const Arguments& a) {
  const pcr::SpatialRobotDescription nominal = pcr::load_spatial_robot(a.robot_path);
  const int n = nominal.params.num_rods;
  pcr::SpatialCalibrationOptions options;
  if (!a.stages_path.empty()) options.stages = pcr::load_spatial_calibration_stages(a.stages_path);
  if (a.identify_load) options.stages = pcr::with_load_stage(options.stages);
  const pcr::SpatialDataset calibration = spatial_rows(a.data_path, n, "calibration");
  pcr::SpatialDataset validation;
  if (!a.validation_path.empty()) validation = spatial_rows(a.validation_path, n, "validation");
  if (a.weight_given) options.orientation_weight = a.weight;  // else the library's default
  options.robust_scale = a.robust_scale;
  options.drop_unreachable = a.drop_unreachable;
  if (!a.quiet) options.progress = [](const std::string& line) { std::cerr << line << "\n"; };

  // With --select-load the stages' model and, when tried, the load model; `result` is chosen.
  pcr::SpatialModelSelection selection;
  if (a.select_load) {
    selection = pcr::calibrate_selecting_model(nominal, calibration, validation, options);
  } else {
    selection.stages = pcr::calibrate_spatial(nominal, calibration, options);
    selection.stages_table =
        pcr::spatial_calibration_table(selection.stages, calibration, validation, options.fk);
  }
  const pcr::SpatialCalibrationResult& result = selection.chosen();
  const pcr::SpatialCalibrationTable& table = selection.chosen_table();

  pcr::OutputTransaction outputs;                     // the robot and the report: all or none
  pcr::SpatialRobotDescription identified = nominal;  // uncertainty section kept
  identified.params = result.identified;
  pcr::save_spatial_robot(identified, a.output_path);

  std::cout << pcr::spatial_calibration_report_text(result, table);
  if (a.select_load) std::cout << "\nModel selection: " << selection.decision << "\n";
  if (!a.report_path.empty()) {
    json report = json::parse(pcr::spatial_calibration_report_json(result, table));
    if (a.select_load) {
      report["model_selection"] = json::parse(pcr::model_selection_json(selection));
    }
    report["inputs"] = inputs_json(a, result.orientation_weight);
    pcr::write_file_atomically(a.report_path, report.dump(2) + "\n");
  }
  if (!a.residuals_path.empty()) {
    pcr::write_file_atomically(a.residuals_path,
                               pcr::spatial_residuals_csv(result, table, calibration));
  }
  outputs.commit();
  return finish(a, pcr::spatial_calibration_warnings(result, table));
}

}  // namespace

int main(int argc, char** argv) {
  pcr::protect_inputs();  // the identified robot is never written over the nominal one
  CLI::App app{
      "Identify a pcr-robot description, planar or spatial, from measured platform poses (Mauze "
      "et al. 2021, Section 5)."};
  Arguments a;
  app.add_option("--robot", a.robot_path,
                 "nominal pcr-robot description (with uncertainty), planar or spatial")
      ->required();
  app.add_option("--data", a.data_path,
                 "calibration dataset CSV (q1..qn,x,y,theta; a spatial robot's: "
                 "q1..qn,x,y,z,rx,ry,rz)")
      ->required();
  app.add_option("--validation", a.validation_path, "validation dataset CSV");
  app.add_option("--stages", a.stages_path,
                 "stages JSON: [{\"name\", \"free\": [kinds], \"bounds_scale\"}]");
  CLI::Option* weight =
      app.add_option(
             "--weight", a.weight,
             "orientation weight w of Eq. 6 (m/rad); default: the paper's noise ratio 9.13e-9 m / "
             "1.2e-6 rad for a planar robot, and for a spatial one the library's default "
             "(NaN: its residual scale, the declared position noise, over 1.2e-6 rad)")
          ->check(pcr::cli::within(pcr::CalibrationOptions::kOrientationWeight));
  app.add_option("--robust-scale", a.robust_scale,
                 "Huber loss beyond this many times the declared noise on a row's residual "
                 "(0: plain least squares)")
      ->check(pcr::cli::within(pcr::CalibrationOptions::kRobustScale))
      ->capture_default_str();
  app.add_option("--output", a.output_path, "identified pcr-robot description")
      ->required()
      ->check(CLI::Validator(
          [](std::string& value) {
            return value.empty() ? std::string("the option is empty: give a file name") : "";
          },
          "", "NONEMPTY"));
  app.add_option("--report", a.report_path, "report JSON");
  app.add_option("--residuals", a.residuals_path,
                 "per-configuration residuals CSV (row,line,q1..qn,e_p,e_theta,residual_norm,"
                 "outlier; a spatial robot's: e_angle for e_theta)");
  app.add_flag("--quiet", a.quiet, "no progress on stderr");
  app.add_flag("--drop-unreachable", a.drop_unreachable,
               "leave out (and list) the rows without an FK solution on the nominal geometry "
               "instead of refusing the dataset");
  app.add_flag("--strict", a.strict, "exit 3 when the report has a warning");
  app.add_flag("--identify-load", a.identify_load,
               "identify a constant platform load (f_x, f_y, m_z: air-bearing drag, a cable; a "
               "spatial robot's force and moment, 6 values) with the last stage; the report gives "
               "it, and pcr fk --force --moment predicts under it (a spatial robot's output file "
               "carries it as its external wrench)");
  app.add_flag("--select-load", a.select_load,
               "when the residuals exceed the declared noise, also fit the load model (as "
               "--identify-load) and keep it when the validation set supports it (a paired "
               "t-test on its rows); the report gives both fits")
      ->needs(app.get_option("--validation"))
      ->excludes(app.get_option("--identify-load"));
  CLI11_PARSE(app, argc, argv);
  a.weight_given = weight->count() > 0;

  try {
    check_outputs(a);
    return pcr::cli::is_spatial_robot(a.robot_path) ? calibrate_spatial_robot(a)
                                                    : calibrate_planar(a);
  } catch (const std::exception& e) {
    std::cerr << "pcr_calibrate: " << e.what() << "\n";
    return 1;
  }
}
