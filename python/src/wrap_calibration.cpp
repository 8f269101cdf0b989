// Calibration (pcr::calib): sensitivity table, virtual robot, datasets, Poisson-disc sampling and
// D-optimal design, staged identification. Reports come back as dicts, arrays as NumPy arrays.
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "bindings.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/dataset.hpp"
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
  o.min_distance = checked_number(min_distance, "min_distance", "m", 0.0);
  if (box_min) o.box_min = JointVector(*box_min);
  if (box_max) o.box_max = JointVector(*box_max);
  o.strain_limit = checked_number(strain_limit, "strain_limit", "", 0.0);
  o.attempts = attempts;
  o.load = make_load(force, moment);
  return o;
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

std::vector<CalibrationSample> samples(const InputMatrix& q, const InputMatrix& measured, int n) {
  const std::vector<JointVector> joints = joint_rows(q, n, "q");
  if (measured.cols() != 3 || measured.rows() != q.rows()) {
    throw std::invalid_argument(
        "measured: expected an (N, 3) array of pattern poses (m, m, rad) "
        "with N = " +
        std::to_string(q.rows()) + ", got (" + std::to_string(measured.rows()) + ", " +
        std::to_string(measured.cols()) + ")");
  }
  if (!measured.allFinite()) throw std::invalid_argument("measured: non-finite value");
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

std::vector<CalibrationStage> stages_from(const py::list& list) {
  std::vector<CalibrationStage> stages;
  for (const py::handle& item : list) {
    const py::dict d = py::reinterpret_borrow<py::object>(item).cast<py::dict>();
    for (const auto& kv : d) {
      const std::string key = kv.first.cast<std::string>();
      if (key != "name" && key != "free" && key != "bounds_scale") {
        throw InputError("stages[" + std::to_string(stages.size()) + "]." + key +
                         ": unknown field (expected name, free, bounds_scale)");
      }
    }
    CalibrationStage stage;
    stage.name = d.contains("name") ? d["name"].cast<std::string>()
                                    : "stage " + std::to_string(stages.size() + 1);
    if (!d.contains("free")) {
      throw InputError("stages[" + std::to_string(stages.size()) +
                       "].free: missing required field");
    }
    stage.free = d["free"].cast<std::vector<std::string>>();
    if (d.contains("bounds_scale")) stage.bounds_scale = d["bounds_scale"].cast<double>();
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

py::dict report_dict(const CalibrationResult& r) {
  py::list stages;
  for (const StageReport& s : r.stages) {
    py::dict d;
    d["name"] = s.name;
    d["free_parameters"] = s.free_parameters;
    d["initial_cost"] = s.initial_cost;
    d["final_cost"] = s.final_cost;
    d["iterations"] = s.iterations;
    d["time_s"] = s.time_s;
    d["termination"] = s.termination;
    d["usable"] = s.usable;
    stages.append(d);
  }
  py::list parameters;
  for (const ParameterEstimate& p : r.parameters) {
    py::dict d;
    d["name"] = p.name;
    d["nominal"] = p.nominal;
    d["value"] = p.value;
    d["std_dev"] = p.std_dev;
    d["half_width"] = p.half_width;
    d["free"] = p.free;
    d["gauge_reference"] = p.gauge_reference;
    d["box_deviation"] = p.box_deviation;
    d["at_bound"] = p.at_bound;
    d["identifiable"] = p.identifiable;
    parameters.append(d);
  }
  py::list gauge;
  for (const GaugeDirection& g : r.gauge) {
    py::dict d;
    d["name"] = g.name;
    d["combination"] = g.combination;
    d["relative_gain"] = g.relative_gain;
    d["free"] = g.free;
    d["present"] = g.present;
    gauge.append(d);
  }
  py::dict d;
  d["stages"] = stages;
  d["parameters"] = parameters;
  d["gauge"] = gauge;
  d["load"] = py::make_tuple(r.load.force.x(), r.load.force.y(), r.load.moment);
  d["load_identified"] = r.load_identified;
  d["free_count"] = r.free_count;
  d["jacobian_rank"] = r.jacobian_rank;
  d["singular_values"] = r.singular_values;
  d["residual_variance"] = r.residual_variance;
  d["covariance_ok"] = r.covariance_ok;
  // A pcr.ParameterCovariance (Robot.predicted_accuracy), or None without compute_covariance.
  d["covariance"] =
      r.covariance.size() > 0 ? py::cast(parameter_covariance(r)) : py::object(py::none());
  d["dropped"] = r.dropped;
  d["outliers"] = r.outliers;
  d["unidentifiable"] = r.unidentifiable;
  d["warnings"] = r.warnings;
  return d;
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

py::object virtual_measure(VirtualRobot& robot, const py::object& q_in) {
  const int n = robot.nominal().params.num_limbs;
  const InputArray q = input_array(q_in, n, "q", "m");
  const Eigen::Index rows = q.ndim() == 1 ? 1 : q.shape(0);
  const InputMatrix matrix = Eigen::Map<const RowMatrix>(q.data(), rows, n);
  const std::vector<JointVector> joints = joint_rows(matrix, n, "q");
  std::vector<VirtualMeasurement> out(joints.size());
  {
    py::gil_scoped_release release;
    for (std::size_t r = 0; r < joints.size(); ++r) out[r] = robot.measure(joints[r]);
  }
  if (q.ndim() == 1) return measurement_dict(out[0]);
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

SolverOptions options_or_default(const std::optional<SolverOptions>& o, const SolverOptions& d) {
  return o ? *o : d;
}

// The grid steps `pcr sensitivity --step` accepts (m): below, the configurations collapse onto
// the centre (a table of zeros); above, they leave the strokes of a robot of the paper's size.
constexpr double kMinSensitivityStep = 1e-6;
constexpr double kMaxSensitivityStep = 0.01;

/// The sensitivity grid's arguments, checked before any solve: `step` (m) in the range above,
/// `centre` None (the middle of the strokes: an empty JointVector, the library's default) or n
/// finite joint values (m) within the strokes q_range.
JointVector sensitivity_centre(const RobotParams<double>& robot, double step,
                               const py::object& centre) {
  checked_number(step, "step", "m", kMinSensitivityStep, kMaxSensitivityStep);
  if (centre.is_none()) return JointVector();
  const int n = robot.num_limbs;
  const JointVector c = to_vector<Eigen::Dynamic>(centre, "centre", "joint values in m", n);
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    if (c(i) < limb.q_min || c(i) > limb.q_max) {
      std::ostringstream s;
      s << "centre: joint " << i << " at " << c(i) << " m is outside its stroke q_range ["
        << limb.q_min << ", " << limb.q_max << "] m";
      throw std::invalid_argument(s.str());
    }
  }
  return c;
}

/// The stages argument of calibrate() when it names a file: a str or an os.PathLike.
bool is_path(const py::handle& object) {
  return py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__");
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
        py::list rows;
        for (const SensitivityRow& r : report.rows) {
          py::dict d;
          d["kind"] = r.kind;
          d["dx"] = r.dx;
          d["dy"] = r.dy;
          d["dtheta"] = r.dtheta;
          d["half_width"] = r.half_width;
          d["position_error"] = r.position_error;
          d["orientation_error"] = r.orientation_error;
          rows.append(d);
        }
        py::dict d;
        d["step"] = report.step;
        d["configurations"] = joints_matrix(report.configurations, robot.params.num_limbs);
        d["rows"] = rows;
        d["ranking"] = report.ranking;
        d["table"] = sensitivity_table_text(report);
        return d;
      },
      py::arg("robot"), py::kw_only(), py::arg("step") = 1e-3, py::arg("centre") = py::none(),
      py::arg("force") = no_force(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
      "The paper's Table 2 for `robot`: a dict with 'rows' (kind, dx, dy, dtheta: max |d pose / "
      "d p| in SI units; half_width; position_error m; orientation_error rad), 'ranking' "
      "(indices into rows, most influential first), 'configurations' and 'table' (text). "
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
             return VirtualRobot(nominal, o);
           }),
           py::arg("nominal"), py::kw_only(), py::arg("seed") = 1,
           py::arg("noise_position") = kDefaultNoisePosition,
           py::arg("noise_angle") = kDefaultNoiseAngle, py::arg("misalignments") = false,
           py::arg("misalignment_half_width") = 5e-3, py::arg("unequal_diameters") = false,
           py::arg("diameter_half_width") = 2e-6, py::arg("force") = py::none(),
           py::arg("moment") = 0.0, py::arg("options") = py::none(),
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
      .def("measure", &virtual_measure, py::arg("q"),
           "Moves to q (m) and measures ^Se T_M. One configuration -> dict(ok, measured, exact, "
           "platform (Pose), status); an (N, n) array -> dict of arrays (N, 3), NaN where ok is "
           "False. Warm-started from the previous measurement. Releases the GIL.");

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
        o.theta = checked_number(theta, "theta", "rad");
        o.grid = grid;
        o.range = range;
        o.load = make_load(force, moment);
        if (solver) o.solver = *solver;
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
                             checked_number(theta, "theta", "rad"),
                             solver ? *solver : SolverOptions(), load);
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
        checked_number(strain_limit, "strain_limit", "", 0.0);
        py::gil_scoped_release release;
        return admissible_configuration(robot.params, JointVector(q), strain_limit,
                                        sampling_solver_options());
      },
      py::arg("robot"), py::arg("q"), py::arg("strain_limit") = 0.01,
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
      py::arg("box_max") = py::none(), py::arg("strain_limit") = 0.01, py::arg("attempts") = 30,
      py::arg("force") = no_force(), py::arg("moment") = 0.0,
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
      py::arg("strain_limit") = 0.01, py::arg("attempts") = 30, py::arg("force") = no_force(),
      py::arg("moment") = 0.0,
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
      "under the platform load (force fx, fy in N, moment in N m; e.g. calibrate's report "
      "\"load\"): dict of max_p, mean_p, min_p (m, Eq. 8), max_theta, mean_theta, min_theta "
      "(rad, Eq. 9), count, failed.");

  m.def(
      "calibrate",
      [](const RobotDescription& nominal, const InputMatrix& q, const InputMatrix& measured,
         const py::object& stages, double orientation_weight, double residual_scale,
         const std::string& derivatives, int max_iterations, bool fix_gauge,
         double gauge_prior_weight, bool compute_covariance, bool drop_unreachable,
         double robust_scale, const py::object& progress) {
        CalibrationOptions o;
        if (is_path(stages)) {
          o.stages = load_calibration_stages(input_path(stages.cast<std::filesystem::path>()));
        } else if (!stages.is_none()) {
          o.stages = stages_from(stages.cast<py::list>());
        }
        o.orientation_weight =
            checked_number(orientation_weight, "orientation_weight", "m/rad", 0.0);
        o.residual_scale = checked_number(residual_scale, "residual_scale", "m");
        o.derivatives = derivative_mode(derivatives);
        o.max_iterations = max_iterations;
        o.fix_gauge = fix_gauge;
        o.gauge_prior_weight = checked_number(gauge_prior_weight, "gauge_prior_weight", "", 0.0);
        o.compute_covariance = compute_covariance;
        o.drop_unreachable = drop_unreachable;
        o.robust_scale = checked_number(robust_scale, "robust_scale", "", 0.0);
        // A Python exception in `progress` must not unwind through Ceres: it is kept, later
        // lines are dropped, and it is raised once calibrate() has returned.
        auto progress_error = std::make_shared<std::unique_ptr<py::error_already_set>>();
        if (!progress.is_none()) {
          o.progress = [progress, progress_error](const std::string& line) {
            py::gil_scoped_acquire acquire;
            if (*progress_error) return;
            try {
              progress(line);
            } catch (py::error_already_set& e) {
              *progress_error = std::make_unique<py::error_already_set>(std::move(e));
            }
          };
        }
        const std::vector<CalibrationSample> data = samples(q, measured, nominal.params.num_limbs);
        CalibrationResult result;
        {
          py::gil_scoped_release release;
          result = calibrate(nominal, data, o);
        }
        if (*progress_error) throw std::move(**progress_error);
        RobotDescription identified = nominal;  // uncertainty section kept from the nominal
        identified.params = result.identified;
        return py::make_tuple(identified, report_dict(result));
      },
      py::arg("nominal"), py::arg("q"), py::arg("measured"), py::kw_only(),
      py::arg("stages") = py::none(), py::arg("orientation_weight") = kDefaultOrientationWeight,
      py::arg("residual_scale") = kDefaultResidualScale, py::arg("derivatives") = "implicit",
      py::arg("max_iterations") = 100, py::arg("fix_gauge") = true,
      py::arg("gauge_prior_weight") = 1e-3, py::arg("compute_covariance") = true,
      py::arg("drop_unreachable") = false, py::arg("robust_scale") = 5.0,
      py::arg("progress") = py::none(),
      "Staged, bounded identification (the paper's Section 5) of `nominal` from q (N, n) (m) "
      "and the measured pattern poses ^Se T_M (N, 3) (m, m, rad). stages: None (the paper's "
      "three), a list of dicts (name, free, bounds_scale) or a stages JSON file's path. "
      "orientation_weight: w of Eq. 6 (m/rad); residual_scale (m). derivatives: 'implicit', "
      "'numeric' or 'autodiff'. drop_unreachable: leave out the rows without an FK solution "
      "on the nominal geometry (else ValueError naming them). robust_scale: Huber loss beyond "
      "this many times the declared noise (0: plain least squares). progress: optional "
      "callable(str). "
      "Returns (identified Robot, report dict: stages, parameters, gauge, free_count, "
      "jacobian_rank, singular_values, residual_variance, covariance_ok, dropped, outliers, "
      "unidentifiable, warnings). "
      "Releases the GIL.");
}

}  // namespace pcr::python
