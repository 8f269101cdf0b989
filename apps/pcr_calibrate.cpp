// pcr_calibrate: staged, bounded identification of a robot description from measured poses
// (issue 3, section 5). Thin: parse arguments, call pcr::calibrate, print and write the report.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/robot_io.hpp"

namespace {

using nlohmann::json;

std::vector<pcr::CalibrationSample> to_samples(const pcr::Dataset& data) {
  std::vector<pcr::CalibrationSample> out;
  for (std::size_t j = 0; j < data.size(); ++j) out.push_back({data.q[j], data.poses[j]});
  return out;
}

/// {"stages": [{"name": ..., "free": [...], "bounds_scale": 1}]} or the bare list.
std::vector<pcr::CalibrationStage> load_stages(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw pcr::InputError(path + ": cannot open the stages file");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw pcr::InputError(path + ": invalid JSON: " + e.what());
  }
  if (j.is_object() && j.contains("stages")) j = j["stages"];
  if (!j.is_array()) throw pcr::InputError(path + ": expected a list of stages");
  std::vector<pcr::CalibrationStage> stages;
  for (std::size_t s = 0; s < j.size(); ++s) {
    const std::string where = path + ": stages[" + std::to_string(s) + "]";
    const json& e = j[s];
    if (!e.is_object()) throw pcr::InputError(where + ": expected an object");
    for (auto it = e.begin(); it != e.end(); ++it) {
      if (it.key() != "name" && it.key() != "free" && it.key() != "bounds_scale") {
        throw pcr::InputError(where + ": unknown field \"" + it.key() + "\"");
      }
    }
    pcr::CalibrationStage stage;
    stage.name = e.value("name", "stage " + std::to_string(s + 1));
    if (!e.contains("free") || !e["free"].is_array()) {
      throw pcr::InputError(where + ".free: expected a list of parameter kinds");
    }
    for (const json& k : e["free"]) {
      if (!k.is_string()) throw pcr::InputError(where + ".free: expected strings, got " + k.dump());
      stage.free.push_back(k.get<std::string>());
    }
    if (e.contains("bounds_scale")) {
      if (!e["bounds_scale"].is_number()) {
        throw pcr::InputError(where + ".bounds_scale: expected a number, got " +
                              e["bounds_scale"].dump());
      }
      stage.bounds_scale = e["bounds_scale"].get<double>();
    }
    stages.push_back(stage);
  }
  pcr::validate_stages(stages, path);
  return stages;
}

json stats_json(const pcr::PoseErrorStats& s) {
  return json{{"e_p_m", {{"max", s.max_p}, {"mean", s.mean_p}, {"min", s.min_p}}},
              {"e_theta_rad", {{"max", s.max_theta}, {"mean", s.mean_theta}, {"min", s.min_theta}}},
              {"configurations", s.count},
              {"failed", s.failed}};
}

