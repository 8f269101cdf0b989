// Calibration (pcr::calib): sensitivity table, virtual robot, datasets, Poisson-disc sampling and
// D-optimal design, staged identification. Reports come back as dicts, arrays as NumPy arrays;
// the identification's options, result and Table 3 as classes, the result's report through the
// C++ JSON writer (one serialiser for pcr_calibrate, pcr demo and Python).
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "bindings.hpp"
#include "pcr/calib/calibration_report.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/calib/predicted_accuracy.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/calib/virtual_robot.hpp"
#include "pcr/calib/workspace_map.hpp"
#include "pcr/parameters.hpp"

namespace pcr::python {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using InputMatrix = Eigen::Ref<const RowMatrix>;

RowMatrix joints_matrix(const std::vector<JointVector>& rows, int n) {
  RowMatrix out(static_cast<Eigen::Index>(rows.size()), n);
  for (std::size_t r = 0; r < rows.size(); ++r)
    out.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
  return out;
}

SamplingOptions sampling_options(int count, std::uint64_t seed, double min_distance,
                                 const std::optional<Eigen::VectorXd>& box_min,
                                 const std::optional<Eigen::VectorXd>& box_max, double strain_limit,
                                 int attempts, const py::object& force, double moment) {
  SamplingOptions o;
  o.count = count;
  o.seed = seed;
  o.min_distance = min_distance;
  if (box_min) o.box_min = JointVector(*box_min);
  if (box_max) o.box_max = JointVector(*box_max);
  o.strain_limit = strain_limit;
  o.attempts = attempts;
  o.load = make_load(force, moment);
  return checked_options(o);
}

py::dict sampling_dict(const SamplingResult& r, int n) {
  py::dict d;
  d["configurations"] = joints_matrix(r.configurations, n);
  d["min_distance"] = r.min_distance;
  d["box_min"] = Eigen::VectorXd(r.box_min);
  d["box_max"] = Eigen::VectorXd(r.box_max);
  d["candidates"] = r.candidates;
  d["rejected_fk"] = r.rejected_fk;
  d["rejected_strain"] = r.rejected_strain;
  d["complete"] = r.complete;
  return d;
}

RowMatrix poses_matrix(const std::vector<Pose2<double>>& poses) {
  RowMatrix out(static_cast<Eigen::Index>(poses.size()), 3);
  for (std::size_t r = 0; r < poses.size(); ++r) {
    out.row(static_cast<Eigen::Index>(r)) << poses[r].x, poses[r].y, poses[r].theta;
  }
  return out;
}

/// (N, n) joints, checked against the robot's limb count and for finite values.
std::vector<JointVector> joint_rows(const InputMatrix& q, int n, const char* what) {
  if (q.cols() != n) {
    throw std::invalid_argument(std::string(what) + ": expected an (N, " + std::to_string(n) +
                                ") array of joint values (m), got " + std::to_string(q.cols()) +
                                " columns");
  }
  if (!q.allFinite()) throw std::invalid_argument(std::string(what) + ": non-finite value");
  std::vector<JointVector> rows;
  for (Eigen::Index r = 0; r < q.rows(); ++r) rows.emplace_back(q.row(r).transpose());
  return rows;
}

/// The rows of a dataset: q (N, n) and measured (N, 3), named in messages as `q_name` and
/// `measured_name`.
std::vector<CalibrationSample> samples(const InputMatrix& q, const InputMatrix& measured, int n,
                                       const char* q_name = "q",
                                       const char* measured_name = "measured") {
  const std::vector<JointVector> joints = joint_rows(q, n, q_name);
  if (measured.cols() != 3 || measured.rows() != q.rows()) {
    throw std::invalid_argument(std::string(measured_name) +
                                ": expected an (N, 3) array of pattern poses (m, m, rad) "
                                "with N = " +
                                std::to_string(q.rows()) + ", got (" +
                                std::to_string(measured.rows()) + ", " +
                                std::to_string(measured.cols()) + ")");
  }
  if (!measured.allFinite()) {
    throw std::invalid_argument(std::string(measured_name) + ": non-finite value");
  }
  std::vector<CalibrationSample> data;
  for (std::size_t r = 0; r < joints.size(); ++r) {
    const auto row = measured.row(static_cast<Eigen::Index>(r));
    data.push_back(CalibrationSample{joints[r], Pose2<double>{row(0), row(1), row(2)}});
  }
  return data;
}

py::dict stats_dict(const PoseErrorStats& s) {
  py::dict d;
  d["max_p"] = s.max_p;
  d["mean_p"] = s.mean_p;
  d["min_p"] = s.min_p;
  d["max_theta"] = s.max_theta;
  d["mean_theta"] = s.mean_theta;
  d["min_theta"] = s.min_theta;
  d["count"] = s.count;
  d["failed"] = s.failed;
  d["branch_mismatches"] = s.branch_mismatches;
  return d;
}

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

/// A stages argument as a list of dicts (name, free, bounds_scale; default_stages() gives them)
/// or a stages JSON file's path (a str or an os.PathLike). ValueError naming the stage and the
/// field otherwise.
std::vector<CalibrationStage> stages_from(const py::handle& object) {
  if (py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__")) {
    return load_calibration_stages(input_path(object.cast<std::filesystem::path>()));
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
  validate_stages(stages, "stages");
  return stages;
}

DerivativeMode derivative_mode(const std::string& name) {
  if (name == "implicit") return DerivativeMode::kImplicit;
  if (name == "numeric") return DerivativeMode::kNumericCentral;
  if (name == "autodiff") return DerivativeMode::kAutoDiff;
  throw std::invalid_argument("derivatives: expected 'implicit', 'numeric' or 'autodiff', got '" +
                              name + "'");
}

const char* derivative_mode_name(DerivativeMode mode) {
  switch (mode) {
    case DerivativeMode::kNumericCentral:
      return "numeric";
    case DerivativeMode::kAutoDiff:
      return "autodiff";
    default:
      return "implicit";
  }
}

StageGauge stage_gauge(const std::string& name) {
  if (name == "subspace") return StageGauge::kSubspace;
  if (name == "prior") return StageGauge::kPrior;
  throw std::invalid_argument("stage_gauge: expected 'subspace' or 'prior', got '" + name + "'");
}

/// pcr.CalibrationResult: the C++ result, with the nominal description (identified and
/// extrinsics_only as pcr.Robot) and the calibration set (Table 3 of a report given no table).
struct Calibration {
  CalibrationResult result;
  RobotDescription nominal;
  std::vector<CalibrationSample> calibration;
};

/// The CalibrationOptions of a call: `options` (None: the defaults) with the keyword changes made
/// through the properties' setters (checked alike, no default written here), and `progress`.
/// A Python exception in `progress` must not unwind through Ceres: it is kept, later lines are
/// dropped, and raise_progress_error() raises it once the calibration has returned.
struct CalledOptions {
  CalibrationOptions options;
  std::shared_ptr<std::unique_ptr<py::error_already_set>> progress_error =
      std::make_shared<std::unique_ptr<py::error_already_set>>();

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
    if (progress.is_none()) return;
    options.progress = [progress, error = progress_error](const std::string& line) {
      py::gil_scoped_acquire acquire;
      if (*error) return;
      try {
        progress(line);
      } catch (py::error_already_set& e) {
        *error = std::make_unique<py::error_already_set>(std::move(e));
      }
    };
  }

  void raise_progress_error() {
    if (*progress_error) throw std::move(**progress_error);
  }
};

/// The fields of a CalibrationResult that pickle as they are, in the order of the pickled state.
auto result_fields(CalibrationResult& r) {
  return std::tie(r.stages, r.parameters, r.load_identified, r.gauge, r.free_count, r.jacobian_rank,
                  r.singular_values, r.residual_variance, r.residuals_exceed_noise, r.covariance_ok,
                  r.covariance, r.dropped, r.outliers, r.outlier_threshold, r.unidentifiable,
                  r.warnings);
}

RobotDescription with_params(const RobotDescription& nominal, const RobotParams<double>& params) {
  RobotDescription out = nominal;  // uncertainty section kept from the nominal
  out.params = params;
  return out;
}

/// `table`, or Table 3 on the calibration set alone (what pcr_calibrate reports without
/// --validation).
CalibrationTable table_or_calibration_set(const Calibration& c, const CalibrationTable* table) {
  if (table) return *table;
  py::gil_scoped_release release;
  return calibration_table(c.result, c.calibration, {});
}

py::dict measurement_dict(const VirtualMeasurement& v) {
  py::dict d;
  d["ok"] = v.ok;
  d["measured"] = v.measured;
  d["exact"] = v.exact;
  d["platform"] = v.platform;
  d["status"] = std::string(to_string(v.summary.status));
  return d;
}

/// `robot.measure` of each row of q (one configuration or (N, n)), or with `dataset`
/// `robot.measure_dataset` of them.
py::object virtual_measure(VirtualRobot& robot, const py::object& q_in, bool dataset) {
  const int n = robot.nominal().params.num_limbs;
  const InputArray q = input_array(q_in, n, "q", "m");
  const Eigen::Index rows = q.ndim() == 1 ? 1 : q.shape(0);
  const InputMatrix matrix = Eigen::Map<const RowMatrix>(q.data(), rows, n);
  const std::vector<JointVector> joints = joint_rows(matrix, n, "q");
  std::vector<VirtualMeasurement> out(joints.size());
  {
    py::gil_scoped_release release;
    if (dataset) {
      out = robot.measure_dataset(joints);
    } else {
      for (std::size_t r = 0; r < joints.size(); ++r) out[r] = robot.measure(joints[r]);
    }
  }
  if (q.ndim() == 1 && !dataset) return measurement_dict(out[0]);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RowMatrix measured(rows, 3), exact(rows, 3), platform(rows, 3);
  py::array_t<bool> ok(rows);
  py::list status;
  for (Eigen::Index r = 0; r < rows; ++r) {
    const VirtualMeasurement& v = out[static_cast<std::size_t>(r)];
    ok.mutable_at(r) = v.ok;
    status.append(to_string(v.summary.status));
    if (v.ok) {
      measured.row(r) << v.measured.x, v.measured.y, v.measured.theta;
      exact.row(r) << v.exact.x, v.exact.y, v.exact.theta;
      platform.row(r) << v.platform.x, v.platform.y, v.platform.theta;
    } else {
      measured.row(r).setConstant(nan);
      exact.row(r).setConstant(nan);
      platform.row(r).setConstant(nan);
    }
  }
  py::dict d;
  d["ok"] = ok;
  d["measured"] = measured;
  d["exact"] = exact;
  d["platform"] = platform;
  d["status"] = py::module_::import("numpy").attr("array")(status, py::arg("dtype") = "U14");
  return d;
}

/// The sensitivity grid's arguments, checked before any solve: `step` (m) in its range,
/// `centre` None (the middle of the strokes: an empty JointVector, the library's default) or n
/// finite joint values (m) within the strokes q_range.
JointVector sensitivity_centre(const RobotParams<double>& robot, double step,
                               const py::object& centre) {
  in_range(step, SensitivityOptions::kStep);
  if (centre.is_none()) return JointVector();
  // The stroke is checked by the library (sensitivity_configurations).
  return to_vector<Eigen::Dynamic>(centre, "centre", "joint values in m", robot.num_limbs);
}

}  // namespace

