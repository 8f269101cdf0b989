// The paper's method on a virtual spatial robot as one call: pcr.SpatialVirtualRobot
// (pcr/calib/spatial_virtual_robot.hpp), pcr.run_spatial_method and pcr.SpatialMethodResult
// (pcr/calib/spatial_method.hpp), what `pcr demo --robot FILE` runs for a spatial file. Thin: the
// reports are the library's JSON texts parsed, their names and units the C++ ones.
#include <cmath>
#include <limits>

#include "calibration_bindings.hpp"
#include "pcr/calib/spatial_method.hpp"
#include "pcr/spatial/quaternion.hpp"

namespace pcr::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A run with its nominal description (the calibration's dict needs none, the views the
/// truth): the SpatialVirtualRobot's truth at the time of the run.
struct SpatialMethodRun {
  SpatialMethodResult result;
  SpatialRobotDescription nominal;
  SpatialRobotDescription truth;
};

py::object parsed_json(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

/// A spatial dataset as (q (N, n) m, measured (N, 6): x, y, z m and the rotation vector rx, ry,
/// rz rad), the columns of a spatial dataset file and pcr.calibrate_spatial's arguments.
py::tuple spatial_dataset_tuple(const SpatialDataset& data, int n) {
  RowMatrix q(static_cast<Eigen::Index>(data.size()), n);
  RowMatrix measured(static_cast<Eigen::Index>(data.size()), 6);
  for (std::size_t r = 0; r < data.size(); ++r) {
    const Eigen::Index row = static_cast<Eigen::Index>(r);
    q.row(row) = data.q[r].head(n).transpose();
    measured.block<1, 3>(row, 0) = data.poses[r].position.transpose();
    measured.block<1, 3>(row, 3) = quaternion_log(data.poses[r].orientation).transpose();
  }
  return py::make_tuple(q, measured);
}

RowMatrix spatial_joints_matrix(const std::vector<SpatialJointVector>& rows, int n) {
  RowMatrix out(static_cast<Eigen::Index>(rows.size()), n);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    out.row(static_cast<Eigen::Index>(r)) = rows[r].head(n).transpose();
  }
  return out;
}

void bind_spatial_virtual_robot(py::module_& m) {
  py::class_<SpatialVirtualRobot>(
      m, "SpatialVirtualRobot",
      "A simulated spatial robot: a truth drawn from the nominal description inside its "
      "uncertainty intervals, measured by a noisy tracker (pcr::SpatialVirtualRobot).")
      .def(
          py::init([](const SpatialRobotDescription& nominal, std::uint64_t seed,
                      double truth_at_fraction, double noise_position, double noise_angle,
                      double payload, double misalignment_half_width, double diameter_half_width,
                      double rod_density, const std::optional<SolverOptions>& solver) {
            SpatialVirtualRobotOptions o;
            o.seed = seed;
            o.truth_at_fraction = truth_at_fraction;
            o.noise_position = noise_position;
            o.noise_angle = noise_angle;
            o.effects.payload = payload;
            o.effects.misalignment_half_width = misalignment_half_width;
            o.effects.diameter_half_width = diameter_half_width;
            o.effects.rod_density = rod_density;
            o.solver = options_or_default(solver, SpatialVirtualRobotOptions().solver);
            return SpatialVirtualRobot(nominal, checked_options(o));
          }),
          py::arg("nominal"), py::kw_only(), py::arg("seed") = SpatialVirtualRobotOptions().seed,
          py::arg("truth_at_fraction") = SpatialVirtualRobotOptions().truth_at_fraction,
          py::arg("noise_position") = kNaN,
          py::arg("noise_angle") = SpatialVirtualRobotOptions().noise_angle,
          py::arg("payload") = SpatialUnmodelledEffects().payload,
          py::arg("misalignment_half_width") = SpatialUnmodelledEffects().misalignment_half_width,
          py::arg("diameter_half_width") = SpatialUnmodelledEffects().diameter_half_width,
          py::arg("rod_density") = SpatialUnmodelledEffects().rod_density,
          py::arg("options") = py::none(),
          "Draws the truth from `nominal` (a SpatialRobot with an uncertainty section): uniform "
          "inside the intervals, or with truth_at_fraction f > 0 at +- f half-widths. "
          "noise_position (m; NaN: the paper's repeatability scaled to the robot's rod length) "
          "and noise_angle (rad) are standard deviations. Unmodelled effects: payload (kg at P's "
          "origin), misalignment_half_width (rad, U(-h, h) on each base turn component beyond "
          "the intervals), diameter_half_width (m, U(-h, h) on each rod's d on its own, beyond the "
          "one wire's draw), rod_density (kg/m^3 of the truth's rods; < 0: as described).")
      .def_property_readonly(
          "nominal", [](const SpatialVirtualRobot& v) { return v.nominal(); },
          "the nominal description (a copy)")
      .def_property_readonly(
          "truth", [](const SpatialVirtualRobot& v) { return v.truth(); },
          "the true description (a copy)")
      .def_property_readonly("noise_position", &SpatialVirtualRobot::noise_position,
                             "m, the position noise's standard deviation (resolved)")
      .def_property_readonly(
          "noise_angle", [](const SpatialVirtualRobot& v) { return v.options().noise_angle; },
          "rad, the angle noise's standard deviation")
      .def("return_home", &SpatialVirtualRobot::return_home,
           "The robot goes back home: the next measurement starts there.");
}

void bind_spatial_method_result(py::module_& m) {
  using R = SpatialMethodRun;
  py::class_<R>(m, "SpatialMethodResult",
                "What pcr.run_spatial_method found at each stage of the method (SI units).")
      .def_property_readonly(
          "sensitivity",
          [](const R& r) -> py::object {
            if (!r.result.sensitivity) return py::none();
            return parsed_json(spatial_sensitivity_json(*r.result.sensitivity));
          },
          "Table 2 as `pcr sensitivity --json` writes it for a spatial robot; None when not run")
      .def_property_readonly(
          "configurations",
          [](const R& r) {
            const int n = r.nominal.params.num_rods;
            py::dict d;
            d["calibration"] = spatial_joints_matrix(r.result.configurations.calibration, n);
            d["validation"] = spatial_joints_matrix(r.result.configurations.validation, n);
            return d;
          },
          "the sampled configurations: {'calibration': (N, n), 'validation': (M, n)} (m)")
      .def_property_readonly(
          "measured",
          [](const R& r) {
            const int n = r.nominal.params.num_rods;
            py::dict d;
            d["calibration"] = spatial_dataset_tuple(r.result.calibration_data, n);
            d["validation"] = spatial_dataset_tuple(r.result.validation_data, n);
            return d;
          },
          "the configurations the virtual robot measured, in the order it visited them: "
          "{'calibration': (q (N, n), measured (N, 6)), 'validation': (...)}, measured as x, y, "
          "z (m) and the rotation vector rx, ry, rz (rad), pcr.calibrate_spatial's arguments")
      .def_property_readonly(
          "unmeasured", [](const R& r) { return r.result.unmeasured; },
          "configurations of either set the virtual robot holds no stable equilibrium at")
      .def_property_readonly(
          "calibration",
          [](const R& r) { return spatial_calibration_dict(r.result.calibration, r.result.table); },
          "the calibration's fields as pcr.calibrate_spatial returns them (a dict; report_json "
          "holds Table 3 on both sets, pose_errors)")
      .def_property_readonly(
          "selection",
          [](const R& r) -> py::object {
            if (!r.result.selection) return py::none();
            return py::cast(*r.result.selection);
          },
          "the SpatialModelSelection (model 'selected'), else None")
      .def_property_readonly(
          "identified", [](const R& r) { return r.result.identified; },
          "the identified robot, a SpatialRobot")
      .def_property_readonly(
          "truth", [](const R& r) { return r.truth; },
          "the virtual robot's truth, a SpatialRobot (in its own frames, not the calibration's "
          "gauge)")
      .def_property_readonly(
          "centre",
          [](const R& r) {
            return py::make_tuple(Eigen::Vector3d(r.result.centre.position),
                                  Eigen::Vector3d(quaternion_log(r.result.centre.orientation)));
          },
          "the paths' centre pose ^W T_P: (position (3,) m, rotation vector (3,) rad)")
      .def_property_readonly(
          "accuracy",
          [](const R& r) {
            py::dict d;
            for (const SpatialPathAccuracy& a : r.result.accuracy) {
              const std::string name = a.path + ", " + a.model;
              d[py::make_tuple(a.path, a.model)] =
                  parsed_json(iso9283_spatial_json({{name, &a.evaluation.iso}}))["iso9283_spatial"]
                      .cast<py::list>()[0];
            }
            return d;
          },
          "{(path, model): Table 4's entry as `pcr demo` writes it in report.json (ap_p, "
          "ap_abc_abs, rp_l, rp_abc: max, mean, min; poses)} for the paths 'square', 'circle' "
          "and 'helix' and the models 'nominal' and 'identified', in that order")
      .def_property_readonly(
          "seconds",
          [](const R& r) {
            py::dict d;
            for (int k = 0; k < kMethodStages; ++k) {
              d[to_string(static_cast<MethodStage>(k))] = r.result.seconds[k];
            }
            return d;
          },
          "wall time of each stage (s; 0 when not run)");
}

}  // namespace

