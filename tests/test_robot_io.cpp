// The pcr-robot JSON format: every kind of bad file gives a message naming the file, the field
// path and the value; writing and reading back is lossless to the bit; the shipped default file.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "pcr/robot_io.hpp"
#include "random_doubles.hpp"
#include "scratch_directory.hpp"

namespace {

using Json = nlohmann::json;

// A valid 3-limb description written by hand (not by the code under test).
const char* const kValid = R"({
  "pcr_robot": 1,
  "name": "test-3pf",
  "E": 69e9,
  "limbs": [
    {"A": [0.0, -0.05], "alpha": 1.5, "gamma": 0.0, "B": [0.0, -0.02], "beta": 1.5,
     "l": 0.03, "d": 125e-6, "q_range": [-0.01, 0.01]},
    {"A": [0.04, 0.03], "alpha": 3.6, "gamma": 0.001, "B": [0.02, 0.01], "beta": 3.6,
     "l": 0.031, "d": 125e-6, "q_range": [-0.01, 0.01], "E": 70e9},
    {"A": [-0.04, 0.03], "alpha": 5.7, "gamma": 0.0, "B": [-0.02, 0.01], "beta": 5.7,
     "l": 0.03, "d": 125e-6, "q_range": [-0.01, 0.01]}
  ],
  "extrinsics": {"camera": [0.1, 0.2, 0.3], "pattern": [0.01, 0.02, -0.03]},
  "uncertainty": {"l": 126e-6, "A": [160e-6, 150e-6], "alpha": 5e-3, "camera": [1e-3, 1e-3, 0.05],
                  "limbs": [{}, {"l": 1e-6, "B": [1e-5, 2e-5]}, {"E": 1e9}]}
})";

Json valid() { return Json::parse(kValid); }

/// The message of parsing `text`, or "" when it loads.
std::string error_of(const std::string& text) {
  try {
    pcr::parse_robot(text, "bad.json");
  } catch (const pcr::InputError& e) {
    return e.what();
  }
  return "";
}
std::string error_of(const char* text) { return error_of(std::string(text)); }
std::string error_of(const Json& j) { return error_of(j.dump()); }

#define EXPECT_MESSAGE(message, ...)                                                    \
  do {                                                                                  \
    const std::string m_ = (message);                                                   \
    EXPECT_NE(m_.find("bad.json"), std::string::npos) << m_;                            \
    for (const char* part : {__VA_ARGS__}) {                                            \
      EXPECT_NE(m_.find(part), std::string::npos) << "'" << part << "' not in: " << m_; \
    }                                                                                   \
  } while (0)

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_limb_uncertainty(const pcr::LimbUncertainty& a, const pcr::LimbUncertainty& b) {
  EXPECT_TRUE(same(a.A.x(), b.A.x()) && same(a.A.y(), b.A.y()));
  EXPECT_TRUE(same(a.B.x(), b.B.x()) && same(a.B.y(), b.B.y()));
  EXPECT_TRUE(same(a.alpha, b.alpha));
  EXPECT_TRUE(same(a.beta, b.beta));
  EXPECT_TRUE(same(a.gamma, b.gamma));
  EXPECT_TRUE(same(a.rod.length, b.rod.length));
  EXPECT_TRUE(same(a.rod.diameter, b.rod.diameter));
  EXPECT_TRUE(same(a.rod.young_modulus, b.rod.young_modulus));
  EXPECT_TRUE(same(a.rod.precurvature, b.rod.precurvature));
}