std::string stats_line(const std::string& label, const pcr::PoseErrorStats& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%-40s %9.3f %9.3f %9.3f | %9.4f %9.4f %9.4f\n", label.c_str(),
                s.max_p * 1e6, s.mean_p * 1e6, s.min_p * 1e6, s.max_theta * 1e3,
                s.mean_theta * 1e3, s.min_theta * 1e3);
  return buf;
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) {
    return std::filesystem::equivalent(a, b, ec);
  }
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Identify a pcr-robot description from measured platform poses (Mauze et al. 2021, "
               "Section 5)."};
  std::string robot_path, data_path, validation_path, stages_path, output_path, report_path;
  double weight = pcr::kDefaultOrientationWeight;
  bool quiet = false;
  app.add_option("--robot", robot_path, "nominal pcr-robot description (with uncertainty)")
      ->required();
  app.add_option("--data", data_path, "calibration dataset CSV (q1..qn,x,y,theta)")->required();
  app.add_option("--validation", validation_path, "validation dataset CSV");
  app.add_option("--stages", stages_path,
                 "stages JSON: [{\"name\", \"free\": [kinds], \"bounds_scale\"}]");
  app.add_option("--weight", weight, "orientation weight w of Eq. 6 (m/rad)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--output", output_path, "identified pcr-robot description")->required();
  app.add_option("--report", report_path, "report JSON");
  app.add_flag("--quiet", quiet, "no progress on stderr");
  CLI11_PARSE(app, argc, argv);

  try {
    for (const std::string& input : {robot_path, data_path, validation_path, stages_path}) {
      if (input.empty()) continue;
      if (same_file(input, output_path) || (!report_path.empty() && same_file(input, report_path))) {
        throw pcr::InputError("refusing to overwrite the input " + input);
      }
    }
    const pcr::RobotDescription nominal = pcr::load_robot(robot_path);
    const int n = nominal.params.num_limbs;
    const std::vector<pcr::CalibrationSample> calibration =
        to_samples(pcr::read_dataset(data_path, n));
    std::vector<pcr::CalibrationSample> validation;
    if (!validation_path.empty()) validation = to_samples(pcr::read_dataset(validation_path, n));

    pcr::CalibrationOptions options;
    if (!stages_path.empty()) options.stages = load_stages(stages_path);
    options.orientation_weight = weight;
    if (!quiet) options.progress = [](const std::string& line) { std::cerr << line << "\n"; };

    const pcr::CalibrationResult result = pcr::calibrate(nominal, calibration, options);

    pcr::RobotDescription identified = nominal;  // uncertainty section kept from the nominal
    identified.params = result.identified;
    pcr::save_robot(identified, output_path);

    const pcr::PoseErrorStats nominal_cal = pcr::pose_errors(result.extrinsics_only, calibration);
    const pcr::PoseErrorStats identified_cal = pcr::pose_errors(result.identified, calibration);
    pcr::PoseErrorStats identified_val;
    if (!validation.empty()) identified_val = pcr::pose_errors(result.identified, validation);

    std::ostringstream out;
    out << "Table 3 (e_p in um, e_theta in mrad)          max      mean       min |      max"
           "      mean       min\n";
    out << stats_line("nominal model (extrinsics), calibration", nominal_cal);
    out << stats_line("identified model, calibration", identified_cal);
    if (!validation.empty()) out << stats_line("identified model, validation", identified_val);
    out << "\nstages:\n";
    json stages = json::array();
    for (const pcr::StageReport& s : result.stages) {
      char buf[256];
      std::snprintf(buf, sizeof buf, "  %-12s %2zu free  cost %.4e -> %.4e m^2  %3d iterations  %.2f s\n",
                    s.name.c_str(), s.free_parameters.size(), s.initial_cost, s.final_cost,
                    s.iterations, s.time_s);
      out << buf;
      stages.push_back({{"name", s.name},
                        {"free_parameters", s.free_parameters},
                        {"initial_cost_m2", s.initial_cost},
                        {"final_cost_m2", s.final_cost},
                        {"iterations", s.iterations},
                        {"time_s", s.time_s},
                        {"termination", s.termination},
                        {"usable", s.usable}});
    }
    out << "\nparameters (value, std; limb-0 gauge):\n";
    json parameters = json::array();
    std::vector<std::string> at_bound;
    for (const pcr::ParameterEstimate& p : result.parameters) {
      if (p.free) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "  %-14s %+.9e  nominal %+.9e  std %.3e%s%s\n",
                      p.name.c_str(), p.value, p.nominal, p.std_dev,
                      p.gauge_reference ? "  (gauge reference)" : "", p.at_bound ? "  AT BOUND" : "");
        out << buf;
      }
      if (p.at_bound) at_bound.push_back(p.name);
      parameters.push_back({{"name", p.name},
                            {"nominal", p.nominal},
                            {"value", p.value},
                            {"std", p.std_dev},
                            {"half_width", p.half_width},
                            {"free", p.free},
                            {"gauge_reference", p.gauge_reference},
                            {"at_bound", p.at_bound}});
    }
    out << "parameters at a bound:";
    for (const std::string& name : at_bound) out << " " << name;
    out << (at_bound.empty() ? " none\n" : "\n");
    out << "\ngauge directions (rank " << result.jacobian_rank << " of " << result.free_count
        << " free parameters):\n";
    json gauge = json::array();
    for (const pcr::GaugeDirection& g : result.gauge) {
      out << "  " << g.name << " [" << g.combination << "]: "
          << (g.present ? "present, |J g| / (s_max |g|) = " + std::to_string(g.relative_gain)
                        : std::string("not free"))
          << "\n";
      gauge.push_back({{"name", g.name},
                       {"combination", g.combination},
                       {"present", g.present},
                       {"relative_gain", g.relative_gain}});
    }
    out << "residual variance (whitened): " << result.residual_variance << "\n";
    std::cout << out.str();

    if (!report_path.empty()) {
      json report{{"robot", robot_path},
                  {"data", data_path},
                  {"validation", validation_path},
                  {"orientation_weight_m_per_rad", weight},
                  {"table3",
                   {{"nominal_model_calibration_set", stats_json(nominal_cal)},
                    {"identified_model_calibration_set", stats_json(identified_cal)}}},
                  {"stages", stages},
                  {"parameters", parameters},
                  {"parameters_at_bound", at_bound},
                  {"gauge_directions", gauge},
                  {"jacobian_rank", result.jacobian_rank},
                  {"free_parameters", result.free_count},
                  {"residual_variance", result.residual_variance},
                  {"covariance_ok", result.covariance_ok},
                  {"gauge_fix",
                   "limb 0 defines the frames: A_0, alpha_0, B_0, beta_0 and d_0 keep their nominal "
                   "values; std are relative to them"}};
      if (!validation.empty()) {
        report["table3"]["identified_model_validation_set"] = stats_json(identified_val);
      }
      pcr::write_file_atomically(report_path, report.dump(2) + "\n");
    }
  } catch (const std::exception& e) {
    std::cerr << "pcr_calibrate: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
