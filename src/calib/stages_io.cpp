// The calibration stages file (docs/formats.md): {"stages": [...]} or the bare list.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"

namespace pcr {
namespace {

using nlohmann::json;

/// The file's stages, their kinds not checked: the planar and the spatial readers check them.
std::vector<CalibrationStage> read_stages(const std::string& path) {
  const std::string text = read_input_file(path, kMaxJsonFileBytes, "a calibration stages file");
  check_json_nesting(text, path);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(path + ": invalid JSON: " + e.what());
  }
  if (j.is_object() && j.contains("stages")) j = j["stages"];
  if (!j.is_array()) throw InputError(path + ": expected a list of stages");
  std::vector<CalibrationStage> stages;
  for (std::size_t s = 0; s < j.size(); ++s) {
    const std::string where = path + ": stages[" + std::to_string(s) + "]";
    const json& e = j[s];
    if (!e.is_object()) throw InputError(where + ": expected an object");
    for (auto it = e.begin(); it != e.end(); ++it) {
      if (it.key() != "name" && it.key() != "free" && it.key() != "bounds_scale") {
        throw InputError(where + ": unknown field \"" + it.key() + "\"");
      }
    }
    CalibrationStage stage;
    stage.name = "stage " + std::to_string(s + 1);
    if (e.contains("name")) {
      if (!e["name"].is_string()) throw InputError(where + ".name: expected a string");
      stage.name = e["name"].get<std::string>();
    }
    if (!e.contains("free") || !e["free"].is_array()) {
      throw InputError(where + ".free: expected a list of parameter kinds");
    }
    for (const json& k : e["free"]) {
      if (!k.is_string())
        throw InputError(where + ".free: expected strings, got " + excerpt(k.dump()));
      stage.free.push_back(k.get<std::string>());
    }
    if (e.contains("bounds_scale")) {
      if (!e["bounds_scale"].is_number()) {
        throw InputError(where + ".bounds_scale: expected a number, got " +
                         excerpt(e["bounds_scale"].dump()));
      }
      stage.bounds_scale = e["bounds_scale"].get<double>();
    }
    stages.push_back(stage);
  }
  return stages;
}

}  // namespace

std::vector<CalibrationStage> load_calibration_stages(const std::string& path) {
  std::vector<CalibrationStage> stages = read_stages(path);
  validate_stages(stages, path);
  return stages;
}

std::vector<CalibrationStage> load_spatial_calibration_stages(const std::string& path) {
  std::vector<CalibrationStage> stages = read_stages(path);
  validate_spatial_stages(stages, path);
  return stages;
}

}  // namespace pcr