/// Bit-for-bit equality of two descriptions.
void expect_same(const pcr::RobotDescription& a, const pcr::RobotDescription& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_TRUE(same(a.young_modulus, b.young_modulus));
  ASSERT_EQ(a.params.num_limbs, b.params.num_limbs);
  for (int i = 0; i < a.params.num_limbs; ++i) {
    const pcr::LimbParams<double>& x = a.params.limb(i);
    const pcr::LimbParams<double>& y = b.params.limb(i);
    EXPECT_TRUE(same(x.A.x(), y.A.x()) && same(x.A.y(), y.A.y())) << "limb " << i;
    EXPECT_TRUE(same(x.B.x(), y.B.x()) && same(x.B.y(), y.B.y())) << "limb " << i;
    EXPECT_TRUE(same(x.alpha, y.alpha) && same(x.beta, y.beta) && same(x.gamma, y.gamma));
    EXPECT_TRUE(same(x.rod.length, y.rod.length) && same(x.rod.diameter, y.rod.diameter));
    EXPECT_TRUE(same(x.rod.young_modulus, y.rod.young_modulus));
    EXPECT_TRUE(same(x.rod.precurvature, y.rod.precurvature));
    EXPECT_TRUE(same(x.rod.precurvature_slope, y.rod.precurvature_slope));
    EXPECT_TRUE(same(x.rod.diameter_slope, y.rod.diameter_slope));
    EXPECT_TRUE(same(x.q_min, y.q_min) && same(x.q_max, y.q_max));
    EXPECT_EQ(x.home_bow, y.home_bow);
  }
  const pcr::Extrinsics<double>& e = a.params.extrinsics;
  const pcr::Extrinsics<double>& f = b.params.extrinsics;
  EXPECT_TRUE(same(e.camera.x, f.camera.x) && same(e.camera.y, f.camera.y) &&
              same(e.camera.theta, f.camera.theta));
  EXPECT_TRUE(same(e.pattern.x, f.pattern.x) && same(e.pattern.y, f.pattern.y) &&
              same(e.pattern.theta, f.pattern.theta));
  ASSERT_EQ(a.uncertainty.has_value(), b.uncertainty.has_value());
  if (a.uncertainty) {
    expect_same_limb_uncertainty(a.uncertainty->global, b.uncertainty->global);
    ASSERT_EQ(a.uncertainty->limbs.size(), b.uncertainty->limbs.size());
    for (std::size_t i = 0; i < a.uncertainty->limbs.size(); ++i) {
      expect_same_limb_uncertainty(a.uncertainty->limbs[i], b.uncertainty->limbs[i]);
    }
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(same(a.uncertainty->camera(k), b.uncertainty->camera(k)));
      EXPECT_TRUE(same(a.uncertainty->pattern(k), b.uncertainty->pattern(k)));
    }
  }
}

TEST(RobotIo, ParsesAValidFile) {
  const pcr::RobotDescription r = pcr::parse_robot(kValid, "valid.json");
  EXPECT_EQ(r.name, "test-3pf");
  EXPECT_EQ(r.young_modulus, 69e9);
  ASSERT_EQ(r.params.num_limbs, 3);
  EXPECT_EQ(r.params.limb(0).rod.young_modulus, 69e9);  // global E
  EXPECT_EQ(r.params.limb(1).rod.young_modulus, 70e9);  // per-limb override
  EXPECT_EQ(r.params.limb(1).gamma, 0.001);
  EXPECT_EQ(r.params.limb(1).rod.length, 0.031);
  EXPECT_EQ(r.params.limb(2).q_min, -0.01);
  EXPECT_EQ(r.params.extrinsics.camera.theta, 0.3);
  EXPECT_EQ(r.params.extrinsics.pattern.y, 0.02);
  ASSERT_TRUE(r.uncertainty.has_value());
  const pcr::RobotUncertainty& u = *r.uncertainty;
  EXPECT_EQ(u.global.rod.length, 126e-6);
  EXPECT_EQ(u.global.A.y(), 150e-6);
  EXPECT_EQ(u.global.rod.diameter, 0.0);  // absent: 0
  ASSERT_EQ(u.limbs.size(), 3u);
  EXPECT_EQ(u.limbs[0].rod.length, 126e-6);  // {} keeps the global values
  EXPECT_EQ(u.limbs[1].rod.length, 1e-6);
  EXPECT_EQ(u.limbs[1].alpha, 5e-3);  // not overridden
  EXPECT_EQ(u.limbs[1].B.y(), 2e-5);
  EXPECT_EQ(u.limbs[2].rod.young_modulus, 1e9);
  EXPECT_EQ(u.camera.z(), 0.05);
  EXPECT_EQ(u.pattern.z(), 0.0);
}

