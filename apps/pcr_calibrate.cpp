// pcr_calibrate: staged, bounded identification of a robot description from measured poses
// (the paper's Section 5). Thin: parse arguments, call pcr::calibrate, print and write the report.

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
#include "pcr/commands.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/parameters.hpp"
#include "pcr/robot_io.hpp"

namespace {

using json = nlohmann::ordered_json;

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) {
    return std::filesystem::equivalent(a, b, ec);
  }
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

}  // namespace

int main(int argc, char** argv) {
  pcr::protect_inputs();  // the identified robot is never written over the nominal one
  CLI::App app{
      "Identify a pcr-robot description from measured platform poses (Mauze et al. 2021, "
      "Section 5)."};
  std::string robot_path, data_path, validation_path, stages_path, output_path, report_path,
      residuals_path;
  double weight = pcr::kDefaultOrientationWeight;
  double robust_scale = pcr::CalibrationOptions().robust_scale;
  bool quiet = false, drop_unreachable = false, strict = false, identify_load = false,
       select_load = false;
  app.add_option("--robot", robot_path, "nominal pcr-robot description (with uncertainty)")
      ->required();
  app.add_option("--data", data_path, "calibration dataset CSV (q1..qn,x,y,theta)")->required();
  app.add_option("--validation", validation_path, "validation dataset CSV");
  app.add_option("--stages", stages_path,
                 "stages JSON: [{\"name\", \"free\": [kinds], \"bounds_scale\"}]");
  app.add_option("--weight", weight, "orientation weight w of Eq. 6 (m/rad)")
      ->check(pcr::cli::within(pcr::CalibrationOptions::kOrientationWeight));
  app.add_option("--robust-scale", robust_scale,
                 "Huber loss beyond this many times the declared noise on a row's residual "
                 "(0: plain least squares)")
      ->check(pcr::cli::within(pcr::CalibrationOptions::kRobustScale))
      ->capture_default_str();
  app.add_option("--output", output_path, "identified pcr-robot description")
      ->required()
      ->check(CLI::Validator(
          [](std::string& value) {
            return value.empty() ? std::string("the option is empty: give a file name") : "";
          },
          "", "NONEMPTY"));
  app.add_option("--report", report_path, "report JSON");
  app.add_option("--residuals", residuals_path,
                 "per-configuration residuals CSV (row,line,q1..qn,e_p,e_theta,residual_norm,"
                 "outlier)");
  app.add_flag("--quiet", quiet, "no progress on stderr");
  app.add_flag("--drop-unreachable", drop_unreachable,
               "leave out (and list) the rows without an FK solution on the nominal geometry "
               "instead of refusing the dataset");
  app.add_flag("--strict", strict, "exit 3 when the report has a warning");
  app.add_flag("--identify-load", identify_load,
               "identify a constant platform load (f_x, f_y, m_z: air-bearing drag, a cable) with "
               "the last stage; the report gives it, and pcr fk --force --moment predicts under "
               "it");
  app.add_flag("--select-load", select_load,
               "when the residuals exceed the declared noise, also fit the load model (as "
               "--identify-load) and keep it when the validation set supports it (a paired "
               "t-test on its rows); the report gives both fits")
      ->needs(app.get_option("--validation"))
      ->excludes(app.get_option("--identify-load"));
  CLI11_PARSE(app, argc, argv);

  try {
    pcr::check_distinct_outputs(
        {{"--output", output_path}, {"--report", report_path}, {"--residuals", residuals_path}});
    for (const std::string& input : {robot_path, data_path, validation_path, stages_path}) {
      if (input.empty()) continue;
      if (same_file(input, output_path) ||
          (!report_path.empty() && same_file(input, report_path)) ||
          (!residuals_path.empty() && same_file(input, residuals_path))) {
        throw pcr::InputError("refusing to overwrite the input " + input);
      }
    }
    const pcr::RobotDescription nominal = pcr::load_robot(robot_path);
    const int n = nominal.params.num_limbs;
    const std::vector<pcr::CalibrationSample> calibration =
        pcr::calibration_samples(pcr::read_dataset(data_path, n), data_path);
    if (calibration.empty()) {
      throw pcr::InputError(data_path + ": no calibration configuration (no data rows)");
    }
    std::vector<pcr::CalibrationSample> validation;
    if (!validation_path.empty()) {
      validation = pcr::calibration_samples(pcr::read_dataset(validation_path, n), validation_path);
      if (validation.empty()) {
        throw pcr::InputError(validation_path + ": no validation configuration (no data rows)");
      }
    }

    pcr::CalibrationOptions options;
    if (!stages_path.empty()) options.stages = pcr::load_calibration_stages(stages_path);
    if (identify_load) options.stages = pcr::with_load_stage(options.stages);
    pcr::check_enough_measurements(options.stages, nominal, calibration.size(), data_path);
    options.orientation_weight = weight;
    options.drop_unreachable = drop_unreachable;
    options.robust_scale = robust_scale;
    if (!quiet) options.progress = [](const std::string& line) { std::cerr << line << "\n"; };

    // With --select-load the stages' model and, when tried, the load model; `result` is chosen.
    pcr::ModelSelection selection;
    if (select_load) {
      selection = pcr::calibrate_selecting_model(nominal, calibration, validation, options);
    } else {
      selection.stages = pcr::calibrate(nominal, calibration, options);
      selection.stages_table = pcr::calibration_table(selection.stages, calibration, validation);
    }
    const pcr::CalibrationResult& result = selection.chosen();

    pcr::OutputTransaction outputs;              // the robot and the report: all or none
    pcr::RobotDescription identified = nominal;  // uncertainty section kept from the nominal
    identified.params = result.identified;
    pcr::save_robot(identified, output_path);

    const pcr::CalibrationTable& table = selection.chosen_table();
    std::cout << pcr::calibration_report_text(result, table);
    if (select_load) std::cout << "\nModel selection: " << selection.decision << "\n";
    if (!report_path.empty()) {
      json report = json::parse(pcr::calibration_report_json(result, table));
      if (select_load) {
        report["model_selection"] = json::parse(pcr::model_selection_json(selection));
      }
      report["inputs"] = {{"robot", robot_path},
                          {"data", data_path},
                          {"validation", validation_path},
                          {"stages", stages_path},
                          {"orientation_weight_m_per_rad", weight}};
      pcr::write_file_atomically(report_path, report.dump(2) + "\n");
    }
    if (!residuals_path.empty()) {
      pcr::write_file_atomically(residuals_path,
                                 pcr::residuals_csv(result, table, calibration, options));
    }
    outputs.commit();
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("<stdout>: write error");
    const std::vector<std::string> warnings = pcr::calibration_warnings(result, table);
    for (const std::string& warning : warnings)
      std::cerr << "pcr_calibrate: warning: " << warning << "\n";
    if (strict && !warnings.empty()) return 3;
  } catch (const std::exception& e) {
    std::cerr << "pcr_calibrate: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
