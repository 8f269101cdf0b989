// pcr.SpatialRobot (a spatial robot file, pcr/spatial/robot_io.hpp), pcr.SpatialLimb, and its
// kinematics: SpatialRobot.forward / inverse / home, pcr.SpatialSolution, pcr.SpatialBatchResult.
// The planar robot's API (wrap_robot.cpp, wrap_kinematics.cpp) for the spatial solvers of
// pcr/spatial/kinematics.hpp; rows of a batch solved as `pcr fk` / `pcr ik` solve a spatial file's.
#include <array>
#include <cmath>
#include <memory>
#include <sstream>

#include "bindings.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "solve.hpp"
#include "summary.hpp"

namespace pcr::python {

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using SpatialWrenches = std::array<SpatialWrench<double>, kMaxSpatialRods>;

/// A solved configuration of a spatial robot as Python sees it (Solution's counterpart).
struct SpatialSolution {
  int num_rods = 0;
  SpatialJointVector q;
  SpatialPose<double> pose;
  SpatialWrenches wrenches{};
  SolverSummary summary;
  py::object shapes = py::none();
  /// What the solve leaves for a warm start of the same problem (FK or IK); not pickled.
  SpatialWarmStart warm;
  bool inverse = false;
};

/// Arrays of a spatial batch: the values, and the summary arrays.
struct SpatialBatchResult : SummaryArrays {
  py::array_t<double> q, position, quaternion, rotation, rotation_vector, wrenches;
  /// Every field, in the order of its pickled state.
  auto fields() {
    return std::tuple_cat(std::tie(q, position, quaternion, rotation, rotation_vector, wrenches),
                          SummaryArrays::fields());
  }
};

std::string numbers_text(const double* v, int size) {
  std::ostringstream s;
  s.precision(9);
  s << "(";
  for (int k = 0; k < size; ++k) s << (k ? ", " : "") << v[k];
  s << ")";
  return s.str();
}

std::string row_text(bool many, py::ssize_t row) {
  return many ? " in row " + std::to_string(row) : std::string();
}

/// A unit vector (a quaternion, a direction) within the files' tolerance; ValueError naming
/// `name` and showing the values and their norm otherwise.
template <int N>
Eigen::Matrix<double, N, 1> unit_vector(const double* v, const char* name, const char* meaning,
                                        const std::string& where = "") {
  const Eigen::Matrix<double, N, 1> out = Eigen::Map<const Eigen::Matrix<double, N, 1>>(v);
  const double norm = out.norm();
  if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
    std::ostringstream s;
    s << name << ": expected " << meaning << " of unit norm (within " << kUnitQuaternionTolerance
      << "), got " << numbers_text(v, N) << where << ", of norm " << norm;
    throw std::invalid_argument(s.str());
  }
  return out;
}

/// A property setter of a unit vector: N finite numbers of unit norm.
template <int N>
Eigen::Matrix<double, N, 1> unit_argument(const py::handle& value, const char* name,
                                          const char* meaning) {
  const Eigen::Matrix<double, N, 1> v = to_vector<N>(value, name, meaning);
  return unit_vector<N>(v.data(), name, meaning);
}

/// The rotation R (row-major 3 x 3) as a quaternion, when it is one: R^T R = I within the files'
/// tolerance and det R = +1; ValueError naming `rotation` otherwise.
Vector4<double> rotation_quaternion(const double* values, const std::string& where) {
  const Matrix3<double> R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values);
  const double off = (R.transpose() * R - Matrix3<double>::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (!(off <= kUnitQuaternionTolerance) || !(det > 0)) {
    std::ostringstream s;
    s << "rotation: expected a rotation matrix (R^T R = I within " << kUnitQuaternionTolerance
      << ", det R = 1), got " << numbers_text(values, 9) << where << ": |R^T R - I| = " << off
      << ", det R = " << det;
    throw std::invalid_argument(s.str());
  }
  return quaternion_of(R);
}

