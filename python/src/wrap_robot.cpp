// pcr.Robot (the pcr-robot description), pcr.Limb, pcr.Pose, pcr.Extrinsics, pcr.Uncertainty.
// Attribute access returns references into the robot, so robot.limbs[0].l = 0.031 edits it.
#include <cerrno>
#include <cmath>
#include <sstream>
#include <system_error>

#include "bindings.hpp"
#include "pcr/parameters.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace pcr::python {

std::string input_path(const std::filesystem::path& path) {
  std::error_code error;
  const bool exists = std::filesystem::exists(std::filesystem::status(path, error));
  if (!exists && error == std::errc::no_such_file_or_directory) {
    errno = ENOENT;
    PyErr_SetFromErrnoWithFilename(PyExc_FileNotFoundError, path.c_str());
    throw py::error_already_set();
  }
  return path.string();
}

InputArray as_input_array(const py::handle& object) {
  // A null array (InputArray() would be an empty one).
  const InputArray none = py::reinterpret_steal<InputArray>(py::handle());
  if (py::isinstance<py::str>(object) || py::isinstance<py::bytes>(object)) return none;
  try {
    return InputArray::ensure(object);
  } catch (const py::error_already_set&) {
    return none;
  }
}

namespace {

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// "(1, 0, 0)": the values of a 1-D array.
std::string values_text(const InputArray& a) {
  std::string out = "(";
  for (py::ssize_t k = 0; k < a.size(); ++k) out += (k ? ", " : "") + number_text(a.data()[k]);
  return out + ")";
}

std::string describe_array(const py::handle& object, const InputArray& a) {
  if (!a) {
    const std::string text = py::repr(object).cast<std::string>();
    return text.size() <= 200 ? text : text.substr(0, 200) + "...";
  }
  if (a.ndim() == 0) return "a single number " + number_text(*a.data());
  if (a.ndim() == 1) {
    if (a.size() == 0) return "an empty sequence";
    const std::string count = std::to_string(a.size()) + (a.size() == 1 ? " number" : " numbers");
    return a.size() <= 8 ? count + " " + values_text(a) : count;
  }
  std::string shape = "an array of shape (";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(a.shape(d));
  return shape + ")";
}

}  // namespace

std::string describe_value(const py::handle& object) {
  if (object.is_none()) return "None";
  return describe_array(object, as_input_array(object));
}

void read_numbers(const py::handle& object, const char* name, const std::string& expected,
                  Eigen::Index size, double* out) {
  const InputArray a = as_input_array(object);  // None: a 0-d NaN, refused below
  const bool shaped = a && a.ndim() == 1 && a.shape(0) == size;
  bool finite = shaped;
  for (py::ssize_t k = 0; finite && k < a.size(); ++k) finite = std::isfinite(a.data()[k]);
  if (!finite) {
    // The right count with a NaN or an infinity: the values say it all.
    const std::string got = shaped             ? values_text(a)
                            : object.is_none() ? "None"
                                               : describe_array(object, a);
    throw std::invalid_argument(std::string(name) + ": expected " + expected + ", got " + got);
  }
  std::copy(a.data(), a.data() + size, out);
}

double in_range(double value, const OptionRange& range) {
  std::string error;
  if (!range.check(value, &error)) throw std::invalid_argument(error);
  return value;
}

InputArray input_array(const py::handle& object, int columns, const char* what, const char* unit) {
  const InputArray a = as_input_array(object);
  if (!a || a.ndim() < 1 || a.ndim() > 2 || a.shape(a.ndim() - 1) != columns) {
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(columns) +
                                " numbers or an (N, " + std::to_string(columns) + ") array (" +
                                unit + "), got " + describe_value(object));
  }
  const double* data = a.data();
  for (py::ssize_t k = 0; k < a.size(); ++k) {
    if (!std::isfinite(data[k])) {
      const py::ssize_t row = k / columns, col = k % columns;
      throw std::invalid_argument(std::string(what) + ": non-finite value " + number_text(data[k]) +
                                  " at row " + std::to_string(row) + ", column " +
                                  std::to_string(col));
    }
  }
  return a;
}

