// Predicted accuracy of a calibrated robot (pcr/calib/predicted_accuracy.hpp):
// pcr.ParameterCovariance, pcr.read_parameter_covariance and Robot.predicted_accuracy (one
// configuration, or a batch as arrays).
#include <limits>
#include <optional>

#include "bindings.hpp"
#include "pcr/calib/predicted_accuracy.hpp"

namespace pcr::python {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// The keys of a prediction, with the number of values each holds.
struct Field {
  const char* name;
  int size;
};
constexpr Field kFields[] = {
    {"pose", 3},        // the solution's ^W T_P (m, m, rad)
    {"covariance", 9},  // (3, 3)
    {"position_1sigma", 1},
    {"position_3sigma", 1},
    {"position_axis", 2},
    {"orientation_1sigma", 1},
    {"orientation_3sigma", 1},
    {"worst_components", 3},
    {"worst_position", 1},
    {"worst_position_direction", 2},
    {"worst_orientation", 1},
};

/// The values of kFields in order.
void flatten(const Pose2<double>& pose, const PredictedAccuracy& a, double* out) {
  const double values[] = {pose.x, pose.y, pose.theta};
  out = std::copy(values, values + 3, out);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) *out++ = a.covariance(r, c);
  }
  *out++ = a.position_1sigma;
  *out++ = a.position_3sigma;
  *out++ = a.position_axis(0);
  *out++ = a.position_axis(1);
  *out++ = a.orientation_1sigma;
  *out++ = a.orientation_3sigma;
  for (int k = 0; k < 3; ++k) *out++ = a.worst_components(k);
  *out++ = a.worst_position;
  *out++ = a.worst_position_direction(0);
  *out++ = a.worst_position_direction(1);
  *out++ = a.worst_orientation;
}

constexpr int kValues = 3 + 9 + 1 + 1 + 2 + 1 + 1 + 3 + 1 + 2 + 1;

/// 3 variances (x m^2, y m^2, theta rad^2) or a finite, symmetric (3, 3) covariance.
Eigen::Matrix3d measurement_matrix(const py::object& object) {
  const InputArray a = as_input_array(object);
  const bool diagonal = a && a.ndim() == 1 && a.shape(0) == 3;
  const bool full = a && a.ndim() == 2 && a.shape(0) == 3 && a.shape(1) == 3;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  if (diagonal) {
    m.diagonal() = Eigen::Map<const Eigen::Vector3d>(a.data());
  } else if (full) {
    m = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.data());
  }
  if (!(diagonal || full) || !m.allFinite() || !m.isApprox(m.transpose()) ||
      (m.diagonal().array() < 0).any()) {
    throw std::invalid_argument(
        "measurement_covariance: expected 3 variances (x m^2, y m^2, theta rad^2) or a "
        "symmetric (3, 3) covariance with finite values, got " +
        describe_value(object));
  }
  return m;
}

py::dict predict(const RobotDescription& robot, const py::object& q_in,
                 const std::optional<ParameterCovariance>& covariance_in, const std::string& frame,
                 const py::object& measurement_covariance, bool worst_case, const py::object& force,
                 double moment, const std::optional<SolverOptions>& options_in) {
  const RobotParams<double>& params = robot.params;
  const int n = params.num_limbs;
  PredictedAccuracyOptions options;
  options.load = make_load(force, moment);
  options.solver = options_or_default(options_in);
  if (frame == "measurement") {
    options.frame = PoseFrame::kMeasurement;
  } else if (frame != "platform") {
    throw std::invalid_argument("frame: expected 'platform' or 'measurement', got '" + frame + "'");
  }
  if (!measurement_covariance.is_none()) {
    options.measurement_covariance = measurement_matrix(measurement_covariance);
  }
  if (worst_case && robot.uncertainty) {
    options.half_widths = parameter_half_widths(*robot.uncertainty, n);
  }
  const ParameterCovariance covariance = covariance_in ? *covariance_in : ParameterCovariance();

  // One solution (no FK solve), one configuration, or (N, n) configurations solved in sequence.
  std::vector<ForwardSolution> solutions;
  bool single = true;
  if (py::isinstance<Solution>(q_in)) {
    solutions.push_back(as_forward(q_in.cast<const Solution&>()));
  } else {
    const InputArray q = input_array(q_in, n, "q", "m");
    single = q.ndim() == 1;
    const py::ssize_t rows = single ? 1 : q.shape(0);
    solutions.resize(static_cast<std::size_t>(rows));
    py::gil_scoped_release release;
    ForwardSequence sequence(params, options.solver, options.load);
    JointVector joints(n);
    for (py::ssize_t r = 0; r < rows; ++r) {
      for (int i = 0; i < n; ++i) joints(i) = q.data()[r * n + i];
      solutions[static_cast<std::size_t>(r)] = sequence.solve(joints);
    }
  }
  const py::ssize_t rows = static_cast<py::ssize_t>(solutions.size());
  RowMatrix values(rows, kValues);
  std::vector<PredictionStatus> status(solutions.size());
  {
    py::gil_scoped_release release;
    for (py::ssize_t r = 0; r < rows; ++r) {
      const ForwardSolution& s = solutions[static_cast<std::size_t>(r)];
      const PredictedAccuracy a = predicted_accuracy(params, s, covariance, options);
      status[static_cast<std::size_t>(r)] = a.status;
      flatten(s.pose, a, values.row(r).data());
    }
  }
  py::dict d;
  if (single) {
    d["status"] = to_string(status[0]);
    d["ok"] = status[0] == PredictionStatus::kOk;
  } else {
    py::list names;
    py::array_t<bool> ok(rows);
    for (py::ssize_t r = 0; r < rows; ++r) {
      names.append(to_string(status[static_cast<std::size_t>(r)]));
      ok.mutable_at(r) = status[static_cast<std::size_t>(r)] == PredictionStatus::kOk;
    }
    d["status"] = py::module_::import("numpy").attr("array")(names, py::arg("dtype") = "U16");
    d["ok"] = ok;
  }
  int column = 0;
  for (const Field& f : kFields) {
    const RowMatrix block = values.middleCols(column, f.size);
    column += f.size;
    if (f.size == 1) {
      if (single) {
        d[f.name] = block(0, 0);
      } else {
        d[f.name] = Eigen::VectorXd(block.col(0));
      }
    } else if (f.size == 9) {
      py::array_t<double> a(single ? std::vector<py::ssize_t>{3, 3}
                                   : std::vector<py::ssize_t>{rows, 3, 3});
      std::copy(block.data(), block.data() + block.size(), a.mutable_data());
      d[f.name] = a;
    } else if (single) {
      d[f.name] = Eigen::VectorXd(block.row(0).transpose());
    } else {
      d[f.name] = block;
    }
  }
  return d;
}

}  // namespace