/// The poses of SpatialRobot.inverse: a position (3,) or (N, 3) and at most one orientation,
/// given once (broadcast) or per row. `single`: both given once.
std::vector<SpatialPose<double>> input_poses(const py::object& position_in,
                                             const py::object& rotation_in,
                                             const py::object& quaternion_in,
                                             const py::object& rotation_vector_in, bool& single) {
  const InputArray position = input_array(position_in, 3, "position", "x, y, z in m");
  const int given =
      !rotation_in.is_none() + !quaternion_in.is_none() + !rotation_vector_in.is_none();
  if (given > 1) {
    throw std::invalid_argument(
        "inverse: the orientation is given once, as rotation, quaternion or rotation_vector; got " +
        std::to_string(given) + " of them");
  }
  // The orientation's rows (one each), how many, and how one is read.
  InputArray orientation = position;  // no orientation: unused
  py::ssize_t orientation_rows = 1;
  bool orientation_many = false;
  if (!quaternion_in.is_none()) {
    orientation = input_array(quaternion_in, 4, "quaternion", "w, x, y, z");
  } else if (!rotation_vector_in.is_none()) {
    orientation = input_array(rotation_vector_in, 3, "rotation_vector",
                              "rx, ry, rz in rad: angle times axis");
  } else if (!rotation_in.is_none()) {
    orientation = as_input_array(rotation_in);
    const bool shaped = orientation && (orientation.ndim() == 2 || orientation.ndim() == 3) &&
                        orientation.shape(orientation.ndim() - 1) == 3 &&
                        orientation.shape(orientation.ndim() - 2) == 3;
    if (!shaped) {
      throw std::invalid_argument(
          "rotation: expected a (3, 3) rotation matrix or an (N, 3, 3) array, got " +
          describe_value(rotation_in));
    }
    for (py::ssize_t k = 0; k < orientation.size(); ++k) {
      if (!std::isfinite(orientation.data()[k])) {
        throw std::invalid_argument(
            "rotation: non-finite value " +
            py::repr(py::float_(orientation.data()[k])).cast<std::string>() + " at entry " +
            std::to_string(k % 9) + row_text(orientation.ndim() == 3, k / 9));
      }
    }
  }
  if (given == 1) {
    orientation_many = orientation.ndim() == (rotation_in.is_none() ? 2 : 3);
    orientation_rows = orientation_many ? orientation.shape(0) : 1;
  }
  const bool position_many = position.ndim() == 2;
  const py::ssize_t position_rows = position_many ? position.shape(0) : 1;
  if (position_many && orientation_many && position_rows != orientation_rows) {
    throw std::invalid_argument("inverse: " + std::to_string(position_rows) + " positions and " +
                                std::to_string(orientation_rows) +
                                " orientations; give one orientation or one per position");
  }
  single = !position_many && !orientation_many;
  const py::ssize_t rows = std::max(position_rows, orientation_rows);
  std::vector<SpatialPose<double>> poses(static_cast<std::size_t>(rows));
  const bool many = !single;
  for (py::ssize_t r = 0; r < rows; ++r) {
    SpatialPose<double>& pose = poses[static_cast<std::size_t>(r)];
    const double* p = position.data() + (position_many ? 3 * r : 0);
    pose.position = Vector3<double>(p[0], p[1], p[2]);
    const py::ssize_t o = orientation_many ? r : 0;
    if (!quaternion_in.is_none()) {
      pose.orientation = unit_vector<4>(orientation.data() + 4 * o, "quaternion",
                                        "a quaternion (w, x, y, z)", row_text(many, o));
    } else if (!rotation_vector_in.is_none()) {
      const double* v = orientation.data() + 3 * o;
      pose.orientation = quaternion_exp(Vector3<double>(v[0], v[1], v[2]));
    } else if (!rotation_in.is_none()) {
      pose.orientation = rotation_quaternion(orientation.data() + 9 * o, row_text(many, o));
    }
  }
  return poses;
}

/// The rods' shapes of a configuration: one (steps + 1, 8) array per rod, s, x, y, z (m) and the
/// rod's frame as a quaternion (w, x, y, z), w >= 0, in W.
py::list spatial_rod_shapes(const SpatialRobotParams<double>& robot, const SpatialJointVector& q,
                            const SpatialWrenches& wrenches, int rod_steps) {
  py::list out;
  for (int i = 0; i < robot.num_rods; ++i) {
    const SpatialLimbParams<double>& limb = robot.limb(i);
    RowMatrix shape(rod_steps + 1, 8);
    int row = 0;
    sample_spatial_rod(spatial_proximal_state(limb, q(i), wrenches[i]), limb.rod_at(q(i)),
                       robot.gravity, rod_steps,
                       [&](double s, const SpatialRodState<double>& node) {
                         if (row > rod_steps) return;
                         const Vector4<double> h = canonical_quaternion(node.orientation);
                         shape.row(row++) << s, node.position.transpose(), h.transpose();
                       });
    out.append(py::cast(shape));
  }
  return out;
}

