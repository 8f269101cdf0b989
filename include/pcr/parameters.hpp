#pragma once
// A flat view of a robot description's parameters, for sensitivity analysis and calibration:
// per limb (E, d, l, A_x, A_y, alpha, B_x, B_y, beta, gamma), then the six extrinsics. The
// calibration may append the constant platform load (pcr/calib/cost.hpp): flat indices past
// num_parameters(n), which parameter_id names but which no RobotParams holds.

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
  kGamma,  // per limb
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

inline constexpr int kLimbParameters = 10;
inline constexpr int kExtrinsicParameters = 6;
inline constexpr int kMaxParameters = kLimbParameters * kMaxLimbs + kExtrinsicParameters;

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

/// Short kind name as in the paper's Table 2: "E", "d", "l", "A_x", ..., "camera_x", ...
inline const char* parameter_kind_name(ParameterKind kind) {
  static const char* const kNames[] = {"E",
                                       "d",
                                       "l",
                                       "A_x",
                                       "A_y",
                                       "alpha",
                                       "B_x",
                                       "B_y",
                                       "beta",
                                       "gamma",
                                       "camera_x",
                                       "camera_y",
                                       "camera_theta",
                                       "pattern_x",
                                       "pattern_y",
                                       "pattern_theta",
                                       "load_f_x",
                                       "load_f_y",
                                       "load_m_z"};
  return kNames[static_cast<int>(kind)];
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
  if (id.limb >= 0) {
    LimbParams<T>& limb = robot.limb(id.limb);
    switch (id.kind) {
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
      default:
        return limb.gamma;
    }
  }
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
