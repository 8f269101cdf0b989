// The spatial robot file ("kind": "spatial"): a hand-written file reads as written, the shipped
// file is continuum_stewart_gough() to the bit, writing and reading back is lossless, and every
// bad field gives a message naming the file, the field path and the value.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <utility>

#include "pcr/robot_io.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "random_doubles.hpp"
#include "scratch_directory.hpp"

namespace {

using Json = nlohmann::json;
using pcr::testing::random_double;

// A valid two-rod description written by hand (not by the code under test): one rod pushed
// through its hole and clamped, one on a translated clamp with a ball joint, precurved, shearable.
const char* const kValid = R"({
  "pcr_robot": 1,
  "kind": "spatial",
  "name": "test-2rod",
  "rods": [
    {"length": 0.4, "diameter": 2e-3, "young_modulus": 200e9, "shear_modulus": 80e9,
     "density": 8000, "A": [0.1, 0, 0], "base_orientation": [1, 0, 0, 0],
     "actuation": "length_through_hole", "B": [0.05, 0, 0], "tip_orientation": [0, 1, 0, 0],
     "attachment": "clamped"},
    {"length": 0.3, "diameter": 1e-3, "young_modulus": 50e9, "shear_modulus": 20e9,
     "density": 6500, "intrinsic_curvature": [0.5, -0.25, 1], "shear_and_extension": true,
     "A": [-0.1, 0, 0.01], "base_orientation": [0.6, 0, 0.8, 0], "actuation": "translated_clamp",
     "actuator_direction": [0, 0.6, 0.8], "B": [-0.05, 0, 0], "attachment": "spherical"}
  ],
  "platform_mass": 0.25,
  "platform_centre_of_mass": [0, 0, 0.01],
  "gravity": [0, 0, -9.81],
  "external_force": [1, 2, 3],
  "external_moment": [0.1, 0.2, 0.3],
  "extrinsics": {"tracker": {"position": [0.5, -0.25, 1.5], "orientation": [0, 0, 0.6, 0.8]},
                 "marker": {"position": [0, 0, -0.01]}},
  "uncertainty": {"l": 5e-4, "A": [1e-4, 2e-4, 3e-4], "tip_rotation": [5e-3, 5e-3, 0],
                  "tracker": [1e-3, 1e-3, 2e-3, 0.05, 0.05, 0.1],
                  "rods": [{}, {"l": 1e-3, "G": 4e9, "base_rotation": [0, 0, 0.01]}]}
})";

Json valid() { return Json::parse(kValid); }

