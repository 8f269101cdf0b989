#pragma once
// The unmodelled effects a front end switches on by name (pcr demo --effects, pcr simulate
// --effects): one list of names, and what each name means for the planar and for the spatial
// virtual robot, so that a name means the same on both.
//
//   misalignments  the holes and attachments turned beyond their declared intervals: U(-h, h),
//                  h = 5 mrad (the paper's Section 4.3), on the planar beta_i and gamma_i, on
//                  every component of each spatial rod's base turn
//   diameters      unequal rods: each rod's d gets an extra, independent U(-h, h): 2 um on the
//                  planar robot's wire; 10 um on a spatial rod (the reference robot's interval on
//                  its 2 mm wire)
//   load           a load the nominal model does not know: planar, 5 mN along x on the platform;
//                  spatial, a 100 g payload at P's origin (the reference robot's platform mass:
//                  its weight is what the spatial load stage finds, docs/calibration.md)
//   all            the three

#include <string>
#include <vector>

#include "pcr/calib/spatial_virtual_robot.hpp"
#include "pcr/calib/virtual_robot.hpp"

namespace pcr {

inline constexpr double kNamedSpatialPayload = 0.1;              ///< kg, "load"
inline constexpr double kNamedSpatialDiameterHalfWidth = 10e-6;  ///< m, "diameters"

/// The names, "all" last.
const std::vector<std::string>& unmodelled_effect_names();

/// The planar virtual robot's effects `names` switch on, at UnmodelledEffects' default sizes.
/// Throws InputError naming `source` and the name for an unknown one.
UnmodelledEffects planar_effects_named(const std::vector<std::string>& names,
                                       const std::string& source);

/// The spatial virtual robot's effects `names` switch on, at the sizes above. Throws InputError
/// naming `source` and the name for an unknown one.
SpatialUnmodelledEffects spatial_effects_named(const std::vector<std::string>& names,
                                               const std::string& source);

/// In words, for a report: "a 0.1 kg payload at P's origin; ..." ("none" when all are off).
std::string describe(const SpatialUnmodelledEffects& effects);

}  // namespace pcr