void wrap_spatial_method(py::module_& m) {
  bind_spatial_virtual_robot(m);
  bind_spatial_method_result(m);
  const SpatialMethodOptions defaults;
  m.def(
      "run_spatial_method",
      [](const SpatialRobotDescription& nominal, SpatialVirtualRobot& robot, int count,
         int validation_count, const std::string& design, std::uint64_t seed,
         const py::object& stages, const std::string& model, int repeat, int square_poses,
         int circle_poses, int helix_poses, bool sensitivity, const py::object& on_stage,
         const py::object& progress) {
        SpatialMethodOptions o;
        o.sampling.count = count;
        o.sampling.seed = seed;
        o.sampling.design = parse_sampling_design(design);
        o.validation_count = validation_count;
        if (!stages.is_none()) o.calibration.stages = stages_from(stages, /*spatial=*/true);
        o.model = parse_calibrated_model(model);
        o.accuracy.repeat = repeat;
        o.square.num_poses = square_poses;
        o.circle.num_poses = circle_poses;
        o.helix.num_poses = helix_poses;
        o.sensitivity = sensitivity;
        if (!on_stage.is_none()) {
          o.on_stage_begin = [on_stage](MethodStage stage) {
            py::gil_scoped_acquire acquire;
            on_stage(to_string(stage));
          };
        }
        ProgressRelay relay;
        o.calibration.progress = relay.callback(progress);
        checked_options(o);
        SpatialMethodRun run;
        run.nominal = nominal;
        run.truth = robot.truth();
        {
          py::gil_scoped_release release;
          run.result = run_spatial_method(nominal, robot, o);
        }
        relay.raise();
        return run;
      },
      py::arg("nominal"), py::arg("robot"), py::kw_only(),
      py::arg("count") = defaults.sampling.count,
      py::arg("validation_count") = defaults.validation_count, py::arg("design") = "poisson-disc",
      py::arg("seed") = defaults.sampling.seed, py::arg("stages") = py::none(),
      py::arg("model") = calibrated_model_name(defaults.model),
      py::arg("repeat") = defaults.accuracy.repeat,
      py::arg("square_poses") = defaults.square.num_poses,
      py::arg("circle_poses") = defaults.circle.num_poses,
      py::arg("helix_poses") = defaults.helix.num_poses,
      py::arg("sensitivity") = defaults.sensitivity, py::arg("on_stage") = py::none(),
      py::arg("progress") = py::none(),
      "The paper's method on the SpatialVirtualRobot `robot` from the nominal description "
      "`nominal` (a SpatialRobot with an uncertainty section): Table 2 (`sensitivity`), "
      "sampling (`count` calibration configurations by `design`, 'poisson-disc' or "
      "'d-optimal', and `validation_count` validation ones, drawn with `seed`), the robot's "
      "measurements (each set in visiting order), the staged calibration (`stages`: as "
      "pcr.calibrate_spatial takes them; None: default_spatial_stages(); `model`: 'stages', "
      "'load' (the stages with the platform load) or 'selected', as pcr.run_method's), Table 3 "
      "on both sets, "
      "and a square, a circle and a helix about the nominal robot's pose at the middle of the "
      "joint box commanded with both models (ISO 9283 in 3-D, `repeat` cycles): what `pcr demo "
      "--robot FILE` runs for a spatial file. on_stage: optional callable(str) called as each "
      "stage begins ('sensitivity', 'sampling', 'measurement', 'calibration', 'validation', "
      "'accuracy'); progress: optional callable(str) for the calibration's lines. Returns a "
      "SpatialMethodResult. Releases the GIL.");
}

}  // namespace pcr::python
