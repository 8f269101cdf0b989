#include "pcr/robot_io.hpp"

#include <cmath>
#include <sstream>

#include "json_reader.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/files.hpp"

namespace pcr {

std::string excerpt(std::string text) {
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}
namespace {

using namespace json_io;

constexpr int kFormatVersion = 1;

/// Reads and validates one description; every error names the source and the field path.
class Reader : public JsonReader {
 public:
  using JsonReader::JsonReader;

  Eigen::Vector2d position_half_widths(const Json& value, const std::string& path) const {
    return half_widths<2>(value, path, 1e-12, 0.1, "m");
  }

  Eigen::Vector3d pose_half_widths(const Json& value, const std::string& path) const {
    const Eigen::Vector3d v = vector<3>(value, path);
    for (std::size_t i = 0; i < 2; ++i) half_width(value[i], index(path, i), 1e-12, 0.1, "m");
    half_width(value[2], index(path, 2), 1e-12, 1.0, "rad");
    return v;
  }

  Pose2<double> pose(const Json& value, const std::string& path) const {
    const Eigen::Vector3d v = vector<3>(value, path);
    in_range(value[0], index(path, 0), -kMaxCoordinate, kMaxCoordinate, "m");
    in_range(value[1], index(path, 1), -kMaxCoordinate, kMaxCoordinate, "m");
    angle(value[2], index(path, 2));
    return Pose2<double>{v(0), v(1), v(2)};
  }
  /// A point or an interval of the plane (m): within kMaxCoordinate of the origin.
  Eigen::Vector2d position(const Json& value, const std::string& path) const {
    const Eigen::Vector2d v = vector<2>(value, path);
    for (int i = 0; i < 2; ++i) {
      in_range(value[static_cast<std::size_t>(i)], index(path, i), -kMaxCoordinate, kMaxCoordinate,
               "m");
    }
    return v;
  }
  double angle(const Json& value, const std::string& path) const {
    return in_range(value, path, -kMaxAngle, kMaxAngle, "rad");
  }

  /// Reads the limb uncertainty fields present in `object` over `out` (overrides).
  void limb_uncertainty(const Json& object, const std::string& path, LimbUncertainty& out) const {
    for (auto it = object.begin(); it != object.end(); ++it) {
      const std::string key = it.key();
      const std::string p = join(path, key);
      if (key == "E") {
        out.rod.young_modulus = half_width(*it, p, kMinYoungModulus * 1e-9, 1e12, "Pa");
      }
      if (key == "l") out.rod.length = half_width(*it, p, 1e-12, 0.1, "m");
      if (key == "d") out.rod.diameter = half_width(*it, p, 1e-12, 1e-2, "m");
      if (key == "precurvature") out.rod.precurvature = half_width(*it, p, 1e-9, 1e4, "1/m");
      if (key == "alpha") out.alpha = half_width(*it, p, 1e-12, 1.0, "rad");
      if (key == "beta") out.beta = half_width(*it, p, 1e-12, 1.0, "rad");
      if (key == "gamma") out.gamma = half_width(*it, p, 1e-12, 1.0, "rad");
      if (key == "A") out.A = position_half_widths(*it, p);
      if (key == "B") out.B = position_half_widths(*it, p);
    }
  }

  RobotUncertainty uncertainty(const Json& object, int num_limbs) const {
    const std::string path = "uncertainty";
    check_object(object, path,
                 {"E", "l", "d", "precurvature", "A", "alpha", "B", "beta", "gamma", "camera",
                  "pattern", "limbs"});
    RobotUncertainty u;
    limb_uncertainty(object, path, u.global);
    if (object.contains("camera")) {
      u.camera = pose_half_widths(object["camera"], join(path, "camera"));
    }
    if (object.contains("pattern")) {
      u.pattern = pose_half_widths(object["pattern"], join(path, "pattern"));
    }
    u.limbs.assign(static_cast<std::size_t>(num_limbs), u.global);
    if (object.contains("limbs")) {
      const Json& limbs = object["limbs"];
      const std::string lpath = join(path, "limbs");
      if (!limbs.is_array() || limbs.size() != static_cast<std::size_t>(num_limbs)) {
        fail(lpath,
             "expected an array of " + std::to_string(num_limbs) +
                 " objects (one per limb; {} for no override)",
             limbs);
      }
      for (std::size_t i = 0; i < limbs.size(); ++i) {
        check_object(limbs[i], index(lpath, i),
                     {"E", "l", "d", "precurvature", "A", "alpha", "B", "beta", "gamma"});
        limb_uncertainty(limbs[i], index(lpath, i), u.limbs[i]);
      }
    }
    return u;
  }