/// The Python view of a solution; values NaN when it is not usable, except FK's q, which echoes
/// `input_q`.
template <class S>
SpatialSolution spatial_solution(const SpatialRobotParams<double>& robot, const S& s, bool shapes,
                                 const SpatialJointVector* input_q = nullptr) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int n = robot.num_rods;
  const bool usable = is_equilibrium(s.summary);
  SpatialSolution out;
  out.num_rods = n;
  out.summary = s.summary;
  out.q = s.q;
  if (!usable) out.q.setConstant(n, nan);
  if (input_q != nullptr) out.q = *input_q;
  out.pose = s.pose;
  if (usable) {
    out.pose.orientation = canonical_quaternion(s.pose.orientation);
  } else {
    out.pose.position.setConstant(nan);
    out.pose.orientation.setConstant(nan);
  }
  out.wrenches = s.wrenches;
  for (int i = 0; i < n && !usable; ++i) {
    out.wrenches[i].force.setConstant(nan);
    out.wrenches[i].moment.setConstant(nan);
  }
  if (!usable) out.summary.max_strain = nan;
  if (usable && shapes)
    out.shapes = spatial_rod_shapes(robot, s.q, s.wrenches, s.summary.rod_steps);
  out.warm = s.warm;
  out.inverse = std::is_same_v<S, SpatialInverseSolution>;
  return out;
}

/// A SpatialSolution as the C++ solvers take a warm start (FK's or IK's); the solver's
/// factorisation only when it was solved for the same problem.
template <class S>
S as_spatial(const SpatialSolution& s) {
  S out;
  out.q = s.q;
  out.pose = s.pose;
  out.wrenches = s.wrenches;
  out.summary = s.summary;
  if (s.inverse == std::is_same_v<S, SpatialInverseSolution>) out.warm = s.warm;
  return out;
}

/// A warm start to solve from: the solution's, when it is usable (else a cold solve); a
/// solution of a robot with another rod count is refused.
template <class S>
std::unique_ptr<S> warm_start_of(const std::optional<SpatialSolution>& warm_start, int n) {
  if (!warm_start) return nullptr;
  if (warm_start->num_rods != n) {
    throw std::invalid_argument("warm_start: a solution of a robot with " +
                                std::to_string(warm_start->num_rods) + " rods; this one has " +
                                std::to_string(n));
  }
  if (!usable_as_warm_start(warm_start->summary)) return nullptr;
  return std::make_unique<S>(as_spatial<S>(*warm_start));
}

SpatialBatchResult allocate_spatial_batch(py::ssize_t rows, int n, SpatialBatchBuffers& buffers) {
  SpatialBatchResult b;
  const auto rods = static_cast<py::ssize_t>(n);
  b.q = py::array_t<double>({rows, rods});
  b.position = py::array_t<double>({rows, py::ssize_t{3}});
  b.quaternion = py::array_t<double>({rows, py::ssize_t{4}});
  b.rotation = py::array_t<double>({rows, py::ssize_t{3}, py::ssize_t{3}});
  b.rotation_vector = py::array_t<double>({rows, py::ssize_t{3}});
  b.wrenches = py::array_t<double>({rows, rods, py::ssize_t{6}});
  buffers = SpatialBatchBuffers{
      b.q.mutable_data(),        b.position.mutable_data(),        b.quaternion.mutable_data(),
      b.rotation.mutable_data(), b.rotation_vector.mutable_data(), b.wrenches.mutable_data(),
      b.allocate(rows)};
  return b;
}

/// The batch's shapes (with shapes=True): per row, the rods' shapes or None when it failed.
template <class S>
py::list batch_shapes(const SpatialRobotParams<double>& robot, const std::vector<S>& solutions) {
  py::list all;
  for (const S& s : solutions) {
    all.append(is_equilibrium(s.summary)
                   ? py::object(spatial_rod_shapes(robot, s.q, s.wrenches, s.summary.rod_steps))
                   : py::object(py::none()));
  }
  return all;
}

py::object spatial_forward(const SpatialRobotDescription& robot, const py::object& q_in,
                           const std::optional<SpatialSolution>& warm_start, bool shapes,
                           const std::optional<SolverOptions>& options_in, bool path) {
  const SpatialRobotParams<double>& params = robot.params;
  const int n = params.num_rods;
  const InputArray q = input_array(q_in, n, "q", "m");
  const SolverOptions options = options_or_default(options_in);
  if (q.ndim() == 1) {
    SpatialJointVector joints(n);
    for (int i = 0; i < n; ++i) joints(i) = q.at(i);
    const auto warm = warm_start_of<SpatialForwardSolution>(warm_start, n);
    SpatialForwardSolution s;
    {
      py::gil_scoped_release release;
      s = SequenceTraits<SpatialForwardSolution>::continued(params, joints, warm.get(), options,
                                                            SpatialNoLoad());
    }
    return py::cast(spatial_solution(params, s, shapes, &joints));
  }
  if (warm_start) throw std::invalid_argument("warm_start: only for a single configuration");
  const py::ssize_t rows = q.shape(0);
  SpatialBatchBuffers buffers{};
  SpatialBatchResult batch = allocate_spatial_batch(rows, n, buffers);
  std::vector<SpatialForwardSolution> solutions(shapes ? static_cast<std::size_t>(rows) : 0);
  {
    py::gil_scoped_release release;
    spatial_forward_batch(params, q.data(), rows, options, sequence_mode(path), buffers,
                          shapes ? solutions.data() : nullptr);
  }
  batch.name_statuses();
  if (shapes) batch.shapes = batch_shapes(params, solutions);
  return py::cast(std::move(batch));
}

