// The spatial calibration (pcr/calib/spatial_calibrator.hpp) and its report
// (pcr/calib/spatial_calibration_report.hpp): pcr.calibrate_spatial, and
// pcr.simulate_spatial_measurements, the virtual spatial robot's measurements
// (pcr/calib/spatial_virtual_robot.hpp). Thin: the result's fields as a dict, the names from C++.
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "calibration_bindings.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/calib/spatial_calibration_report.hpp"
#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"
#include "pcr/spatial/quaternion.hpp"

namespace pcr::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The rows of a spatial dataset: q (N, n) (m) and measured (N, 6): the marker pose ^S T_M as x,
/// y, z (m) and the rotation vector rx, ry, rz (rad), the columns of a spatial dataset file.
SpatialDataset spatial_rows(const py::handle& q_in, const py::handle& measured_in, int n,
                            const char* q_name, const char* measured_name) {
  const InputArray q = input_array(q_in, n, q_name, "m");
  const InputArray m = input_array(measured_in, 6, measured_name, "m, m, m, rad, rad, rad");
  const auto rows = [](const InputArray& a) { return a.ndim() == 1 ? 1 : a.shape(0); };
  if (rows(q) != rows(m)) {
    throw std::invalid_argument(std::string(measured_name) + ": expected " +
                                std::to_string(rows(q)) + " rows (as " + q_name + "), got " +
                                std::to_string(rows(m)));
  }
  SpatialDataset data;
  data.num_joints = n;
  for (py::ssize_t r = 0; r < rows(q); ++r) {
    const double* row = m.data() + 6 * r;
    SpatialJointVector joints(n);
    for (int i = 0; i < n; ++i) joints(i) = q.data()[n * r + i];
    data.add(joints, SpatialPose<double>{Eigen::Vector3d(row[0], row[1], row[2]),
                                         quaternion_exp(Eigen::Vector3d(row[3], row[4], row[5]))});
  }
  return data;
}

/// The arguments pcr.calibrate_spatial and pcr.calibrate_selecting_model (a spatial robot) share:
/// the datasets and the options.
struct SpatialCall {
  SpatialDataset calibration, validation;
  SpatialCalibrationOptions options;
  ProgressRelay relay;

  SpatialCall(const SpatialRobotDescription& nominal, const py::object& q,
              const py::object& measured, const py::object& validation_q,
              const py::object& validation_measured, const py::object& stages,
              double orientation_weight, double residual_scale, double robust_scale,
              int max_iterations, double function_tolerance, bool compute_covariance,
              bool drop_unreachable, const py::object& progress) {
    if (validation_q.is_none() != validation_measured.is_none()) {
      throw std::invalid_argument("validation_q and validation_measured: expected both or neither");
    }
    const int n = nominal.params.num_rods;
    calibration = spatial_rows(q, measured, n, "q", "measured");
    if (!validation_q.is_none()) {
      validation =
          spatial_rows(validation_q, validation_measured, n, "validation_q", "validation_measured");
    }
    if (!stages.is_none()) options.stages = stages_from(stages, /*spatial=*/true);
    options.orientation_weight = orientation_weight;
    options.residual_scale = residual_scale;
    options.robust_scale = robust_scale;
    options.max_iterations = max_iterations;
    options.function_tolerance = function_tolerance;
    options.compute_covariance = compute_covariance;
    options.drop_unreachable = drop_unreachable;
    checked_options(options);
    options.progress = relay.callback(progress);
  }
};

/// Defines `name`: nominal, q, measured, the validation rows (`validation`: their two py::arg),
/// then pcr.calibrate_spatial's keyword arguments with their defaults; `run(nominal, call)`
/// calibrates (the GIL released) and returns the Python result.
template <class Run, class... Validation>
void def_spatial_calibration(py::module_& m, const char* name, Run run, const char* doc,
                             Validation... validation) {
  const SpatialCalibrationOptions defaults;
  m.def(
      name,
      [run](const SpatialRobotDescription& nominal, const py::object& q, const py::object& measured,
            const py::object& validation_q, const py::object& validation_measured,
            const py::object& stages, double orientation_weight, double residual_scale,
            double robust_scale, int max_iterations, double function_tolerance,
            bool compute_covariance, bool drop_unreachable, const py::object& progress) {
        SpatialCall call(nominal, q, measured, validation_q, validation_measured, stages,
                         orientation_weight, residual_scale, robust_scale, max_iterations,
                         function_tolerance, compute_covariance, drop_unreachable, progress);
        py::object out = run(nominal, call);
        call.relay.raise();
        return out;
      },
      py::arg("nominal"), py::arg("q"), py::arg("measured"), validation..., py::kw_only(),
      py::arg("stages") = py::none(), py::arg("orientation_weight") = kNaN,
      py::arg("residual_scale") = kNaN, py::arg("robust_scale") = defaults.robust_scale,
      py::arg("max_iterations") = defaults.max_iterations,
      py::arg("function_tolerance") = defaults.function_tolerance,
      py::arg("compute_covariance") = defaults.compute_covariance,
      py::arg("drop_unreachable") = defaults.drop_unreachable, py::arg("progress") = py::none(),
      doc);
}

