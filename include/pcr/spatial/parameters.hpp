#pragma once
// A flat view of a spatial robot's uncertain parameters, for its sensitivity, its virtual robot
// and its calibration: the spatial counterpart of pcr/parameters.hpp. Per rod (16): E, G, d, l,
// A (3), the base frame's turn (3), B (3), the tip frame's turn (3); then the measuring system's
// extrinsics (12): the tracker frame ^W T_S and the marker frame ^M T_P, each a position (3) and a
// turn (3). The calibration may append a constant platform wrench (kSpatialLoadParameters: force,
// then moment, in W): kinds of their own, outside the flat view, as the planar load's.
//
// The flat values are deviations from a nominal description, not the values themselves: a turn
// has no flat value of its own, only a rotation vector relative to the nominal orientation. Each
// turn is composed on the right, in the body frame it turns: R = R_nominal exp([delta]x), so that
// the rod's (x, y) components tilt its axis d3 and its z component twists it about d3, whatever
// way the nominal frame points. Lengths, positions and moduli deviate by addition.
//
// kSpatialParameterKinds is the one table of the kinds (name, unit, display unit); the half-widths
// of a description's intervals (SpatialUncertainty) are read through spatial_half_width, the
// description's values through spatial_with_deviations and spatial_deviations.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pcr/spatial/robot.hpp"
#include "pcr/spatial/shooting.hpp"  // quaternion_exp