  RobotDescription robot(const Json& root) const {
    require_kind(*this, root,
                 RobotKind::kPlanar);  // first: a spatial file's fields are unknown here
    check_object(root, "",
                 {"pcr_robot", "kind", "name", "E", "limbs", "extrinsics", "uncertainty"});
    const Json& version = required(root, "", "pcr_robot");
    if (!version.is_number_integer() || version.get<long long>() != kFormatVersion) {
      fail("pcr_robot",
           "unsupported format version (this build reads version " +
               std::to_string(kFormatVersion) + ")",
           version);
    }
    RobotDescription out;
    const Json& name = required(root, "", "name");
    if (!name.is_string()) fail("name", "expected a string", name);
    out.name = name.get<std::string>();
    out.young_modulus =
        in_range(required(root, "", "E"), "E", kMinYoungModulus, kMaxYoungModulus, "Pa");

    const Json& limbs = required(root, "", "limbs");
    if (!limbs.is_array()) fail("limbs", "expected an array of limb objects", limbs);
    if (limbs.size() < 2 || limbs.size() > static_cast<std::size_t>(kMaxLimbs)) {
      fail("limbs", "expected between 2 and " + std::to_string(kMaxLimbs) + " limbs, got " +
                        std::to_string(limbs.size()));
    }
    out.params.num_limbs = static_cast<int>(limbs.size());
    for (std::size_t i = 0; i < limbs.size(); ++i) {
      const std::string path = index("limbs", i);
      const Json& l = limbs[i];
      check_object(l, path,
                   {"A", "alpha", "gamma", "B", "beta", "l", "d", "q_range", "E", "precurvature",
                    "precurvature_slope", "diameter_slope", "home_bow"});
      LimbParams<double>& limb = out.params.limb(static_cast<int>(i));
      limb.A = position(required(l, path, "A"), join(path, "A"));
      limb.alpha = angle(required(l, path, "alpha"), join(path, "alpha"));
      limb.gamma = angle(required(l, path, "gamma"), join(path, "gamma"));
      limb.B = position(required(l, path, "B"), join(path, "B"));
      limb.beta = angle(required(l, path, "beta"), join(path, "beta"));
      limb.rod.length = in_range(required(l, path, "l"), join(path, "l"), 1e-4, 10.0, "m");
      limb.rod.diameter = in_range(required(l, path, "d"), join(path, "d"), 1e-6, 0.1, "m");
      if (!(limb.rod.diameter < limb.rod.length)) {
        fail(join(path, "d"), "a rod's diameter must be smaller than its length (l)", l["d"]);
      }
      limb.rod.young_modulus = l.contains("E") ? in_range(l["E"], join(path, "E"), kMinYoungModulus,
                                                          kMaxYoungModulus, "Pa")
                                               : out.young_modulus;
      // A shape-set rod turns by at most one full turn over its length, u0 l and u1 l^2 / 2 each.
      const double turn_per_length = 2.0 * M_PI / limb.rod.length;
      if (l.contains("precurvature")) {
        limb.rod.precurvature = in_range(l["precurvature"], join(path, "precurvature"),
                                         -turn_per_length, turn_per_length, "1/m");
      }
      if (l.contains("precurvature_slope")) {
        const double bound = 2.0 * turn_per_length / limb.rod.length;
        limb.rod.precurvature_slope = in_range(
            l["precurvature_slope"], join(path, "precurvature_slope"), -bound, bound, "1/m^2");
      }
      // A tapered rod ends between half and twice its proximal diameter (EI within 16 times).
      if (l.contains("diameter_slope")) {
        const double per_length = limb.rod.diameter / limb.rod.length;
        limb.rod.diameter_slope = in_range(l["diameter_slope"], join(path, "diameter_slope"),
                                           -0.5 * per_length, per_length, "m/m");
      }
      const Json& range = required(l, path, "q_range");
      const Eigen::Vector2d q = position(range, join(path, "q_range"));
      if (q(0) > q(1)) fail(join(path, "q_range"), "min > max", range);
      limb.q_min = q(0);
      limb.q_max = q(1);
      if (l.contains("home_bow")) {
        const Json& bow = l["home_bow"];
        if (bow != "left" && bow != "right") {
          fail(join(path, "home_bow"), "expected \"left\" or \"right\"", bow);
        }
        limb.home_bow = bow == "left" ? 1 : -1;
      }
    }

    if (root.contains("extrinsics")) {
      const Json& e = root["extrinsics"];
      check_object(e, "extrinsics", {"camera", "pattern"});
      if (e.contains("camera")) {
        out.params.extrinsics.camera = pose(e["camera"], "extrinsics.camera");
      }
      if (e.contains("pattern")) {
        out.params.extrinsics.pattern = pose(e["pattern"], "extrinsics.pattern");
      }
    }
    if (root.contains("uncertainty")) {
      out.uncertainty = uncertainty(root["uncertainty"], out.params.num_limbs);
    }
    return out;
  }
};

using json_io::same_bits;  // and the overload below
bool same_bits(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return same_bits(a(0), b(0)) && same_bits(a(1), b(1));
}

Ordered pair(const Eigen::Vector2d& v) { return Ordered::array({v(0), v(1)}); }
Ordered triple(const Eigen::Vector3d& v) { return Ordered::array({v(0), v(1), v(2)}); }

/// Uncertainty fields of `u` that differ from `base` (all of them when base is null).
Ordered limb_uncertainty_json(const LimbUncertainty& u, const LimbUncertainty* base) {
  Ordered out = Ordered::object();
  if (!base || !same_bits(u.rod.young_modulus, base->rod.young_modulus))
    out["E"] = u.rod.young_modulus;
  if (!base || !same_bits(u.rod.length, base->rod.length)) out["l"] = u.rod.length;
  if (!base || !same_bits(u.rod.diameter, base->rod.diameter)) out["d"] = u.rod.diameter;
  // Only a robot that declares it: the paper's files keep their fields.
  if (base ? !same_bits(u.rod.precurvature, base->rod.precurvature) : u.rod.precurvature != 0.0)
    out["precurvature"] = u.rod.precurvature;
  if (!base || !same_bits(u.A, base->A)) out["A"] = pair(u.A);
  if (!base || !same_bits(u.alpha, base->alpha)) out["alpha"] = u.alpha;
  if (!base || !same_bits(u.B, base->B)) out["B"] = pair(u.B);
  if (!base || !same_bits(u.beta, base->beta)) out["beta"] = u.beta;
  if (!base || !same_bits(u.gamma, base->gamma)) out["gamma"] = u.gamma;
  return out;
}

}  // namespace

void check_json_nesting(const std::string& json_text, const std::string& source) {
  int depth = 0, line = 1, column = 0;
  bool in_string = false, escaped = false;
  for (const char c : json_text) {
    ++column;
    if (c == '\n') {
      ++line;
      column = 0;
    }
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonNesting) {
        throw InputError(source + ":" + std::to_string(line) + ":" + std::to_string(column) +
                         ": JSON nested deeper than " + std::to_string(kMaxJsonNesting) +
                         " levels; not a pcr file");
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

RobotDescription parse_robot(const std::string& json_text, const std::string& source) {
  return Reader(source).robot(json_io::parse_json(json_text, source));
}

RobotKind robot_kind(const std::string& json_text, const std::string& source) {
  return json_io::robot_kind(json_io::JsonReader(source), json_io::parse_json(json_text, source));
}

RobotKind load_robot_kind(const std::string& path) {
  return robot_kind(read_input_file(path, kMaxJsonFileBytes, "a robot description"), path);
}

RobotDescription load_robot(const std::string& path) {
  return parse_robot(read_input_file(path, kMaxJsonFileBytes, "a robot description"), path);
}

std::string robot_to_json(const RobotDescription& robot) {
  const RobotParams<double>& params = robot.params;
  if (params.num_limbs < 2 || params.num_limbs > kMaxLimbs) {
    throw InputError("robot_to_json: robot '" + robot.name + "' has " +
                     std::to_string(params.num_limbs) + " limbs (expected 2 to " +
                     std::to_string(kMaxLimbs) + ")");
  }
  Ordered root = Ordered::object();
  root["pcr_robot"] = kFormatVersion;
  root["name"] = robot.name;
  root["E"] = robot.young_modulus;
  Ordered limbs = Ordered::array();
  for (int i = 0; i < params.num_limbs; ++i) {
    const LimbParams<double>& limb = params.limb(i);
    Ordered l = Ordered::object();
    l["A"] = pair(limb.A);
    l["alpha"] = limb.alpha;
    l["gamma"] = limb.gamma;
    l["B"] = pair(limb.B);
    l["beta"] = limb.beta;
    l["l"] = limb.rod.length;
    l["d"] = limb.rod.diameter;
    l["q_range"] = Ordered::array({limb.q_min, limb.q_max});
    if (!same_bits(limb.rod.young_modulus, robot.young_modulus)) l["E"] = limb.rod.young_modulus;
    if (limb.rod.precurvature != 0.0) l["precurvature"] = limb.rod.precurvature;
    if (limb.rod.precurvature_slope != 0.0) l["precurvature_slope"] = limb.rod.precurvature_slope;
    if (limb.rod.diameter_slope != 0.0) l["diameter_slope"] = limb.rod.diameter_slope;
    if (limb.home_bow != 0) l["home_bow"] = limb.home_bow > 0 ? "left" : "right";
    limbs.push_back(l);
  }
  root["limbs"] = limbs;
  const Extrinsics<double>& e = params.extrinsics;
  root["extrinsics"] = Ordered{{"camera", triple({e.camera.x, e.camera.y, e.camera.theta})},
                               {"pattern", triple({e.pattern.x, e.pattern.y, e.pattern.theta})}};
  if (robot.uncertainty) {
    const RobotUncertainty& u = *robot.uncertainty;
    Ordered uj = limb_uncertainty_json(u.global, nullptr);
    uj["camera"] = triple(u.camera);
    uj["pattern"] = triple(u.pattern);
    if (!u.limbs.empty()) {
      if (u.limbs.size() != static_cast<std::size_t>(params.num_limbs)) {
        throw InputError("robot_to_json: robot '" + robot.name + "': uncertainty.limbs has " +
                         std::to_string(u.limbs.size()) + " entries for " +
                         std::to_string(params.num_limbs) + " limbs");
      }
      Ordered overrides = Ordered::array();
      bool any = false;
      for (const LimbUncertainty& lu : u.limbs) {
        overrides.push_back(limb_uncertainty_json(lu, &u.global));
        any = any || !overrides.back().empty();
      }
      if (any) uj["limbs"] = overrides;
    }
    root["uncertainty"] = uj;
  }
  std::ostringstream out;
  print(root, 0, out);
  out << "\n";
  return out.str();
}

void save_robot(const RobotDescription& robot, const std::string& path) {
  const std::string text = robot_to_json(robot);
  // Never write a file that would not load: validate the text first (NaN, l <= 0, ...).
  parse_robot(text, path + " (being written)");
  write_file_atomically(path, text);
}

RobotDescription load_robot_or_default(const std::string& path) {
  return path.empty() ? default_robot() : load_robot(path);
}

}  // namespace pcr