SpatialRobotDescription with_spatial_params(const SpatialRobotDescription& nominal,
                                            const SpatialRobotParams<double>& params) {
  SpatialRobotDescription out = nominal;  // uncertainty section kept
  out.params = params;
  return out;
}

/// Marker poses as an (N, 6) array (x, y, z, rx, ry, rz), NaN where `ok` is false.
RowMatrix pose_rows(const std::vector<SpatialVirtualMeasurement>& m, bool exact) {
  RowMatrix out(static_cast<Eigen::Index>(m.size()), 6);
  for (std::size_t r = 0; r < m.size(); ++r) {
    const SpatialPose<double>& p = exact ? m[r].exact : m[r].measured;
    const Eigen::Index row = static_cast<Eigen::Index>(r);
    if (!m[r].ok) {
      out.row(row).setConstant(kNaN);
      continue;
    }
    out.block<1, 3>(row, 0) = p.position.transpose();
    out.block<1, 3>(row, 3) = quaternion_log(p.orientation).transpose();
  }
  return out;
}

}  // namespace

py::dict spatial_calibration_dict(const SpatialCalibrationResult& result,
                                  const SpatialCalibrationTable& table) {
  py::list stages;
  for (const SpatialStageReport& s : result.stages) {
    py::dict d;
    d["name"] = s.name;
    d["free_parameters"] = s.free_parameters;
    d["unseen_directions"] = s.unseen_directions;
    d["initial_cost"] = s.initial_cost;
    d["final_cost"] = s.final_cost;
    d["iterations"] = s.iterations;
    d["time_s"] = s.time_s;
    d["termination"] = s.termination;
    d["usable"] = s.usable;
    stages.append(d);
  }
  py::list parameters;
  for (const SpatialParameterEstimate& p : result.parameters) {
    py::dict d;
    d["name"] = p.name;
    d["unit"] = std::string(spatial_parameter_kind_info(p.id.kind).unit);
    d["deviation"] = p.deviation;
    d["std"] = p.std_dev;
    d["half_width"] = p.half_width;
    d["free"] = p.free;
    d["at_bound"] = p.at_bound;
    d["identifiable"] = p.identifiable;
    parameters.append(d);
  }
  py::dict out;
  out["stages"] = stages;
  out["parameters"] = parameters;
  out["orientation_weight"] = result.orientation_weight;
  out["residual_scale"] = result.residual_scale;
  out["free_count"] = result.free_count;
  out["jacobian_rank"] = result.jacobian_rank;
  out["unidentifiable"] = result.unidentifiable;
  out["residual_variance"] = result.residual_variance;
  out["residuals_exceed_noise"] = result.residuals_exceed_noise;
  out["dropped"] = result.dropped;
  out["outliers"] = result.outliers;
  out["outlier_threshold"] = result.outlier_threshold;
  out["covariance_ok"] = result.covariance_ok;
  out["covariance"] = result.covariance;  // parameters' order; NaN where not identifiable
  out["load_identified"] = result.load_identified;
  out["load_force"] = result.load_force;
  out["load_moment"] = result.load_moment;
  out["rms_position"] = result.rms_position;
  out["rms_angle"] = result.rms_angle;
  out["warnings"] = spatial_calibration_warnings(result, table);
  out["time_s"] = result.time_s;
  if (table.has_validation) {
    out["validation_rms_position"] = table.identified_validation.rms_position;
    out["validation_rms_angle"] = table.identified_validation.rms_angle;
  }
  out["report"] = spatial_calibration_report_text(result, table);
  out["report_json"] = spatial_calibration_report_json(result, table);
  return out;
}