namespace pcr {

enum class SpatialParameterKind {
  kYoungModulus,
  kShearModulus,
  kDiameter,
  kLength,
  kAx,
  kAy,
  kAz,
  kBaseRx,
  kBaseRy,
  kBaseRz,
  kBx,
  kBy,
  kBz,
  kTipRx,
  kTipRy,
  kTipRz,  // per rod
  kTrackerX,
  kTrackerY,
  kTrackerZ,
  kTrackerRx,
  kTrackerRy,
  kTrackerRz,
  kMarkerX,
  kMarkerY,
  kMarkerZ,
  kMarkerRx,
  kMarkerRy,
  kMarkerRz,  // extrinsics
  kLoadForceX,
  kLoadForceY,
  kLoadForceZ,
  kLoadMomentX,
  kLoadMomentY,
  kLoadMomentZ,  // the calibration's optional platform load: not in the flat view
};

inline constexpr int kSpatialRodParameters = 16;
inline constexpr int kSpatialExtrinsicParameters = 12;
/// The calibration's optional constant platform wrench (force, then moment, in W, added to
/// SpatialRobotParams::external_force and external_moment): appended after the flat parameters,
/// as the planar kLoadParameters, never part of num_spatial_parameters.
inline constexpr int kSpatialLoadParameters = 6;
inline constexpr int kMaxSpatialParameters =
    kSpatialRodParameters * kMaxSpatialRods + kSpatialExtrinsicParameters;

/// What pcr knows of a spatial parameter kind (as ParameterKindInfo).
struct SpatialParameterKindInfo {
  SpatialParameterKind kind;
  const char* name;          ///< "E", "A_x", "base_rx", "tracker_z" ...
  const char* unit;          ///< SI
  double display_factor;     ///< from SI to display_unit
  const char* display_unit;  ///< the unit deviations are shown in
};

/// Every kind, in SpatialParameterKind's order.
inline constexpr SpatialParameterKindInfo kSpatialParameterKinds[] = {
    {SpatialParameterKind::kYoungModulus, "E", "Pa", 1e-6, "MPa"},
    {SpatialParameterKind::kShearModulus, "G", "Pa", 1e-6, "MPa"},
    {SpatialParameterKind::kDiameter, "d", "m", 1e6, "um"},
    {SpatialParameterKind::kLength, "l", "m", 1e6, "um"},
    {SpatialParameterKind::kAx, "A_x", "m", 1e6, "um"},
    {SpatialParameterKind::kAy, "A_y", "m", 1e6, "um"},
    {SpatialParameterKind::kAz, "A_z", "m", 1e6, "um"},
    {SpatialParameterKind::kBaseRx, "base_rx", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kBaseRy, "base_ry", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kBaseRz, "base_rz", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kBx, "B_x", "m", 1e6, "um"},
    {SpatialParameterKind::kBy, "B_y", "m", 1e6, "um"},
    {SpatialParameterKind::kBz, "B_z", "m", 1e6, "um"},
    {SpatialParameterKind::kTipRx, "tip_rx", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kTipRy, "tip_ry", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kTipRz, "tip_rz", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kTrackerX, "tracker_x", "m", 1e6, "um"},
    {SpatialParameterKind::kTrackerY, "tracker_y", "m", 1e6, "um"},
    {SpatialParameterKind::kTrackerZ, "tracker_z", "m", 1e6, "um"},
    {SpatialParameterKind::kTrackerRx, "tracker_rx", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kTrackerRy, "tracker_ry", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kTrackerRz, "tracker_rz", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kMarkerX, "marker_x", "m", 1e6, "um"},
    {SpatialParameterKind::kMarkerY, "marker_y", "m", 1e6, "um"},
    {SpatialParameterKind::kMarkerZ, "marker_z", "m", 1e6, "um"},
    {SpatialParameterKind::kMarkerRx, "marker_rx", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kMarkerRy, "marker_ry", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kMarkerRz, "marker_rz", "rad", 1e3, "mrad"},
    {SpatialParameterKind::kLoadForceX, "load_f_x", "N", 1e3, "mN"},
    {SpatialParameterKind::kLoadForceY, "load_f_y", "N", 1e3, "mN"},
    {SpatialParameterKind::kLoadForceZ, "load_f_z", "N", 1e3, "mN"},
    {SpatialParameterKind::kLoadMomentX, "load_m_x", "N m", 1e3, "mNm"},
    {SpatialParameterKind::kLoadMomentY, "load_m_y", "N m", 1e3, "mNm"},
    {SpatialParameterKind::kLoadMomentZ, "load_m_z", "N m", 1e3, "mNm"},
};

namespace internal {
constexpr bool spatial_kinds_in_enum_order() {
  int i = 0;
  for (const SpatialParameterKindInfo& info : kSpatialParameterKinds) {
    if (static_cast<int>(info.kind) != i++) return false;
  }
  return i == kSpatialRodParameters + kSpatialExtrinsicParameters + kSpatialLoadParameters;
}
static_assert(spatial_kinds_in_enum_order(),
              "kSpatialParameterKinds lists every kind in SpatialParameterKind's order");
}  // namespace internal

inline const SpatialParameterKindInfo& spatial_parameter_kind_info(SpatialParameterKind kind) {
  return kSpatialParameterKinds[static_cast<int>(kind)];
}

/// Half-widths of one rod's intervals (SI units, rad), deviations as the flat view's.
struct SpatialRodUncertainty {
  double young_modulus{0};                 ///< Pa
  double shear_modulus{0};                 ///< Pa
  double diameter{0};                      ///< m
  double length{0};                        ///< m (the free length at q = 0)
  Eigen::Vector3d A{0, 0, 0};              ///< m, on A_x, A_y, A_z (in W)
  Eigen::Vector3d base_rotation{0, 0, 0};  ///< rad, the base frame's turn
  Eigen::Vector3d B{0, 0, 0};              ///< m, on B_x, B_y, B_z (in P)
  Eigen::Vector3d tip_rotation{0, 0, 0};   ///< rad, the tip frame's turn
};

/// A spatial description's intervals: a default for every rod, each rod's (the default with the
/// file's overrides), and the extrinsics' (x, y, z in m, then rx, ry, rz in rad).
struct SpatialUncertainty {
  SpatialRodUncertainty global;
  std::vector<SpatialRodUncertainty> rods;
  Eigen::Matrix<double, 6, 1> tracker = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> marker = Eigen::Matrix<double, 6, 1>::Zero();
};

inline int num_spatial_parameters(int num_rods) {
  return kSpatialRodParameters * num_rods + kSpatialExtrinsicParameters;
}

struct SpatialParameterId {
  SpatialParameterKind kind;
  int rod;  ///< -1 for the extrinsics (and the load)
};

/// The index num_spatial_parameters(n) + k is the load's k-th value (kLoadForceX + k).
inline SpatialParameterId spatial_parameter_id(int index, int num_rods) {
  if (index < kSpatialRodParameters * num_rods) {
    return SpatialParameterId{static_cast<SpatialParameterKind>(index % kSpatialRodParameters),
                              index / kSpatialRodParameters};
  }
  return SpatialParameterId{static_cast<SpatialParameterKind>(kSpatialRodParameters + index -
                                                              kSpatialRodParameters * num_rods),
                            -1};
}

inline int spatial_parameter_index(const SpatialParameterId& id, int num_rods) {
  const int kind = static_cast<int>(id.kind);
  if (id.rod >= 0) return id.rod * kSpatialRodParameters + kind;
  return kSpatialRodParameters * num_rods + kind - kSpatialRodParameters;
}

/// "l[1]", "base_rx[0]", "tracker_z" ...
inline std::string spatial_parameter_name(const SpatialParameterId& id) {
  std::string name = spatial_parameter_kind_info(id.kind).name;
  if (id.rod >= 0) name += "[" + std::to_string(id.rod) + "]";
  return name;
}

/// The half-width of a parameter's interval (the rod's own, or the default when the uncertainty
/// lists no rods); 0 for the load, which has no interval.
inline double spatial_half_width(const SpatialUncertainty& u, const SpatialParameterId& id) {
  const int kind = static_cast<int>(id.kind);
  if (kind >= static_cast<int>(SpatialParameterKind::kLoadForceX)) return 0.0;
  if (id.rod < 0) {
    const int e = kind - kSpatialRodParameters;
    return e < 6 ? u.tracker(e) : u.marker(e - 6);
  }
  const SpatialRodUncertainty& r = id.rod < static_cast<int>(u.rods.size())
                                       ? u.rods[static_cast<std::size_t>(id.rod)]
                                       : u.global;
  switch (id.kind) {
    case SpatialParameterKind::kYoungModulus:
      return r.young_modulus;
    case SpatialParameterKind::kShearModulus:
      return r.shear_modulus;
    case SpatialParameterKind::kDiameter:
      return r.diameter;
    case SpatialParameterKind::kLength:
      return r.length;
    default:
      break;
  }
  const int axis = (kind - static_cast<int>(SpatialParameterKind::kAx)) % 3;
  if (kind < static_cast<int>(SpatialParameterKind::kBaseRx)) return r.A(axis);
  if (kind < static_cast<int>(SpatialParameterKind::kBx)) return r.base_rotation(axis);
  if (kind < static_cast<int>(SpatialParameterKind::kTipRx)) return r.B(axis);
  return r.tip_rotation(axis);
}

namespace internal {
/// pose turned and moved by deviations d[0..5] (position added in the parent frame, the turn on
/// the right).
template <class T>
SpatialPose<T> deviated_pose(const SpatialPose<double>& nominal, const T* d) {
  const SpatialPose<T> p = nominal.template cast<T>();
  return SpatialPose<T>{
      p.position + Vector3<T>(d[0], d[1], d[2]),
      quaternion_product<T>(p.orientation, quaternion_exp<T>(Vector3<T>(d[3], d[4], d[5])))};
}

/// The rotation vector of R_nominal^T R: the turn deviated_pose composes.
inline Vector3<double> turn_from(const Vector4<double>& nominal, const Vector4<double>& h) {
  const Vector4<double> conjugate(nominal(0), -nominal(1), -nominal(2), -nominal(3));
  return quaternion_log<double>(quaternion_product<double>(conjugate, h));
}
}  // namespace internal

/// The description `nominal` moved by the flat deviations d[0 .. num_spatial_parameters): in T, so
/// that a Jet carries their derivatives through the model.
template <class T>
SpatialRobotParams<T> spatial_with_deviations(const SpatialRobotParams<double>& nominal,
                                              const T* d) {
  SpatialRobotParams<T> robot = nominal.template cast<T>();
  for (int i = 0; i < nominal.num_rods; ++i) {
    const T* r = d + kSpatialRodParameters * i;
    SpatialLimbParams<T>& limb = robot.limb(i);
    limb.rod.young_modulus += r[0];
    limb.rod.shear_modulus += r[1];
    limb.rod.diameter += r[2];
    limb.rod.length += r[3];
    limb.A += Vector3<T>(r[4], r[5], r[6]);
    limb.base_orientation = quaternion_product<T>(limb.base_orientation,
                                                  quaternion_exp<T>(Vector3<T>(r[7], r[8], r[9])));
    limb.B += Vector3<T>(r[10], r[11], r[12]);
    limb.tip_orientation = quaternion_product<T>(
        limb.tip_orientation, quaternion_exp<T>(Vector3<T>(r[13], r[14], r[15])));
  }
  const T* e = d + kSpatialRodParameters * nominal.num_rods;
  robot.extrinsics.tracker = internal::deviated_pose(nominal.extrinsics.tracker, e);
  robot.extrinsics.marker = internal::deviated_pose(nominal.extrinsics.marker, e + 6);
  return robot;
}

/// The flat deviations of `robot` from `nominal` (the same rods): the inverse of
/// spatial_with_deviations (turns of up to pi).
inline void spatial_deviations(const SpatialRobotParams<double>& nominal,
                               const SpatialRobotParams<double>& robot, double* d) {
  const auto put = [](double* at, const Vector3<double>& v) {
    for (int k = 0; k < 3; ++k) at[k] = v(k);
  };
  for (int i = 0; i < nominal.num_rods; ++i) {
    double* r = d + kSpatialRodParameters * i;
    const SpatialLimbParams<double>& a = nominal.limb(i);
    const SpatialLimbParams<double>& b = robot.limb(i);
    r[0] = b.rod.young_modulus - a.rod.young_modulus;
    r[1] = b.rod.shear_modulus - a.rod.shear_modulus;
    r[2] = b.rod.diameter - a.rod.diameter;
    r[3] = b.rod.length - a.rod.length;
    put(r + 4, b.A - a.A);
    put(r + 7, internal::turn_from(a.base_orientation, b.base_orientation));
    put(r + 10, b.B - a.B);
    put(r + 13, internal::turn_from(a.tip_orientation, b.tip_orientation));
  }
  double* e = d + kSpatialRodParameters * nominal.num_rods;
  const SpatialExtrinsics<double>&x = nominal.extrinsics, &y = robot.extrinsics;
  put(e, y.tracker.position - x.tracker.position);
  put(e + 3, internal::turn_from(x.tracker.orientation, y.tracker.orientation));
  put(e + 6, y.marker.position - x.marker.position);
  put(e + 9, internal::turn_from(x.marker.orientation, y.marker.orientation));
}

}  // namespace pcr
