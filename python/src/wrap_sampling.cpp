// Admissible configurations, Poisson-disc sampling and D-optimal design (pcr/calib/sampling.hpp).
#include "calibration_bindings.hpp"
#include "pcr/calib/sampling.hpp"

namespace pcr::python {
namespace {

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

}  // namespace

void wrap_sampling(py::module_& m) {
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
}

}  // namespace pcr::python
