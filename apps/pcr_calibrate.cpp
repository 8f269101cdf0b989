// pcr_calibrate: staged, bounded identification of a robot description from measured poses
// (issue 3, section 5). Thin: parse arguments, call pcr::calibrate, print and write the report.

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

/// Whether the stage kind `kind` frees the flat parameter `index` (the kinds of
/// pcr::CalibrationStage: a parameter's own name, its prefix before '_' such as "A" or "camera",
/// "extrinsics" for camera and pattern, "all" for every one).
bool kind_frees(const std::string& kind, int index, int num_limbs) {
  const std::string name = pcr::parameter_kind_name(pcr::parameter_id(index, num_limbs).kind);
  const bool extrinsic = index >= pcr::kLimbParameters * num_limbs;
  return kind == "all" || kind == name || name.rfind(kind + "_", 0) == 0 ||
         (kind == "extrinsics" && extrinsic);
}

/// The free parameters of `stage`: those its kinds name with a non-zero half-width (the others
/// are held at their value), plus the platform load's for "load".
int free_parameters(const pcr::CalibrationStage& stage, const std::vector<double>& half_widths,
                    int num_limbs) {
  int count = 0;
  for (int k = 0; k < pcr::num_parameters(num_limbs); ++k) {
    bool freed = false;
    for (const std::string& kind : stage.free) freed = freed || kind_frees(kind, k, num_limbs);
    count += freed && half_widths[static_cast<std::size_t>(k)] > 0 ? 1 : 0;
  }
  for (const std::string& kind : stage.free) count += kind == "load" ? pcr::kLoadParameters : 0;
  return count;
}

/// A stage with more free parameters than measured values (3 per row) has no unique solution: the
/// least-squares problem is underdetermined whatever the data.
void check_enough_measurements(const std::vector<pcr::CalibrationStage>& stages,
                               const pcr::RobotDescription& nominal, std::size_t rows,
                               const std::string& source) {
  const int n = nominal.params.num_limbs;
  if (!nominal.uncertainty) return;  // pcr::calibrate names the missing section
  const std::vector<double> half_widths = pcr::parameter_half_widths(*nominal.uncertainty, n);
  // The stage with the most free parameters (the last, "all", for the default stages) decides.
  const pcr::CalibrationStage* largest = nullptr;
  int free = 0;
  for (const pcr::CalibrationStage& stage : stages) {
    const int count = free_parameters(stage, half_widths, n);
    if (largest == nullptr || count > free) {
      largest = &stage;
      free = count;
    }
  }
  const std::size_t measured = 3 * rows;
  if (largest == nullptr || measured >= static_cast<std::size_t>(free)) return;
  throw pcr::InputError(
      source + ": " + std::to_string(rows) +
      (rows == 1 ? " configuration gives " : " configurations give ") + std::to_string(measured) +
      " measured values (x, y, theta each), fewer than the " + std::to_string(free) +
      " free parameters of stage '" + largest->name + "': at least " +
      std::to_string((free + 2) / 3) + " configurations are needed");
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
      ->check(pcr::cli::within(0.0, 10.0, "m/rad"));
  app.add_option("--robust-scale", robust_scale,
                 "Huber loss beyond this many times the declared noise on a row's residual "
                 "(0: plain least squares)")
      ->check(pcr::cli::within(0.0, 1e6))
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
    check_enough_measurements(options.stages, nominal, calibration.size(), data_path);
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
    }
    const pcr::CalibrationResult& result = selection.chosen();

    pcr::OutputTransaction outputs;              // the robot and the report: all or none
    pcr::RobotDescription identified = nominal;  // uncertainty section kept from the nominal
    identified.params = result.identified;
    pcr::save_robot(identified, output_path);

    const pcr::CalibrationTable table = pcr::calibration_table(result, calibration, validation);
    std::cout << pcr::calibration_report_text(result, table);
    if (select_load) std::cout << "\nModel selection: " << selection.decision << "\n";
    if (!report_path.empty()) {
      json report = json::parse(pcr::calibration_report_json(result, table));
      if (select_load) {
        report["model_selection"] =
            json::parse(pcr::model_selection_json(selection, calibration, validation));
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
