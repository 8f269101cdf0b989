// Pose errors of a model on a dataset (the paper's Table 3 statistics) and pcr.PoseErrorStats.
#include <sstream>

#include "calibration_bindings.hpp"

namespace pcr::python {
namespace {

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

}  // namespace

void wrap_pose_errors(py::module_& m) {
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
}

}  // namespace pcr::python