TEST(RobotIo, OptionalSectionsDefault) {
  Json j = valid();
  j.erase("extrinsics");
  j.erase("uncertainty");
  const pcr::RobotDescription r = pcr::parse_robot(j.dump(), "x.json");
  EXPECT_EQ(r.params.extrinsics.camera.x, 0.0);
  EXPECT_EQ(r.params.extrinsics.pattern.theta, 0.0);
  EXPECT_FALSE(r.uncertainty.has_value());
}

TEST(RobotIo, UnknownFieldsAreErrorsAtEveryLevel) {
  Json j = valid();
  j["nmae"] = "x";
  EXPECT_MESSAGE(error_of(j), "nmae", "unknown field");
  j = valid();
  j["limbs"][1]["lenght"] = 0.03;
  EXPECT_MESSAGE(error_of(j), "limbs[1].lenght", "unknown field");
  j = valid();
  j["extrinsics"]["camra"] = Json::array({0, 0, 0});
  EXPECT_MESSAGE(error_of(j), "extrinsics.camra", "unknown field");
  j = valid();
  j["uncertainty"]["q_range"] = 1e-3;
  EXPECT_MESSAGE(error_of(j), "uncertainty.q_range", "unknown field");
  j = valid();
  j["uncertainty"]["limbs"][2]["camera"] = Json::array({0, 0, 0});
  EXPECT_MESSAGE(error_of(j), "uncertainty.limbs[2].camera", "unknown field");
}

TEST(RobotIo, MissingRequiredFields) {
  for (const char* key : {"pcr_robot", "name", "E", "limbs"}) {
    Json j = valid();
    j.erase(key);
    EXPECT_MESSAGE(error_of(j), key, "missing required field");
  }
  for (const char* key : {"A", "alpha", "gamma", "B", "beta", "l", "d", "q_range"}) {
    Json j = valid();
    j["limbs"][2].erase(key);
    const std::string path = "limbs[2]." + std::string(key);
    EXPECT_MESSAGE(error_of(j), path.c_str(), "missing required");
  }
}

TEST(RobotIo, NonFiniteNumbers) {
  // JSON has no NaN: a string "nan" is a type error, 1e999 overflows to infinity.
  std::string text = kValid;
  text.replace(text.find("\"l\": 0.031"), 10, "\"l\": \"nan\"");
  EXPECT_MESSAGE(error_of(text), "limbs[1].l", "expected a number", "\"nan\"");
  text = kValid;
  text.replace(text.find("\"alpha\": 3.6"), 12, "\"alpha\": 1e999");
  EXPECT_MESSAGE(error_of(text), "limbs[1].alpha", "finite", "1e999");
  text = kValid;
  text.replace(text.find("\"E\": 69e9"), 9, "\"E\": -1e999");
  EXPECT_MESSAGE(error_of(text), "E", "finite", "-1e999");
  text = kValid;
  text.replace(text.find("[0.1, 0.2, 0.3]"), 15, "[0.1, NaN, 0.3]");
  EXPECT_NE(error_of(text).find("bad.json:"), std::string::npos);  // a syntax error
}

TEST(RobotIo, TypeAndShapeErrors) {
  Json j = valid();
  j["limbs"][0]["A"] = Json::array({0.0, 1.0, 2.0});
  EXPECT_MESSAGE(error_of(j), "limbs[0].A", "array of 2", "[0.0,1.0,2.0]");
  j = valid();
  j["limbs"][0]["A"] = "origin";
  EXPECT_MESSAGE(error_of(j), "limbs[0].A", "\"origin\"");
  j = valid();
  j["limbs"][0]["B"][1] = true;
  EXPECT_MESSAGE(error_of(j), "limbs[0].B[1]", "expected a number", "true");
  j = valid();
  j["name"] = 3;
  EXPECT_MESSAGE(error_of(j), "name", "expected a string", "3");
  j = valid();
  j["limbs"] = Json::object();
  EXPECT_MESSAGE(error_of(j), "limbs", "array");
  j = valid();
  j["limbs"][1] = 0.5;
  EXPECT_MESSAGE(error_of(j), "limbs[1]", "expected an object", "0.5");
  j = valid();
  j["extrinsics"]["pattern"] = Json::array({0.0, 0.0});
  EXPECT_MESSAGE(error_of(j), "extrinsics.pattern", "array of 3");
  j = valid();
  j["pcr_robot"] = 2;
  EXPECT_MESSAGE(error_of(j), "pcr_robot", "version", "2");
  EXPECT_MESSAGE(error_of("[1, 2]"), "expected an object");
}