Pose2<double> to_pose(const py::handle& object, const char* what) {
  py::object values = py::reinterpret_borrow<py::object>(object);
  if (py::isinstance<Pose2<double>>(object)) {
    const Pose2<double> p = object.cast<Pose2<double>>();
    values = py::make_tuple(p.x, p.y, p.theta);
  }
  double v[3];
  read_numbers(values, what, "a pcr.Pose or 3 finite numbers (x m, y m, theta rad)", 3, v);
  return Pose2<double>{v[0], v[1], v[2]};
}

namespace {

std::string pose_repr(const Pose2<double>& p) {
  std::ostringstream s;
  s.precision(17);
  s << "Pose(x=" << p.x << ", y=" << p.y << ", theta=" << p.theta << ")";
  return s.str();
}

py::list limb_list(RobotDescription& robot, const py::object& owner) {
  py::list limbs;
  for (int i = 0; i < robot.params.num_limbs; ++i) {
    limbs.append(
        py::cast(&robot.params.limb(i), py::return_value_policy::reference_internal, owner));
  }
  return limbs;
}

void set_limbs(RobotDescription& robot, const std::vector<LimbParams<double>>& limbs) {
  if (limbs.size() < 2 || limbs.size() > static_cast<std::size_t>(kMaxLimbs)) {
    throw InputError("Robot.limbs: expected 2 to " + std::to_string(kMaxLimbs) + " limbs, got " +
                     std::to_string(limbs.size()));
  }
  robot.params.num_limbs = static_cast<int>(limbs.size());
  for (std::size_t i = 0; i < static_cast<std::size_t>(kMaxLimbs); ++i) {
    robot.params.limbs[i] = i < limbs.size() ? limbs[i] : LimbParams<double>();
  }
}

/// pcr.Pose: a planar pose that also reads as [x, y, theta].
void bind_pose(py::module_& m) {
  py::class_<Pose2<double>>(m, "Pose",
                            "A planar pose ^A T_B: x, y (m) and theta (rad) of frame B in frame A.")
      .def(py::init([](double x, double y, double theta) {
             return Pose2<double>{x, y, theta};
           }),
           py::arg("x") = 0.0, py::arg("y") = 0.0, py::arg("theta") = 0.0)
      .def_readwrite("x", &Pose2<double>::x, "m")
      .def_readwrite("y", &Pose2<double>::y, "m")
      .def_readwrite("theta", &Pose2<double>::theta, "rad")
      .def(
          "to_array", [](const Pose2<double>& p) { return Eigen::Vector3d(p.x, p.y, p.theta); },
          "[x, y, theta] as a NumPy array (m, m, rad).")
      .def("__mul__", &Pose2<double>::operator*, py::arg("other"), "Composition ^A T_B * ^B T_C.")
      .def("inverse", &Pose2<double>::inverse, "^B T_A.")
      .def("__repr__", &pose_repr)
      .def("__eq__",
           [](const Pose2<double>& a, const Pose2<double>& b) {
             return a.x == b.x && a.y == b.y && a.theta == b.theta;
           })
      .def(py::pickle(
          [](const Pose2<double>& p) { return py::make_tuple(p.x, p.y, p.theta); },
          [](const py::tuple& t) {
            return Pose2<double>{t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>()};
          }))
      .def("__copy__", [](const Pose2<double>& p) { return p; })
      .def(
          "__deepcopy__", [](const Pose2<double>& p, const py::dict&) { return p; },
          py::arg("memo"))
      .def("__len__", [](const Pose2<double>&) { return 3; })
      .def(
          "__getitem__",
          [](const Pose2<double>& p, int i) {
            if (i < -3 || i >= 3) throw py::index_error("Pose index out of range (x, y, theta)");
            const double values[3] = {p.x, p.y, p.theta};
            return values[(i + 3) % 3];
          },
          py::arg("index"), "x, y, theta by index: x, y, theta = pose")
      .def(
          "__array__",
          [](const Pose2<double>& p, const py::object& dtype, const py::object&) {
            py::array out = py::cast(Eigen::Vector3d(p.x, p.y, p.theta));
            return dtype.is_none() ? out : py::array(out.attr("astype")(dtype));
          },
          py::arg("dtype") = py::none(), py::arg("copy") = py::none(),
          "numpy.asarray(pose): [x, y, theta] (m, m, rad)");
}

/// compose_poses: Pose's product over rows of arrays.
void bind_compose_poses(py::module_& m) {
  m.def(
      "compose_poses",
      [](const py::object& a_in, const py::object& b_in) -> py::object {
        const InputArray a = input_array(a_in, 3, "a", "x m, y m, theta rad");
        const InputArray b = input_array(b_in, 3, "b", "x m, y m, theta rad");
        const py::ssize_t na = a.ndim() == 1 ? 1 : a.shape(0);
        const py::ssize_t nb = b.ndim() == 1 ? 1 : b.shape(0);
        if (na != nb && na != 1 && nb != 1) {
          throw std::invalid_argument("compose_poses: " + std::to_string(na) + " and " +
                                      std::to_string(nb) + " rows do not broadcast");
        }
        const py::ssize_t n = std::max(na, nb);
        py::array_t<double> out(a.ndim() == 1 && b.ndim() == 1 ? std::vector<py::ssize_t>{3}
                                                               : std::vector<py::ssize_t>{n, 3});
        double* o = out.mutable_data();
        for (py::ssize_t r = 0; r < n; ++r) {
          const double* pa = a.data() + (na == 1 ? 0 : 3 * r);
          const double* pb = b.data() + (nb == 1 ? 0 : 3 * r);
          const Pose2<double> c =
              Pose2<double>{pa[0], pa[1], pa[2]} * Pose2<double>{pb[0], pb[1], pb[2]};
          o[3 * r] = c.x;
          o[3 * r + 1] = c.y;
          o[3 * r + 2] = c.theta;
        }
        return std::move(out);
      },
      py::arg("a"), py::arg("b"),
      "Row-wise SE(2) product ^A T_B * ^B T_C (Pose's product) of (N, 3) or (3,) arrays (x m, y "
      "m, theta rad); a single pose broadcasts over the other's rows.");
}

/// pcr.Limb: one limb's parameters.
void bind_limb(py::module_& m) {
  auto limb =
      py::class_<LimbParams<double>>(
          m, "Limb", "One limb (rod + actuator), notation of Mauze et al. 2021 Fig. 3.")
          .def(py::init<>())
          .def_property(
              "A", [](LimbParams<double>& l) -> Eigen::Vector2d& { return l.A; },
              [](LimbParams<double>& l, const py::object& v) {
                l.A = to_vector<2>(v, "Limb.A", "x, y in m");
              },
              py::return_value_policy::reference_internal,
              "proximal clamp [x, y] in W at q = 0 (m)")
          .def_readwrite("alpha", &LimbParams<double>::alpha,
                         "rod tangent angle at the proximal clamp, in W (rad)")
          .def_readwrite("gamma", &LimbParams<double>::gamma,
                         "actuator misalignment: the clamp moves along alpha + gamma (rad)")
          .def_property(
              "B", [](LimbParams<double>& l) -> Eigen::Vector2d& { return l.B; },
              [](LimbParams<double>& l, const py::object& v) {
                l.B = to_vector<2>(v, "Limb.B", "x, y in m");
              },
              py::return_value_policy::reference_internal, "distal clamp [x, y] in P (m)")
          .def_readwrite("beta", &LimbParams<double>::beta,
                         "rod tangent angle at the distal clamp, in P (rad)")
          .def_property("l", rod_field<LimbParams<double>>(&Rod<double>::length),
                        rod_setter<LimbParams<double>>(&Rod<double>::length),
                        "stress-free rod length (m)")
          .def_property("d", rod_field<LimbParams<double>>(&Rod<double>::diameter),
                        rod_setter<LimbParams<double>>(&Rod<double>::diameter), "rod diameter (m)")
          .def_property("E", rod_field<LimbParams<double>>(&Rod<double>::young_modulus),
                        rod_setter<LimbParams<double>>(&Rod<double>::young_modulus),
                        "Young's modulus of this rod (Pa)")
          .def_property("precurvature", rod_field<LimbParams<double>>(&Rod<double>::precurvature),
                        rod_setter<LimbParams<double>>(&Rod<double>::precurvature),
                        "intrinsic curvature u*(0) of a rod shape-set to a curve (1/m, positive "
                        "counterclockwise); 0 for a straight rod")
          .def_property("precurvature_slope",
                        rod_field<LimbParams<double>>(&Rod<double>::precurvature_slope),
                        rod_setter<LimbParams<double>>(&Rod<double>::precurvature_slope),
                        "du*/ds (1/m^2): u*(s) = precurvature + precurvature_slope s")
          .def_property("diameter_slope",
                        rod_field<LimbParams<double>>(&Rod<double>::diameter_slope),
                        rod_setter<LimbParams<double>>(&Rod<double>::diameter_slope),
                        "dd/ds (m/m) of a tapered rod: d(s) = d + diameter_slope s; 0 for a "
                        "uniform rod")
          .def_property(
              "q_range",
              [](const LimbParams<double>& l) { return std::make_pair(l.q_min, l.q_max); },
              [](LimbParams<double>& l, const std::pair<double, double>& r) {
                l.q_min = r.first;
                l.q_max = r.second;
              },
              "actuator stroke (min, max) (m)")
          .def_property(
              "home_bow",
              [](const LimbParams<double>& l) -> py::object {
                if (l.home_bow == 0) return py::none();
                return py::str(l.home_bow > 0 ? "left" : "right");
              },
              [](LimbParams<double>& l, const py::object& side) {
                if (side.is_none()) {
                  l.home_bow = 0;
                } else if (py::isinstance<py::str>(side) && (side.cast<std::string>() == "left" ||
                                                             side.cast<std::string>() == "right")) {
                  l.home_bow = side.cast<std::string>() == "left" ? 1 : -1;
                } else {
                  throw py::value_error(
                      "Limb.home_bow: expected 'left', 'right' or None, "
                      "got " +
                      py::repr(side).cast<std::string>());
                }
              },
              "the side of the line between its clamps the rod bows to at home, 'left' "
              "or 'right' (which home a pre-stressed robot, n >= 4, is in), or None")
          .def_property_readonly(
              "EI", [](const LimbParams<double>& l) { return l.rod.bending_stiffness(); },
              "bending stiffness E pi d^4 / 64 (N m^2), at the proximal end of a tapered rod")
          .def("__repr__", [](const LimbParams<double>& l) {
            std::ostringstream s;
            s.precision(9);
            s << "Limb(A=[" << l.A.x() << ", " << l.A.y() << "], alpha=" << l.alpha
              << ", gamma=" << l.gamma << ", B=[" << l.B.x() << ", " << l.B.y()
              << "], beta=" << l.beta << ", l=" << l.rod.length << ", d=" << l.rod.diameter
              << ", E=" << l.rod.young_modulus;
            if (!l.rod.straight()) {
              s << ", precurvature=" << l.rod.precurvature
                << ", precurvature_slope=" << l.rod.precurvature_slope;
            }
            if (!l.rod.uniform()) s << ", diameter_slope=" << l.rod.diameter_slope;
            s << ", q_range=(" << l.q_min << ", " << l.q_max << ")"
              << (l.home_bow == 0  ? ""
                  : l.home_bow > 0 ? ", home_bow='left'"
                                   : ", home_bow='right'")
              << ")";
            return s.str();
          });
  def_value_semantics(limb);
}

/// pcr.Extrinsics: the measurement frames of Eq. 5.
void bind_extrinsics(py::module_& m) {
  auto extrinsics =
      py::class_<Extrinsics<double>>(
          m, "Extrinsics", "Measurement extrinsics (Eq. 5): ^W T_P = camera * ^Se T_M * pattern.")
          .def(py::init<>())
          .def_readwrite("camera", &Extrinsics<double>::camera, "^W T_Se: the camera frame in W")
          .def_readwrite("pattern", &Extrinsics<double>::pattern,
                         "^M T_P: the platform in the pattern frame")
          .def("platform_from_measurement", &Extrinsics<double>::platform_from_measurement,
               py::arg("camera_T_pattern"), "^W T_P from a measured pattern pose ^Se T_M.")
          .def("measurement_from_platform", &Extrinsics<double>::measurement_from_platform,
               py::arg("world_T_platform"),
               "^Se T_M that the camera sees for a platform pose ^W T_P.");
  def_value_semantics(extrinsics);
}

/// pcr.LimbUncertainty: one limb's half-widths.
void bind_limb_uncertainty(py::module_& m) {
  auto limb_uncertainty =
      py::class_<LimbUncertainty>(
          m, "LimbUncertainty", "Half-widths of one limb's uncertainty intervals (SI units, rad).")
          .def(py::init<>())
          .def_property(
              "A", [](LimbUncertainty& u) -> Eigen::Vector2d& { return u.A; },
              [](LimbUncertainty& u, const py::object& v) {
                u.A = to_vector<2>(v, "LimbUncertainty.A", "half-widths on x, y in m");
              },
              py::return_value_policy::reference_internal, "m, on [A_x, A_y]")
          .def_readwrite("alpha", &LimbUncertainty::alpha, "rad")
          .def_readwrite("gamma", &LimbUncertainty::gamma, "rad")
          .def_property(
              "B", [](LimbUncertainty& u) -> Eigen::Vector2d& { return u.B; },
              [](LimbUncertainty& u, const py::object& v) {
                u.B = to_vector<2>(v, "LimbUncertainty.B", "half-widths on x, y in m");
              },
              py::return_value_policy::reference_internal, "m, on [B_x, B_y]")
          .def_readwrite("beta", &LimbUncertainty::beta, "rad")
          .def_property("l", rod_field<LimbUncertainty>(&RodUncertainty::length),
                        rod_setter<LimbUncertainty>(&RodUncertainty::length), "m")
          .def_property("d", rod_field<LimbUncertainty>(&RodUncertainty::diameter),
                        rod_setter<LimbUncertainty>(&RodUncertainty::diameter), "m")
          .def_property("E", rod_field<LimbUncertainty>(&RodUncertainty::young_modulus),
                        rod_setter<LimbUncertainty>(&RodUncertainty::young_modulus), "Pa")
          .def_property("precurvature", rod_field<LimbUncertainty>(&RodUncertainty::precurvature),
                        rod_setter<LimbUncertainty>(&RodUncertainty::precurvature), "1/m");
  def_value_semantics(limb_uncertainty);
}

/// pcr.Uncertainty: the robot's half-widths.
void bind_uncertainty(py::module_& m) {
  auto uncertainty =
      py::class_<RobotUncertainty>(
          m, "Uncertainty",
          "Uncertainty half-widths: `global_` (top level), `limbs` (resolved "
          "per limb), camera and pattern ([x m, y m, theta rad]).")
          .def(py::init<>())
          .def_readwrite("global_", &RobotUncertainty::global, "the top-level half-widths")
          .def_property(
              "limbs",
              [](py::object self) {
                py::list limbs;
                for (LimbUncertainty& u : self.cast<RobotUncertainty&>().limbs) {
                  limbs.append(py::cast(&u, py::return_value_policy::reference_internal, self));
                }
                return limbs;
              },
              [](RobotUncertainty& u, const std::vector<LimbUncertainty>& limbs) {
                u.limbs = limbs;
              },
              "per-limb half-widths with the overrides applied (references, like Robot.limbs)")
          .def_property(
              "camera", [](RobotUncertainty& u) -> Eigen::Vector3d& { return u.camera; },
              [](RobotUncertainty& u, const py::object& v) {
                u.camera =
                    to_vector<3>(v, "Uncertainty.camera", "half-widths on x m, y m, theta rad");
              },
              py::return_value_policy::reference_internal, "on extrinsics.camera (m, m, rad)")
          .def_property(
              "pattern", [](RobotUncertainty& u) -> Eigen::Vector3d& { return u.pattern; },
              [](RobotUncertainty& u, const py::object& v) {
                u.pattern =
                    to_vector<3>(v, "Uncertainty.pattern", "half-widths on x m, y m, theta rad");
              },
              py::return_value_policy::reference_internal, "on extrinsics.pattern (m, m, rad)");
  def_value_semantics(uncertainty);
}

/// pcr.Robot: the description, its files and its parts (references into it).
void bind_robot_description(py::module_& m) {
  py::class_<RobotDescription>(m, "Robot",
                               "A planar parallel continuum robot: the pcr-robot JSON description "
                               "(docs/formats.md). SI units.")
      .def(py::init([] { return default_robot(); }), "The default robot (same as Robot.default()).")
      .def_static("default", &default_robot,
                  "The paper's 3-PF robot (femto-3pf) with the paper's uncertainty intervals.")
      .def_static(
          "load",
          [](const std::filesystem::path& path) -> py::object {
            const std::string file = input_path(path);
            if (load_robot_kind(file) == RobotKind::kSpatial) {
              return py::cast(load_spatial_robot(file));
            }
            return py::cast(load_robot(file));
          },
          py::arg("path"),
          "Reads a pcr-robot JSON file (str or os.PathLike): a Robot, or a SpatialRobot when the "
          "file says \"kind\": \"spatial\". FileNotFoundError when it does not exist, ValueError "
          "naming the file, field and value when it is not a valid robot.")
      .def_static(
          "from_json",
          [](const std::string& text, const std::string& source) -> py::object {
            if (robot_kind(text, source) == RobotKind::kSpatial) {
              return py::cast(parse_spatial_robot(text, source));
            }
            return py::cast(parse_robot(text, source));
          },
          py::arg("text"), py::arg("source") = "<string>",
          "Parses pcr-robot JSON text (a Robot, or a SpatialRobot for a spatial one); `source` "
          "names it in error messages.")
      .def(
          "save",
          [](const RobotDescription& r, const std::filesystem::path& path) {
            save_robot(r, output_path(path));
          },
          py::arg("path"),
          "Validates and writes the description atomically (temp file + rename) to `path` (str or "
          "os.PathLike).")
      .def_property_readonly(
          "parameters",
          [](const RobotDescription& r) {
            Eigen::VectorXd values(num_parameters(r.params.num_limbs));
            get_parameters(r.params, values.data());
            return values;
          },
          "(10 n + 6,) the flat parameters in parameter_names order (SI units), a copy")
      .def("to_json", &robot_to_json, "The canonical JSON text (full precision).")
      .def(
          "copy", [](const RobotDescription& r) { return r; }, "A deep copy.")
      .def("__copy__", [](const RobotDescription& r) { return r; })
      .def(
          "__deepcopy__", [](const RobotDescription& r, const py::dict&) { return r; },
          py::arg("memo"))
      .def(py::pickle([](const RobotDescription& r) { return robot_to_json(r); },
                      [](const std::string& text) { return parse_robot(text, "<pickle>"); }))
      .def_readwrite("name", &RobotDescription::name, "the description's name (str)")
      .def_property(
          "E", [](const RobotDescription& r) { return r.young_modulus; },
          [](RobotDescription& r, double e) {
            r.young_modulus = e;
            for (int i = 0; i < r.params.num_limbs; ++i) r.params.limb(i).rod.young_modulus = e;
          },
          "the global Young's modulus (Pa); setting it sets every limb's E too")
      .def_property_readonly(
          "num_limbs", [](const RobotDescription& r) { return r.params.num_limbs; },
          "number of limbs (rods)")
      .def_property(
          "limbs", [](py::object self) { return limb_list(self.cast<RobotDescription&>(), self); },
          &set_limbs,
          "the limbs (references: robot.limbs[0].l = x edits the robot); assign a list of Limb "
          "to replace them")
      .def_property(
          "extrinsics",
          [](RobotDescription& r) -> Extrinsics<double>& { return r.params.extrinsics; },
          [](RobotDescription& r, const Extrinsics<double>& e) { r.params.extrinsics = e; },
          py::return_value_policy::reference_internal, "measurement extrinsics (Eq. 5)")
      .def_property(
          "uncertainty",
          [](py::object self) -> py::object {
            RobotDescription& r = self.cast<RobotDescription&>();
            if (!r.uncertainty) return py::none();
            return py::cast(&*r.uncertainty, py::return_value_policy::reference_internal, self);
          },
          [](RobotDescription& r, std::optional<RobotUncertainty> u) {
            r.uncertainty = std::move(u);
          },
          "uncertainty half-widths, or None (every parameter known exactly)")
      .def("__repr__", [](const RobotDescription& r) {
        return "<pcr.Robot '" + r.name + "' with " + std::to_string(r.params.num_limbs) + " limbs>";
      });
}

}  // namespace

void wrap_robot(py::module_& m) {
  bind_pose(m);
  bind_compose_poses(m);
  bind_limb(m);
  bind_extrinsics(m);
  bind_limb_uncertainty(m);
  bind_uncertainty(m);
  bind_robot_description(m);
}

}  // namespace pcr::python