py::object spatial_inverse(const SpatialRobotDescription& robot, const py::object& position,
                           const py::object& rotation, const py::object& quaternion,
                           const py::object& rotation_vector,
                           const std::optional<SpatialSolution>& warm_start, bool shapes,
                           const std::optional<SolverOptions>& options_in, bool path) {
  // The rod counts the solver takes are its own to say (status 'unsupported' for the others).
  const SpatialRobotParams<double>& params = robot.params;
  const int n = params.num_rods;
  bool single = false;
  const std::vector<SpatialPose<double>> poses =
      input_poses(position, rotation, quaternion, rotation_vector, single);
  const SolverOptions options = options_or_default(options_in);
  if (single) {
    const auto warm = warm_start_of<SpatialInverseSolution>(warm_start, n);
    SpatialInverseSolution s;
    {
      py::gil_scoped_release release;
      s = SequenceTraits<SpatialInverseSolution>::continued(params, poses[0], warm.get(), options,
                                                            SpatialNoLoad());
    }
    return py::cast(spatial_solution(params, s, shapes));
  }
  if (warm_start) throw std::invalid_argument("warm_start: only for a single pose");
  const auto rows = static_cast<py::ssize_t>(poses.size());
  SpatialBatchBuffers buffers{};
  SpatialBatchResult batch = allocate_spatial_batch(rows, n, buffers);
  std::vector<SpatialInverseSolution> solutions(shapes ? poses.size() : 0);
  {
    py::gil_scoped_release release;
    spatial_inverse_batch(params, poses.data(), rows, options, sequence_mode(path), buffers,
                          shapes ? solutions.data() : nullptr);
  }
  batch.name_statuses();
  if (shapes) batch.shapes = batch_shapes(params, solutions);
  return py::cast(std::move(batch));
}

/// A property of an enumeration read and written by its file name (pcr::to_string).
template <class Owner, class E>
auto named_getter(E Owner::*field) {
  return [field](const Owner& owner) { return std::string(to_string(owner.*field)); };
}
template <class Owner, class E>
auto named_setter(E Owner::*field, const char* name, std::array<E, 2> values) {
  return [field, name, values](Owner& owner, const std::string& text) {
    for (const E value : values) {
      if (text == to_string(value)) {
        owner.*field = value;
        return;
      }
    }
    throw std::invalid_argument(std::string(name) + ": expected '" + to_string(values[0]) +
                                "' or '" + to_string(values[1]) + "', got '" + text + "'");
  };
}