TEST(RobotIo, ValueRules) {
  Json j = valid();
  j["limbs"][0]["l"] = std::string(1 << 20, 'x');  // shown as its first characters only
  const std::string long_value = error_of(j);
  EXPECT_LT(long_value.size(), 200u) << long_value.substr(0, 200);
  EXPECT_MESSAGE(long_value, "limbs[0].l", "xxx...");
  j = valid();
  j["limbs"][2]["l"] = -0.03;
  EXPECT_MESSAGE(error_of(j), "limbs[2].l", "physical range", "-0.03");
  j = valid();
  j["limbs"][0]["d"] = 0.0;
  EXPECT_MESSAGE(error_of(j), "limbs[0].d", "physical range", "got 0");
  j = valid();
  j["E"] = 0;
  EXPECT_MESSAGE(error_of(j), "E", "physical range", "got 0");
  j = valid();
  j["limbs"][1]["E"] = -70e9;
  EXPECT_MESSAGE(error_of(j), "limbs[1].E", "physical range", "-70000000000");
  j = valid();  // a shape-set rod turns by at most one full turn: |u0| <= 2 pi / l
  j["limbs"][1]["precurvature"] = 250.0;
  EXPECT_MESSAGE(error_of(j), "limbs[1].precurvature", "physical range", "1/m", "got 250");
  j["limbs"][1]["precurvature"] = -150.0;
  j["limbs"][1]["precurvature_slope"] = "steep";
  EXPECT_MESSAGE(error_of(j), "limbs[1].precurvature_slope", "steep");
  j["limbs"][1]["precurvature_slope"] = 2e4;
  EXPECT_MESSAGE(error_of(j), "limbs[1].precurvature_slope", "physical range", "1/m^2");
  j = valid();  // a tapered rod's tip: from half to twice its base diameter, d' l / d in [-0.5, 1]
  j["limbs"][1]["diameter_slope"] =
      -0.6 * j["limbs"][1]["d"].get<double>() / j["limbs"][1]["l"].get<double>();
  EXPECT_MESSAGE(error_of(j), "limbs[1].diameter_slope", "physical range", "m/m");
  j["limbs"][1]["diameter_slope"] = "thin";
  EXPECT_MESSAGE(error_of(j), "limbs[1].diameter_slope", "thin");
  j = valid();
  j["limbs"][1]["q_range"] = Json::array({0.01, -0.01});
  EXPECT_MESSAGE(error_of(j), "limbs[1].q_range", "min > max", "[0.01,-0.01]");
  j = valid();
  j["limbs"][2]["home_bow"] = "up";
  EXPECT_MESSAGE(error_of(j), "limbs[2].home_bow", "\"left\" or \"right\"", "\"up\"");
  j["limbs"][2]["home_bow"] = 1;
  EXPECT_MESSAGE(error_of(j), "limbs[2].home_bow", "\"left\" or \"right\"", "got 1");
  j = valid();
  j["limbs"].erase(1);
  j["limbs"].erase(1);
  j.erase("uncertainty");
  EXPECT_MESSAGE(error_of(j), "limbs", "between 2 and", "got 1");
  j = valid();
  j.erase("uncertainty");
  for (int i = 0; i < 4; ++i) j["limbs"].push_back(j["limbs"][0]);
  EXPECT_MESSAGE(error_of(j), "limbs", "got 7");
}