void wrap_spatial_calibration(py::module_& m) {
  m.def(
      "default_spatial_stages", [] { return stages_list(default_spatial_stages()); },
      "The spatial calibration's default stages, a list of dicts (name, free, bounds_scale).");

  def_spatial_calibration(
      m, "calibrate_spatial",
      [](const SpatialRobotDescription& nominal, SpatialCall& call) -> py::object {
        SpatialCalibrationResult result;
        SpatialCalibrationTable table;
        {
          py::gil_scoped_release release;
          result = calibrate_spatial(nominal, call.calibration, call.options);
          table =
              spatial_calibration_table(result, call.calibration, call.validation, call.options.fk);
        }
        return py::make_tuple(with_spatial_params(nominal, result.identified),
                              spatial_calibration_dict(result, table));
      },
      "Staged, bounded identification of the spatial robot `nominal` (a SpatialRobot with an "
      "uncertainty section) from q (N, n) (m) and the measured marker poses (N, 6): x, y, z (m) "
      "and the rotation vector rx, ry, rz (rad), a spatial dataset's columns; the validation "
      "rows, when given, are scored in the report. stages: a list of dicts or a stages JSON "
      "file's path (None: default_spatial_stages()); orientation_weight and residual_scale: NaN "
      "for the library's defaults; drop_unreachable: rows without an equilibrium on the nominal "
      "robot are left out (listed in 'dropped') instead of a ValueError naming them. Returns "
      "(identified SpatialRobot, dict of the result's fields: stages, parameters (name, unit, "
      "deviation, std, half_width, free, at_bound, identifiable), unidentifiable, "
      "residual_variance, residuals_exceed_noise, outliers, outlier_threshold, dropped, "
      "rms_position, rms_angle, warnings, ..., report (text) and report_json, what "
      "pcr_calibrate writes). Releases the GIL.",
      py::arg("validation_q") = py::none(), py::arg("validation_measured") = py::none());

  bind_model_selection_class<SpatialModelSelection>(
      m, "SpatialModelSelection",
      "A spatial calibration's stages against the load model, chosen on the validation set "
      "(pcr.calibrate_selecting_model on a SpatialRobot).");
  def_spatial_calibration(
      m, "calibrate_selecting_model",
      [](const SpatialRobotDescription& nominal, SpatialCall& call) -> py::object {
        SpatialModelSelection selection;
        {
          py::gil_scoped_release release;
          selection =
              calibrate_selecting_model(nominal, call.calibration, call.validation, call.options);
        }
        py::object load = py::none();
        if (selection.tried_load) {
          load = spatial_calibration_dict(selection.load, selection.load_table);
        }
        return py::make_tuple(
            with_spatial_params(nominal, selection.chosen().identified),
            spatial_calibration_dict(selection.chosen(), selection.chosen_table()),
            spatial_calibration_dict(selection.stages, selection.stages_table), load, selection);
      },
      "pcr.calibrate_spatial with model selection, for a SpatialRobot: when the residuals exceed "
      "the noise (residuals_exceed_noise), the load model (the last stage also frees the "
      "platform's constant force and moment) is fitted too and kept when a paired one-sided "
      "t-test on the validation rows' squared whitened pose errors passes pcr.MODEL_SELECTION_T "
      "(1 %). Keywords as pcr.calibrate_spatial's. Returns (identified SpatialRobot, the chosen "
      "fit's dict, the stages' dict, the load model's dict or None, SpatialModelSelection). "
      "Releases the GIL.",
      py::arg("validation_q"), py::arg("validation_measured"));

  m.def(
      "simulate_spatial_measurements",
      [](const SpatialRobotDescription& nominal, const py::object& q_in, std::uint64_t seed,
         double truth_at_fraction, double noise_position, double noise_angle) {
        SpatialVirtualRobotOptions options;
        options.seed = seed;
        options.truth_at_fraction = truth_at_fraction;
        options.noise_position = noise_position;
        options.noise_angle = noise_angle;
        const int n = nominal.params.num_rods;
        const InputArray q = input_array(q_in, n, "q", "m");
        const Eigen::Index rows = q.ndim() == 1 ? 1 : q.shape(0);
        std::vector<SpatialJointVector> joints;
        for (Eigen::Index r = 0; r < rows; ++r) {
          SpatialJointVector row(n);
          for (int i = 0; i < n; ++i) row(i) = q.data()[n * r + i];
          joints.push_back(row);
        }
        SpatialVirtualRobot robot(nominal, options);
        std::vector<SpatialVirtualMeasurement> m;
        {
          py::gil_scoped_release release;
          m = robot.measure_dataset(joints);
        }
        py::array_t<bool> ok(rows);
        for (Eigen::Index r = 0; r < rows; ++r)
          ok.mutable_at(r) = m[static_cast<std::size_t>(r)].ok;
        py::dict out;
        out["truth"] = robot.truth();
        out["measured"] = pose_rows(m, false);
        out["exact"] = pose_rows(m, true);
        out["ok"] = ok;
        out["noise_position"] = robot.noise_position();
        return out;
      },
      py::arg("nominal"), py::arg("q"), py::kw_only(),
      py::arg("seed") = SpatialVirtualRobotOptions().seed, py::arg("truth_at_fraction") = 0.0,
      py::arg("noise_position") = kNaN,
      py::arg("noise_angle") = SpatialVirtualRobotOptions().noise_angle,
      "A virtual spatial robot drawn from `nominal`'s intervals (seeded) measured at each row of "
      "q (N, n) from home, in order: a dict of truth (SpatialRobot), measured and exact (N, 6) "
      "marker poses (x, y, z, rx, ry, rz; NaN where ok is false), ok (N,) and noise_position "
      "(m, resolved; NaN: the library's default). Releases the GIL.");
}

}  // namespace pcr::python