/// The message of parsing `text` as a spatial robot, or "" when it loads.
std::string error_of(const Json& j) {
  try {
    pcr::parse_spatial_robot(j.dump(), "bad.json");
  } catch (const pcr::InputError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_MESSAGE(message, ...)                                                    \
  do {                                                                                  \
    const std::string m_ = (message);                                                   \
    EXPECT_NE(m_.find("bad.json"), std::string::npos) << m_;                            \
    for (const char* part : {__VA_ARGS__}) {                                            \
      EXPECT_NE(m_.find(part), std::string::npos) << "'" << part << "' not in: " << m_; \
    }                                                                                   \
  } while (0)

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
template <class A, class B>
bool same(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    if (!same(a(i), b(i))) return false;
  }
  return a.size() == b.size();
}

/// Bit-for-bit equality of two spatial robots (every member of SpatialRobotParams).
void expect_same(const pcr::SpatialRobotParams<double>& a,
                 const pcr::SpatialRobotParams<double>& b) {
  ASSERT_EQ(a.num_rods, b.num_rods);
  for (int i = 0; i < a.num_rods; ++i) {
    const pcr::SpatialLimbParams<double>& x = a.limb(i);
    const pcr::SpatialLimbParams<double>& y = b.limb(i);
    EXPECT_TRUE(same(x.rod.length, y.rod.length)) << "rod " << i;
    EXPECT_TRUE(same(x.rod.diameter, y.rod.diameter)) << "rod " << i;
    EXPECT_TRUE(same(x.rod.young_modulus, y.rod.young_modulus)) << "rod " << i;
    EXPECT_TRUE(same(x.rod.shear_modulus, y.rod.shear_modulus)) << "rod " << i;
    EXPECT_TRUE(same(x.rod.density, y.rod.density)) << "rod " << i;
    EXPECT_TRUE(same(x.rod.intrinsic_curvature, y.rod.intrinsic_curvature)) << "rod " << i;
    EXPECT_EQ(x.rod.shear_and_extension, y.rod.shear_and_extension) << "rod " << i;
    EXPECT_TRUE(same(x.A, y.A)) << "rod " << i;
    EXPECT_TRUE(same(x.base_orientation, y.base_orientation)) << "rod " << i;
    EXPECT_EQ(x.actuation, y.actuation) << "rod " << i;
    EXPECT_TRUE(same(x.actuator_direction, y.actuator_direction)) << "rod " << i;
    EXPECT_TRUE(same(x.B, y.B)) << "rod " << i;
    EXPECT_TRUE(same(x.tip_orientation, y.tip_orientation)) << "rod " << i;
    EXPECT_EQ(x.attachment, y.attachment) << "rod " << i;
  }
  EXPECT_TRUE(same(a.platform_mass, b.platform_mass));
  EXPECT_TRUE(same(a.platform_centre_of_mass, b.platform_centre_of_mass));
  EXPECT_TRUE(same(a.gravity, b.gravity));
  EXPECT_TRUE(same(a.external_force, b.external_force));
  EXPECT_TRUE(same(a.external_moment, b.external_moment));
  for (const auto& [x, y] : {std::pair(a.extrinsics.tracker, b.extrinsics.tracker),
                             std::pair(a.extrinsics.marker, b.extrinsics.marker)}) {
    EXPECT_TRUE(same(x.position, y.position));
    EXPECT_TRUE(same(x.orientation, y.orientation));
  }
}

void expect_same(const pcr::SpatialRodUncertainty& a, const pcr::SpatialRodUncertainty& b) {
  EXPECT_TRUE(same(a.young_modulus, b.young_modulus));
  EXPECT_TRUE(same(a.shear_modulus, b.shear_modulus));
  EXPECT_TRUE(same(a.diameter, b.diameter));
  EXPECT_TRUE(same(a.length, b.length));
  EXPECT_TRUE(same(a.A, b.A));
  EXPECT_TRUE(same(a.base_rotation, b.base_rotation));
  EXPECT_TRUE(same(a.B, b.B));
  EXPECT_TRUE(same(a.tip_rotation, b.tip_rotation));
}

void expect_same(const std::optional<pcr::SpatialUncertainty>& a,
                 const std::optional<pcr::SpatialUncertainty>& b) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  expect_same(a->global, b->global);
  ASSERT_EQ(a->rods.size(), b->rods.size());
  for (std::size_t i = 0; i < a->rods.size(); ++i) expect_same(a->rods[i], b->rods[i]);
  EXPECT_TRUE(same(a->tracker, b->tracker));
  EXPECT_TRUE(same(a->marker, b->marker));
}