/// pcr.SpatialLimb: one rod and how it is held.
void bind_spatial_limb(py::module_& m) {
  using Limb = SpatialLimbParams<double>;
  using Rod = SpatialRod<double>;
  const auto point_setter = [](Vector3<double> Limb::*field, const char* name) {
    return [field, name](Limb& l, const py::object& v) {
      l.*field = to_vector<3>(v, name, "x, y, z in m");
    };
  };
  const auto quaternion_setter = [](Vector4<double> Limb::*field, const char* name) {
    return [field, name](Limb& l, const py::object& v) {
      l.*field = unit_argument<4>(v, name, "a quaternion (w, x, y, z)");
    };
  };
  auto limb =
      py::class_<Limb>(m, "SpatialLimb",
                       "One rod of a spatial robot and how it is held: the fields of a spatial "
                       "robot file's rod (docs/formats.md, \"Spatial robots\"). SI units; "
                       "quaternions (w, x, y, z), body -> parent.")
          .def(py::init<>())
          .def_property("length", rod_field<Limb>(&Rod::length), rod_setter<Limb>(&Rod::length),
                        "stress-free length (m); the free length at q = 0 of a rod pushed "
                        "through its hole")
          .def_property("diameter", rod_field<Limb>(&Rod::diameter),
                        rod_setter<Limb>(&Rod::diameter), "rod diameter (m)")
          .def_property("young_modulus", rod_field<Limb>(&Rod::young_modulus),
                        rod_setter<Limb>(&Rod::young_modulus), "Young's modulus E (Pa)")
          .def_property("shear_modulus", rod_field<Limb>(&Rod::shear_modulus),
                        rod_setter<Limb>(&Rod::shear_modulus), "shear modulus G (Pa)")
          .def_property("density", rod_field<Limb>(&Rod::density), rod_setter<Limb>(&Rod::density),
                        "density (kg/m^3): the rod's weight under the robot's gravity")
          .def_property("shear_and_extension", rod_field<Limb>(&Rod::shear_and_extension),
                        rod_setter<Limb>(&Rod::shear_and_extension),
                        "False: a Kirchhoff rod (inextensible, unshearable); True: Cosserat")
          .def_property(
              "intrinsic_curvature",
              [](Limb& l) -> Vector3<double>& { return l.rod.intrinsic_curvature; },
              [](Limb& l, const py::object& v) {
                l.rod.intrinsic_curvature =
                    to_vector<3>(v, "SpatialLimb.intrinsic_curvature", "u1*, u2*, u3* in 1/m");
              },
              py::return_value_policy::reference_internal,
              "(3,) u* of the stress-free rod in its body frame (1/m): curvatures about d1, d2, "
              "twist")
          .def_property(
              "A", [](Limb& l) -> Vector3<double>& { return l.A; },
              point_setter(&Limb::A, "SpatialLimb.A"), py::return_value_policy::reference_internal,
              "(3,) the hole (or the clamp at q = 0) in W (m): the rod's proximal end")
          .def_property(
              "base_orientation", [](Limb& l) -> Vector4<double>& { return l.base_orientation; },
              quaternion_setter(&Limb::base_orientation, "SpatialLimb.base_orientation"),
              py::return_value_policy::reference_internal,
              "(4,) the rod's frame at A, body -> W (w, x, y, z): it leaves A along its d3")
          .def_property("actuation", named_getter(&Limb::actuation),
                        named_setter(&Limb::actuation, "SpatialLimb.actuation",
                                     {SpatialActuation::kLengthThroughHole,
                                      SpatialActuation::kTranslatedClamp}),
                        "'length_through_hole' (q lengthens the free rod) or 'translated_clamp' "
                        "(q moves the clamp along actuator_direction)")
          .def_property(
              "actuator_direction",
              [](Limb& l) -> Vector3<double>& { return l.actuator_direction; },
              [](Limb& l, const py::object& v) {
                l.actuator_direction =
                    unit_argument<3>(v, "SpatialLimb.actuator_direction", "a direction");
              },
              py::return_value_policy::reference_internal,
              "(3,) unit direction in W along which q moves a translated clamp")
          .def_property(
              "B", [](Limb& l) -> Vector3<double>& { return l.B; },
              point_setter(&Limb::B, "SpatialLimb.B"), py::return_value_policy::reference_internal,
              "(3,) the attachment point on the platform, in P (m)")
          .def_property(
              "tip_orientation", [](Limb& l) -> Vector4<double>& { return l.tip_orientation; },
              quaternion_setter(&Limb::tip_orientation, "SpatialLimb.tip_orientation"),
              py::return_value_policy::reference_internal,
              "(4,) a clamped rod's tip frame in P (w, x, y, z)")
          .def_property("attachment", named_getter(&Limb::attachment),
                        named_setter(&Limb::attachment, "SpatialLimb.attachment",
                                     {SpatialAttachment::kClamped, SpatialAttachment::kSpherical}),
                        "'clamped' (position and orientation) or 'spherical' (a ball joint)")
          .def_property_readonly(
              "EI", [](const Limb& l) { return l.rod.bending_stiffness(); },
              "bending stiffness E pi d^4 / 64 (N m^2)")
          .def("__repr__", [](const Limb& l) {
            std::ostringstream s;
            s.precision(9);
            s << "SpatialLimb(length=" << l.rod.length << ", diameter=" << l.rod.diameter
              << ", A=" << numbers_text(l.A.data(), 3) << ", B=" << numbers_text(l.B.data(), 3)
              << ", actuation='" << to_string(l.actuation) << "', attachment='"
              << to_string(l.attachment) << "')";
            return s.str();
          });
  def_value_semantics(limb);
}

