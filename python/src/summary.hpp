#pragma once
// What a solve reports beyond its values (pcr::SolverSummary), as Python sees it, for the planar
// and the spatial solutions alike: the properties of a Solution, the per-row arrays of a batch
// and the buffers the batch loops fill with the GIL released (solve.hpp).

#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <tuple>

#include "bindings.hpp"

namespace pcr::python {

/// Every field of a SolverSummary, in the order of a pickled solution's summary.
inline auto summary_fields(SolverSummary& s) {
  return std::tie(s.status, s.iterations, s.residual_evaluations, s.continuation_steps,
                  s.initial_residual_norm, s.final_residual_norm, s.max_strain, s.rod_steps,
                  s.position_error_estimate, s.angle_error_estimate, s.path_fraction, s.stability,
                  s.stability_margin, s.singularity, s.folds_passed, s.first_fold);
}

/// The summary properties of a solution class whose C++ type has a `summary` (Solution,
/// SpatialSolution).
template <class T, class... Extra>
void def_summary_properties(py::class_<T, Extra...>& cls) {
  cls.def_property_readonly(
         "converged", [](const T& s) { return s.summary.converged(); },
         "the solve reached its input (status 'converged')")
      .def_property_readonly(
          "status", [](const T& s) { return std::string(to_string(s.summary.status)); },
          "the status in words: the name of one of pcr.SolveStatus's values (status_code)")
      .def_property_readonly(
          "status_code", [](const T& s) { return s.summary.status; },
          "the status as a SolveStatus (s.status_code == pcr.SolveStatus.converged)")
      .def_property_readonly(
          "iterations", [](const T& s) { return s.summary.iterations; },
          "Newton iterations (warm attempt and cold retry included)")
      .def_property_readonly(
          "residual_evaluations", [](const T& s) { return s.summary.residual_evaluations; },
          "shooting residuals evaluated (with or without the Jacobian), the solve's cost")
      .def_property_readonly(
          "residual", [](const T& s) { return s.summary.final_residual_norm; },
          "final max-norm of the scaled shooting residual")
      .def_property_readonly(
          "max_strain", [](const T& s) { return s.summary.max_strain; },
          "largest bending strain |kappa| d / 2 over the rods")
      .def_property_readonly(
          "rod_steps", [](const T& s) { return s.summary.rod_steps; },
          "RK4 steps per rod of this solution")
      .def_property_readonly(
          "stable",
          [](const T& s) -> std::optional<bool> {
            if (s.summary.stability == Stability::kUnchecked) return std::nullopt;
            return s.summary.stability == Stability::kStable;
          },
          "whether the equilibrium holds with the joints held (None: not checked)")
      .def_property_readonly(
          "stability_margin", [](const T& s) { return s.summary.stability_margin; },
          "platform stiffness's eigenvalue nearest zero in units of EI / L, negated when "
          "unstable (docs/stability.md)")
      .def_property_readonly(
          "singularity", [](const T& s) { return s.summary.singularity; },
          "reciprocal condition number of the scaled forward Jacobian (zero at a fold)")
      .def_property_readonly(
          "position_error_estimate", [](const T& s) { return s.summary.position_error_estimate; },
          "estimated discretisation error of the solved lengths (m)")
      .def_property_readonly(
          "angle_error_estimate", [](const T& s) { return s.summary.angle_error_estimate; },
          "estimated discretisation error of the solved angles (rad)")
      .def_property_readonly(
          "continuation_steps", [](const T& s) { return s.summary.continuation_steps; },
          "sub-solves of the continuation (0: a direct solve)");
}

/// copy.copy and copy.deepcopy of a solution class (Solution, SpatialSolution): its rods' shapes
/// deep-copied by deepcopy.
template <class T, class... Extra>
void def_solution_copies(py::class_<T, Extra...>& cls) {
  cls.def("__copy__", [](const T& s) { return s; })
      .def(
          "__deepcopy__",
          [](const T& s, const py::dict& memo) {
            T out = s;
            out.shapes = py::module_::import("copy").attr("deepcopy")(s.shapes, memo);
            return out;
          },
          py::arg("memo"));
}

/// Where a batch loop writes row r's summary (plain pointers: filled with the GIL released).
struct SummaryBuffers {
  bool* converged;                  ///< N
  int* status;                      ///< N, SolveStatus
  int* iterations;                  ///< N
  int* residual_evaluations;        ///< N
  double* residual;                 ///< N
  double* max_strain;               ///< N
  int* rod_steps;                   ///< N
  bool* stable;                     ///< N (false when not checked)
  double* stability_margin;         ///< N
  double* singularity;              ///< N
  double* position_error_estimate;  ///< N
  double* angle_error_estimate;     ///< N