TEST(SpatialRobotIo, ParsesAValidFile) {
  const pcr::SpatialRobotDescription r = pcr::parse_spatial_robot(kValid, "valid.json");
  EXPECT_EQ(r.name, "test-2rod");
  const pcr::SpatialRobotParams<double>& p = r.params;
  ASSERT_EQ(p.num_rods, 2);
  const pcr::SpatialLimbParams<double>& a = p.limb(0);
  const pcr::SpatialLimbParams<double>& b = p.limb(1);
  EXPECT_EQ(a.rod.length, 0.4);
  EXPECT_EQ(a.rod.diameter, 2e-3);
  EXPECT_EQ(a.rod.young_modulus, 200e9);
  EXPECT_EQ(a.rod.shear_modulus, 80e9);
  EXPECT_EQ(a.rod.density, 8000);
  EXPECT_EQ(a.rod.intrinsic_curvature, pcr::Vector3<double>::Zero());  // the defaults
  EXPECT_FALSE(a.rod.shear_and_extension);
  EXPECT_EQ(a.actuator_direction, pcr::Vector3<double>::UnitZ());
  EXPECT_EQ(a.A, pcr::Vector3<double>(0.1, 0, 0));
  EXPECT_EQ(a.actuation, pcr::SpatialActuation::kLengthThroughHole);
  EXPECT_EQ(a.B, pcr::Vector3<double>(0.05, 0, 0));
  EXPECT_EQ(a.tip_orientation, pcr::Vector4<double>(0, 1, 0, 0));
  EXPECT_EQ(a.attachment, pcr::SpatialAttachment::kClamped);
  EXPECT_EQ(b.rod.intrinsic_curvature, pcr::Vector3<double>(0.5, -0.25, 1));
  EXPECT_TRUE(b.rod.shear_and_extension);
  EXPECT_EQ(b.base_orientation, pcr::Vector4<double>(0.6, 0, 0.8, 0));
  EXPECT_EQ(b.actuation, pcr::SpatialActuation::kTranslatedClamp);
  EXPECT_EQ(b.actuator_direction, pcr::Vector3<double>(0, 0.6, 0.8));
  EXPECT_EQ(b.tip_orientation, pcr::Vector4<double>(1, 0, 0, 0));  // the default
  EXPECT_EQ(b.attachment, pcr::SpatialAttachment::kSpherical);
  EXPECT_EQ(p.platform_mass, 0.25);
  EXPECT_EQ(p.platform_centre_of_mass, pcr::Vector3<double>(0, 0, 0.01));
  EXPECT_EQ(p.gravity, pcr::Vector3<double>(0, 0, -9.81));
  EXPECT_EQ(p.external_force, pcr::Vector3<double>(1, 2, 3));
  EXPECT_EQ(p.external_moment, pcr::Vector3<double>(0.1, 0.2, 0.3));
  EXPECT_EQ(p.extrinsics.tracker.position, pcr::Vector3<double>(0.5, -0.25, 1.5));
  EXPECT_EQ(p.extrinsics.tracker.orientation, pcr::Vector4<double>(0, 0, 0.6, 0.8));
  EXPECT_EQ(p.extrinsics.marker.position, pcr::Vector3<double>(0, 0, -0.01));
  EXPECT_EQ(p.extrinsics.marker.orientation, pcr::Vector4<double>(1, 0, 0, 0));  // the default
  ASSERT_TRUE(r.uncertainty.has_value());
  const pcr::SpatialUncertainty& u = *r.uncertainty;
  ASSERT_EQ(u.rods.size(), 2u);
  for (const pcr::SpatialRodUncertainty& rod : {u.global, u.rods[0], u.rods[1]}) {
    EXPECT_EQ(rod.A, Eigen::Vector3d(1e-4, 2e-4, 3e-4));
    EXPECT_EQ(rod.tip_rotation, Eigen::Vector3d(5e-3, 5e-3, 0));
    EXPECT_EQ(rod.young_modulus, 0.0);
    EXPECT_EQ(rod.B, Eigen::Vector3d::Zero());
  }
  EXPECT_EQ(u.rods[0].length, 5e-4);
  EXPECT_EQ(u.rods[0].shear_modulus, 0.0);
  EXPECT_EQ(u.rods[1].length, 1e-3);
  EXPECT_EQ(u.rods[1].shear_modulus, 4e9);
  EXPECT_EQ(u.rods[1].base_rotation, Eigen::Vector3d(0, 0, 0.01));
  EXPECT_EQ(u.global.base_rotation, Eigen::Vector3d::Zero());
  EXPECT_EQ(u.tracker(2), 2e-3);
  EXPECT_EQ(u.tracker(5), 0.1);
  EXPECT_EQ(u.marker, (Eigen::Matrix<double, 6, 1>::Zero()));
}

TEST(SpatialRobotIo, ShippedFileIsTheReferenceRobot) {
  const pcr::SpatialRobotDescription r =
      pcr::load_spatial_robot(std::string(PCR_SOURCE_DIR) + "/robots/continuum-stewart-gough.json");
  EXPECT_EQ(r.name, "continuum-stewart-gough");
  expect_same(r.params, pcr::continuum_stewart_gough());
  expect_same(r.uncertainty, std::optional(pcr::continuum_stewart_gough_uncertainty()));
  EXPECT_EQ(
      pcr::load_robot_kind(std::string(PCR_SOURCE_DIR) + "/robots/continuum-stewart-gough.json"),
      pcr::RobotKind::kSpatial);
}

