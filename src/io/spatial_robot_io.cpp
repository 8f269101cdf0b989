#include <cmath>
#include <sstream>

#include "json_reader.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/files.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace pcr {

namespace {

using namespace json_io;

constexpr int kFormatVersion = 1;

// Physical ranges of the spatial fields beyond the shared ones (docs/formats.md, "Spatial
// robots"). G of soft polymers reaches down to a third of their E (0.3 MPa); no metal is denser
// than 23 t/m^3; a lab platform weighs less than a tonne; gravity on Earth or a centrifuge test
// rig stays within 100 m/s^2; external loads as pcr::PlatformLoad's moment, a kilo-unit being a
// unit typo.
constexpr double kMinShearModulus = 1e5;  // Pa
constexpr double kMaxDensity = 1e5;       // kg/m^3
constexpr double kMaxPlatformMass = 1e3;  // kg
constexpr double kMaxGravity = 100.0;     // m/s^2
constexpr double kMaxForce = 1e4;         // N
constexpr double kMaxMoment = 1e3;        // N m

class SpatialReader : public JsonReader {
 public:
  using JsonReader::JsonReader;

  SpatialLimbParams<double> limb(const Json& l, const std::string& path) const {
    check_object(l, path,
                 {"length", "diameter", "young_modulus", "shear_modulus", "density",
                  "intrinsic_curvature", "shear_and_extension", "A", "base_orientation",
                  "actuation", "actuator_direction", "B", "tip_orientation", "attachment"});
    SpatialLimbParams<double> limb;
    SpatialRod<double>& rod = limb.rod;
    rod.length = in_range(required(l, path, "length"), join(path, "length"), 1e-4, 10.0, "m");
    rod.diameter = in_range(required(l, path, "diameter"), join(path, "diameter"), 1e-6, 0.1, "m");
    if (!(rod.diameter < rod.length)) {
      fail(join(path, "diameter"), "a rod's diameter must be smaller than its length",
           l["diameter"]);
    }
    rod.young_modulus = in_range(required(l, path, "young_modulus"), join(path, "young_modulus"),
                                 kMinYoungModulus, kMaxYoungModulus, "Pa");
    rod.shear_modulus = in_range(required(l, path, "shear_modulus"), join(path, "shear_modulus"),
                                 kMinShearModulus, kMaxYoungModulus, "Pa");
    rod.density =
        in_range(required(l, path, "density"), join(path, "density"), 0.0, kMaxDensity, "kg/m^3");
    if (l.contains("intrinsic_curvature")) {
      // As the planar precurvature: at most one full turn over the rod's length.
      const double turn_per_length = 2.0 * M_PI / rod.length;
      rod.intrinsic_curvature =
          vector_in_range<3>(l["intrinsic_curvature"], join(path, "intrinsic_curvature"),
                             -turn_per_length, turn_per_length, "1/m");
    }
    if (l.contains("shear_and_extension")) {
      const Json& v = l["shear_and_extension"];
      if (!v.is_boolean()) fail(join(path, "shear_and_extension"), "expected true or false", v);
      rod.shear_and_extension = v.get<bool>();
    }
    limb.A = point(required(l, path, "A"), join(path, "A"));
    if (l.contains("base_orientation")) {
      limb.base_orientation = unit<4>(l["base_orientation"], join(path, "base_orientation"),
                                      "a quaternion (w, x, y, z)");
    }
    const Json& actuation = required(l, path, "actuation");
    if (actuation == "length_through_hole") {
      limb.actuation = SpatialActuation::kLengthThroughHole;
    } else if (actuation == "translated_clamp") {
      limb.actuation = SpatialActuation::kTranslatedClamp;
    } else {
      fail(join(path, "actuation"), "expected \"length_through_hole\" or \"translated_clamp\"",
           actuation);
    }
    if (l.contains("actuator_direction")) {
      limb.actuator_direction =
          unit<3>(l["actuator_direction"], join(path, "actuator_direction"), "a direction");
    }
    limb.B = point(required(l, path, "B"), join(path, "B"));
    if (l.contains("tip_orientation")) {
      limb.tip_orientation =
          unit<4>(l["tip_orientation"], join(path, "tip_orientation"), "a quaternion (w, x, y, z)");
    }
    const Json& attachment = required(l, path, "attachment");
    if (attachment == "clamped") {
      limb.attachment = SpatialAttachment::kClamped;
    } else if (attachment == "spherical") {
      limb.attachment = SpatialAttachment::kSpherical;
    } else {
      fail(join(path, "attachment"), "expected \"clamped\" or \"spherical\"", attachment);
    }
    return limb;
  }