void wrap_calibration(py::module_& m) {
  m.def(
      "parameter_names",
      [](int num_limbs) {
        std::vector<std::string> names;
        for (int k = 0; k < num_parameters(num_limbs); ++k) {
          names.push_back(parameter_name(parameter_id(k, num_limbs)));
        }
        return names;
      },
      py::arg("num_limbs"),
      "Names of the flat parameters (per limb E, d, l, A_x, A_y, alpha, B_x, B_y, beta, gamma, "
      "precurvature, "
      "then the six extrinsics), e.g. 'l[1]', 'camera_theta'.");

  m.def(
      "sensitivity_configurations",
      [](const RobotDescription& robot, double step, const py::object& centre) {
        const JointVector c = sensitivity_centre(robot.params, step, centre);
        return joints_matrix(sensitivity_configurations(robot.params, step, c),
                             robot.params.num_limbs);
      },
      py::arg("robot"), py::arg("step") = 1e-3, py::arg("centre") = py::none(),
      "The 3^n grid of joint values (step in m, 1e-6 to 0.01) around `centre` (n joint values "
      "in m within the strokes; None: the middle of the strokes), minus the centre.");

  m.def(
      "platform_parameter_jacobian",
      [](const RobotDescription& robot, const Eigen::VectorXd& q, const py::object& force,
         double moment, const std::optional<SolverOptions>& options) -> py::object {
        if (q.size() != robot.params.num_limbs || !q.allFinite()) {
          throw std::invalid_argument("q: expected " + std::to_string(robot.params.num_limbs) +
                                      " finite joint values (m)");
        }
        const PlatformLoad<double> load = make_load(force, moment);
        Eigen::MatrixXd jacobian;
        bool ok;
        {
          py::gil_scoped_release release;
          ok = platform_parameter_jacobian(robot.params, JointVector(q), &jacobian, load,
                                           options_or_default(options, SolverOptions()));
        }
        if (!ok) return py::none();
        return py::cast(jacobian);
      },
      py::arg("robot"), py::arg("q"), py::kw_only(), py::arg("force") = no_force(),
      py::arg("moment") = 0.0, py::arg("options") = py::none(),
      "d(^W T_P)/d(limb parameters) at q: a (3, 10 n) array (rows x, y, theta; columns in "
      "parameter_names order), exact (implicit function theorem); None when FK fails.");

  m.def(
      "sensitivity",
      [](const RobotDescription& robot, double step, const py::object& centre,
         const py::object& force, double moment, const std::optional<SolverOptions>& solver) {
        SensitivityOptions options;
        options.step = step;
        options.centre = sensitivity_centre(robot.params, step, centre);
        options.load = make_load(force, moment);
        options.solver = options_or_default(solver, SolverOptions());
        SensitivityReport report;
        {
          py::gil_scoped_release release;
          report = sensitivity_analysis(robot, options);
        }
        // The report `pcr sensitivity --json` writes, one serialiser; the configurations as an
        // array, and the text table.
        py::dict d = py::module_::import("json").attr("loads")(sensitivity_json(report));
        d["configurations"] = joints_matrix(report.configurations, robot.params.num_limbs);
        d["text"] = sensitivity_table_text(report);
        return d;
      },
      py::arg("robot"), py::kw_only(), py::arg("step") = 1e-3, py::arg("centre") = py::none(),
      py::arg("force") = no_force(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
      "The paper's Table 2 for `robot`, the report `pcr sensitivity --json` writes: a dict with "
      "'step_m', 'table' (rows: param, dx_dp, dy_dp, dtheta_dp: max |d pose / d p| in SI units; "
      "half_width; position_error_m; orientation_error_rad), 'ranking' (the params, most "
      "influential first), 'configurations' ((N, n) array, m) and 'text' (the table as text). "
      "The grid: `step` (m, 1e-6 to 0.01) around `centre` (n joint values in m within the "
      "strokes; None: the middle of the strokes). ValueError naming the argument for a bad "
      "one; RuntimeError when FK fails at a configuration.");

  py::class_<VirtualRobot>(m, "VirtualRobot",
                           "A simulated robot: a truth drawn from the nominal description inside "
                           "its uncertainty intervals, measured by a noisy camera (Eq. 5).")
      .def(py::init([](const RobotDescription& nominal, std::uint64_t seed, double noise_position,
                       double noise_angle, bool misalignments, double misalignment_half_width,
                       bool unequal_diameters, double diameter_half_width, const py::object& force,
                       double moment, const std::optional<SolverOptions>& solver) {
             VirtualRobotOptions o;
             o.seed = seed;
             o.noise_position = noise_position;
             o.noise_angle = noise_angle;
             o.effects.misalignments = misalignments;
             o.effects.misalignment_half_width = misalignment_half_width;
             o.effects.unequal_diameters = unequal_diameters;
             o.effects.diameter_half_width = diameter_half_width;
             // force None with a moment: the moment alone.
             o.effects.load = make_load(force.is_none() ? no_force() : force, moment);
             o.effects.external_load = !force.is_none() || moment != 0.0;
             o.solver = options_or_default(solver, SolverOptions());
             return VirtualRobot(nominal, checked_options(o));
           }),
           py::arg("nominal"), py::kw_only(), py::arg("seed") = 1,
           py::arg("noise_position") = kDefaultNoisePosition,
           py::arg("noise_angle") = kDefaultNoiseAngle, py::arg("misalignments") = false,
           py::arg("misalignment_half_width") = UnmodelledEffects().misalignment_half_width,
           py::arg("unequal_diameters") = false,
           py::arg("diameter_half_width") = UnmodelledEffects().diameter_half_width,
           py::arg("force") = py::none(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
           "noise_position (m) and noise_angle (rad) are standard deviations; misalignments adds "
           "U(-h, h) (rad) to beta and gamma; unequal_diameters U(-h, h) (m) to each d; force "
           "(fx, fy) in N and/or moment (N m) apply a constant external load on the platform.")
      .def_property_readonly(
          "nominal", [](const VirtualRobot& v) { return v.nominal(); },
          "the nominal description (a copy)")
      .def_property_readonly(
          "truth", [](const VirtualRobot& v) { return v.truth(); }, "the true description (a copy)")
      .def_property_readonly(
          "load",
          [](const VirtualRobot& v) {
            return py::make_tuple(Eigen::Vector2d(v.load().force), v.load().moment);
          },
          "the applied load: (force (fx, fy) N, moment N m)")
      .def(
          "measure",
          [](VirtualRobot& robot, const py::object& q) { return virtual_measure(robot, q, false); },
          py::arg("q"),
          "Moves to q (m) and measures ^Se T_M. One configuration -> dict(ok, measured, exact, "
          "platform (Pose), status); an (N, n) array -> dict of arrays (N, 3), NaN where ok is "
          "False. Continued from the previous measurement, as the robot moves. Releases the GIL.")
      .def(
          "measure_dataset",
          [](VirtualRobot& robot, const py::object& q) { return virtual_measure(robot, q, true); },
          py::arg("q"),
          "A dataset's experiment: the robot goes home, then measures the rows of q (N, n) m in "
          "their order (a dataset's measurement order, which calibrate and Table 3 follow) -> "
          "measure's dict of arrays. Releases the GIL.")
      .def("return_home", &VirtualRobot::return_home,
           "The robot goes back home: the next measurement starts there.");

  m.def(
      "read_dataset",
      [](const std::filesystem::path& path, int num_joints) {
        const Dataset d = read_dataset(input_path(path), num_joints);
        return py::make_tuple(joints_matrix(d.q, d.num_joints), poses_matrix(d.poses));
      },
      py::arg("path"), py::arg("num_joints") = -1,
      "Reads a calibration dataset CSV (q1..qn,x,y,theta) -> (q (N, n) m, measured (N, 3) "
      "m, m, rad). FileNotFoundError when it does not exist, ValueError naming the file, line "
      "and column.");
  m.def(
      "write_dataset",
      [](const std::filesystem::path& path, const InputMatrix& q, const InputMatrix& measured) {
        Dataset d;
        d.num_joints = static_cast<int>(q.cols());
        for (const CalibrationSample& s : samples(q, measured, d.num_joints))
          d.add(s.q, s.measured);
        write_dataset(d, output_path(path));
      },
      py::arg("path"), py::arg("q"), py::arg("measured"),
      "Writes a dataset CSV atomically (full precision).");
  m.def(
      "read_configurations",
      [](const std::filesystem::path& path, int num_joints) {
        const std::vector<JointVector> rows = read_configurations(input_path(path), num_joints);
        const int n = rows.empty() ? std::max(num_joints, 0) : static_cast<int>(rows[0].size());
        return joints_matrix(rows, n);
      },
      py::arg("path"), py::arg("num_joints") = -1,
      "Reads joint configurations (q1..qn, m) -> (N, n) array.");
  m.def(
      "write_configurations",
      [](const std::filesystem::path& path, const InputMatrix& q) {
        write_configurations(joint_rows(q, static_cast<int>(q.cols()), "q"), output_path(path));
      },
      py::arg("path"), py::arg("q"), "Writes joint configurations (m) atomically.");

  m.def(
      "workspace_map",
      [](const RobotDescription& robot, double theta, int grid,
         const std::optional<std::array<double, 4>>& range, const py::object& force, double moment,
         const std::optional<SolverOptions>& solver) {
        WorkspaceMapOptions o;
        o.theta = theta;
        o.grid = grid;
        o.range = range;
        o.load = make_load(force, moment);
        o.solver = options_or_default(solver);
        checked_options(o);
        WorkspaceMap map;
        {
          py::gil_scoped_release release;
          map = workspace_map(robot.params, o);
        }
        const int n = robot.params.num_limbs;
        const auto nx = static_cast<py::ssize_t>(map.nx), ny = static_cast<py::ssize_t>(map.ny);
        py::array_t<double> xs(nx), ys(ny), q({ny, nx, static_cast<py::ssize_t>(n)});
        py::array_t<bool> reachable({ny, nx}), stable({ny, nx});
        py::array_t<int> status({ny, nx});
        const char* names[] = {"max_strain",       "stability_margin",   "singularity",
                               "position_3sigma",  "orientation_3sigma", "worst_position",
                               "worst_orientation"};
        std::vector<py::array_t<double>> fields;
        for (std::size_t f = 0; f < 7; ++f) fields.emplace_back(std::vector<py::ssize_t>{ny, nx});
        for (py::ssize_t i = 0; i < nx; ++i) xs.mutable_at(i) = map.points[i].x;
        for (py::ssize_t j = 0; j < ny; ++j) ys.mutable_at(j) = map.points[j * nx].y;
        for (py::ssize_t j = 0; j < ny; ++j) {
          for (py::ssize_t i = 0; i < nx; ++i) {
            const WorkspaceMapPoint& p = map.points[static_cast<std::size_t>(j * nx + i)];
            reachable.mutable_at(j, i) = p.reachable;
            stable.mutable_at(j, i) = p.stable;
            status.mutable_at(j, i) = static_cast<int>(p.status);
            for (int k = 0; k < n; ++k) q.mutable_at(j, i, k) = p.q(k);
            const double values[] = {p.max_strain,       p.stability_margin,   p.singularity,
                                     p.position_3sigma,  p.orientation_3sigma, p.worst_position,
                                     p.worst_orientation};
            for (std::size_t f = 0; f < 7; ++f) fields[f].mutable_at(j, i) = values[f];
          }
        }
        py::dict d;
        d["x"] = xs;
        d["y"] = ys;
        d["theta"] = map.theta;
        d["reachable"] = reachable;
        d["stable"] = stable;
        d["status_code"] = status;
        d["q"] = q;
        for (std::size_t f = 0; f < 7; ++f) d[names[f]] = fields[f];
        d["reachable_area"] = map.reachable_area;
        d["stable_area"] = map.stable_area;
        d["seconds"] = map.seconds;
        return d;
      },
      py::arg("robot"), py::kw_only(), py::arg("theta") = 0.0, py::arg("grid") = 200,
      py::arg("range") = py::none(), py::arg("force") = no_force(), py::arg("moment") = 0.0,
      py::arg("options") = py::none(),
      "Workspace map at orientation theta (rad): IK over a grid x grid of platform positions "
      "(range = (x_min, x_max, y_min, y_max) m; default: the positions an FK scan of the stroke "
      "box reaches, a tenth wider), warm-started along it. Returns a dict: x (grid,), y (grid,), "
      "theta, and (grid, grid) arrays indexed [iy, ix]: reachable (an equilibrium within the "
      "stroke), stable, status_code, q (grid, grid, n) m, max_strain, stability_margin, "
      "singularity, position_3sigma, orientation_3sigma, worst_position, worst_orientation (NaN "
      "without a covariance); reachable_area, stable_area (m^2), seconds. Releases the GIL.");

  m.def(
      "rotation_range",
      [](const RobotDescription& robot, double x, double y, double theta, const py::object& force,
         double moment, const std::optional<SolverOptions>& solver) {
        const PlatformLoad<double> load = make_load(force, moment);
        RotationRange r;
        {
          py::gil_scoped_release release;
          r = rotation_range(robot.params, checked_number(x, "x", "m"), checked_number(y, "y", "m"),
                             checked_number(theta, "theta", "rad"), options_or_default(solver),
                             load);
        }
        return py::make_tuple(r.reachable, r.theta_min, r.theta_max);
      },
      py::arg("robot"), py::arg("x"), py::arg("y"), py::kw_only(), py::arg("theta") = 0.0,
      py::arg("force") = no_force(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
      "The interval of platform orientations reachable (an equilibrium within the stroke, and "
      "stable) at the position (x, y) (m), searched from theta both ways: (reachable, theta_min, "
      "theta_max) in rad. Releases the GIL.");

  m.def(
      "admissible_configuration",
      [](const RobotDescription& robot, const Eigen::VectorXd& q, double strain_limit) {
        if (q.size() != robot.params.num_limbs) {
          throw std::invalid_argument("q: expected " + std::to_string(robot.params.num_limbs) +
                                      " joint values (m)");
        }
        in_range(strain_limit, kStrainLimitRange);
        py::gil_scoped_release release;
        return admissible_configuration(robot.params, JointVector(q), strain_limit,
                                        sampling_solver_options());
      },
      py::arg("robot"), py::arg("q"), py::arg("strain_limit") = kDefaultStrainLimit,
      "True when FK from home converges at q (m) with max bending strain <= strain_limit.");

  m.def(
      "poisson_disc_sample",
      [](const RobotDescription& robot, int count, std::uint64_t seed, double min_distance,
         const std::optional<Eigen::VectorXd>& box_min,
         const std::optional<Eigen::VectorXd>& box_max, double strain_limit, int attempts,
         const py::object& force, double moment) {
        const SamplingOptions o = sampling_options(count, seed, min_distance, box_min, box_max,
                                                   strain_limit, attempts, force, moment);
        SamplingResult r;
        {
          py::gil_scoped_release release;
          r = poisson_disc_sample(robot.params, o);
        }
        return sampling_dict(r, robot.params.num_limbs);
      },
      py::arg("robot"), py::kw_only(), py::arg("count") = kDefaultCalibrationCount,
      py::arg("seed") = 1, py::arg("min_distance") = 0.0, py::arg("box_min") = py::none(),
      py::arg("box_max") = py::none(), py::arg("strain_limit") = kDefaultStrainLimit,
      py::arg("attempts") = 30, py::arg("force") = no_force(), py::arg("moment") = 0.0,
      "Poisson-disc sample of `count` reachable joint configurations (Bridson), every pair at "
      "least min_distance apart (m; 0 = chosen from count). Returns a dict: configurations "
      "(count, n), min_distance, box_min, box_max, candidates, rejected_fk, rejected_strain, "
      "complete. Releases the GIL.");

  m.def(
      "sample_configurations",
      [](const RobotDescription& robot, int count, int validation_count, const std::string& design,
         int candidates, std::uint64_t seed, double min_distance,
         const std::optional<Eigen::VectorXd>& box_min,
         const std::optional<Eigen::VectorXd>& box_max, double strain_limit, int attempts,
         const py::object& force, double moment) {
        SamplingOptions o = sampling_options(count, seed, min_distance, box_min, box_max,
                                             strain_limit, attempts, force, moment);
        o.design = parse_sampling_design(design);  // InputError: ValueError naming the value
        o.candidates = candidates;
        ConfigurationSets sets;
        {
          py::gil_scoped_release release;
          sets = sample_configurations(robot, o, validation_count);
        }
        const int n = robot.params.num_limbs;
        py::dict d;
        d["calibration"] = joints_matrix(sets.calibration, n);
        d["validation"] = joints_matrix(sets.validation, n);
        d["design"] = sampling_design_name(o.design);
        if (!sets.spread.configurations.empty()) d["spread"] = sampling_dict(sets.spread, n);
        if (o.design == SamplingDesign::kDOptimal) {
          d["candidates"] = sampling_dict(sets.candidates, n);
          d["selected"] = sets.design.selected;
          d["parameters"] = sets.design.parameters;
          d["dimension"] = sets.design.dimension;
          d["rank"] = sets.design.rank;
          d["log_det"] = sets.design.log_det;
        }
        return d;
      },
      py::arg("robot"), py::kw_only(), py::arg("count") = kDefaultCalibrationCount,
      py::arg("validation_count") = 0, py::arg("design") = "poisson-disc",
      py::arg("candidates") = 0, py::arg("seed") = 1, py::arg("min_distance") = 0.0,
      py::arg("box_min") = py::none(), py::arg("box_max") = py::none(),
      py::arg("strain_limit") = kDefaultStrainLimit, py::arg("attempts") = 30,
      py::arg("force") = no_force(), py::arg("moment") = 0.0,
      "Calibration configurations by design ('poisson-disc': spread; 'd-optimal': greedy max "
      "log det of the scaled information on the identifiable subspace among `candidates` "
      "Poisson-disc candidates, 0 = 10 x count) and a disjoint Poisson-disc validation set of "
      "validation_count. Returns a dict: calibration (count, n), validation, design, and for "
      "d-optimal candidates, selected (indices into candidates['configurations']), parameters, "
      "dimension, rank, log_det. Releases the GIL.");

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

  m.def(
      "pose_errors",
      [](const RobotDescription& robot, const InputMatrix& q, const InputMatrix& measured,
         const py::object& force, double moment) {
        const std::vector<CalibrationSample> data = samples(q, measured, robot.params.num_limbs);
        const PlatformLoad<double> load = make_load(force, moment);
        PoseErrorStats stats;
        {
          py::gil_scoped_release release;
          stats = pose_errors(robot.params, data, SolverOptions(), load);
        }
        return stats_dict(stats);
      },
      py::arg("robot"), py::arg("q"), py::arg("measured"), py::kw_only(),
      py::arg("force") = no_force(), py::arg("moment") = 0.0,
      "The paper's Table 3 statistics of `robot` on (q (N, n) m, measured ^Se T_M (N, 3)), FK "
      "under the platform load (force fx, fy in N, moment in N m; e.g. a CalibrationResult's "
      "load): dict of max_p, mean_p, min_p (m, Eq. 8), max_theta, mean_theta, min_theta (rad, "
      "Eq. 9), count, failed, branch_mismatches. The rows are predicted in their order from home, "
      "the path the experiment followed (a dataset's row order is its measurement order).");

  m.def(
      "pose_errors_per_configuration",
      [](const RobotDescription& robot, const InputMatrix& q, const InputMatrix& measured,
         const py::object& force, double moment, const std::optional<SolverOptions>& options,
         bool path) {
        const std::vector<CalibrationSample> data = samples(q, measured, robot.params.num_limbs);
        const PlatformLoad<double> load = make_load(force, moment);
        const SolverOptions fk = options_or_default(options);
        ConfigurationErrors e;
        {
          py::gil_scoped_release release;
          e = configuration_errors(robot.params, data, fk, load,
                                   path ? SequenceMode::kPath : SequenceMode::kIndependent);
        }
        const auto rows = static_cast<Eigen::Index>(data.size());
        return py::make_tuple(Eigen::VectorXd(Eigen::VectorXd::Map(e.e_p.data(), rows)),
                              Eigen::VectorXd(Eigen::VectorXd::Map(e.e_theta.data(), rows)));
      },
      py::arg("robot"), py::arg("q"), py::arg("measured"), py::kw_only(),
      py::arg("force") = no_force(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
      py::arg("path") = true,
      "Per-configuration errors of `robot` (with its extrinsics) on (q (N, n) m, measured ^Se "
      "T_M (N, 3)), the ones pose_errors summarises: (e_p (N,) m, Eq. 8; e_theta (N,) rad, "
      "Eq. 9), NaN where FK failed. The platform pose follows from the measurement by Eq. 5; FK "
      "runs under the platform load, along the rows in their order from home (path=False: each "
      "row on its own). Releases the GIL.");

  auto options =
      py::class_<CalibrationOptions>(
          m, "CalibrationOptions",
          "Settings of pcr.calibrate (pcr/calib/calibrator.hpp); a new one holds the C++ "
          "defaults. Assignments are checked: ValueError naming the field and the value.")
          .def(py::init<>())
          .def_property(
              "stages", [](const CalibrationOptions& o) { return stages_list(o.stages); },
              [](CalibrationOptions& o, const py::object& v) { o.stages = stages_from(v); },
              "the stages, a list of dicts (name, free: [kinds], bounds_scale; default: "
              "default_stages()), a copy: assign such a list, or a stages JSON file's path "
              "(read then), to change them")
          .def_property(
              "orientation_weight",
              [](const CalibrationOptions& o) { return o.orientation_weight; },
              [](CalibrationOptions& o, double v) {
                o.orientation_weight = in_range(v, CalibrationOptions::kOrientationWeight);
              },
              "w of Eq. 6 (m/rad), >= 0")
          .def_property(
              "residual_scale", [](const CalibrationOptions& o) { return o.residual_scale; },
              [](CalibrationOptions& o, double v) {
                o.residual_scale = in_range(v, CalibrationOptions::kResidualScale);
              },
              "whitening of the residuals, the declared measurement noise (m), > 0")
          .def_property(
              "derivatives",
              [](const CalibrationOptions& o) { return derivative_mode_name(o.derivatives); },
              [](CalibrationOptions& o, const std::string& v) {
                o.derivatives = derivative_mode(v);
              },
              "'implicit' (implicit function theorem, per limb), 'numeric' (central differences) "
              "or 'autodiff' (one Jet through the whole residual)")
          .def_readwrite("fk", &CalibrationOptions::fk,
                         "FK settings of the cost (a SolverOptions; every solve runs to the "
                         "Newton tolerance)")
          .def_property(
              "max_iterations", [](const CalibrationOptions& o) { return o.max_iterations; },
              [](CalibrationOptions& o, int v) {
                o.max_iterations =
                    static_cast<int>(in_range(v, CalibrationOptions::kMaxIterations));
              },
              "Levenberg-Marquardt iterations per stage, >= 1")
          .def_readwrite("fix_gauge", &CalibrationOptions::fix_gauge,
                         "move the result to the limb-0 gauge (limb 0's clamps and d_0 keep "
                         "their nominal values)")
          .def_property(
              "gauge_prior_weight",
              [](const CalibrationOptions& o) { return o.gauge_prior_weight; },
              [](CalibrationOptions& o, double v) {
                o.gauge_prior_weight = in_range(v, CalibrationOptions::kGaugePriorWeight);
              },
              "weight of the weak prior towards the nominal values with stage_gauge 'prior' "
              "(whitened residual per half-width), >= 0")
          .def_property(
              "stage_gauge",
              [](const CalibrationOptions& o) {
                return o.stage_gauge == StageGauge::kPrior ? "prior" : "subspace";
              },
              [](CalibrationOptions& o, const std::string& v) { o.stage_gauge = stage_gauge(v); },
              "'subspace' (steps restricted to the complement of the gauge directions) or "
              "'prior' (a weak prior towards the nominal values)")
          .def_property(
              "function_tolerance",
              [](const CalibrationOptions& o) { return o.function_tolerance; },
              [](CalibrationOptions& o, double v) {
                o.function_tolerance = in_range(v, CalibrationOptions::kFunctionTolerance);
              },
              "the last stage stops when an iteration lowers the cost by less than this "
              "fraction, 0 to 1")
          .def_property(
              "intermediate_function_tolerance",
              [](const CalibrationOptions& o) { return o.intermediate_function_tolerance; },
              [](CalibrationOptions& o, double v) {
                o.intermediate_function_tolerance =
                    in_range(v, CalibrationOptions::kIntermediateFunctionTolerance);
              },
              "the same for the stages before the last, 0 to 1")
          .def_readwrite("compute_covariance", &CalibrationOptions::compute_covariance,
                         "compute the standard deviations and the covariance")
          .def_property(
              "robust_scale", [](const CalibrationOptions& o) { return o.robust_scale; },
              [](CalibrationOptions& o, double v) {
                o.robust_scale = in_range(v, CalibrationOptions::kRobustScale);
              },
              "Huber loss on a row's whitened residual beyond this many declared noise units "
              "(0: plain least squares), >= 0")
          .def_readwrite("drop_unreachable", &CalibrationOptions::drop_unreachable,
                         "leave out (and list in CalibrationResult.dropped) the rows without an "
                         "FK solution on the nominal geometry instead of a ValueError naming "
                         "them");
  def_value_semantics(options);

  auto stage_report =
      py::class_<StageReport>(m, "StageReport", "One calibration stage, as Ceres ran it.")
          .def_readonly("name", &StageReport::name, "the stage's name")
          .def_readonly("free_parameters", &StageReport::free_parameters,
                        "names of its free parameters")
          .def_readonly("initial_cost", &StageReport::initial_cost,
                        "1/2 sum F^T F at its start (Eq. 7 / 2, m^2)")
          .def_readonly("final_cost", &StageReport::final_cost, "1/2 sum F^T F at its end (m^2)")
          .def_readonly("iterations", &StageReport::iterations, "Levenberg-Marquardt iterations")
          .def_readonly("time_s", &StageReport::time_s, "wall time (s)")
          .def_readonly("termination", &StageReport::termination, "Ceres' brief report")
          .def_readonly("usable", &StageReport::usable, "Ceres' IsSolutionUsable()")
          .def_readonly("residual_evaluations", &StageReport::residual_evaluations,
                        "Ceres residual-only evaluations of the whole problem")
          .def_readonly("jacobian_evaluations", &StageReport::jacobian_evaluations,
                        "Ceres residual + Jacobian evaluations")
          .def_readonly("residual_time_s", &StageReport::residual_time_s,
                        "Ceres' residual evaluation time (s)")
          .def_readonly("jacobian_time_s", &StageReport::jacobian_time_s,
                        "Ceres' Jacobian evaluation time (s)")
          .def_readonly("linear_solver_time_s", &StageReport::linear_solver_time_s,
                        "Ceres' linear solver time (s)")
          .def_readonly("fk_solves", &StageReport::fk_solves,
                        "double FK solves (all configurations)")
          .def_readonly("fk_warm_start_failures", &StageReport::fk_warm_start_failures,
                        "FK warm solves that failed (continued in the parameters)")
          .def_readonly("fk_newton_iterations", &StageReport::fk_newton_iterations,
                        "FK Newton iterations, all solves")
          .def("__repr__", [](const StageReport& s) {
            std::ostringstream out;
            out << "<pcr.StageReport '" << s.name << "' " << s.free_parameters.size()
                << " free, cost " << s.initial_cost << " -> " << s.final_cost << ", "
                << s.iterations << " iterations>";
            return out.str();
          });
  def_pickle_fields(
      stage_report,
      [](StageReport& s) {
        return std::tie(s.name, s.free_parameters, s.initial_cost, s.final_cost, s.iterations,
                        s.time_s, s.termination, s.usable, s.residual_evaluations,
                        s.jacobian_evaluations, s.residual_time_s, s.jacobian_time_s,
                        s.linear_solver_time_s, s.fk_solves, s.fk_warm_start_failures,
                        s.fk_newton_iterations);
      },
      "StageReport");

  auto parameter_estimate =
      py::class_<ParameterEstimate>(m, "ParameterEstimate",
                                    "One identified parameter, in the limb-0 gauge (SI units).")
          .def_readonly("name", &ParameterEstimate::name, "e.g. 'l[1]', 'camera_x', 'load_f_x'")
          .def_property_readonly(
              "kind", [](const ParameterEstimate& p) { return parameter_kind_name(p.kind); },
              "the kind, e.g. 'l', 'A_x', 'camera_theta'")
          .def_readonly("nominal", &ParameterEstimate::nominal, "the nominal value")
          .def_readonly("value", &ParameterEstimate::value,
                        "the identified value, in the final gauge")
          .def_readonly("std_dev", &ParameterEstimate::std_dev,
                        "standard deviation: 0 when not free or a gauge reference, NaN when not "
                        "identifiable or not computed")
          .def_readonly("half_width", &ParameterEstimate::half_width,
                        "its uncertainty half-width (the nominal's)")
          .def_readonly("free", &ParameterEstimate::free, "free in the last stage")
          .def_readonly("gauge_reference", &ParameterEstimate::gauge_reference,
                        "held by the gauge fix")
          .def_readonly(
              "box_deviation", &ParameterEstimate::box_deviation,
              "(value - nominal) / (bounds_scale half-width) at the end of the last stage, "
              "before the gauge fix (NaN when unbounded or not free); +-1: at a bound")
          .def_readonly("at_bound", &ParameterEstimate::at_bound,
                        "|box_deviation| within 1e-6 of 1")
          .def_readonly("identifiable", &ParameterEstimate::identifiable,
                        "False when it has a share in a direction the data cannot identify")
          .def("__repr__", [](const ParameterEstimate& p) {
            std::ostringstream out;
            out.precision(9);
            out << "<pcr.ParameterEstimate " << p.name << " = " << p.value << " (nominal "
                << p.nominal << ", std " << p.std_dev << ")>";
            return out.str();
          });
  def_pickle_fields(
      parameter_estimate,
      [](ParameterEstimate& p) {
        return std::tie(p.name, p.kind, p.nominal, p.value, p.std_dev, p.half_width, p.free,
                        p.gauge_reference, p.box_deviation, p.at_bound, p.identifiable);
      },
      "ParameterEstimate");

  auto gauge_direction =
      py::class_<GaugeDirection>(m, "GaugeDirection",
                                 "A motion of the parameters that changes no prediction (a gauge).")
          .def_readonly("name", &GaugeDirection::name, "e.g. 'proximal clamps + camera: rotation'")
          .def_readonly("combination", &GaugeDirection::combination,
                        "the parameters it moves, e.g. 'A_x[*] + camera_x'")
          .def_readonly("relative_gain", &GaugeDirection::relative_gain,
                        "|J g| / (sigma_max |g|) in scaled units: ~0 means a gauge")
          .def_readonly("free", &GaugeDirection::free,
                        "every parameter it moves is free in the last stage")
          .def_readonly("present", &GaugeDirection::present, "free and a gauge (fixed by limb 0)")
          .def("__repr__", [](const GaugeDirection& g) {
            return "<pcr.GaugeDirection '" + g.name + "'" +
                   (g.present ? " present"
                    : g.free  ? " free"
                              : " not free") +
                   ">";
          });
  def_pickle_fields(
      gauge_direction,
      [](GaugeDirection& g) {
        return std::tie(g.name, g.combination, g.relative_gain, g.free, g.present);
      },
      "GaugeDirection");

  auto pose_error_stats =
      py::class_<PoseErrorStats>(m, "PoseErrorStats",
                                 "Table 3 statistics of one model on one set: e_p (Eq. 8, m) and "
                                 "e_theta (Eq. 9, rad) over the configurations whose FK converged.")
          .def_readonly("max_p", &PoseErrorStats::max_p, "largest e_p (m)")
          .def_readonly("mean_p", &PoseErrorStats::mean_p, "mean e_p (m)")
          .def_readonly("min_p", &PoseErrorStats::min_p, "smallest e_p (m)")
          .def_readonly("max_theta", &PoseErrorStats::max_theta, "largest e_theta (rad)")
          .def_readonly("mean_theta", &PoseErrorStats::mean_theta, "mean e_theta (rad)")
          .def_readonly("min_theta", &PoseErrorStats::min_theta, "smallest e_theta (rad)")
          .def_readonly("count", &PoseErrorStats::count, "configurations evaluated")
          .def_readonly("failed", &PoseErrorStats::failed,
                        "configurations whose FK did not converge (not in the statistics)")
          .def_readonly("branch_mismatches", &PoseErrorStats::branch_mismatches,
                        "configurations measured next to another equilibrium of the model at the "
                        "same joints (not in the statistics)")
          .def("__repr__", [](const PoseErrorStats& s) {
            std::ostringstream out;
            out << "<pcr.PoseErrorStats e_p max " << s.max_p * 1e6 << " um, mean " << s.mean_p * 1e6
                << " um; e_theta max " << s.max_theta * 1e3 << " mrad; " << s.count
                << " configurations, " << s.failed << " failed>";
            return out.str();
          });
  def_pickle_fields(
      pose_error_stats,
      [](PoseErrorStats& s) {
        return std::tie(s.max_p, s.mean_p, s.min_p, s.max_theta, s.mean_theta, s.min_theta, s.count,
                        s.failed, s.branch_mismatches);
      },
      "PoseErrorStats");

  // The validation rows are None without a validation set, not zeros.
  const auto validation_stats = [](PoseErrorStats CalibrationTable::*field) {
    return [field](const CalibrationTable& t) -> py::object {
      return t.has_validation ? py::cast(t.*field) : py::none();
    };
  };
  auto calibration_table_class =
      py::class_<CalibrationTable>(m, "CalibrationTable",
                                   "The paper's Table 3: the nominal model (nominal geometry, "
                                   "identified extrinsics) and the identified model on the "
                                   "calibration and validation sets (pcr.calibration_table).")
          .def_readonly("nominal_calibration", &CalibrationTable::nominal_calibration,
                        "PoseErrorStats of the nominal model on the calibration set")
          .def_readonly("identified_calibration", &CalibrationTable::identified_calibration,
                        "PoseErrorStats of the identified model on the calibration set")
          .def_property_readonly("nominal_validation",
                                 validation_stats(&CalibrationTable::nominal_validation),
                                 "PoseErrorStats of the nominal model on the validation set, or "
                                 "None without one")
          .def_property_readonly("identified_validation",
                                 validation_stats(&CalibrationTable::identified_validation),
                                 "PoseErrorStats of the identified model on the validation set, or "
                                 "None without one")
          .def_readonly("has_validation", &CalibrationTable::has_validation,
                        "whether a validation set was given")
          .def_readonly("warnings", &CalibrationTable::warnings,
                        "what makes the validation doubtful, in words")
          .def("to_text", &calibration_table_text,
               "Table 3 as text (um and mrad), as pcr_calibrate.")
          .def("__repr__", [](const CalibrationTable& t) {
            std::ostringstream out;
            out << "<pcr.CalibrationTable identified e_p mean "
                << t.identified_calibration.mean_p * 1e6 << " um on the calibration set";
            if (t.has_validation)
              out << ", " << t.identified_validation.mean_p * 1e6 << " um on the "
                  << "validation set";
            out << ">";
            return out.str();
          });
  def_pickle_fields(
      calibration_table_class,
      [](CalibrationTable& t) {
        return std::tie(t.nominal_calibration, t.identified_calibration, t.nominal_validation,
                        t.identified_validation, t.nominal_calibration_errors.e_p,
                        t.nominal_calibration_errors.e_theta, t.identified_calibration_errors.e_p,
                        t.identified_calibration_errors.e_theta, t.nominal_validation_errors.e_p,
                        t.nominal_validation_errors.e_theta, t.identified_validation_errors.e_p,
                        t.identified_validation_errors.e_theta, t.has_validation, t.warnings);
      },
      "CalibrationTable");

  py::class_<Calibration>(m, "CalibrationResult",
                          "What pcr.calibrate identified (pcr/calib/calibrator.hpp, SI units). "
                          "to_json() is the report pcr_calibrate --report writes.")
      .def_property_readonly(
          "identified",
          [](const Calibration& c) { return with_params(c.nominal, c.result.identified); },
          "the identified robot (limb-0 gauge; uncertainty section of the nominal)")
      .def_property_readonly(
          "extrinsics_only",
          [](const Calibration& c) { return with_params(c.nominal, c.result.extrinsics_only); },
          "the paper's nominal model: the nominal geometry with the identified extrinsics")
      .def_property_readonly(
          "stages", [](const Calibration& c) { return c.result.stages; }, "a StageReport per stage")
      .def_property_readonly(
          "parameters", [](const Calibration& c) { return c.result.parameters; },
          "a ParameterEstimate per flat parameter (parameter_names order), then the load's three "
          "(load_f_x, load_f_y N, load_m_z N m) when a stage frees 'load'")
      .def_property_readonly(
          "gauge", [](const Calibration& c) { return c.result.gauge; },
          "a GaugeDirection per gauge generator")
      .def_property_readonly(
          "load",
          [](const Calibration& c) {
            const PlatformLoad<double>& l = c.result.load;
            return py::make_tuple(l.force.x(), l.force.y(), l.moment);
          },
          "the identified constant platform load (f_x N, f_y N, m_z N m; in W, the moment about "
          "the platform origin), zeros unless a stage frees 'load': the identified robot "
          "predicts under it (Robot.forward(q, force=(f_x, f_y), moment=m_z))")
      .def_property_readonly(
          "load_identified", [](const Calibration& c) { return c.result.load_identified; },
          "whether a stage freed 'load'")
      .def_property_readonly(
          "free_count", [](const Calibration& c) { return c.result.free_count; },
          "free parameters of the last stage")
      .def_property_readonly(
          "jacobian_rank", [](const Calibration& c) { return c.result.jacobian_rank; },
          "numerical rank of the scaled Jacobian on them")
      .def_property_readonly(
          "singular_values",
          [](const Calibration& c) {
            return Eigen::Map<const Eigen::VectorXd>(
                       c.result.singular_values.data(),
                       static_cast<Eigen::Index>(c.result.singular_values.size()))
                .eval();
          },
          "singular values of the scaled Jacobian, relative to the largest (array)")
      .def_property_readonly(
          "residual_variance", [](const Calibration& c) { return c.result.residual_variance; },
          "of the whitened residuals: ~1 at the noise floor; NaN when the model could not be "
          "evaluated at the result")
      .def_property_readonly(
          "residuals_exceed_noise",
          [](const Calibration& c) { return c.result.residuals_exceed_noise; },
          "the residual test: the residual variance lies more than 5 standard deviations of its "
          "chi-square estimate above 1 (an unmodelled effect, outliers, wrong extrinsics or more "
          "noise than declared)")
      .def_property_readonly(
          "covariance_ok", [](const Calibration& c) { return c.result.covariance_ok; },
          "the standard deviations and the covariance were computed")
      .def_property_readonly(
          "covariance",
          [](const Calibration& c) -> py::object {
            if (c.result.covariance.size() == 0) return py::none();
            return py::cast(parameter_covariance(c.result));
          },
          "a ParameterCovariance (for Robot.predicted_accuracy), or None without "
          "compute_covariance")
      .def_property_readonly(
          "dropped", [](const Calibration& c) { return c.result.dropped; },
          "rows left out (drop_unreachable): origin, joints and the nominal FK status")
      .def_property_readonly(
          "outliers", [](const Calibration& c) { return c.result.outliers; },
          "rows whose whitened residual norm exceeds outlier_threshold: origin and norm")
      .def_property_readonly(
          "outlier_threshold", [](const Calibration& c) { return c.result.outlier_threshold; },
          "the whitened residual norm beyond which a row is an outlier (0 without a robust "
          "loss)")
      .def_property_readonly(
          "unidentifiable", [](const Calibration& c) { return c.result.unidentifiable; },
          "the parameter combinations the data cannot identify beyond the gauge, in words")
      .def_property_readonly(
          "warnings", [](const Calibration& c) { return c.result.warnings; },
          "what makes the result doubtful, in words (the report's warnings add the table's)")
      .def(
          "in_gauge",
          [](const Calibration& c, const RobotDescription& robot) {
            // The gauge directions the calibration fixed are those whose limb-0 references it
            // held (CalibrationOptions.fix_gauge).
            const auto held = [&c](const char* name) {
              for (const ParameterEstimate& p : c.result.parameters) {
                if (p.name == name) return p.gauge_reference;
              }
              return false;
            };
            if (robot.params.num_limbs != c.nominal.params.num_limbs) {
              throw std::invalid_argument("robot: expected " +
                                          std::to_string(c.nominal.params.num_limbs) +
                                          " limbs, got " + std::to_string(robot.params.num_limbs));
            }
            return with_params(
                robot, fix_gauge(robot.params, c.nominal.params, held("A_x[0]") && held("A_y[0]"),
                                 held("alpha[0]"), held("B_x[0]") && held("B_y[0]"),
                                 held("beta[0]"), held("d[0]")));
          },
          py::arg("robot"),
          "`robot` (e.g. a virtual robot's truth) moved along the gauge directions this "
          "calibration fixed, to the same references (limb 0's held values): its predictions "
          "are unchanged (with no load), so its parameters compare one by one with the "
          "identified ones.")
      .def(
          "to_json",
          [](const Calibration& c, const CalibrationTable* table) {
            return calibration_report_json(c.result, table_or_calibration_set(c, table));
          },
          py::arg("table") = py::none(),
          "The calibration report as JSON text, the one pcr_calibrate --report and pcr demo "
          "write (SI units; NaN as null), with Table 3 from `table` (pcr.calibration_table), or "
          "on the calibration set alone when None (FK solves on it).")
      .def(
          "to_dict",
          [](const Calibration& c, const CalibrationTable* table) {
            return py::module_::import("json").attr("loads")(
                calibration_report_json(c.result, table_or_calibration_set(c, table)));
          },
          py::arg("table") = py::none(), "json.loads(to_json(table)).")
      .def(
          "to_text",
          [](const Calibration& c, const CalibrationTable* table) {
            return calibration_report_text(c.result, table_or_calibration_set(c, table));
          },
          py::arg("table") = py::none(),
          "The report as text, the one pcr_calibrate prints (Table 3 as in to_json).")
      .def("__repr__",
           [](const Calibration& c) {
             std::ostringstream out;
             out << "<pcr.CalibrationResult " << c.result.stages.size() << " stages, "
                 << c.result.free_count << " free parameters, rank " << c.result.jacobian_rank
                 << ", residual variance " << c.result.residual_variance << ", "
                 << c.result.warnings.size() << " warnings>";
             return out.str();
           })
      // Pickling (and with it copy.copy and copy.deepcopy), so that calibrations run in worker
      // processes: the nominal, the robots, the load, the calibration set and the other fields.
      .def(py::pickle(
          [](Calibration c) {
            const PlatformLoad<double>& l = c.result.load;
            RowMatrix q(static_cast<Eigen::Index>(c.calibration.size()),
                        c.nominal.params.num_limbs);
            RowMatrix measured(q.rows(), 3);
            for (Eigen::Index r = 0; r < q.rows(); ++r) {
              const CalibrationSample& s = c.calibration[static_cast<std::size_t>(r)];
              q.row(r) = s.q.transpose();
              measured.row(r) << s.measured.x, s.measured.y, s.measured.theta;
            }
            return py::make_tuple(c.nominal, with_params(c.nominal, c.result.identified),
                                  with_params(c.nominal, c.result.extrinsics_only),
                                  py::make_tuple(l.force.x(), l.force.y(), l.moment), q, measured,
                                  fields_to_tuple(result_fields(c.result)));
          },
          [](const py::tuple& state) {
            if (state.size() != 7) {
              throw py::value_error(
                  "CalibrationResult: a pickled state of 7 fields expected, got " +
                  std::to_string(state.size()));
            }
            Calibration c;
            c.nominal = state[0].cast<RobotDescription>();
            c.result.identified = state[1].cast<RobotDescription>().params;
            c.result.extrinsics_only = state[2].cast<RobotDescription>().params;
            const auto load = state[3].cast<std::array<double, 3>>();
            c.result.load = PlatformLoad<double>{Eigen::Vector2d(load[0], load[1]), load[2]};
            c.calibration = samples(state[4].cast<RowMatrix>(), state[5].cast<RowMatrix>(),
                                    c.nominal.params.num_limbs);
            fields_from_tuple(result_fields(c.result), state[6].cast<py::tuple>(),
                              "CalibrationResult");
            return c;
          }));

  m.def(
      "calibration_table",
      [](const Calibration& c, const InputMatrix& q, const InputMatrix& measured,
         const py::object& validation_q, const py::object& validation_measured) {
        if (validation_q.is_none() != validation_measured.is_none()) {
          throw std::invalid_argument(
              "validation_q and validation_measured: expected both or neither");
        }
        const int n = c.nominal.params.num_limbs;
        const std::vector<CalibrationSample> calibration = samples(q, measured, n);
        std::vector<CalibrationSample> validation;
        if (!validation_q.is_none()) {
          const InputArray vq = input_array(validation_q, n, "validation_q", "m");
          const InputArray vm =
              input_array(validation_measured, 3, "validation_measured", "m, m, rad");
          const auto rows = [](const InputArray& a) { return a.ndim() == 1 ? 1 : a.shape(0); };
          validation = samples(Eigen::Map<const RowMatrix>(vq.data(), rows(vq), n),
                               Eigen::Map<const RowMatrix>(vm.data(), rows(vm), 3), n,
                               "validation_q", "validation_measured");
        }
        py::gil_scoped_release release;
        return calibration_table(c.result, calibration, validation);
      },
      py::arg("result"), py::arg("q"), py::arg("measured"), py::arg("validation_q") = py::none(),
      py::arg("validation_measured") = py::none(),
      "The paper's Table 3 of a CalibrationResult: its nominal model (extrinsics_only) and its "
      "identified model (under its load) on the calibration set (q (N, n) m, measured ^Se T_M "
      "(N, 3)) and, when given, the validation set. Returns a CalibrationTable; warns (its "
      "warnings) of a validation set unlike the calibration set. Releases the GIL.");

  m.def(
      "calibrate",
      [](const RobotDescription& nominal, const InputMatrix& q, const InputMatrix& measured,
         const std::optional<CalibrationOptions>& options, const py::object& progress,
         const py::kwargs& changes) {
        CalledOptions o("calibrate", options, progress, changes);
        Calibration c;
        c.nominal = nominal;
        c.calibration = samples(q, measured, nominal.params.num_limbs);
        {
          py::gil_scoped_release release;
          c.result = calibrate(nominal, c.calibration, o.options);
        }
        o.raise_progress_error();
        return py::make_tuple(with_params(nominal, c.result.identified), std::move(c));
      },
      py::arg("nominal"), py::arg("q"), py::arg("measured"), py::arg("options") = py::none(),
      py::kw_only(), py::arg("progress") = py::none(),
      "Staged, bounded identification (the paper's Section 5) of `nominal` from q (N, n) (m) "
      "and the measured pattern poses ^Se T_M (N, 3) (m, m, rad). options: a "
      "CalibrationOptions (None: the defaults); keyword arguments change fields of a copy of "
      "it by name (stages=..., drop_unreachable=True, ...; TypeError for a name it lacks, "
      "ValueError for a bad value). With drop_unreachable the rows without an FK solution on "
      "the nominal geometry are left out, else they are a ValueError naming them. progress: "
      "optional callable(str). Returns (identified Robot, CalibrationResult); "
      "result.to_json() is the report pcr_calibrate writes. Releases the GIL.");

  py::class_<ModelSelection>(m, "ModelSelection",
                             "The calibration's stages against the load model, chosen on the "
                             "validation set (pcr.calibrate_selecting_model).")
      .def_property_readonly(
          "load_chosen", [](const ModelSelection& s) { return s.load_chosen; },
          "the validation test kept the load model")
      .def_property_readonly(
          "tried_load", [](const ModelSelection& s) { return s.tried_load; },
          "the residuals exceeded the noise and the load model was fitted")
      .def_property_readonly(
          "rows", [](const ModelSelection& s) { return s.rows; }, "validation rows in the test")
      .def_property_readonly(
          "mean_difference", [](const ModelSelection& s) { return s.mean_difference; },
          "mean over the rows of the stages' squared whitened error less the "
          "load model's")
      .def_property_readonly(
          "t", [](const ModelSelection& s) { return s.t; },
          "the paired t statistic (the load model is kept above "
          "pcr.MODEL_SELECTION_T)")
      .def_property_readonly(
          "decision", [](const ModelSelection& s) { return s.decision; },
          "the choice in words, with the numbers");
  m.attr("MODEL_SELECTION_T") = kModelSelectionT;

  m.def(
      "calibrate_selecting_model",
      [](const RobotDescription& nominal, const InputMatrix& q, const InputMatrix& measured,
         const InputMatrix& validation_q, const InputMatrix& validation_measured,
         const std::optional<CalibrationOptions>& options, const py::object& progress,
         const py::kwargs& changes) {
        CalledOptions o("calibrate_selecting_model", options, progress, changes);
        const int n = nominal.params.num_limbs;
        const std::vector<CalibrationSample> calibration = samples(q, measured, n);
        const std::vector<CalibrationSample> validation =
            samples(validation_q, validation_measured, n);
        ModelSelection selection;
        {
          py::gil_scoped_release release;
          selection = calibrate_selecting_model(nominal, calibration, validation, o.options);
        }
        o.raise_progress_error();
        const auto wrapped = [&](CalibrationResult result) {
          return Calibration{std::move(result), nominal, calibration};
        };
        py::object load = py::none();
        if (selection.tried_load) load = py::cast(wrapped(selection.load));
        const CalibrationResult& chosen = selection.chosen();
        return py::make_tuple(with_params(nominal, chosen.identified), wrapped(chosen),
                              wrapped(selection.stages), load, selection);
      },
      py::arg("nominal"), py::arg("q"), py::arg("measured"), py::arg("validation_q"),
      py::arg("validation_measured"), py::arg("options") = py::none(), py::kw_only(),
      py::arg("progress") = py::none(),
      "calibrate() with model selection: when the residuals exceed the noise "
      "(CalibrationResult.residuals_exceed_noise), the load model (the last stage also frees a "
      "constant platform load) is fitted too and kept when a paired one-sided t-test on the "
      "validation rows' squared whitened pose errors passes pcr.MODEL_SELECTION_T (1 %). "
      "Returns (identified Robot, chosen CalibrationResult, the stages' CalibrationResult, the "
      "load model's CalibrationResult or None, ModelSelection). Releases the GIL.");
}

}  // namespace pcr::python