TEST(RobotIo, UncertaintyRules) {
  Json j = valid();
  j["uncertainty"]["l"] = -1e-6;
  EXPECT_MESSAGE(error_of(j), "uncertainty.l", "must be 0 or in", "-1e-06");
  j = valid();
  j["uncertainty"]["camera"][2] = -0.05;
  EXPECT_MESSAGE(error_of(j), "uncertainty.camera[2]", "must be 0 or in", "-0.05");
  j = valid();
  j["uncertainty"]["limbs"][1]["B"][0] = -1e-5;
  EXPECT_MESSAGE(error_of(j), "uncertainty.limbs[1].B[0]", "must be 0 or in", "-1e-05");
  j = valid();
  j["uncertainty"]["limbs"].erase(2);
  EXPECT_MESSAGE(error_of(j), "uncertainty.limbs", "array of 3");
}

TEST(RobotIo, SyntaxErrorsNameLineAndColumn) {
  const std::string m = error_of("{\n  \"pcr_robot\": 1,\n  \"name\": oops\n}\n");
  EXPECT_MESSAGE(m, "bad.json:3:", "syntax error");
  EXPECT_MESSAGE(error_of("{\"name\": \"a\", \"name\": \"b\"}"), "duplicate field", "name");
  EXPECT_MESSAGE(error_of(""), "bad.json:1:1");
}

TEST(RobotIo, UnreadableFileNamesIt) {
  try {
    pcr::load_robot("/nonexistent/robot.json");
    FAIL();
  } catch (const pcr::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.json"), std::string::npos);
  }
}

using pcr::testing::random_double;

TEST(RobotIo, RoundTripIsBitExact) {
  std::mt19937_64 rng(7);
  const pcr::test::ScratchDirectory scratch("robot_io");
  const std::filesystem::path& dir = scratch.path();
  for (int trial = 0; trial < 50; ++trial) {
    pcr::RobotDescription r;
    r.name = "random \"robot\" \\ " + std::to_string(trial);
    // Random bits over every magnitude the loader accepts (a double's binary exponent, so the
    // decimal bounds below sit inside each field's physical range).
    r.young_modulus = random_double(rng, 6.1, 11.9, true);
    r.params.num_limbs = 2 + trial % (pcr::kMaxLimbs - 1);
    auto any = [&] { return random_double(rng, -300, 0.9, false); };  // |x| < 8: m or rad
    auto length = [&] { return random_double(rng, -2.9, 0.9, true); };
    auto diameter = [&] { return random_double(rng, -5.5, -3.1, true); };  // below any length
    auto half = [&] { return random_double(rng, -11.5, -2.1, true); };
    pcr::RobotUncertainty u;
    u.global.rod.length = half();
    u.global.A = Eigen::Vector2d(half(), 0.0);
    u.camera = Eigen::Vector3d(half(), half(), 0.0);
    for (int i = 0; i < r.params.num_limbs; ++i) {
      pcr::LimbParams<double>& l = r.params.limb(i);
      l.A = Eigen::Vector2d{any(), any()};
      l.B = Eigen::Vector2d(any(), -0.0);
      l.alpha = any();
      l.beta = any();
      l.gamma = any();
      l.rod.length = length();
      l.rod.diameter = diameter();
      l.rod.young_modulus = (i % 2) ? random_double(rng, 6.1, 11.9, true) : r.young_modulus;
      if (i % 3 == 1) {  // |u0| < 0.63 1/m and |u1| < 0.16 1/m^2: inside 2 pi / l, 4 pi / l^2
        l.rod.precurvature = random_double(rng, -300, -0.2, false);
        l.rod.precurvature_slope = random_double(rng, -300, -0.8, false);
      }
      if (i % 3 == 2) {  // a tapered rod: |d' l / d| < 0.4, its tip 0.6 to 1.4 times as thick
        l.rod.diameter_slope =
            0.4 * l.rod.diameter / l.rod.length * random_double(rng, -300, -0.01, false);
      }
      l.q_min = -std::abs(any());
      l.q_max = std::abs(any());
      l.home_bow = (trial + i) % 3 - 1;  // right, not said, left
      pcr::LimbUncertainty lu = u.global;
      if (i == 1) lu.beta = half();
      if (i == 2) lu.rod.young_modulus = random_double(rng, 6.1, 8.9, true);
      if (i == 3) lu.rod.precurvature = random_double(rng, -8.9, 3.9, true);  // 1/m
      u.limbs.push_back(lu);
    }
    r.params.extrinsics.camera = pcr::Pose2<double>{any(), any(), any()};
    r.params.extrinsics.pattern = pcr::Pose2<double>{any(), any(), any()};
    if (trial % 3 != 0) r.uncertainty = u;

    expect_same(pcr::parse_robot(pcr::robot_to_json(r), "memory"), r);
    const std::string path = (dir / "robot.json").string();
    pcr::save_robot(r, path);
    expect_same(pcr::load_robot(path), r);
    if (HasFailure()) break;
  }
  // save_robot refuses an invalid description and leaves nothing behind.
  pcr::RobotDescription bad = pcr::default_robot();
  bad.params.limb(1).rod.length = std::nan("");
  const std::string bad_path = (dir / "bad.json").string();
  EXPECT_THROW(pcr::save_robot(bad, bad_path), pcr::InputError);
  EXPECT_FALSE(std::filesystem::exists(bad_path));
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);  // robot.json only, no temporaries
}