void wrap_predicted_accuracy(py::module_& m) {
  py::class_<ParameterCovariance>(
      m, "ParameterCovariance",
      "Covariance of a robot's flat parameters as a calibration identified them (SI units, "
      "flat order, then the load's three when identified): zero rows for held parameters, NaN "
      "rows for those the data could not identify.")
      .def(py::init([](std::vector<std::string> names, const RowMatrix& matrix) {
             ParameterCovariance c{std::move(names), matrix};
             validate_parameter_covariance(c, "ParameterCovariance");
             return c;
           }),
           py::arg("names"), py::arg("matrix"),
           "From names (parameter_names order) and a (p, p) array; ValueError naming the field "
           "and the value when they are not a valid covariance.")
      .def_readonly("names", &ParameterCovariance::names,
                    "the parameter of each row and column (pcr.parameter_names order)")
      .def_property_readonly(
          "matrix", [](const ParameterCovariance& c) { return RowMatrix(c.matrix); },
          "(p, p) covariance in SI units squared (m^2, rad^2, Pa^2, N^2, ...)")
      .def_property_readonly("num_limbs", &ParameterCovariance::num_limbs,
                             "limbs of the robot whose parameters the rows are")
      .def_property_readonly(
          "has_load", &ParameterCovariance::has_load,
          "whether the last three rows are the platform load (fx, fy in N, moment in N m)")
      .def("__repr__", [](const ParameterCovariance& c) {
        return "ParameterCovariance(" + std::to_string(c.names.size()) + " parameters, " +
               std::to_string(c.num_limbs()) + " limbs" + (c.has_load() ? ", load" : "") + ")";
      });

  m.def(
      "read_parameter_covariance",
      [](const std::filesystem::path& path, int num_limbs) {
        return read_parameter_covariance(input_path(path), num_limbs);
      },
      py::arg("path"), py::arg("num_limbs") = 0,
      "The \"covariance\" block of a calibration report (pcr_calibrate --report): ValueError "
      "naming the file, the field and the value when it is missing or malformed (names not the "
      "flat parameters of a robot, of num_limbs limbs when > 0; NaN off the rows of "
      "unidentifiable parameters; not symmetric; not positive semi-definite).");

  auto robot = py::reinterpret_borrow<py::class_<RobotDescription>>(m.attr("Robot"));
  robot.def(
      "predicted_accuracy", &predict, py::arg("q"), py::arg("covariance") = py::none(),
      py::kw_only(), py::arg("frame") = "platform", py::arg("measurement_covariance") = py::none(),
      py::arg("worst_case") = true, py::arg("force") = no_force(), py::arg("moment") = 0.0,
      py::arg("options") = py::none(),
      "Predicted accuracy of this (identified) model at q: a Solution (no FK solve), n joint "
      "values (m), or an (N, n) array solved in sequence (then every value is an array over the "
      "rows). The error of the model's pose from `covariance` (a ParameterCovariance; None: "
      "none), of ^W T_P in the model's (limb-0) frames with frame='platform', of the pattern pose "
      "the camera measures (Eq. 5, the extrinsics' covariance included) with 'measurement': "
      "'covariance' (3, 3) of x, y, theta plus `measurement_covariance` (a (3, 3) covariance of "
      "a measured pose, for the scatter of measurements about the model), 'position_1sigma' "
      "(m, semi-major axis of the position ellipse, along 'position_axis'), 'position_3sigma', "
      "'orientation_1sigma' and 'orientation_3sigma' (rad); with `worst_case` and the robot's "
      "uncertainty intervals, the first-order worst case: 'worst_components' (sum |d pose / d p| "
      "half-width: m, m, rad), 'worst_position' (m, the largest |(dx, dy)| over the intervals, "
      "towards 'worst_position_direction'), 'worst_orientation' (rad). 'status': ok, "
      "no_jacobian (no FK solution), not_identifiable, no_covariance; 'pose': the solution's.");
}

}  // namespace pcr::python
