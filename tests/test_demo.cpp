// pcr demo end to end (README.md, "The main job"), small: the report's numbers against the noise
// floor and the truth, and the output directory's safety rules.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "sanitized_build.hpp"
#include "scratch_directory.hpp"

namespace {

namespace fs = std::filesystem;

int run_demo(const pcr::test::ScratchDirectory& scratch, const std::string& args) {
  const std::string command = std::string(PCR_CLI_PATH) + " demo --quiet " + args + " > '" +
                              scratch.file("demo.out") + "' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(Demo, SmallRunReachesTheNoiseFloor) {
  const pcr::test::ScratchDirectory scratch("demo");
  const fs::path out = scratch.path() / "out";
  // Vision included when built: it is the nominal description's source.
  ASSERT_EQ(
      run_demo(scratch, "--output " + out.string() +
                            " --calibration 40 --validation 12 --repeat 6 --poses 8 --seed 3"),
      0);
  const nlohmann::json report = read_json(out / "report.json");
  const auto& table3 = report["calibration"]["table3"];
  // The paper's repeatability is 9.13 nm per axis: e_p ~ 11 nm on average at the noise floor.
  EXPECT_LT(table3["identified_model_validation_set"]["e_p_m"]["mean"].get<double>(), 0.05e-6);
  EXPECT_LT(table3["identified_model_validation_set"]["e_theta_rad"]["mean"].get<double>(), 5e-6);
  EXPECT_GT(table3["nominal_model_validation_set"]["e_p_m"]["mean"].get<double>(), 1e-6);
  int rows = 0;
  for (const auto& row : report["accuracy"]["iso9283"]) {
    const std::string name = row["path"].get<std::string>();
    const double ap_max = row["ap_p"]["max"].get<double>();  // m
    if (name.find("identified") != std::string::npos) {
      EXPECT_LT(ap_max, 0.05e-6) << name;
    } else {
      EXPECT_GT(ap_max, 1e-6) << name;
    }
    ++rows;
  }
  EXPECT_EQ(rows, 4);
  for (const char* file : {"report.md", "identified.json", "nominal.json", "calibration.csv",
                           "validation.csv", "sensitivity.csv", "calibration-errors.csv"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  // Running again into its own directory is allowed.
  EXPECT_EQ(
      run_demo(scratch, "--output " + out.string() +
                            " --calibration 20 --validation 4 --repeat 3 --poses 4 --no-vision"),
      0);
}

TEST(Demo, RefusesSomeoneElsesDirectory) {
  const pcr::test::ScratchDirectory scratch("demo");
  const fs::path out = scratch.path() / "foreign";
  fs::create_directories(out);
  { std::ofstream(out / "thesis.tex") << "precious\n"; }
  EXPECT_NE(run_demo(scratch, "--output " + out.string() + " --no-vision"), 0);
  std::ifstream in(out / "thesis.tex");
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_EQ(s.str(), "precious\n");
  EXPECT_FALSE(fs::exists(out / "report.json"));
}

// Without the measurement (--no-vision) nothing makes images/: the run writes its report and the
// map's data all the same (the figures are drawn from it by Python, not here). The stages are
// numbered from one list.
TEST(Demo, NoVisionRunIntoAFreshDirectoryWritesItsReport) {
  const pcr::test::ScratchDirectory scratch("demo");
  const fs::path out = scratch.path() / "fresh";
  const std::string command = std::string(PCR_CLI_PATH) + " demo --no-vision --output '" +
                              out.string() +
                              "' --calibration 20 --validation 4 --repeat 3 --poses 4 > /dev/null "
                              "2> '" +
                              scratch.file("progress.txt") + "'";
  const int status = std::system(command.c_str());
  std::ifstream in(scratch.file("progress.txt"));
  std::stringstream progress;
  progress << in.rdbuf();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << progress.str();
  EXPECT_TRUE(fs::exists(out / "report.md"));
  EXPECT_TRUE(fs::exists(out / "report.json"));
  const nlohmann::json report = read_json(out / "report.json");
  for (const auto& file : report["workspace"]["files"]) {
    EXPECT_TRUE(fs::exists(out / file.get<std::string>())) << file;
  }
  EXPECT_FALSE(fs::exists(out / "images"));
  // The figures are Python's (python -m pcr.plot writes figures.md): the report links to them.
  std::ifstream md(out / "report.md");
  std::stringstream report_md;
  report_md << md.rdbuf();
  EXPECT_NE(report_md.str().find("[figures.md](figures.md)"), std::string::npos);
  // Stages [1/N] to [N/N], none beyond.
  const std::string text = progress.str();
  const std::size_t last = text.rfind("\n[");
  ASSERT_NE(last, std::string::npos) << text;
  const std::size_t slash = text.find('/', last), close = text.find(']', last);
  const std::string stage = text.substr(last + 2, slash - last - 2);
  const std::string count = text.substr(slash + 1, close - slash - 1);
  EXPECT_EQ(stage, count) << text;
  for (int k = 1; k <= std::stoi(count); ++k) {
    EXPECT_NE(text.find("[" + std::to_string(k) + "/" + count + "] "), std::string::npos) << k;
  }
}

/// `pcr demo --robot` with a spatial robot file: the whole method on a virtual robot drawn from
/// it (pcr::run_spatial_method), its report at the noise floor sqrt(3) sigma (211 nm for the
/// reference robot) and its six paths; then the same robot with an unmodelled payload.
TEST(Demo, SpatialRobotFileRunsTheSpatialMethod) {
  // Its Table 2 alone is 728 FK solves with derivatives: 3 s in Release, minutes under the
  // sanitizers (the spatial method's code runs there in test_spatial_trajectory's evaluation).
  if (pcr::test::kSanitized) GTEST_SKIP() << "Release build only (slow under the sanitizers)";
  const pcr::test::ScratchDirectory scratch("demo");
  const fs::path out = scratch.path() / "out";
  ASSERT_EQ(run_demo(scratch, "--robot " + std::string(PCR_SOURCE_DIR) +
                                  "/robots/continuum-stewart-gough.json --output " + out.string() +
                                  " --calibration 40 --validation 12 --repeat 3 --poses 8"),
            0);
  const nlohmann::json report = read_json(out / "report.json");
  const double floor = std::sqrt(3.0) * report["noise"]["position_m"].get<double>();
  const auto& errors = report["calibration"]["pose_errors"];
  EXPECT_LT(errors["identified_model_validation_set"]["rms_position_m"].get<double>(), 2 * floor);
  EXPECT_GT(errors["nominal_model_validation_set"]["rms_position_m"].get<double>(), 30 * floor);
  int rows = 0;
  for (const auto& row : report["accuracy"]["iso9283_spatial"]) {
    const std::string name = row["path"].get<std::string>();
    const double ap_max = row["ap_p"]["max"].get<double>();  // m
    EXPECT_LT(ap_max, name.find("identified") != std::string::npos ? 3 * floor : 1.0) << name;
    EXPECT_GT(ap_max, name.find("nominal") != std::string::npos ? 10 * floor : 0.0) << name;
    ++rows;
  }
  EXPECT_EQ(rows, 6);
  for (const char* file : {"report.md", "identified.json", "nominal.json", "truth.json",
                           "calibration.csv", "validation.csv", "sensitivity.csv",
                           "calibration-report.txt", "accuracy-helix-identified.csv"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  // The errors behind Table 3, one row per set, configuration and model (python -m pcr.plot
  // draws them into figures.md, which the report links): the identified model's on the
  // validation set give the report's rms.
  std::ifstream errors_csv(out / "calibration-errors.csv");
  std::string line;
  ASSERT_TRUE(std::getline(errors_csv, line));
  EXPECT_EQ(line, "set,configuration,model,e_p,e_angle");
  int count = 0, validation_rows = 0;
  double sum2 = 0;
  while (std::getline(errors_csv, line)) {
    ++count;
    if (line.rfind("validation,", 0) == 0 && line.find(",identified,") != std::string::npos) {
      const std::size_t model_end = line.find(",identified,") + 12;
      const double e_p = std::stod(line.substr(model_end, line.find(',', model_end) - model_end));
      sum2 += e_p * e_p;
      ++validation_rows;
    }
  }
  const int calibration = report["configurations"]["calibration"].get<int>();
  const int validation = report["configurations"]["validation"].get<int>();
  EXPECT_EQ(count, 2 * (calibration + validation));
  ASSERT_EQ(validation_rows, validation);
  EXPECT_NEAR(std::sqrt(sum2 / validation_rows),
              errors["identified_model_validation_set"]["rms_position_m"].get<double>(), 1e-12);
  std::ifstream md(out / "report.md");
  std::stringstream report_md;
  report_md << md.rdbuf();
  EXPECT_NE(report_md.str().find("[figures.md](figures.md)"), std::string::npos);
  EXPECT_EQ(report["unmodelled_effects"].size(), 0u);

  // The same robot (its truth, configurations and noise: each effect has its own stream) with
  // the named effect "load", a 100 g payload the model does not know (pcr/calib/named_effects.hpp),
  // and the load stage: the stage finds the payload's weight within its uncertainty, and the
  // identified model stays at the floor. (The nominal model's error need not grow: its fitted
  // extrinsics absorb most of the platform's sag.)
  const fs::path loaded = scratch.path() / "load";
  ASSERT_EQ(
      run_demo(scratch, "--robot " + std::string(PCR_SOURCE_DIR) +
                            "/robots/continuum-stewart-gough.json --output " + loaded.string() +
                            " --calibration 40 --validation 12 --repeat 3 --poses 8 "
                            "--effects load --identify-load"),
      0);
  const nlohmann::json with_load = read_json(loaded / "report.json");
  EXPECT_EQ(with_load["unmodelled_effects"], nlohmann::json::array({"load"}));
  EXPECT_EQ(with_load["unmodelled_effect_sizes"]["payload_kg"].get<double>(), 0.1);
  const double added = read_json(loaded / "truth.json")["platform_mass"].get<double>() -
                       read_json(out / "truth.json")["platform_mass"].get<double>();
  EXPECT_NEAR(added, 0.1, 1e-15);
  const auto& loaded_errors = with_load["calibration"]["pose_errors"];
  const auto rms = [](const nlohmann::json& e, const char* set) {
    return e[set]["rms_position_m"].get<double>();
  };
  EXPECT_LT(rms(loaded_errors, "identified_model_validation_set"), 2 * floor);
  ASSERT_TRUE(with_load["calibration"]["platform_load"]["identified"].get<bool>());
  bool found = false;
  for (const auto& p : with_load["calibration"]["parameters"]) {
    if (p["name"] != "load_f_z") continue;
    found = true;
    const double weight = 0.1 * 9.81;  // N, the reference robot's gravity
    EXPECT_NEAR(p["deviation"].get<double>(), -weight, 3.5 * p["std"].get<double>());
    EXPECT_LT(p["std"].get<double>(), 0.2 * weight);
  }
  EXPECT_TRUE(found);
  std::ifstream loaded_md(loaded / "report.md");
  std::stringstream loaded_text;
  loaded_text << loaded_md.rdbuf();
  EXPECT_NE(loaded_text.str().find("Unmodelled effects: load (a 0.1 kg payload at P's origin)"),
            std::string::npos)
      << loaded_text.str().substr(0, 600);
}

TEST(Demo, RejectsAnUnknownEffect) {
  const pcr::test::ScratchDirectory scratch("demo");
  EXPECT_NE(run_demo(scratch, "--effects gravity --output " + scratch.file("x")), 0);
  EXPECT_FALSE(fs::exists(scratch.path() / "x" / "report.json"));
  // The load stage is the spatial demo's: the planar one chooses its model on the validation set.
  EXPECT_NE(run_demo(scratch, "--identify-load --no-vision --output " + scratch.file("y")), 0);
  EXPECT_FALSE(fs::exists(scratch.path() / "y" / "report.json"));
}

}  // namespace
