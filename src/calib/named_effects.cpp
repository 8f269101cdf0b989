#include "pcr/calib/named_effects.hpp"

#include <cstdio>

namespace pcr {
namespace {

struct Switches {
  bool misalignments = false;
  bool diameters = false;
  bool load = false;
};

Switches switches_named(const std::vector<std::string>& names, const std::string& source) {
  Switches on;
  for (const std::string& name : names) {
    const bool all = name == "all";
    if (all || name == "misalignments") on.misalignments = true;
    if (all || name == "diameters") on.diameters = true;
    if (all || name == "load") on.load = true;
    if (!all && name != "misalignments" && name != "diameters" && name != "load") {
      throw InputError(source + ": unknown unmodelled effect '" + name +
                       "' (known: misalignments, diameters, load, all)");
    }
  }
  return on;
}

}  // namespace

const std::vector<std::string>& unmodelled_effect_names() {
  static const std::vector<std::string> names = {"misalignments", "diameters", "load", "all"};
  return names;
}

UnmodelledEffects planar_effects_named(const std::vector<std::string>& names,
                                       const std::string& source) {
  const Switches on = switches_named(names, source);
  UnmodelledEffects effects;
  effects.misalignments = on.misalignments;
  effects.unequal_diameters = on.diameters;
  effects.external_load = on.load;
  return effects;
}

SpatialUnmodelledEffects spatial_effects_named(const std::vector<std::string>& names,
                                               const std::string& source) {
  const Switches on = switches_named(names, source);
  SpatialUnmodelledEffects effects;
  // The planar robot's misalignment: the paper's, for holes in any robot.
  if (on.misalignments)
    effects.misalignment_half_width = UnmodelledEffects().misalignment_half_width;
  if (on.diameters) effects.diameter_half_width = kNamedSpatialDiameterHalfWidth;
  if (on.load) effects.payload = kNamedSpatialPayload;
  return effects;
}

std::string describe(const SpatialUnmodelledEffects& effects) {
  std::string out;
  char buf[160];
  const auto add = [&](const char* format, double value) {
    std::snprintf(buf, sizeof buf, format, value);
    out += (out.empty() ? "" : "; ") + std::string(buf);
  };
  if (effects.payload > 0) add("a %.3g kg payload at P's origin", effects.payload);
  if (effects.misalignment_half_width > 0)
    add("each base turn component off by U(-h, h), h = %.3g mrad",
        effects.misalignment_half_width * 1e3);
  if (effects.diameter_half_width > 0)
    add("each rod's d off by U(-h, h), h = %.3g um", effects.diameter_half_width * 1e6);
  if (effects.rod_density >= 0) add("the true rods' density %.4g kg/m^3", effects.rod_density);
  return out.empty() ? "none" : out;
}

}  // namespace pcr