  /// Reads the rod uncertainty fields present in `object` over `out` (overrides).
  void rod_uncertainty(const Json& object, const std::string& path,
                       SpatialRodUncertainty& out) const {
    for (auto it = object.begin(); it != object.end(); ++it) {
      const std::string key = it.key();
      const std::string p = join(path, key);
      if (key == "E") out.young_modulus = half_width(*it, p, 1e3, 1e12, "Pa");
      if (key == "G") out.shear_modulus = half_width(*it, p, 1e3, 1e12, "Pa");
      if (key == "d") out.diameter = half_width(*it, p, 1e-12, 1e-2, "m");
      if (key == "l") out.length = half_width(*it, p, 1e-12, 0.1, "m");
      if (key == "A") out.A = half_widths<3>(*it, p, 1e-12, 0.1, "m");
      if (key == "base_rotation") out.base_rotation = half_widths<3>(*it, p, 1e-12, 1.0, "rad");
      if (key == "B") out.B = half_widths<3>(*it, p, 1e-12, 0.1, "m");
      if (key == "tip_rotation") out.tip_rotation = half_widths<3>(*it, p, 1e-12, 1.0, "rad");
    }
  }

  /// Half-widths of a frame's (x, y, z) in m, then (rx, ry, rz) in rad.
  Eigen::Matrix<double, 6, 1> frame_half_widths(const Json& value, const std::string& path) const {
    Eigen::Matrix<double, 6, 1> v = vector<6>(value, path);
    for (std::size_t i = 0; i < 6; ++i) {
      half_width(value[i], index(path, i), 1e-12, i < 3 ? 0.1 : 1.0, i < 3 ? "m" : "rad");
    }
    return v;
  }

  SpatialUncertainty uncertainty(const Json& object, int num_rods) const {
    const std::string path = "uncertainty";
    check_object(object, path,
                 {"E", "G", "d", "l", "A", "base_rotation", "B", "tip_rotation", "tracker",
                  "marker", "rods"});
    SpatialUncertainty u;
    rod_uncertainty(object, path, u.global);
    if (object.contains("tracker")) {
      u.tracker = frame_half_widths(object["tracker"], join(path, "tracker"));
    }
    if (object.contains("marker")) {
      u.marker = frame_half_widths(object["marker"], join(path, "marker"));
    }
    u.rods.assign(static_cast<std::size_t>(num_rods), u.global);
    if (object.contains("rods")) {
      const Json& rods = object["rods"];
      const std::string rpath = join(path, "rods");
      if (!rods.is_array() || rods.size() != static_cast<std::size_t>(num_rods)) {
        fail(rpath,
             "expected an array of " + std::to_string(num_rods) +
                 " objects (one per rod; {} for no override)",
             rods);
      }
      for (std::size_t i = 0; i < rods.size(); ++i) {
        check_object(rods[i], index(rpath, i),
                     {"E", "G", "d", "l", "A", "base_rotation", "B", "tip_rotation"});
        rod_uncertainty(rods[i], index(rpath, i), u.rods[i]);
      }
    }
    return u;
  }

