// The paper's method as one call on a virtual robot: pcr.run_method and pcr.MethodResult
// (pcr/calib/method.hpp), the pipeline `pcr demo` runs.
#include "calibration_bindings.hpp"
#include "pcr/calib/method.hpp"

namespace pcr::python {
namespace {

/// A run with what its Python views need: the nominal description (the identified model as a
/// pcr.Robot, the calibration's wrapper) and the truth (its gauge-moved copy as a pcr.Robot).
struct MethodRun {
  MethodResult result;
  RobotDescription nominal;
  RobotDescription truth;

  Calibration calibration() const {
    return Calibration{result.calibration, nominal, calibration_samples(result.calibration_data)};
  }
};

/// A dataset as pcr.read_dataset returns it: (q (N, n), measured (N, 3)).
py::tuple dataset_tuple(const Dataset& data) {
  return py::make_tuple(joints_matrix(data.q, data.num_joints), poses_matrix(data.poses));
}

}  // namespace

void wrap_method(py::module_& m) {
  py::class_<MethodRun>(m, "MethodResult",
                        "What pcr.run_method found at each stage of the method (SI units).")
      .def_property_readonly(
          "sensitivity",
          [](const MethodRun& r) -> py::object {
            if (!r.result.sensitivity) return py::none();
            return sensitivity_dict(*r.result.sensitivity, r.nominal.params.num_limbs);
          },
          "Table 2 as pcr.sensitivity returns it; None when not run")
      .def_property_readonly(
          "configurations",
          [](const MethodRun& r) {
            const int n = r.nominal.params.num_limbs;
            py::dict d;
            d["calibration"] = joints_matrix(r.result.configurations.calibration, n);
            d["validation"] = joints_matrix(r.result.configurations.validation, n);
            return d;
          },
          "the sampled configurations: {'calibration': (N, n), 'validation': (M, n)} (m)")
      .def_property_readonly(
          "measured",
          [](const MethodRun& r) {
            py::dict d;
            d["calibration"] = dataset_tuple(r.result.calibration_data);
            d["validation"] = dataset_tuple(r.result.validation_data);
            return d;
          },
          "the configurations the virtual robot measured, in the order it visited them, as "
          "pcr.read_dataset returns a dataset: {'calibration': (q (N, n), measured (N, 3)), "
          "'validation': (...)}")
      .def_property_readonly(
          "unmeasured", [](const MethodRun& r) { return r.result.unmeasured; },
          "configurations of either set the virtual robot holds no stable equilibrium at")
      .def_property_readonly(
          "calibration", [](const MethodRun& r) { return r.calibration(); },
          "the chosen fit, a CalibrationResult")
      .def_property_readonly(
          "selection",
          [](const MethodRun& r) -> py::object {
            if (!r.result.selection) return py::none();
            return py::cast(*r.result.selection);
          },
          "the ModelSelection (model 'selected'), else None")
      .def_property_readonly(
          "table", [](const MethodRun& r) { return r.result.table; },
          "Table 3 of the chosen fit on both sets, a CalibrationTable")
      .def_property_readonly(
          "identified", [](const MethodRun& r) { return r.result.identified; },
          "the identified robot, a pcr.Robot")
      .def_property_readonly(
          "truth_in_gauge",
          [](const MethodRun& r) { return with_params(r.truth, r.result.truth_in_gauge); },
          "the virtual robot's truth moved along the gauge the calibration fixed (a pcr.Robot): "
          "its parameters compare one by one with calibration.parameters")
      .def_property_readonly(
          "accuracy",
          [](const MethodRun& r) {
            py::dict d;
            for (const PathAccuracy& a : r.result.accuracy) {
              d[py::make_tuple(a.path, a.model)] = a.evaluation;
            }
            return d;
          },
          "{(path, model): AccuracyEvaluation} for the paths 'square' and 'circle' and the models "
          "'nominal' and 'identified', in that order")
      .def_property_readonly(
          "map",
          [](const MethodRun& r) -> py::object {
            if (!r.result.map) return py::none();
            return workspace_map_dict(*r.result.map, r.nominal.params.num_limbs);
          },
          "the identified robot's workspace map as pcr.workspace_map returns it; None when not "
          "run")
      .def_property_readonly(
          "rotation_range",
          [](const MethodRun& r) {
            const RotationRange& rr = r.result.rotation_range;
            return py::make_tuple(rr.reachable, rr.theta_min, rr.theta_max);
          },
          "(reachable, theta_min, theta_max) at the centre of W, with the map")
      .def_property_readonly(
          "seconds",
          [](const MethodRun& r) {
            py::dict d;
            for (int k = 0; k < kMethodStages; ++k) {
              d[to_string(static_cast<MethodStage>(k))] = r.result.seconds[k];
            }
            return d;
          },
          "wall time of each stage (s; 0 when not run)");

  m.def(
      "run_method",
      [](const RobotDescription& nominal, VirtualRobot& robot,
         const std::optional<CalibrationOptions>& options, int count, int validation_count,
         const std::string& design, std::uint64_t seed, const std::string& model, int repeat,
         int square_poses, int circle_poses, bool sensitivity, bool workspace_map, int map_grid,
         const py::object& on_stage, const py::object& progress, const py::kwargs& changes) {
        CalledOptions calibration("run_method", options, progress, changes);
        MethodOptions o;
        o.calibration = calibration.options;
        o.sampling.count = count;
        o.sampling.seed = seed;
        o.sampling.design = parse_sampling_design(design);
        o.validation_count = validation_count;
        o.model = parse_calibrated_model(model);
        o.accuracy.repeat = repeat;
        o.square.num_poses = square_poses;
        o.circle.num_poses = circle_poses;
        o.sensitivity = sensitivity;
        o.workspace_map = workspace_map;
        o.map.grid = map_grid;
        if (!on_stage.is_none()) {
          o.on_stage_begin = [on_stage](MethodStage stage) {
            py::gil_scoped_acquire acquire;
            on_stage(to_string(stage));
          };
        }
        checked_options(o);
        MethodRun run;
        run.nominal = nominal;
        run.truth = robot.truth();
        {
          py::gil_scoped_release release;
          run.result = run_method(nominal, robot, o);
        }
        calibration.raise_progress_error();
        return run;
      },
      py::arg("nominal"), py::arg("robot"), py::arg("options") = py::none(), py::kw_only(),
      py::arg("count") = kDefaultCalibrationCount,
      py::arg("validation_count") = kDefaultValidationCount, py::arg("design") = "poisson-disc",
      py::arg("seed") = 1, py::arg("model") = "selected", py::arg("repeat") = 30,
      py::arg("square_poses") = SquarePath().num_poses,
      py::arg("circle_poses") = CirclePath().num_poses, py::arg("sensitivity") = true,
      py::arg("workspace_map") = true, py::arg("map_grid") = 200, py::arg("on_stage") = py::none(),
      py::arg("progress") = py::none(),
      "The paper's method after the measurement, on the VirtualRobot `robot` from the nominal "
      "description `nominal` (a pcr.Robot): sensitivity (Table 2), sampling (`count` "
      "calibration configurations by `design`, 'poisson-disc' or 'd-optimal', and "
      "`validation_count` validation ones, drawn with `seed`), the robot's measurements (each "
      "set in visiting order), the calibration (`model`: 'stages', 'load' or 'selected'), "
      "Table 3, the square and the circle with both models (ISO 9283, `repeat` cycles) and the "
      "identified robot's workspace map (`map_grid` points per side): what `pcr demo` runs. "
      "options and keyword arguments: the CalibrationOptions, as pcr.calibrate takes them. "
      "on_stage: optional callable(str) called as each stage begins ('sensitivity', 'sampling', "
      "'measurement', 'calibration', 'validation', 'accuracy', 'maps'). Returns a MethodResult. "
      "Releases the GIL.");
}

}  // namespace pcr::python
