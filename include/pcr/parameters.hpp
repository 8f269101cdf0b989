#pragma once
// A flat view of a robot description's parameters, for sensitivity analysis and calibration:
// per limb (E, d, l, A_x, A_y, alpha, B_x, B_y, beta, gamma, precurvature), then the six
// extrinsics. The calibration may append the constant platform load (pcr/calib/cost.hpp): flat
// indices past num_parameters(n), which parameter_id names but which no RobotParams holds.
//
// kParameterKinds is the one table of what pcr knows of each kind (its name, SI unit and the unit
// a report shows its deviations in), and limb_parameter the one accessor of a limb's parameter,
// in a description (LimbParams) as in its half-widths (LimbUncertainty, the same fields): the
// sensitivity, the calibration, its report and the I/O read them, so a new limb parameter is a
// row here and a case there.

#include <string>

#include "pcr/robot.hpp"

namespace pcr {

enum class ParameterKind {
  kYoungModulus,
  kDiameter,
  kLength,
  kAx,
  kAy,
  kAlpha,
  kBx,
  kBy,
  kBeta,
  kGamma,
  kPrecurvature,  // per limb
  kCameraX,
  kCameraY,
  kCameraTheta,
  kPatternX,
  kPatternY,
  kPatternTheta,  // extrinsics
  kLoadForceX,
  kLoadForceY,
  kLoadMoment,  // the calibration's optional platform load: not in RobotParams
};

inline constexpr int kLimbParameters = 11;
inline constexpr int kExtrinsicParameters = 6;
inline constexpr int kMaxParameters = kLimbParameters * kMaxLimbs + kExtrinsicParameters;

/// What pcr knows of a parameter kind.
struct ParameterKindInfo {
  ParameterKind kind;
  const char* name;          ///< as in the paper's Table 2 and the robot file: "E", "l", "A_x" ...
  const char* unit;          ///< SI
  double display_factor;     ///< from SI to display_unit
  const char* display_unit;  ///< the unit a reader of the paper's Table 1 thinks of deviations in
};

/// Every kind, in ParameterKind's order.
inline constexpr ParameterKindInfo kParameterKinds[] = {
    {ParameterKind::kYoungModulus, "E", "Pa", 1e-6, "MPa"},
    {ParameterKind::kDiameter, "d", "m", 1e6, "um"},
    {ParameterKind::kLength, "l", "m", 1e6, "um"},
    {ParameterKind::kAx, "A_x", "m", 1e6, "um"},
    {ParameterKind::kAy, "A_y", "m", 1e6, "um"},
    {ParameterKind::kAlpha, "alpha", "rad", 1e3, "mrad"},
    {ParameterKind::kBx, "B_x", "m", 1e6, "um"},
    {ParameterKind::kBy, "B_y", "m", 1e6, "um"},
    {ParameterKind::kBeta, "beta", "rad", 1e3, "mrad"},
    {ParameterKind::kGamma, "gamma", "rad", 1e3, "mrad"},
    {ParameterKind::kPrecurvature, "precurvature", "1/m", 1.0, "1/m"},
    {ParameterKind::kCameraX, "camera_x", "m", 1e6, "um"},
    {ParameterKind::kCameraY, "camera_y", "m", 1e6, "um"},
    {ParameterKind::kCameraTheta, "camera_theta", "rad", 1e3, "mrad"},
    {ParameterKind::kPatternX, "pattern_x", "m", 1e6, "um"},
    {ParameterKind::kPatternY, "pattern_y", "m", 1e6, "um"},
    {ParameterKind::kPatternTheta, "pattern_theta", "rad", 1e3, "mrad"},
    {ParameterKind::kLoadForceX, "load_f_x", "N", 1e6, "uN"},
    {ParameterKind::kLoadForceY, "load_f_y", "N", 1e6, "uN"},
    {ParameterKind::kLoadMoment, "load_m_z", "N m", 1e6, "uNm"},
};

namespace internal {
constexpr bool kinds_in_enum_order() {
  int i = 0;
  for (const ParameterKindInfo& info : kParameterKinds) {
    if (static_cast<int>(info.kind) != i++) return false;
  }
  return i == static_cast<int>(ParameterKind::kLoadMoment) + 1;
}
static_assert(kinds_in_enum_order(), "kParameterKinds lists every kind in ParameterKind's order");
}  // namespace internal

inline const ParameterKindInfo& parameter_kind_info(ParameterKind kind) {
  return kParameterKinds[static_cast<int>(kind)];
}

/// Short kind name as in the paper's Table 2: "E", "d", "l", "A_x", ..., "camera_x", ...
inline const char* parameter_kind_name(ParameterKind kind) {
  return parameter_kind_info(kind).name;
}

/// A limb's parameter of a per-limb kind (kYoungModulus ... kPrecurvature), in a description
/// (LimbParams<T>) or in its half-widths (LimbUncertainty): the one place a kind meets a field.
template <class Limb>
auto& limb_parameter(Limb& limb, ParameterKind kind) {
  switch (kind) {
    case ParameterKind::kYoungModulus:
      return limb.rod.young_modulus;
    case ParameterKind::kDiameter:
      return limb.rod.diameter;
    case ParameterKind::kLength:
      return limb.rod.length;
    case ParameterKind::kAx:
      return limb.A.x();
    case ParameterKind::kAy:
      return limb.A.y();
    case ParameterKind::kAlpha:
      return limb.alpha;
    case ParameterKind::kBx:
      return limb.B.x();
    case ParameterKind::kBy:
      return limb.B.y();
    case ParameterKind::kBeta:
      return limb.beta;
    case ParameterKind::kPrecurvature:
      return limb.rod.precurvature;
    default:
      return limb.gamma;
  }
}

inline int num_parameters(int num_limbs) {
  return kLimbParameters * num_limbs + kExtrinsicParameters;
}

struct ParameterId {
  ParameterKind kind;
  int limb;  ///< -1 for the extrinsics
};

/// The parameter at flat index `index` of a robot with `num_limbs` limbs (the three after the
/// extrinsics: the load kinds).
inline ParameterId parameter_id(int index, int num_limbs) {
  if (index < kLimbParameters * num_limbs) {
    return ParameterId{static_cast<ParameterKind>(index % kLimbParameters),
                       index / kLimbParameters};
  }
  const int e = index - kLimbParameters * num_limbs;
  return ParameterId{static_cast<ParameterKind>(static_cast<int>(ParameterKind::kCameraX) + e), -1};
}

inline int parameter_index(const ParameterId& id, int num_limbs) {
  const int kind = static_cast<int>(id.kind);
  if (id.limb >= 0) return id.limb * kLimbParameters + kind;
  return kLimbParameters * num_limbs + kind - static_cast<int>(ParameterKind::kCameraX);
}

/// "l[1]", "A_x[0]", "camera_theta" ...
inline std::string parameter_name(const ParameterId& id) {
  std::string name = parameter_kind_name(id.kind);
  if (id.limb >= 0) name += "[" + std::to_string(id.limb) + "]";
  return name;
}

/// Reference to a parameter inside a description (SI units, radians); not for the load kinds.
template <class T>
T& parameter_ref(RobotParams<T>& robot, const ParameterId& id) {
  if (id.limb >= 0) return limb_parameter(robot.limb(id.limb), id.kind);
  switch (id.kind) {
    case ParameterKind::kCameraX:
      return robot.extrinsics.camera.x;
    case ParameterKind::kCameraY:
      return robot.extrinsics.camera.y;
    case ParameterKind::kCameraTheta:
      return robot.extrinsics.camera.theta;
    case ParameterKind::kPatternX:
      return robot.extrinsics.pattern.x;
    case ParameterKind::kPatternY:
      return robot.extrinsics.pattern.y;
    default:
      return robot.extrinsics.pattern.theta;
  }
}

template <class T>
const T& parameter_ref(const RobotParams<T>& robot, const ParameterId& id) {
  return parameter_ref(const_cast<RobotParams<T>&>(robot), id);
}

/// Copies all parameters into values[0 .. num_parameters).
template <class T>
void get_parameters(const RobotParams<T>& robot, T* values) {
  const int count = num_parameters(robot.num_limbs);
  for (int k = 0; k < count; ++k)
    values[k] = parameter_ref(robot, parameter_id(k, robot.num_limbs));
}

/// Writes values[0 .. num_parameters) into a description whose other fields come from `base`.
template <class T>
RobotParams<T> with_parameters(const RobotParams<T>& base, const T* values) {
  RobotParams<T> robot = base;
  const int count = num_parameters(robot.num_limbs);
  for (int k = 0; k < count; ++k)
    parameter_ref(robot, parameter_id(k, robot.num_limbs)) = values[k];
  return robot;
}

}  // namespace pcr
