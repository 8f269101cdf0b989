#pragma once
// Shared declarations of the pcr._pcr module: one wrap_<concept>() per file (module.cpp calls
// them in order), the small value types the bindings hand to Python, and the conversions of
// arguments every wrapper uses (paths, vectors, numbers), so that a bad argument raises the same
// Python exception, worded the same way, whichever function it was given to.

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/robot_io.hpp"

namespace pcr::python {

namespace py = pybind11;

void wrap_robot(py::module_& m);
void wrap_kinematics(py::module_& m);
void wrap_spatial(py::module_& m);
void wrap_sensitivity(py::module_& m);          // needs pcr::calib
void wrap_virtual_robot(py::module_& m);        // needs pcr::calib
void wrap_dataset(py::module_& m);              // needs pcr::calib
void wrap_workspace_map(py::module_& m);        // needs pcr::calib
void wrap_sampling(py::module_& m);             // needs pcr::calib
void wrap_calibration_stages(py::module_& m);   // needs pcr::calib
void wrap_pose_errors(py::module_& m);          // needs pcr::calib
void wrap_calibration(py::module_& m);          // needs pcr::calib
void wrap_spatial_calibration(py::module_& m);  // needs pcr::calib
void wrap_accuracy(py::module_& m);             // needs pcr::calib
void wrap_predicted_accuracy(py::module_& m);   // needs pcr::calib
void wrap_method(py::module_& m);               // needs pcr::calib
void wrap_spatial_method(py::module_& m);       // needs pcr::calib
void wrap_vision(py::module_& m);               // needs pcr::vision

/// A property's getter and setter that reach one field of an owner's rod (Limb and
/// LimbUncertainty keep their flat Python names l, d, E, precurvature...; SpatialLimb the file's
/// names length, diameter, young_modulus...).
template <class Owner, class RodFields, class Field = double>
auto rod_field(Field RodFields::*field) {
  return [field](const Owner& owner) { return owner.rod.*field; };
}
template <class Owner, class RodFields, class Field = double>
auto rod_setter(Field RodFields::*field) {
  return [field](Owner& owner, Field v) { owner.rod.*field = v; };
}

/// A solved configuration (FK or IK) as Python sees it: the solver's result plus, on request,
/// the rods' shapes (one (steps + 1, 4) array per rod: s, x, y, theta in m, m, m, rad).
struct Solution {
  int num_limbs = 0;
  JointVector q;
  Pose2<double> pose;
  std::array<Wrench<double>, kMaxLimbs> wrenches{};
  SolverSummary summary;
  py::object shapes = py::none();
  /// The solver's factorised last Jacobian, so that a warm start from Python costs what it costs
  /// in C++; only for a warm start of the same problem (FK or IK) it was solved by.
  WarmStartJacobian jacobian;
  bool inverse = false;
};

/// Whether `name` is a public read-write property of `type`: the state of a value type
/// (def_value_semantics), and what pcr.calibrate's keywords may change.
inline bool is_read_write_property(const py::handle& type, const std::string& name) {
  if (name.empty() || name[0] == '_' || !py::hasattr(type, name.c_str())) return false;
  const py::object attribute = type.attr(name.c_str());
  return py::isinstance(attribute, py::module_::import("builtins").attr("property")) &&
         !attribute.attr("fset").is_none();
}

/// copy.copy, copy.deepcopy and pickling for a value type whose state is its read-write properties
/// (a value has no shared parts, so a copy is a deep copy). The pickled state is the dict of those
/// properties, read from the class (nothing listed twice), set again on a default value.
template <class T, class... Extra>
void def_value_semantics(py::class_<T, Extra...>& cls) {
  cls.def("__copy__", [](const T& value) { return value; });
  cls.def(
      "__deepcopy__", [](const T& value, const py::dict&) { return value; }, py::arg("memo"));
  cls.def(py::pickle(
      [](const py::object& self) {
        const py::module_ builtins = py::module_::import("builtins");
        const py::object type = py::type::of(self);
        py::dict state;
        for (const py::handle name : builtins.attr("dir")(type)) {
          if (is_read_write_property(type, name.cast<std::string>())) state[name] = self.attr(name);
        }
        return state;
      },
      [](const py::dict& state) {
        py::object value = py::cast(T());
        for (const auto item : state) py::setattr(value, item.first, item.second);
        return value.template cast<T>();
      }));
}

/// A tuple of the fields (enumerations as their integers) and back: the pickled state of a
/// struct whose fields `fields(value)` ties.
template <class Tied>
py::tuple fields_to_tuple(Tied fields) {
  return std::apply(
      [](auto&... f) {
        const auto plain = [](const auto& v) {
          if constexpr (std::is_enum_v<std::decay_t<decltype(v)>>) {
            return static_cast<int>(v);
          } else {
            return v;
          }
        };
        return py::make_tuple(plain(f)...);
      },
      fields);
}
template <class Tied>
void fields_from_tuple(Tied fields, const py::tuple& state, const char* what) {
  if (state.size() != std::tuple_size_v<Tied>) {
    throw py::value_error(std::string(what) + ": a pickled state of " +
                          std::to_string(std::tuple_size_v<Tied>) + " fields expected, got " +
                          std::to_string(state.size()));
  }
  std::size_t i = 0;
  std::apply(
      [&](auto&... f) {
        const auto assign = [&](auto& field) {
          using T = std::decay_t<decltype(field)>;
          if constexpr (std::is_enum_v<T>) {
            field = static_cast<T>(state[i++].cast<int>());
          } else {
            field = state[i++].cast<T>();
          }
        };
        (assign(f), ...);
      },
      fields);
}

/// Pickling (and with it copy.copy and copy.deepcopy) of a value type without setters, field by
/// field: `fields(value)` ties them in the order of the pickled state.
template <class T, class... Extra, class Fields>
void def_pickle_fields(py::class_<T, Extra...>& cls, Fields fields, const char* what) {
  cls.def(py::pickle([fields](T value) { return fields_to_tuple(fields(value)); },
                     [fields, what](const py::tuple& state) {
                       T value;
                       fields_from_tuple(fields(value), state, what);
                       return value;
                     }));
}

/// A Solution as the C++ FK takes it (a warm start, a solved configuration); the solver's chord
/// matrix only when it was an FK solve (defined in wrap_kinematics.cpp).
ForwardSolution as_forward(const Solution& s);

// ---- arguments (defined in wrap_robot.cpp, make_load in wrap_kinematics.cpp) -----------------
// File paths are taken as std::filesystem::path (pybind11's caster: str, bytes or any
// os.PathLike), then handed to the C++ library through input_path / output_path. Vectors and
// poses are taken as py::object and converted here, never by pybind11's Eigen caster, whose
// refusal is a TypeError listing the overloads: a wrong length or a NaN is a ValueError that
// names the argument, says what it expects and shows what it got.

/// An input file's path as the C++ readers take it. When nothing is there, FileNotFoundError
/// (errno ENOENT, the path as its filename), as open() raises; the readers report the rest (a
/// directory, no permission, bad content) as ValueError naming the file.
std::string input_path(const std::filesystem::path& path);

/// An output file's path as the C++ writers take it (they write a temporary and rename it).
inline std::string output_path(const std::filesystem::path& path) { return path.string(); }

/// A float64 C-contiguous array from an array-like (a NumPy array, a sequence of numbers), or a
/// null array when it is none (str and bytes are not numbers).
using InputArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
InputArray as_input_array(const py::handle& object);

/// What a Python value is, for the "..., got <this>" of a message: "3 numbers (1, 0, 0)", "an
/// array of shape (4, 2)", "None", or its repr (shortened).
std::string describe_value(const py::handle& object);

/// Reads `size` finite numbers from `object` into `out`; otherwise ValueError
/// "<name>: expected <expected>, got <what it is>".
void read_numbers(const py::handle& object, const char* name, const std::string& expected,
                  Eigen::Index size, double* out);

/// A vector argument: N finite numbers (or `size` of them when N is Eigen::Dynamic), e.g.
/// to_vector<2>(force, "force", "fx, fy in N"); otherwise ValueError
/// "force: expected 2 finite numbers (fx, fy in N), got 3 numbers (1, 0, 0)".
template <int N>
Eigen::Matrix<double, N, 1> to_vector(const py::handle& object, const char* name,
                                      const char* meaning, Eigen::Index size = N) {
  static_assert(N == Eigen::Dynamic || N > 0, "a vector of N > 0 numbers");
  Eigen::Matrix<double, N, 1> v;
  if constexpr (N == Eigen::Dynamic) v.resize(size);
  read_numbers(object, name,
               std::to_string(v.size()) + " finite numbers (" + std::string(meaning) + ")",
               v.size(), v.data());
  return v;
}

/// `value` when it lies in the library's range of that option (pcr/option_range.hpp), else
/// ValueError with the library's message: "step: expected a number from 1e-06 to 0.01 (m), got 0".
double in_range(double value, const OptionRange& range);

/// A scalar argument the library has no range for (a pose, a path's rotation): finite, and within
/// [lo, hi] when they are given; else ValueError "rotation: expected a finite number (rad), got
/// nan" (`unit` "" for a dimensionless one), as in_range words it.
inline double checked_number(double value, const char* name, const char* unit,
                             double lo = -std::numeric_limits<double>::infinity(),
                             double hi = std::numeric_limits<double>::infinity()) {
  return in_range(value, OptionRange{name, lo, hi, unit});
}

/// `options` when the library accepts them (is_valid), else ValueError with its message naming
/// the field and the value.
template <class Options>
const Options& checked_options(const Options& options) {
  std::string error;
  if (!options.is_valid(&error)) throw std::invalid_argument(error);
  return options;
}

/// The solver options of a Python call (None: `fallback`), checked.
inline SolverOptions options_or_default(const std::optional<SolverOptions>& options,
                                        const SolverOptions& fallback = SolverOptions()) {
  return checked_options(options ? *options : fallback);
}

/// Array-like -> float64 C-contiguous array of 1 or 2 dimensions with `columns` columns and finite
/// values; ValueError naming `what` otherwise (the row and column of a non-finite value).
InputArray input_array(const py::handle& object, int columns, const char* what, const char* unit);

/// A pcr.Pose or 3 finite numbers (x m, y m, theta rad) -> Pose2. ValueError naming `what`
/// otherwise.
Pose2<double> to_pose(const py::handle& object, const char* what);

/// The platform load from Python arguments: force (2 finite numbers fx, fy in N), moment (N m,
/// in PlatformLoad::kMoment). ValueError naming the argument otherwise.
PlatformLoad<double> make_load(const py::handle& force, double moment);

/// The default of a `force` argument: no force, (0.0, 0.0) N.
inline py::tuple no_force() { return py::make_tuple(0.0, 0.0); }

}  // namespace pcr::python