/// pcr.SpatialRobot: the description, its file and its rods (references into it).
void bind_spatial_robot(py::module_& m) {
  using Description = SpatialRobotDescription;
  const auto robot_vector = [](Vector3<double> SpatialRobotParams<double>::*field, const char* name,
                               const char* meaning) {
    return std::make_pair([field](Description& r) -> Vector3<double>& { return r.params.*field; },
                          [field, name, meaning](Description& r, const py::object& v) {
                            r.params.*field = to_vector<3>(v, name, meaning);
                          });
  };
  const auto centre = robot_vector(&SpatialRobotParams<double>::platform_centre_of_mass,
                                   "SpatialRobot.platform_centre_of_mass", "x, y, z in m");
  const auto gravity = robot_vector(&SpatialRobotParams<double>::gravity, "SpatialRobot.gravity",
                                    "gx, gy, gz in m/s^2");
  const auto force = robot_vector(&SpatialRobotParams<double>::external_force,
                                  "SpatialRobot.external_force", "fx, fy, fz in N");
  const auto moment = robot_vector(&SpatialRobotParams<double>::external_moment,
                                   "SpatialRobot.external_moment", "mx, my, mz in N m");
  const auto reference = [] { return continuum_stewart_gough_description(); };
  py::class_<Description>(
      m, "SpatialRobot",
      "A spatial parallel continuum robot: a pcr-robot JSON file with \"kind\": \"spatial\" "
      "(docs/formats.md, \"Spatial robots\"), Cosserat rods between a base and a rigid platform. "
      "SI units; poses ^W T_P. Robot.load gives one for a spatial file.")
      .def(py::init(reference), "The reference robot (same as SpatialRobot.reference()).")
      .def_static("reference", reference,
                  "The continuum Stewart-Gough robot (Black, Till and Rucker 2018), as "
                  "robots/continuum-stewart-gough.json describes it.")
      .def_static(
          "load",
          [](const std::filesystem::path& path) { return load_spatial_robot(input_path(path)); },
          py::arg("path"),
          "Reads a spatial pcr-robot JSON file (str or os.PathLike): FileNotFoundError when it "
          "does not exist, ValueError naming the file, field and value when it is not a valid "
          "spatial robot (a planar one included; Robot.load reads either kind).")
      .def_static("from_json", &parse_spatial_robot, py::arg("text"),
                  py::arg("source") = "<string>",
                  "Parses spatial pcr-robot JSON text; `source` names it in error messages.")
      .def(
          "save",
          [](const Description& r, const std::filesystem::path& path) {
            save_spatial_robot(r, output_path(path));
          },
          py::arg("path"),
          "Validates and writes the description atomically (temp file + rename) to `path` (str or "
          "os.PathLike).")
      .def("to_json", &spatial_robot_to_json, "The canonical JSON text (full precision).")
      .def(
          "copy", [](const Description& r) { return r; }, "A deep copy.")
      .def("__copy__", [](const Description& r) { return r; })
      .def(
          "__deepcopy__", [](const Description& r, const py::dict&) { return r; }, py::arg("memo"))
      .def(
          py::pickle([](const Description& r) { return spatial_robot_to_json(r); },
                     [](const std::string& text) { return parse_spatial_robot(text, "<pickle>"); }))
      .def_readwrite("name", &Description::name, "the description's name (str)")
      .def_property_readonly(
          "num_rods", [](const Description& r) { return r.params.num_rods; }, "number of rods")
      .def_property(
          "rods",
          [](py::object self) {
            Description& r = self.cast<Description&>();
            py::list rods;
            for (int i = 0; i < r.params.num_rods; ++i) {
              rods.append(
                  py::cast(&r.params.limb(i), py::return_value_policy::reference_internal, self));
            }
            return rods;
          },
          [](Description& r, const std::vector<SpatialLimbParams<double>>& rods) {
            if (rods.empty() || rods.size() > static_cast<std::size_t>(kMaxSpatialRods)) {
              throw std::invalid_argument("SpatialRobot.rods: expected 1 to " +
                                          std::to_string(kMaxSpatialRods) + " rods, got " +
                                          std::to_string(rods.size()));
            }
            r.params.num_rods = static_cast<int>(rods.size());
            for (std::size_t i = 0; i < static_cast<std::size_t>(kMaxSpatialRods); ++i) {
              r.params.limbs[i] = i < rods.size() ? rods[i] : SpatialLimbParams<double>();
            }
          },
          "the rods (references: robot.rods[0].length = x edits the robot); assign a list of "
          "SpatialLimb to replace them")
      .def_property(
          "platform_mass", [](const Description& r) { return r.params.platform_mass; },
          [](Description& r, double v) { r.params.platform_mass = v; }, "kg")
      .def_property("platform_centre_of_mass", centre.first, centre.second,
                    py::return_value_policy::reference_internal, "(3,) in P (m)")
      .def_property("gravity", gravity.first, gravity.second,
                    py::return_value_policy::reference_internal,
                    "(3,) in W (m/s^2): acts on the rods and the platform")
      .def_property("external_force", force.first, force.second,
                    py::return_value_policy::reference_internal,
                    "(3,) on the platform at P's origin, in W (N)")
      .def_property("external_moment", moment.first, moment.second,
                    py::return_value_policy::reference_internal, "(3,) on the platform, in W (N m)")
      .def("__repr__", [](const Description& r) {
        return "<pcr.SpatialRobot '" + r.name + "' with " + std::to_string(r.params.num_rods) +
               " rods>";
      });
}

