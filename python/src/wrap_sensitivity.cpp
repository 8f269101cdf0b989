// Flat parameter names and the pose's sensitivity to them (pcr/calib/sensitivity.hpp).
#include "calibration_bindings.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/parameters.hpp"

namespace pcr::python {
namespace {

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

py::dict sensitivity_dict(const SensitivityReport& report, int n) {
  // The report `pcr sensitivity --json` writes, one serialiser; the configurations as an array,
  // and the text table.
  py::dict d = py::module_::import("json").attr("loads")(sensitivity_json(report));
  d["configurations"] = joints_matrix(report.configurations, n);
  d["text"] = sensitivity_table_text(report);
  return d;
}

void wrap_sensitivity(py::module_& m) {
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
        return sensitivity_dict(report, robot.params.num_limbs);
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
}

}  // namespace pcr::python