  SpatialRobotDescription robot(const Json& root) const {
    if (!root.is_object()) fail("<root>", "expected an object", root);
    require_kind(*this, root, RobotKind::kSpatial);  // first: a planar file's fields are unknown
    check_object(root, "",
                 {"pcr_robot", "kind", "name", "rods", "platform_mass", "platform_centre_of_mass",
                  "gravity", "external_force", "external_moment", "extrinsics", "uncertainty"});
    const Json& version = required(root, "", "pcr_robot");
    if (!version.is_number_integer() || version.get<long long>() != kFormatVersion) {
      fail("pcr_robot",
           "unsupported format version (this build reads version " +
               std::to_string(kFormatVersion) + ")",
           version);
    }
    SpatialRobotDescription out;
    const Json& name = required(root, "", "name");
    if (!name.is_string()) fail("name", "expected a string", name);
    out.name = name.get<std::string>();

    const Json& rods = required(root, "", "rods");
    if (!rods.is_array()) fail("rods", "expected an array of rod objects", rods);
    if (rods.empty() || rods.size() > static_cast<std::size_t>(kMaxSpatialRods)) {
      fail("rods", "expected between 1 and " + std::to_string(kMaxSpatialRods) + " rods, got " +
                       std::to_string(rods.size()));
    }
    SpatialRobotParams<double>& params = out.params;
    params.num_rods = static_cast<int>(rods.size());
    for (std::size_t i = 0; i < rods.size(); ++i) {
      params.limb(static_cast<int>(i)) = limb(rods[i], index("rods", i));
    }
    params.platform_mass =
        in_range(required(root, "", "platform_mass"), "platform_mass", 0.0, kMaxPlatformMass, "kg");
    if (root.contains("platform_centre_of_mass")) {
      params.platform_centre_of_mass =
          point(root["platform_centre_of_mass"], "platform_centre_of_mass");
    }
    params.gravity = vector_in_range<3>(required(root, "", "gravity"), "gravity", -kMaxGravity,
                                        kMaxGravity, "m/s^2");
    if (root.contains("external_force")) {
      params.external_force =
          vector_in_range<3>(root["external_force"], "external_force", -kMaxForce, kMaxForce, "N");
    }
    if (root.contains("external_moment")) {
      params.external_moment = vector_in_range<3>(root["external_moment"], "external_moment",
                                                  -kMaxMoment, kMaxMoment, "N m");
    }
    if (root.contains("extrinsics")) {
      const Json& e = root["extrinsics"];
      check_object(e, "extrinsics", {"tracker", "marker"});
      if (e.contains("tracker"))
        params.extrinsics.tracker = frame(e["tracker"], "extrinsics.tracker");
      if (e.contains("marker")) params.extrinsics.marker = frame(e["marker"], "extrinsics.marker");
    }
    if (root.contains("uncertainty")) {
      out.uncertainty = uncertainty(root["uncertainty"], params.num_rods);
    }
    return out;
  }
};

template <int N>
Ordered array(const Eigen::Matrix<double, N, 1>& v) {
  Ordered out = Ordered::array();
  for (int i = 0; i < N; ++i) out.push_back(v(i));
  return out;
}

Ordered frame_json(const SpatialPose<double>& pose) {
  Ordered out = Ordered::object();
  out["position"] = array<3>(pose.position);
  out["orientation"] = array<4>(pose.orientation);
  return out;
}

/// Uncertainty fields of `u` that differ from `base` (all of them when base is null).
Ordered rod_uncertainty_json(const SpatialRodUncertainty& u, const SpatialRodUncertainty* base) {
  Ordered out = Ordered::object();
  const auto differs = [&](const auto& a, const auto& b) { return !base || !same_bits(a, b); };
  const auto same3 = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return same_bits(a(0), b(0)) && same_bits(a(1), b(1)) && same_bits(a(2), b(2));
  };
  if (differs(u.young_modulus, base ? base->young_modulus : 0.0)) out["E"] = u.young_modulus;
  if (differs(u.shear_modulus, base ? base->shear_modulus : 0.0)) out["G"] = u.shear_modulus;
  if (differs(u.diameter, base ? base->diameter : 0.0)) out["d"] = u.diameter;
  if (differs(u.length, base ? base->length : 0.0)) out["l"] = u.length;
  if (!base || !same3(u.A, base->A)) out["A"] = array<3>(u.A);
  if (!base || !same3(u.base_rotation, base->base_rotation))
    out["base_rotation"] = array<3>(u.base_rotation);
  if (!base || !same3(u.B, base->B)) out["B"] = array<3>(u.B);
  if (!base || !same3(u.tip_rotation, base->tip_rotation))
    out["tip_rotation"] = array<3>(u.tip_rotation);
  return out;
}

}  // namespace

SpatialRobotDescription parse_spatial_robot(const std::string& json_text,
                                            const std::string& source) {
  return SpatialReader(source).robot(parse_json(json_text, source));
}