/// pcr.SpatialSolution: one solved configuration of a spatial robot.
void bind_spatial_solution(py::module_& m) {
  using S = SpatialSolution;
  auto solution = py::class_<S>(
      m, "SpatialSolution",
      "One solved configuration of a spatial robot. When the solve failed (converged is False; "
      "out_of_range is a valid equilibrium) the pose and wrenches are NaN (FK keeps its q).");
  def_summary_properties(solution);
  def_solution_copies(solution);
  solution
      .def_property_readonly(
          "q", [](const S& s) -> Eigen::VectorXd { return s.q; }, "(n,) joint values (m)")
      .def_property_readonly(
          "position", [](const S& s) -> Eigen::Vector3d { return s.pose.position; },
          "(3,) the platform's origin in W (m)")
      .def_property_readonly(
          "quaternion", [](const S& s) -> Eigen::Vector4d { return s.pose.orientation; },
          "(4,) the platform's orientation P -> W as a unit quaternion (w, x, y, z), w >= 0")
      .def_property_readonly(
          "rotation", [](const S& s) -> Eigen::Matrix3d { return rotation_of(s.pose.orientation); },
          "(3, 3) the platform's rotation matrix P -> W (its columns: P's axes in W)")
      .def_property_readonly(
          "rotation_vector",
          [](const S& s) -> Eigen::Vector3d { return quaternion_log(s.pose.orientation); },
          "(3,) the orientation as angle (rad, in [0, pi]) times axis, the rx, ry, rz of `pcr fk`")
      .def_property_readonly(
          "wrenches",
          [](const S& s) {
            RowMatrix w(s.num_rods, 6);
            for (int i = 0; i < s.num_rods; ++i) {
              w.row(i) << s.wrenches[i].force.transpose(), s.wrenches[i].moment.transpose();
            }
            return w;
          },
          "(n, 6) each rod's proximal force (N) and moment (N m), in W")
      .def_readonly("shapes", &S::shapes,
                    "None, or (with shapes=True) one (steps + 1, 8) array per rod: s, x, y, z (m) "
                    "and the rod's frame as a quaternion (w, x, y, z), in W")
      .def("__repr__",
           [](const S& s) {
             return "<pcr.SpatialSolution " + std::string(to_string(s.summary.status)) + ", " +
                    std::to_string(s.summary.iterations) + " iterations>";
           })
      // The solver's factorised Jacobian is not pickled, as Solution's.
      .def(py::pickle(
          [](const S& s) {
            SolverSummary summary = s.summary;
            RowMatrix wrenches(s.num_rods, 6);
            for (int i = 0; i < s.num_rods; ++i) {
              wrenches.row(i) << s.wrenches[i].force.transpose(), s.wrenches[i].moment.transpose();
            }
            return py::make_tuple(s.num_rods, Eigen::VectorXd(s.q),
                                  Eigen::Vector3d(s.pose.position),
                                  Eigen::Vector4d(s.pose.orientation), wrenches,
                                  fields_to_tuple(summary_fields(summary)), s.shapes, s.inverse);
          },
          [](const py::tuple& state) {
            const auto bad = [] { return py::value_error("SpatialSolution: not a pickled one"); };
            if (state.size() != 8) throw bad();
            S s;
            s.num_rods = state[0].cast<int>();
            if (s.num_rods < 1 || s.num_rods > kMaxSpatialRods) throw bad();
            const Eigen::VectorXd q = state[1].cast<Eigen::VectorXd>();
            const RowMatrix wrenches = state[4].cast<RowMatrix>();
            if (q.size() != s.num_rods || wrenches.rows() != s.num_rods || wrenches.cols() != 6) {
              throw bad();
            }
            s.q = q;
            s.pose.position = state[2].cast<Eigen::Vector3d>();
            s.pose.orientation = state[3].cast<Eigen::Vector4d>();
            for (int i = 0; i < s.num_rods; ++i) {
              s.wrenches[i].force = wrenches.row(i).head<3>().transpose();
              s.wrenches[i].moment = wrenches.row(i).tail<3>().transpose();
            }
            fields_from_tuple(summary_fields(s.summary), state[5].cast<py::tuple>(),
                              "SpatialSolution.summary");
            s.shapes = state[6];
            s.inverse = state[7].cast<bool>();
            return s;
          }));
}