TEST(RobotIo, DefaultRobotIsThePapersRobot) {
  const pcr::RobotDescription r = pcr::default_robot();
  EXPECT_EQ(r.name, "femto-3pf");
  EXPECT_EQ(r.young_modulus, 69e9);
  ASSERT_EQ(r.params.num_limbs, 3);
  const double pi = std::acos(-1.0);
  const double r_a = 0.060 * std::cos(20.0 * pi / 180.0);
  for (int i = 0; i < 3; ++i) {
    const pcr::LimbParams<double>& l = r.params.limb(i);
    const double phi = (-90.0 + 120.0 * i) * pi / 180.0;
    EXPECT_NEAR(l.A.x(), r_a * std::cos(phi), 1e-15);
    EXPECT_NEAR(l.A.y(), r_a * std::sin(phi), 1e-15);
    EXPECT_NEAR(l.B.norm(), 0.030, 1e-12);  // the distal clamps lie on a 30 mm circle
    EXPECT_NEAR(l.rod.length, 0.030, 0);
    EXPECT_EQ(l.rod.diameter, 125e-6);
    EXPECT_EQ(l.q_min, -0.0105);
    EXPECT_EQ(l.q_max, 0.0105);
  }
  ASSERT_TRUE(r.uncertainty.has_value());
  const pcr::RobotUncertainty& u = *r.uncertainty;
  ASSERT_EQ(u.limbs.size(), 3u);
  for (const pcr::LimbUncertainty& lu : u.limbs) {
    EXPECT_EQ(lu.rod.length, 126e-6);
    EXPECT_EQ(lu.A, Eigen::Vector2d(160e-6, 160e-6));
    EXPECT_EQ(lu.B, Eigen::Vector2d(160e-6, 160e-6));
    EXPECT_EQ(lu.alpha, 5e-3);
    EXPECT_EQ(lu.beta, 5e-3);
    EXPECT_EQ(lu.gamma, 5e-3);
    EXPECT_EQ(lu.rod.diameter, 20e-6);
    EXPECT_EQ(lu.rod.young_modulus, 0.0);
  }
  EXPECT_EQ(u.camera, Eigen::Vector3d(1e-3, 1e-3, 50e-3));
  EXPECT_EQ(u.pattern, Eigen::Vector3d(1e-3, 1e-3, 50e-3));
}

TEST(RobotIo, ShippedFileIsTheDefaultRobot) {
  expect_same(pcr::load_robot(std::string(PCR_SOURCE_DIR) + "/robots/femto-3pf.json"),
              pcr::default_robot());
  EXPECT_TRUE(pcr::load_robot_or_default("").uncertainty.has_value());
}

}  // namespace