SpatialRobotDescription load_spatial_robot(const std::string& path) {
  return parse_spatial_robot(read_input_file(path, kMaxJsonFileBytes, "a robot description"), path);
}

std::string spatial_robot_to_json(const SpatialRobotDescription& robot) {
  const SpatialRobotParams<double>& params = robot.params;
  if (params.num_rods < 1 || params.num_rods > kMaxSpatialRods) {
    throw InputError("spatial_robot_to_json: robot '" + robot.name + "' has " +
                     std::to_string(params.num_rods) + " rods (expected 1 to " +
                     std::to_string(kMaxSpatialRods) + ")");
  }
  Ordered root = Ordered::object();
  root["pcr_robot"] = kFormatVersion;
  root["kind"] = "spatial";
  root["name"] = robot.name;
  Ordered rods = Ordered::array();
  for (int i = 0; i < params.num_rods; ++i) {
    const SpatialLimbParams<double>& limb = params.limb(i);
    Ordered l = Ordered::object();
    l["length"] = limb.rod.length;
    l["diameter"] = limb.rod.diameter;
    l["young_modulus"] = limb.rod.young_modulus;
    l["shear_modulus"] = limb.rod.shear_modulus;
    l["density"] = limb.rod.density;
    l["intrinsic_curvature"] = array<3>(limb.rod.intrinsic_curvature);
    l["shear_and_extension"] = limb.rod.shear_and_extension;
    l["A"] = array<3>(limb.A);
    l["base_orientation"] = array<4>(limb.base_orientation);
    l["actuation"] = to_string(limb.actuation);
    l["actuator_direction"] = array<3>(limb.actuator_direction);
    l["B"] = array<3>(limb.B);
    l["tip_orientation"] = array<4>(limb.tip_orientation);
    l["attachment"] = to_string(limb.attachment);
    rods.push_back(l);
  }
  root["rods"] = rods;
  root["platform_mass"] = params.platform_mass;
  root["platform_centre_of_mass"] = array<3>(params.platform_centre_of_mass);
  root["gravity"] = array<3>(params.gravity);
  root["external_force"] = array<3>(params.external_force);
  root["external_moment"] = array<3>(params.external_moment);
  Ordered extrinsics = Ordered::object();
  extrinsics["tracker"] = frame_json(params.extrinsics.tracker);
  extrinsics["marker"] = frame_json(params.extrinsics.marker);
  root["extrinsics"] = extrinsics;
  if (robot.uncertainty) {
    const SpatialUncertainty& u = *robot.uncertainty;
    if (!u.rods.empty() && u.rods.size() != static_cast<std::size_t>(params.num_rods)) {
      throw InputError("spatial_robot_to_json: robot '" + robot.name + "': uncertainty.rods has " +
                       std::to_string(u.rods.size()) + " entries for " +
                       std::to_string(params.num_rods) + " rods");
    }
    Ordered uj = rod_uncertainty_json(u.global, nullptr);
    uj["tracker"] = array<6>(u.tracker);
    uj["marker"] = array<6>(u.marker);
    bool overridden = false;
    Ordered overrides = Ordered::array();
    for (const SpatialRodUncertainty& r : u.rods) {
      Ordered o = rod_uncertainty_json(r, &u.global);
      overridden = overridden || !o.empty();
      overrides.push_back(o);
    }
    if (overridden) uj["rods"] = overrides;
    root["uncertainty"] = uj;
  }
  std::ostringstream out;
  print(root, 0, out);
  out << "\n";
  return out.str();
}

void save_spatial_robot(const SpatialRobotDescription& robot, const std::string& path) {
  const std::string text = spatial_robot_to_json(robot);
  // Never write a file that would not load: validate the text first.
  parse_spatial_robot(text, path + " (being written)");
  write_file_atomically(path, text);
}

const char* to_string(SpatialActuation actuation) {
  return actuation == SpatialActuation::kTranslatedClamp ? "translated_clamp"
                                                         : "length_through_hole";
}

const char* to_string(SpatialAttachment attachment) {
  return attachment == SpatialAttachment::kSpherical ? "spherical" : "clamped";
}

}  // namespace pcr
