// pcr.VirtualRobot: a simulated robot measured by a noisy camera (pcr/calib/virtual_robot.hpp).
#include "calibration_bindings.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace pcr::python {
namespace {

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

}  // namespace

void wrap_virtual_robot(py::module_& m) {
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
}

}  // namespace pcr::python
