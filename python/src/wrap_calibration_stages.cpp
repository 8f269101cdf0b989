// Calibration stages as lists of dicts, and the stages JSON files (pcr/calib/calibrator.hpp).
#include "calibration_bindings.hpp"
#include "pcr/calib/spatial_calibrator.hpp"

namespace pcr::python {

py::list stages_list(const std::vector<CalibrationStage>& stages) {
  py::list out;
  for (const CalibrationStage& s : stages) {
    py::dict d;
    d["name"] = s.name;
    d["free"] = s.free;
    d["bounds_scale"] = s.bounds_scale;
    out.append(d);
  }
  return out;
}

std::vector<CalibrationStage> stages_from(const py::handle& object, bool spatial) {
  if (py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__")) {
    const std::string path = input_path(object.cast<std::filesystem::path>());
    return spatial ? load_spatial_calibration_stages(path) : load_calibration_stages(path);
  }
  if (!py::isinstance<py::sequence>(object) || py::isinstance<py::bytes>(object)) {
    throw InputError(
        "stages: expected a list of dicts (name, free, bounds_scale) or a stages JSON file's "
        "path, got " +
        describe_value(object));
  }
  std::vector<CalibrationStage> stages;
  for (const py::handle& item : object) {
    const std::string where = "stages[" + std::to_string(stages.size()) + "]";
    if (!py::isinstance<py::dict>(item)) {
      throw InputError(where + ": expected a dict (name, free, bounds_scale), got " +
                       describe_value(item));
    }
    const py::dict d = py::reinterpret_borrow<py::dict>(item);
    for (const auto& kv : d) {
      const std::string key = py::str(kv.first).cast<std::string>();
      if (key != "name" && key != "free" && key != "bounds_scale") {
        throw InputError(where + "." + key + ": unknown field (expected name, free, bounds_scale)");
      }
    }
    if (!d.contains("free")) throw InputError(where + ".free: missing required field");
    CalibrationStage stage;
    try {
      stage.name = d.contains("name") ? d["name"].cast<std::string>()
                                      : "stage " + std::to_string(stages.size() + 1);
    } catch (const py::cast_error&) {
      throw InputError(where + ".name: expected a str, got " + describe_value(d["name"]));
    }
    const py::object free = d["free"];
    try {
      if (py::isinstance<py::str>(free)) throw py::cast_error();
      stage.free = free.cast<std::vector<std::string>>();
    } catch (const py::cast_error&) {
      throw InputError(where + ".free: expected a list of kinds (str), got " +
                       describe_value(free));
    }
    if (d.contains("bounds_scale")) {
      try {
        stage.bounds_scale = d["bounds_scale"].cast<double>();
      } catch (const py::cast_error&) {
        throw InputError(where + ".bounds_scale: expected a number, got " +
                         describe_value(d["bounds_scale"]));
      }
    }
    stages.push_back(stage);
  }
  if (spatial) {
    validate_spatial_stages(stages, "stages");
  } else {
    validate_stages(stages, "stages");
  }
  return stages;
}

void wrap_calibration_stages(py::module_& m) {
  m.def(
      "default_stages", [] { return stages_list(default_stages()); },
      "The paper's three calibration stages, as a list of dicts (name, free, bounds_scale).");
  m.def(
      "with_load_stage",
      [](const py::handle& stages) { return stages_list(with_load_stage(stages_from(stages))); },
      py::arg("stages"),
      "The load model: `stages` (a list of dicts or a stages JSON file's path) with the last "
      "stage also freeing 'load' (unchanged when a stage frees it already).");
  m.def(
      "load_calibration_stages",
      [](const std::filesystem::path& path) {
        return stages_list(load_calibration_stages(input_path(path)));
      },
      py::arg("path"),
      "Reads a stages JSON file (FileNotFoundError when it does not exist, ValueError naming the "
      "file, field, value).");
}

}  // namespace pcr::python
