// The calibrator: pcr.CalibrationOptions, pcr.calibrate, its result and Table 3, model selection.
#include <memory>
#include <sstream>

#include "calibration_bindings.hpp"
#include "pcr/calib/calibration_report.hpp"
#include "pcr/calib/model_selection.hpp"
#include "pcr/calib/predicted_accuracy.hpp"
#include "pcr/parameters.hpp"

namespace pcr::python {
namespace {

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

/// The fields of a CalibrationResult that pickle as they are, in the order of the pickled state.
auto result_fields(CalibrationResult& r) {
  return std::tie(r.stages, r.parameters, r.load_identified, r.gauge, r.free_count, r.jacobian_rank,
                  r.singular_values, r.residual_variance, r.residuals_exceed_noise, r.covariance_ok,
                  r.covariance, r.dropped, r.outliers, r.outlier_threshold, r.unidentifiable,
                  r.warnings);
}

/// `table`, or Table 3 on the calibration set alone (what pcr_calibrate reports without
/// --validation).
CalibrationTable table_or_calibration_set(const Calibration& c, const CalibrationTable* table) {
  if (table) return *table;
  py::gil_scoped_release release;
  return calibration_table(c.result, c.calibration, {});
}

/// pcr.CalibrationOptions: the settings of pcr.calibrate, checked on assignment.
void bind_calibration_options(py::module_& m) {
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
}

/// pcr.StageReport: one stage of a calibration.
void bind_stage_report(py::module_& m) {
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
}

/// pcr.ParameterEstimate: one identified parameter.
void bind_parameter_estimate(py::module_& m) {
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
}

/// pcr.GaugeDirection: a gauge of the parameters.
void bind_gauge_direction(py::module_& m) {
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
}

/// pcr.CalibrationTable: the paper's Table 3.
void bind_calibration_table(py::module_& m) {
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
}

/// pcr.CalibrationResult (a Calibration): its fields, reports and pickling.
void bind_calibration_result(py::module_& m) {
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
            return with_params(robot,
                               in_calibration_gauge(c.result, c.nominal.params, robot.params));
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
}

/// pcr.calibration_table and pcr.calibrate (after the classes of their signatures).
void bind_calibrate(py::module_& m) {
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
}

/// pcr.ModelSelection, pcr.MODEL_SELECTION_T and pcr.calibrate_selecting_model.
void bind_model_selection(py::module_& m) {
  bind_model_selection_class<ModelSelection>(
      m, "ModelSelection",
      "The calibration's stages against the load model, chosen on the validation set "
      "(pcr.calibrate_selecting_model).");
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

}  // namespace

void wrap_calibration(py::module_& m) {
  bind_calibration_options(m);
  bind_stage_report(m);
  bind_parameter_estimate(m);
  bind_gauge_direction(m);
  bind_calibration_table(m);
  bind_calibration_result(m);
  bind_calibrate(m);
  bind_model_selection(m);
}

RobotDescription with_params(const RobotDescription& nominal, const RobotParams<double>& params) {
  RobotDescription out = nominal;  // uncertainty section kept from the nominal
  out.params = params;
  return out;
}

}  // namespace pcr::python