/// pcr.SpatialBatchResult: the arrays of a spatial batch.
void bind_spatial_batch_result(py::module_& m) {
  using B = SpatialBatchResult;
  auto batch = py::class_<B>(m, "SpatialBatchResult",
                             "Results of a spatial batch, one row per input row. Rows that failed "
                             "have NaN values (FK keeps its input q, IK its input pose).");
  def_summary_arrays(batch, "SpatialBatchResult",
                     "None, or a list (one per row) of None or per-rod (steps + 1, 8) arrays");
  batch.def_readonly("q", &B::q, "(N, n) joint values (m)")
      .def_readonly("position", &B::position, "(N, 3) platform positions in W (m)")
      .def_readonly("quaternion", &B::quaternion,
                    "(N, 4) platform orientations P -> W as unit quaternions (w, x, y, z), w >= 0")
      .def_readonly("rotation", &B::rotation, "(N, 3, 3) platform rotation matrices P -> W")
      .def_readonly("rotation_vector", &B::rotation_vector,
                    "(N, 3) orientations as angle (rad) times axis, the rx, ry, rz of `pcr fk`")
      .def_readonly("wrenches", &B::wrenches,
                    "(N, n, 6) proximal forces (N) and moments (N m), in W")
      .def(py::pickle([](B b) { return fields_to_tuple(b.fields()); },
                      [](const py::tuple& state) {
                        B b;
                        fields_from_tuple(b.fields(), state, "SpatialBatchResult");
                        return b;
                      }));
}

/// SpatialRobot.forward, inverse and home, added to the class bind_spatial_robot registered.
void bind_spatial_kinematics(py::module_& m) {
  auto robot = py::reinterpret_borrow<py::class_<SpatialRobotDescription>>(m.attr("SpatialRobot"));
  robot
      .def("forward", &spatial_forward, py::arg("q"), py::kw_only(),
           py::arg("warm_start") = py::none(), py::arg("shapes") = false,
           py::arg("options") = py::none(), py::arg("path") = false,
           "Forward kinematics. q: n joint values (m) -> SpatialSolution, warm-started from "
           "`warm_start` (a usable SpatialSolution; else from straight rods); or an (N, n) array "
           "-> SpatialBatchResult, as `pcr fk` solves a spatial file's rows: each on its own "
           "(from straight rods), or with path=True each continued from the previous usable one "
           "(retried cold when that fails). The load is the robot's (gravity, external_force, "
           "external_moment). Releases the GIL.")
      .def("inverse", &spatial_inverse, py::arg("position"), py::kw_only(),
           py::arg("rotation") = py::none(), py::arg("quaternion") = py::none(),
           py::arg("rotation_vector") = py::none(), py::arg("warm_start") = py::none(),
           py::arg("shapes") = false, py::arg("options") = py::none(), py::arg("path") = false,
           "Inverse kinematics: six rods impose the whole pose; five the position and the "
           "platform's normal, three the position, the rest of the orientation solved (the "
           "solution's is the solved one); other rod counts give status 'unsupported'. "
           "position: (3,) in W (m), with the platform's "
           "orientation P -> W given at most once by keyword: rotation (a (3, 3) rotation "
           "matrix), quaternion (w, x, y, z, unit) or rotation_vector (angle times axis, rad, as "
           "`pcr ik`'s rx, ry, rz); none: the identity -> SpatialSolution. (N, 3) positions "
           "and/or (N, ...) orientations (the other given once) -> SpatialBatchResult, rows as "
           "in forward (each on its own from home, or a path). Releases the GIL.")
      .def(
          "home",
          [](const SpatialRobotDescription& r, bool shapes,
             const std::optional<SolverOptions>& options) {
            const SolverOptions checked = options_or_default(options);
            SpatialForwardSolution s;
            {
              py::gil_scoped_release release;
              s = spatial_forward_kinematics(r.params, SpatialJointVector::Zero(r.params.num_rods),
                                             checked);
            }
            return spatial_solution(r.params, s, shapes);
          },
          py::kw_only(), py::arg("shapes") = false, py::arg("options") = py::none(),
          "The home solution q = 0 (m), from straight rods.");
}

}  // namespace

void wrap_spatial(py::module_& m) {
  bind_spatial_limb(m);
  bind_spatial_robot(m);
  bind_spatial_solution(m);
  bind_spatial_batch_result(m);
  bind_spatial_kinematics(m);
}

}  // namespace pcr::python