TEST(SpatialRobotIo, RoundTripIsBitExact) {
  std::mt19937_64 rng(11);
  const pcr::test::ScratchDirectory scratch("spatial_robot_io");
  const std::string path = (scratch.path() / "robot.json").string();
  auto coordinate = [&] { return random_double(rng, -300, 0.9, false); };  // |x| < 8 m
  auto vector = [&] { return pcr::Vector3<double>(coordinate(), coordinate(), coordinate()); };
  // Components of a unit vector from 1e-3 up: every bit drawn, and no norm that underflows.
  auto component = [&] { return random_double(rng, -3, 0.9, false); };
  auto unit4 = [&] {
    pcr::Vector4<double> h(component(), component(), component(), component());
    return pcr::Vector4<double>(h / h.norm());
  };
  // Random bits over every magnitude the loader accepts: each decimal exponent range below keeps
  // its whole binary exponent inside the field's range (x 2 at most above 10^hi).
  for (int trial = 0; trial < 40; ++trial) {
    pcr::SpatialRobotDescription r;
    r.name = "random \"robot\" \\ " + std::to_string(trial);
    pcr::SpatialRobotParams<double>& p = r.params;
    p.num_rods = 1 + trial % pcr::kMaxSpatialRods;
    for (int i = 0; i < p.num_rods; ++i) {
      pcr::SpatialLimbParams<double>& l = p.limb(i);
      l.rod.length = random_double(rng, -2.9, 0.9, true);
      l.rod.diameter = random_double(rng, -5.5, -3.1, true);  // below any length
      l.rod.young_modulus = random_double(rng, 6.1, 11.9, true);
      l.rod.shear_modulus = random_double(rng, 5.3, 11.9, true);
      l.rod.density = random_double(rng, -3, 4.7, true);
      // |u*| < 0.5 1/m, within a turn over any length drawn here (2 pi / 8 m).
      l.rod.intrinsic_curvature = pcr::Vector3<double>(random_double(rng, -300, -0.4, false),
                                                       random_double(rng, -300, -0.4, false),
                                                       random_double(rng, -300, -0.4, false));
      l.rod.shear_and_extension = (trial + i) % 2 == 0;
      l.A = vector();
      l.base_orientation = unit4();
      l.actuation = i % 2 ? pcr::SpatialActuation::kTranslatedClamp
                          : pcr::SpatialActuation::kLengthThroughHole;
      const pcr::Vector3<double> d(component(), component(), component());
      l.actuator_direction = d / d.norm();
      l.B = vector();
      l.tip_orientation = unit4();
      l.attachment = i % 3 ? pcr::SpatialAttachment::kClamped : pcr::SpatialAttachment::kSpherical;
    }
    p.platform_mass = random_double(rng, -4, 2.7, true);
    p.platform_centre_of_mass = vector();
    p.gravity = vector();
    p.external_force = vector();
    p.external_moment = vector();
    p.extrinsics.tracker = pcr::SpatialPose<double>{vector(), unit4()};
    p.extrinsics.marker = pcr::SpatialPose<double>{vector(), unit4()};
    if (trial % 3 != 0) {
      // Half-widths from 1e-12 up (a position's to 0.1 m, a turn's to 1 rad), some rods overridden.
      auto width = [&](double hi) { return random_double(rng, -11.7, hi, true); };
      auto widths = [&](double hi) { return Eigen::Vector3d(width(hi), width(hi), width(hi)); };
      auto rod = [&] {
        pcr::SpatialRodUncertainty u;
        u.young_modulus = random_double(rng, 3.1, 11.6, true);
        u.shear_modulus = random_double(rng, 3.1, 11.6, true);
        u.diameter = width(-2.4);
        u.length = width(-1.4);
        u.A = widths(-1.4);
        u.base_rotation = widths(-0.4);
        u.B = widths(-1.4);
        u.tip_rotation = widths(-0.4);
        return u;
      };
      pcr::SpatialUncertainty u;
      u.global = rod();
      for (int i = 0; i < p.num_rods; ++i) u.rods.push_back(i % 2 ? rod() : u.global);
      for (int k = 0; k < 6; ++k) {
        u.tracker(k) = width(k < 3 ? -1.4 : -0.4);
        u.marker(k) = width(k < 3 ? -1.4 : -0.4);
      }
      r.uncertainty = u;
    }

    const pcr::SpatialRobotDescription text =
        pcr::parse_spatial_robot(pcr::spatial_robot_to_json(r), "memory");
    EXPECT_EQ(text.name, r.name);
    expect_same(text.params, p);
    expect_same(text.uncertainty, r.uncertainty);
    pcr::save_spatial_robot(r, path);
    expect_same(pcr::load_spatial_robot(path).params, p);
    expect_same(pcr::load_spatial_robot(path).uncertainty, r.uncertainty);
    if (HasFailure()) break;
  }
  // A description that would not load is refused and nothing is written.
  pcr::SpatialRobotDescription bad = pcr::continuum_stewart_gough_description();
  bad.params.limb(2).tip_orientation *= 2.0;
  const std::string bad_path = (scratch.path() / "bad.json").string();
  EXPECT_THROW(pcr::save_spatial_robot(bad, bad_path), pcr::InputError);
  EXPECT_FALSE(std::filesystem::exists(bad_path));
}