  /// Row r; the strain NaN when the solution is not usable (its values are NaN too).
  void store(const SolverSummary& s, bool usable, std::ptrdiff_t r) const {
    converged[r] = s.converged();
    status[r] = static_cast<int>(s.status);
    iterations[r] = s.iterations;
    residual_evaluations[r] = s.residual_evaluations;
    residual[r] = s.final_residual_norm;
    max_strain[r] = usable ? s.max_strain : std::numeric_limits<double>::quiet_NaN();
    rod_steps[r] = s.rod_steps;
    stable[r] = s.stability == Stability::kStable;
    stability_margin[r] = s.stability_margin;
    singularity[r] = s.singularity;
    position_error_estimate[r] = s.position_error_estimate;
    angle_error_estimate[r] = s.angle_error_estimate;
  }
};

/// The summary arrays of a batch (BatchResult, SpatialBatchResult derive from it). `status`
/// holds names (a str array), `status_code` the SolveStatus values.
struct SummaryArrays {
  py::array_t<double> residual, max_strain, stability_margin, singularity, position_error_estimate,
      angle_error_estimate;
  py::array_t<bool> converged, stable;
  py::array_t<int> status_code, iterations, residual_evaluations, rod_steps;
  py::object status = py::none();
  py::object shapes = py::none();

  /// Every field, in the order of the pickled state.
  auto fields() {
    return std::tie(residual, max_strain, stability_margin, singularity, position_error_estimate,
                    angle_error_estimate, converged, stable, status_code, iterations,
                    residual_evaluations, rod_steps, status, shapes);
  }

  SummaryBuffers allocate(py::ssize_t rows) {
    converged = py::array_t<bool>(rows);
    status_code = py::array_t<int>(rows);
    iterations = py::array_t<int>(rows);
    residual_evaluations = py::array_t<int>(rows);
    residual = py::array_t<double>(rows);
    max_strain = py::array_t<double>(rows);
    rod_steps = py::array_t<int>(rows);
    stable = py::array_t<bool>(rows);
    stability_margin = py::array_t<double>(rows);
    singularity = py::array_t<double>(rows);
    position_error_estimate = py::array_t<double>(rows);
    angle_error_estimate = py::array_t<double>(rows);
    return SummaryBuffers{converged.mutable_data(),
                          status_code.mutable_data(),
                          iterations.mutable_data(),
                          residual_evaluations.mutable_data(),
                          residual.mutable_data(),
                          max_strain.mutable_data(),
                          rod_steps.mutable_data(),
                          stable.mutable_data(),
                          stability_margin.mutable_data(),
                          singularity.mutable_data(),
                          position_error_estimate.mutable_data(),
                          angle_error_estimate.mutable_data()};
  }

  /// `status` from `status_code`, once the loop is done (with the GIL).
  void name_statuses() {
    py::list names;
    const int* c = status_code.data();
    for (py::ssize_t r = 0; r < status_code.size(); ++r) {
      names.append(to_string(static_cast<SolveStatus>(c[r])));
    }
    status = py::module_::import("numpy").attr("array")(names, py::arg("dtype") = "U14");
  }
};

/// The summary arrays' attributes, len() and repr of a batch class (`what`: its Python name);
/// `shapes_doc` says what one rod's shape array holds.
template <class T, class... Extra>
void def_summary_arrays(py::class_<T, Extra...>& cls, const char* what, const char* shapes_doc) {
  cls.def_readonly("converged", &T::converged, "(N,) bool")
      .def_readonly("status", &T::status, "(N,) status names (str)")
      .def_readonly("status_code", &T::status_code, "(N,) SolveStatus values (int)")
      .def_readonly("iterations", &T::iterations, "(N,) Newton iterations")
      .def_readonly("residual_evaluations", &T::residual_evaluations,
                    "(N,) shooting residuals evaluated")
      .def_readonly("residual", &T::residual, "(N,) final scaled residual max-norm")
      .def_readonly("max_strain", &T::max_strain, "(N,) largest bending strain")
      .def_readonly("rod_steps", &T::rod_steps, "(N,) RK4 steps per rod")
      .def_readonly("stable", &T::stable,
                    "(N,) bool: the equilibrium holds (False when not checked)")
      .def_readonly("stability_margin", &T::stability_margin,
                    "(N,) see Solution.stability_margin (NaN when not checked)")
      .def_readonly("singularity", &T::singularity,
                    "(N,) reciprocal condition number of the scaled forward Jacobian")
      .def_readonly("position_error_estimate", &T::position_error_estimate,
                    "(N,) estimated discretisation error of the solved lengths (m)")
      .def_readonly("angle_error_estimate", &T::angle_error_estimate,
                    "(N,) estimated discretisation error of the solved angles (rad)")
      .def_readonly("shapes", &T::shapes, shapes_doc)
      .def("__len__", [](const T& b) { return b.converged.size(); })
      .def("__repr__", [what](const T& b) {
        const auto rows = b.converged.size();
        const bool* converged = b.converged.data();
        const auto count = std::count(converged, converged + rows, true);
        return "<pcr." + std::string(what) + " " + std::to_string(rows) + " rows, " +
               std::to_string(count) + " converged>";
      });
}

}  // namespace pcr::python
