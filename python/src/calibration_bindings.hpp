#pragma once
// Shared by the bindings of pcr::calib (wrap_calibration.cpp and the files of its topics): joints
// and poses as row-major arrays, and the checked conversions of datasets and stages.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/calib/workspace_map.hpp"

namespace pcr {
struct SpatialCalibrationResult;
struct SpatialCalibrationTable;
}  // namespace pcr

namespace pcr::python {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using InputMatrix = Eigen::Ref<const RowMatrix>;

// ---- calibrations (wrap_calibration.cpp) ------------------------------------------------------

/// pcr.CalibrationResult: the C++ result, with the nominal description (identified and
/// extrinsics_only as pcr.Robot) and the calibration set (Table 3 of a report given no table).
struct Calibration {
  CalibrationResult result;
  RobotDescription nominal;
  std::vector<CalibrationSample> calibration;
};

/// A Python `progress` callable as a calibration's progress option. A Python exception in it must
/// not unwind through Ceres: it is kept, later lines are dropped, and raise() raises it once the
/// calibration has returned.
struct ProgressRelay {
  std::shared_ptr<std::unique_ptr<py::error_already_set>> error =
      std::make_shared<std::unique_ptr<py::error_already_set>>();

  /// The option (empty for None).
  std::function<void(const std::string&)> callback(const py::object& progress) const {
    if (progress.is_none()) return {};
    return [progress, error = error](const std::string& line) {
      py::gil_scoped_acquire acquire;
      if (*error) return;
      try {
        progress(line);
      } catch (py::error_already_set& e) {
        *error = std::make_unique<py::error_already_set>(std::move(e));
      }
    };
  }
  void raise() {
    if (*error) throw std::move(**error);
  }
};

/// The CalibrationOptions of a call: `options` (None: the defaults) with the keyword changes made
/// through the properties' setters (checked alike, no default written here), and `progress`.
/// A Python exception in `progress` must not unwind through Ceres: it is kept, later lines are
/// dropped, and raise_progress_error() raises it once the calibration has returned.
struct CalledOptions {
  CalibrationOptions options;
  ProgressRelay relay;

  CalledOptions(const char* function, const std::optional<CalibrationOptions>& given,
                const py::object& progress, const py::kwargs& changes) {
    py::object settings = py::cast(given ? *given : CalibrationOptions());
    const py::object type = py::type::of(settings);
    for (const auto& item : changes) {
      const std::string name = py::str(item.first).cast<std::string>();
      if (!is_read_write_property(type, name)) {
        throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" +
                             name + "' (not a CalibrationOptions field)");
      }
      py::setattr(settings, item.first, item.second);
    }
    options = settings.cast<CalibrationOptions>();
    options.progress = relay.callback(progress);
  }

  void raise_progress_error() { relay.raise(); }
};

/// pcr.ModelSelection and pcr.SpatialModelSelection (pcr/calib/model_selection.hpp): the decision
/// and its numbers, one set of properties for both.
template <class Selection>
void bind_model_selection_class(py::module_& m, const char* name, const char* doc) {
  py::class_<Selection>(m, name, doc)
      .def_property_readonly(
          "load_chosen", [](const Selection& s) { return s.load_chosen; },
          "the validation test kept the load model")
      .def_property_readonly(
          "tried_load", [](const Selection& s) { return s.tried_load; },
          "the residuals exceeded the noise and the load model was fitted")
      .def_property_readonly(
          "rows", [](const Selection& s) { return s.rows; }, "validation rows in the test")
      .def_property_readonly(
          "mean_difference", [](const Selection& s) { return s.mean_difference; },
          "mean over the rows of the stages' squared whitened error less the load model's")
      .def_property_readonly(
          "t", [](const Selection& s) { return s.t; },
          "the paired t statistic (the load model is kept above pcr.MODEL_SELECTION_T)")
      .def_property_readonly(
          "decision", [](const Selection& s) { return s.decision; },
          "the choice in words, with the numbers");
}

/// `nominal` with `params` (its name and uncertainty section kept).
RobotDescription with_params(const RobotDescription& nominal, const RobotParams<double>& params);

// ---- results as dicts ------------------------------------------------------------------------

/// The report `pcr sensitivity --json` writes, with the configurations as an (N, n) array and the
/// text table (wrap_sensitivity.cpp).
py::dict sensitivity_dict(const SensitivityReport& report, int n);

/// A spatial calibration's fields as pcr.calibrate_spatial returns them: stages, parameters,
/// rms errors, warnings, the text and JSON reports (wrap_spatial_calibration.cpp).
py::dict spatial_calibration_dict(const SpatialCalibrationResult& result,
                                  const SpatialCalibrationTable& table);

/// A workspace map as arrays over its grid (wrap_workspace_map.cpp).
py::dict workspace_map_dict(const WorkspaceMap& map, int n);

// ---- datasets (defined in wrap_dataset.cpp) ---------------------------------------------------

/// Poses as an (N, 3) array (m, m, rad).
RowMatrix poses_matrix(const std::vector<Pose2<double>>& poses);

/// Joint configurations as an (N, n) array (m).
RowMatrix joints_matrix(const std::vector<JointVector>& rows, int n);

/// (N, n) joints, checked against the robot's limb count and for finite values.
std::vector<JointVector> joint_rows(const InputMatrix& q, int n, const char* what);

/// The rows of a dataset: q (N, n) and measured (N, 3), named in messages as `q_name` and
/// `measured_name`.
std::vector<CalibrationSample> samples(const InputMatrix& q, const InputMatrix& measured, int n,
                                       const char* q_name = "q",
                                       const char* measured_name = "measured");

// ---- stages (defined in wrap_calibration_stages.cpp) ------------------------------------------

/// Stages as a list of dicts (name, free, bounds_scale).
py::list stages_list(const std::vector<CalibrationStage>& stages);

/// A stages argument as a list of dicts (name, free, bounds_scale; default_stages() gives them)
/// or a stages JSON file's path (a str or an os.PathLike). ValueError naming the stage and the
/// field otherwise. `spatial`: the kinds are a spatial robot's (validate_spatial_stages).
std::vector<CalibrationStage> stages_from(const py::handle& object, bool spatial = false);

}  // namespace pcr::python