TEST(SpatialRobotIo, BadFieldsAreNamedWithTheirValues) {
  Json j = valid();
  j["rods"][1].erase("shear_modulus");
  EXPECT_MESSAGE(error_of(j), "rods[1].shear_modulus", "missing required field");

  j = valid();
  j["rods"][0]["diameter"] = -2e-3;
  EXPECT_MESSAGE(error_of(j), "rods[0].diameter", "-0.002");

  j = valid();
  j["rods"][0]["tip_orientation"] = {1, 0, 0, 1e-4};  // |h| - 1 = 5e-9
  EXPECT_MESSAGE(error_of(j), "rods[0].tip_orientation", "unit norm", "0.0001");
  j = valid();
  j["rods"][1]["base_orientation"] = {0.6, 0, 0.8 + 2e-9, 0};
  EXPECT_MESSAGE(error_of(j), "rods[1].base_orientation", "unit norm");
  j = valid();
  j["rods"][1]["base_orientation"] = {0.6, 0, 0.8 + 5e-10, 0};  // within 1e-9: accepted as is
  EXPECT_EQ(error_of(j), "");
  EXPECT_EQ(pcr::parse_spatial_robot(j.dump(), "x").params.limb(1).base_orientation(2),
            0.8 + 5e-10);
  j = valid();
  j["rods"][1]["actuator_direction"] = {0, 1, 1};
  EXPECT_MESSAGE(error_of(j), "rods[1].actuator_direction", "unit norm", "[0,1,1]");

  j = valid();
  for (int i = 0; i < 7; ++i) j["rods"].push_back(j["rods"][0]);
  EXPECT_MESSAGE(error_of(j), "rods", "between 1 and 8 rods, got 9");
  j["rods"] = Json::array();
  EXPECT_MESSAGE(error_of(j), "rods", "got 0");

  j = valid();
  j["kind"] = "planar";
  EXPECT_MESSAGE(error_of(j), "kind", "spatial robot file", "planar");
  j.erase("kind");
  EXPECT_MESSAGE(error_of(j), "kind", "spatial robot file", "no kind field");
  j["kind"] = "hexapod";
  EXPECT_MESSAGE(error_of(j), "kind", "\"hexapod\"");

  j = valid();
  j["rods"][0]["actuation"] = "pushed";
  EXPECT_MESSAGE(error_of(j), "rods[0].actuation", "translated_clamp", "\"pushed\"");
  j = valid();
  j["rods"][1]["attachment"] = "glued";
  EXPECT_MESSAGE(error_of(j), "rods[1].attachment", "spherical", "\"glued\"");
  j = valid();
  j["rods"][1]["shear_and_extension"] = 1;
  EXPECT_MESSAGE(error_of(j), "rods[1].shear_and_extension", "true or false");
  j = valid();
  j["rods"][0]["lenght"] = 0.4;
  EXPECT_MESSAGE(error_of(j), "rods[0].lenght", "unknown field");
  j = valid();
  j["rods"][0]["young_modulus"] = 200;  // GPa typed as Pa
  EXPECT_MESSAGE(error_of(j), "rods[0].young_modulus", "physical range", "200");
  j = valid();
  j["rods"][0]["length"] = 0.05;
  j["rods"][0]["diameter"] = 0.06;  // thicker than long
  EXPECT_MESSAGE(error_of(j), "rods[0].diameter", "smaller than its length", "0.06");
  j = valid();
  j["rods"][1]["intrinsic_curvature"] = {0, 25, 0};  // beyond a turn over 0.3 m
  EXPECT_MESSAGE(error_of(j), "rods[1].intrinsic_curvature[1]", "25");
  j = valid();
  j["platform_mass"] = -0.1;
  EXPECT_MESSAGE(error_of(j), "platform_mass", "-0.1");
  j = valid();
  j["gravity"] = {0, 0};
  EXPECT_MESSAGE(error_of(j), "gravity", "array of 3 numbers");
  j = valid();
  j["external_force"][2] = "3";
  EXPECT_MESSAGE(error_of(j), "external_force[2]", "expected a number");

  j = valid();
  j["uncertainty"]["l"] = -5e-4;
  EXPECT_MESSAGE(error_of(j), "uncertainty.l", "half-width", "-0.0005");
  j = valid();
  j["uncertainty"]["A"] = {1e-4, 0.5, 0};  // half a metre: a unit typo
  EXPECT_MESSAGE(error_of(j), "uncertainty.A[1]", "half-width", "0.5");
  j = valid();
  j["uncertainty"]["tracker"] = {1e-3, 1e-3, 1e-3, 0.05, 0.05};
  EXPECT_MESSAGE(error_of(j), "uncertainty.tracker", "array of 6 numbers");
  j = valid();
  j["uncertainty"]["rods"].push_back(Json::object());
  EXPECT_MESSAGE(error_of(j), "uncertainty.rods", "array of 2 objects");
  j = valid();
  j["uncertainty"]["rods"][1]["alpha"] = 5e-3;  // a planar field
  EXPECT_MESSAGE(error_of(j), "uncertainty.rods[1].alpha", "unknown field");
  j = valid();
  j["uncertainty"]["limbs"] = Json::array();
  EXPECT_MESSAGE(error_of(j), "uncertainty.limbs", "unknown field");
  j = valid();
  j["extrinsics"]["tracker"]["orientation"] = {0, 0, 0.6, 0.81};
  EXPECT_MESSAGE(error_of(j), "extrinsics.tracker.orientation", "unit norm");
  j = valid();
  j["extrinsics"]["camera"] = Json::object();
  EXPECT_MESSAGE(error_of(j), "extrinsics.camera", "unknown field");

  // Non-finite numbers, including a literal that overflows a double.
  std::string text = valid().dump();
  text.replace(text.find("8000"), 4, "1e999");
  try {
    pcr::parse_spatial_robot(text, "bad.json");
    ADD_FAILURE() << "1e999 accepted";
  } catch (const pcr::InputError& e) {
    EXPECT_MESSAGE(e.what(), "rods[0].density", "1e999");
  }
}

TEST(SpatialRobotIo, EachLoaderNamesTheOtherKind) {
  // The planar loader, given a spatial file.
  try {
    pcr::parse_robot(kValid, "bad.json");
    ADD_FAILURE() << "a spatial file loaded as a planar robot";
  } catch (const pcr::InputError& e) {
    EXPECT_MESSAGE(e.what(), "kind", "planar robot file", "\"spatial\"");
  }
  EXPECT_EQ(pcr::robot_kind(kValid, "x"), pcr::RobotKind::kSpatial);
  // A planar file says nothing, or "planar".
  const std::string planar = pcr::robot_to_json(pcr::default_robot());
  EXPECT_EQ(pcr::robot_kind(planar, "x"), pcr::RobotKind::kPlanar);
  Json p = Json::parse(planar);
  p["kind"] = "planar";
  EXPECT_EQ(pcr::robot_kind(p.dump(), "x"), pcr::RobotKind::kPlanar);
  EXPECT_EQ(pcr::parse_robot(p.dump(), "x").params.num_limbs, 3);
  // The spatial loader, given a planar file.
  EXPECT_MESSAGE(error_of(Json::parse(planar)), "kind", "spatial robot file");
}

}  // namespace
