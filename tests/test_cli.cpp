// The `pcr` command-line tool, run as a program on files in a temporary directory.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "pcr/csv_io.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/robot_io.hpp"
#include "random_robots.hpp"
#include "scratch_directory.hpp"

namespace {

namespace fs = std::filesystem;

struct Result {
  int status = -1;
  std::string out, err;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class Cli : public ::testing::Test {
 protected:
  /// Runs `pcr <args>` (or another program) with stdout and stderr captured.
  Result run(const std::string& args, const std::string& stdin_text = "",
             const std::string& program = PCR_CLI_PATH) {
    const fs::path in = dir_ / "stdin.txt", out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    std::ofstream(in) << stdin_text;
    const std::string command = "'" + program + "' " + args + " < '" + in.string() + "' > '" +
                                out.string() + "' 2> '" + err.string() + "'";
    const int raw = std::system(command.c_str());
    Result r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  std::string write(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }

  /// Reads the named numeric columns of a tool's output (the others, like status, skipped).
  static pcr::CsvTable parse(const std::string& text, const std::vector<std::string>& columns) {
    std::istringstream in(text);
    pcr::CsvReadOptions options;
    options.columns = columns;
    options.ignore_other_columns = true;
    return pcr::parse_csv(in, "output", options);
  }

  pcr::test::ScratchDirectory scratch_{"cli"};
  const fs::path& dir_ = scratch_.path();
};

TEST_F(Cli, HelpWorksForEveryCommand) {
  for (const char* command : {"", "fk", "ik", "robot", "workspace"}) {
    const Result r = run(std::string(command) + " --help");
    EXPECT_EQ(r.status, 0) << command;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << command << ": " << r.out;
  }
  EXPECT_NE(run("fk --help").out.find("--robot"), std::string::npos);
  EXPECT_NE(run("").status, 0);            // a subcommand is required
  EXPECT_NE(run("fk --bogus").status, 0);  // bad usage
  EXPECT_NE(run("fk --bogus").err.find("bogus"), std::string::npos);
}

TEST_F(Cli, HelpListsEverySubcommand) {
  std::vector<std::string> commands = {"fk", "ik", "robot", "workspace"};
#ifdef PCR_HAS_CALIB
  commands.insert(commands.end(), {"simulate", "sample", "sensitivity", "accuracy", "demo"});
#endif
#ifdef PCR_HAS_VISION
  commands.insert(commands.end(), {"measure", "render", "camera"});
#endif
  const Result help = run("--help");
  EXPECT_EQ(help.status, 0);
  for (const std::string& command : commands) {
    EXPECT_NE(help.out.find("\n  " + command + " "), std::string::npos) << command << help.out;
    // Also those pcr hands to pcr-full: their usage names the program as it was called.
    const Result r = run(command + " --help");
    EXPECT_EQ(r.status, 0) << command;
    EXPECT_NE(r.out.find("Usage: " + std::string(PCR_CLI_PATH) + " " + command), std::string::npos)
        << r.out;
  }
}

TEST_F(Cli, KinematicsLoadNeitherCalibrationNorVision) {
  // pcr links only pcr::io; what needs Ceres or OpenCV runs in pcr-full.
  const fs::path libraries = dir_ / "ldd.txt";
  const std::string command =
      "ldd '" + std::string(PCR_CLI_PATH) + "' > '" + libraries.string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const std::string text = slurp(libraries);
  for (const char* heavy : {"libceres", "libopencv", "libapriltag", "libglog", "libsundials"}) {
    EXPECT_EQ(text.find(heavy), std::string::npos) << heavy << " in\n" << text;
  }
}

#if defined(PCR_HAS_CALIB) || defined(PCR_HAS_VISION)
TEST_F(Cli, WithoutPcrFullTheKinematicsStillRun) {
  const fs::path alone = dir_ / "alone" / "pcr";
  fs::create_directory(alone.parent_path());
  fs::copy_file(PCR_CLI_PATH, alone);
  Result r = run("fk", "0,0,0\n", alone.string());
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find(",converged,"), std::string::npos) << r.out;
  r = run("--help", "", alone.string());
  EXPECT_NE(r.err.find("pcr-full"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\n  workspace "), std::string::npos) << r.out;
#ifdef PCR_HAS_CALIB
  r = run("demo", "", alone.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("only the kinematics subcommands are available"), std::string::npos)
      << r.err;
#endif
}
#endif

TEST_F(Cli, ForwardThenInverseThenForwardReturnsThePose) {
  // A short joint path (warm starts row to row), a header, a comment, and a symmetric row.
  const std::string joints = write("q.csv",
                                   "q1,q2,q3\n"
                                   "0,0,0\n"
                                   "# symmetric input: the platform only turns\n"
                                   "0.002,0.002,0.002\n"
                                   "0.001,-0.002,0.0005\n"
                                   "0.0011,-0.0021,0.0006\n"
                                   "-0.003,0.004,0.001\n");
  const std::string fk_out = (dir_ / "fk.csv").string();
  Result r = run("fk --input '" + joints + "' --output '" + fk_out + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable fk = parse(slurp(fk_out), {"q1", "q2", "q3", "x", "y", "theta", "converged",
                                                 "iterations", "residual", "max_strain"});
  ASSERT_EQ(fk.rows.size(), 5u);
  for (const auto& row : fk.rows) EXPECT_EQ(row[6], 1.0);
  // Home pose is (0, 0, 0); equal joints on the symmetric robot leave x = y = 0 (120° symmetry).
  EXPECT_NEAR(std::abs(fk.rows[0][3]) + std::abs(fk.rows[0][4]) + std::abs(fk.rows[0][5]), 0,
              1e-15);
  EXPECT_NEAR(fk.rows[1][3], 0, 1e-12);
  EXPECT_NEAR(fk.rows[1][4], 0, 1e-12);
  EXPECT_GT(std::abs(fk.rows[1][5]), 1e-3);
  EXPECT_EQ(fk.rows[2][1], -0.002);  // inputs echoed exactly

  // IK of the poses from stdin, without header.
  std::string poses;
  for (const auto& row : fk.rows) {
    poses += pcr::format_double(row[3]) + "," + pcr::format_double(row[4]) + "," +
             pcr::format_double(row[5]) + "\n";
  }
  r = run("ik", poses);
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable ik = parse(r.out, {"x", "y", "theta", "q1", "q2", "q3", "converged",
                                         "iterations", "residual", "max_strain"});
  ASSERT_EQ(ik.rows.size(), fk.rows.size());
  std::string joints_back = "q1,q2,q3\n";
  for (std::size_t i = 0; i < ik.rows.size(); ++i) {
    EXPECT_EQ(ik.rows[i][6], 1.0);
    // FK's pose is within 1 nm / 1 urad of the exact model, IK's joints within 1 nm: an angle
    // error moves the joints by up to the platform's radius (30 mm) times it.
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(ik.rows[i][3 + k], fk.rows[i][k], 1e-9 + 0.03 * 1e-6) << i;
    }
    joints_back += pcr::format_double(ik.rows[i][3]) + "," + pcr::format_double(ik.rows[i][4]) +
                   "," + pcr::format_double(ik.rows[i][5]) + "\n";
  }
  // FK of the IK output returns the pose.
  r = run("fk --robot '" + std::string(PCR_SOURCE_DIR) + "/robots/femto-3pf.json'", joints_back);
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable back = parse(r.out, {"q1", "q2", "q3", "x", "y", "theta", "converged",
                                           "iterations", "residual", "max_strain"});
  ASSERT_EQ(back.rows.size(), fk.rows.size());
  for (std::size_t i = 0; i < back.rows.size(); ++i) {
    // FK and IK each pick their RK4 step count for the default accuracy (1 nm, 1 urad).
    EXPECT_NEAR(back.rows[i][3], fk.rows[i][3], 1e-9) << i;
    EXPECT_NEAR(back.rows[i][4], fk.rows[i][4], 1e-9) << i;
    EXPECT_NEAR(back.rows[i][5], fk.rows[i][5], 1e-6) << i;
  }
}

// ---- spatial robots --------------------------------------------------------------------------

const std::string kSpatialRobot =
    std::string(PCR_SOURCE_DIR) + "/robots/continuum-stewart-gough.json";
// The numeric columns (the others, text or NaN, are checked as text).
const std::vector<std::string> kSpatialFkColumns = {"q1", "q2", "q3", "q4", "q5", "q6",       "x",
                                                    "y",  "z",  "rx", "ry", "rz", "converged"};
const std::vector<std::string> kSpatialIkColumns = {"x",  "y",  "z",  "rx", "ry", "rz",       "q1",
                                                    "q2", "q3", "q4", "q5", "q6", "converged"};

/// The data lines of a tool's CSV output (the header dropped).
std::vector<std::string> data_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// A three-rod spatial robot (rods 0, 2 and 4 of the reference robot): pcr ik imposes the position
// alone and writes the orientation it solves, which is the one pcr fk gave at those joints.
TEST_F(Cli, SpatialThreeRodInverseSolvesTheOrientation) {
  nlohmann::json robot = nlohmann::json::parse(slurp(kSpatialRobot));
  robot["name"] = "three-rods";
  robot["rods"] = nlohmann::json::array({robot["rods"][0], robot["rods"][2], robot["rods"][4]});
  const std::string file = write("three-rods.json", robot.dump(2));
  Result r = run("fk --robot '" + file + "'", "q1,q2,q3\n0.005,0.005,0.005\n0.01,0,0.004\n");
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable fk = parse(r.out, {"q1", "q2", "q3", "x", "y", "z", "rx", "ry", "rz"});
  std::string poses = "x,y,z,rx,ry,rz\n";
  for (const auto& row : fk.rows) {
    for (int k = 3; k < 6; ++k) poses += pcr::format_double(row[k]) + ",";
    poses += "0,0,0\n";  // the rotation, not imposed by three rods
  }
  r = run("ik --robot '" + file + "'", poses);
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable ik =
      parse(r.out, {"x", "y", "z", "rx", "ry", "rz", "q1", "q2", "q3", "converged"});
  ASSERT_EQ(ik.rows.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(ik.rows[i][9], 1.0) << i;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(ik.rows[i][k], fk.rows[i][3 + k]) << i;                      // echoed
      EXPECT_NEAR(ik.rows[i][3 + k], fk.rows[i][6 + k], 1e-8) << i;          // solved
      EXPECT_NEAR(ik.rows[i][6 + k], fk.rows[i][k], 1e-9) << i << " " << k;  // joints
    }
  }
  EXPECT_GT(std::abs(fk.rows[1][6]) + std::abs(fk.rows[1][7]), 1e-3);  // a tilted platform
}

TEST_F(Cli, SpatialForwardThenInverseRecoversTheJoints) {
  const std::string joints_text =
      "q1,q2,q3,q4,q5,q6\n"
      "0,0,0,0,0,0\n"
      "0.005,0.005,0.005,0.005,0.005,0.005\n"
      "0.012,-0.003,0.004,0.009,-0.001,0.006\n"
      "-0.002,0.008,0.001,0.003,0.011,-0.004\n";
  const std::string joints = write("q.csv", joints_text);
  const std::string fk_out = (dir_ / "fk.csv").string();
  Result r =
      run("fk --robot '" + kSpatialRobot + "' --input '" + joints + "' --output '" + fk_out + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string fk_text = slurp(fk_out);
  EXPECT_EQ(fk_text.substr(0, fk_text.find('\n')),
            "q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz,converged,iterations,residual,status,max_strain,"
            "stable,stability_margin,singularity");
  const pcr::CsvTable fk = parse(fk_text, kSpatialFkColumns);
  ASSERT_EQ(fk.rows.size(), 4u);
  for (const auto& row : fk.rows) EXPECT_EQ(row[12], 1.0);
  // The largest bending strain and the stability check's flag, margin and distance to a
  // singularity on every row: bent rods (strain within the 1e-2 of steel's elastic range), and
  // configurations that hold (margin > 0) and none singular.
  for (const auto& row :
       parse(fk_text, {"max_strain", "stable", "stability_margin", "singularity"}).rows) {
    EXPECT_GT(row[0], 0.0);
    EXPECT_LT(row[0], 1e-2);
    EXPECT_EQ(row[1], 1.0);
    EXPECT_GT(row[2], 0.0);
    EXPECT_GT(row[3], 0.0);
  }
  // Equal joints on the robot symmetric under turns of 120 degrees and the mirror y -> -y: the
  // platform stays on the axis, untilted; longer rods raise it.
  for (int row = 0; row < 2; ++row) {
    for (int k : {6, 7, 9, 10, 11}) EXPECT_NEAR(fk.rows[row][k], 0.0, 1e-12) << row << " " << k;
  }
  EXPECT_GT(fk.rows[1][8], fk.rows[0][8] + 0.004);
  EXPECT_GT(std::abs(fk.rows[2][9]) + std::abs(fk.rows[2][10]), 1e-3);  // unequal joints tilt it

  // IK of the printed poses gives back the joints.
  std::string poses = "x,y,z,rx,ry,rz\n";
  for (const auto& row : fk.rows) {
    for (int k = 6; k < 12; ++k) poses += pcr::format_double(row[k]) + (k < 11 ? "," : "\n");
  }
  r = run("ik --robot '" + kSpatialRobot + "'", poses);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> ik_lines = data_lines(r.out);
  const pcr::CsvTable ik = parse(r.out, kSpatialIkColumns);
  ASSERT_EQ(ik.rows.size(), fk.rows.size());
  double worst = 0;
  for (std::size_t i = 0; i < ik.rows.size(); ++i) {
    EXPECT_EQ(ik.rows[i][12], 1.0) << i;
    for (int k = 0; k < 6; ++k) {
      EXPECT_EQ(ik.rows[i][k], fk.rows[i][6 + k]);  // inputs echoed exactly
      worst = std::max(worst, std::abs(ik.rows[i][6 + k] - fk.rows[i][k]));
    }
  }
  std::printf("pcr ik of pcr fk's poses: joints within %.2e m\n", worst);
  EXPECT_LT(worst, 1e-9);

  // Independent rows: any order gives each row the same output line, to the last digit.
  const std::vector<std::string> lines = data_lines(fk_text);
  const std::vector<std::string> rows = data_lines(joints_text);
  const std::vector<std::size_t> shuffled = {2, 0, 3, 1};
  std::string shuffled_text = "q1,q2,q3,q4,q5,q6\n";
  for (const std::size_t i : shuffled) shuffled_text += rows[i] + "\n";
  r = run("fk --robot '" + kSpatialRobot + "'", shuffled_text);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> shuffled_lines = data_lines(r.out);
  ASSERT_EQ(shuffled_lines.size(), lines.size());
  for (std::size_t k = 0; k < shuffled.size(); ++k) {
    EXPECT_EQ(shuffled_lines[k], lines[shuffled[k]]) << k;
  }
  const std::vector<std::string> pose_rows = data_lines(poses);
  std::string shuffled_poses = "x,y,z,rx,ry,rz\n";
  for (const std::size_t i : shuffled) shuffled_poses += pose_rows[i] + "\n";
  r = run("ik --robot '" + kSpatialRobot + "'", shuffled_poses);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> ik_shuffled = data_lines(r.out);
  ASSERT_EQ(ik_shuffled.size(), ik_lines.size());
  for (std::size_t k = 0; k < shuffled.size(); ++k) {
    EXPECT_EQ(ik_shuffled[k], ik_lines[shuffled[k]]) << k;
  }

  // A path (warm starts) reaches the same poses.
  r = run("fk --path --robot '" + kSpatialRobot + "'", joints_text);
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable path = parse(r.out, kSpatialFkColumns);
  ASSERT_EQ(path.rows.size(), fk.rows.size());
  for (std::size_t i = 0; i < path.rows.size(); ++i) {
    for (int k = 6; k < 9; ++k) EXPECT_NEAR(path.rows[i][k], fk.rows[i][k], 1e-9) << i;
    for (int k = 9; k < 12; ++k) EXPECT_NEAR(path.rows[i][k], fk.rows[i][k], 1e-8) << i;
  }
}

TEST_F(Cli, SpatialRobotFilesAreRefusedWhereTheyDoNotBelong) {
  // A planar command names the file and its kind.
  Result r = run("workspace --samples 1 --robot '" + kSpatialRobot + "'");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("continuum-stewart-gough.json: kind: this command takes a planar robot"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("\"spatial\""), std::string::npos) << r.err;
  // The planar load options.
  r = run("fk --force 1,0 --robot '" + kSpatialRobot + "'", "0,0,0,0,0,0\n");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--force/--moment"), std::string::npos) << r.err;
  // Fold tracing is a spatial path's too: with no fold on the way, the same rows as without it.
  const std::string joints = "0,0,0,0,0,0\n0.002,0.001,0,0,0.001,0.002\n";
  r = run("fk --path --through-folds --robot '" + kSpatialRobot + "'", joints);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(data_lines(r.out).size(), 2u) << r.out;
  EXPECT_EQ(r.out, run("fk --path --robot '" + kSpatialRobot + "'", joints).out);
  // A bad field: file, field and value.
  std::string text = slurp(kSpatialRobot);
  const std::size_t at = text.find("\"density\": 8000.0");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 17, "\"density\": -8000.0");
  const std::string bad = write("bad.json", text);
  for (const char* command : {"fk", "ik", "robot"}) {
    r = run(std::string(command) + " --robot '" + bad + "'", "0,0,0,0,0,0\n");
    EXPECT_EQ(r.status, 2) << command;
    EXPECT_NE(r.err.find("bad.json: rods[0].density"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("-8000"), std::string::npos) << r.err;
  }
  // pcr robot writes the shipped file as it is (it is in canonical form).
  r = run("robot --robot '" + kSpatialRobot + "'");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, slurp(kSpatialRobot));
}

#ifdef PCR_HAS_CALIB
// A 5 x 5 slice of positions and one of rotation vectors: every point's joints, given to
// `pcr fk` (cold, from straight rods, the same RK4 steps), return the point's pose.
TEST_F(Cli, SpatialMapSlicesTheWorkspace) {
  const std::vector<std::string> columns = {"u",  "v",  "x",         "y",     "z",  "rx",
                                            "ry", "rz", "q1",        "q2",    "q3", "q4",
                                            "q5", "q6", "reachable", "stable"};
  const struct {
    const char* plane;
    const char* range;
    const char* unit;
    int u, v;  // the pose columns the grid spans
  } slices[] = {{"xy", "-0.02,0.02,-0.02,0.02", "m^2", 2, 3},
                {"ryrz", "0,0.2,-0.1,0.1", "rad^2", 6, 7}};
  for (const auto& slice : slices) {
    const std::string out = (dir_ / (std::string(slice.plane) + ".csv")).string();
    const std::string common = "map --robot '" + kSpatialRobot + "' --plane " + slice.plane +
                               " --pose 0.01,0,0.4,0,0.1,0 --grid 5 --steps 96 --range " +
                               slice.range;
    Result r = run(common + " --threads 2 --output '" + out + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string text = slurp(out);
    EXPECT_EQ(text.substr(0, text.find('\n')),
              "u,v,x,y,z,rx,ry,rz,reachable,stable,status,q1,q2,q3,q4,q5,q6,max_strain,"
              "stability_margin,singularity");
    EXPECT_NE(r.err.find("25 reachable ("), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string(" ") + slice.unit + ")"), std::string::npos) << r.err;
    const pcr::CsvTable map = parse(text, columns);
    ASSERT_EQ(map.rows.size(), 25u);
    std::string joints = "q1,q2,q3,q4,q5,q6\n";
    for (const auto& row : map.rows) {
      EXPECT_EQ(row[slice.u], row[0]);  // u and v are the slice's coordinates of the pose
      EXPECT_EQ(row[slice.v], row[1]);
      EXPECT_EQ(row[14], 1.0);
      EXPECT_EQ(row[15], 1.0);
      for (int k = 8; k < 14; ++k) joints += pcr::format_double(row[k]) + (k < 13 ? "," : "\n");
    }
    EXPECT_EQ(map.rows[0][4], 0.4);  // z is held at --pose's in both slices
    r = run("fk --steps 96 --robot '" + kSpatialRobot + "'", joints);
    ASSERT_EQ(r.status, 0) << r.err;
    const pcr::CsvTable fk = parse(r.out, {"x", "y", "z", "rx", "ry", "rz"});
    ASSERT_EQ(fk.rows.size(), 25u);
    double worst = 0;
    for (std::size_t i = 0; i < fk.rows.size(); ++i) {
      for (int k = 0; k < 6; ++k) {
        worst = std::max(worst, std::abs(fk.rows[i][k] - map.rows[i][2 + k]));
      }
    }
    std::printf("pcr map --plane %s: pcr fk of its joints within %.2e (m, rad)\n", slice.plane,
                worst);
    EXPECT_LT(worst, 1e-9);
    // One thread writes the same file.
    const std::string one = (dir_ / "one.csv").string();
    r = run(common + " --threads 1 --output '" + one + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(slurp(one), text);
  }
}

TEST_F(Cli, SpatialMapRefusesBadOptions) {
  const std::string robot = " --robot '" + kSpatialRobot + "'";
  const struct {
    std::string args, message;
  } cases[] = {
      {"--theta 0.1" + robot, "--theta: " + kSpatialRobot + " is a spatial robot"},
      {"--worst-case" + robot, "--worst-case: " + kSpatialRobot + " is a spatial robot"},
      {"--force 1,0" + robot, "--force: "},
      {"--range 0,1" + robot, "--range: expected 4 numbers (x_min,x_max,y_min,y_max), got '0,1'"},
      {"--plane yz --range 0,0.1,inf,0.5" + robot, "--range: z_min = inf is not a finite number"},
      {"--plane rxrz --range 0.1,-0.1,-0.1,0.1" + robot,
       "range: expected rx_min < rx_max and rz_min < rz_max for the plane rxrz, got "
       "0.1,-0.1,-0.1,0.1"},
      {"--plane rxrz --range -7,0.1,-0.1,0.1" + robot,
       "range.rx_min: expected a number from -6.283185307179586 to 6.283185307179586 (rad), got "
       "-7"},
      {"--grid 600" + robot, "grid: expected a number from 2 to 500, got 600"},
      {"--pose 0,0,0.4,0,0" + robot, "--pose: expected 6 numbers (x,y,z,rx,ry,rz)"},
      {"--stroke 0.02,-0.02" + robot, "stroke: expected q_min <= q_max (m), got 0.02,-0.02"},
      {"--stroke 0.02,-0.02", "--stroke: <default robot> is a planar robot"},
  };
  for (const auto& c : cases) {
    const std::string out = (dir_ / "map.csv").string();
    const std::string grid = c.args.find("--grid") == std::string::npos ? "--grid 3 " : "";
    const Result r = run("map " + grid + "--output '" + out + "' " + c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}
#endif

TEST_F(Cli, FailedRowsAreReportedAndTheToolGoesOn) {
  // Pulling all three rods by 9 mm lies beyond the singularity (6 mm already does).
  const Result r = run("fk", "0.001,0,0\n-0.009,-0.009,-0.009\n0.001,0.001,0\n");
  EXPECT_EQ(r.status, 1) << r.err;
  const pcr::CsvTable t = parse(r.out, {"q1", "q2", "q3", "converged"});  // x is nan when failed
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0][3], 1.0);
  EXPECT_EQ(t.rows[1][3], 0.0);
  EXPECT_EQ(t.rows[2][3], 1.0);
  EXPECT_NE(r.err.find("<stdin>:2"), std::string::npos) << r.err;
}

TEST_F(Cli, IkOutOfStrokeIsReported) {
  // A pure rotation of 0.5 rad needs about 14.7 mm of stroke on every limb (> 10.5 mm).
  const Result r = run("ik", "x,y,theta\n0,0,0\n0,0,0.5\n");
  EXPECT_EQ(r.status, 1) << r.err;
  const pcr::CsvTable t = parse(r.out, {"q1", "converged"});
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0][1], 1.0);
  EXPECT_EQ(t.rows[1][1], 0.0);
  EXPECT_GT(t.rows[1][0], 0.0105);  // the (valid) joint value beyond the stroke is reported
  EXPECT_NE(r.out.find(",out_of_range,"), std::string::npos) << r.out;
}

TEST_F(Cli, BadRobotFileNamesTheField) {
  std::string text = pcr::robot_to_json(pcr::default_robot());
  const std::size_t first = text.find("\"l\": 0.03");
  const std::size_t third = text.find("\"l\": 0.03", text.find("\"l\": 0.03", first + 1) + 1);
  ASSERT_NE(third, std::string::npos);
  text.replace(third, 9, "\"l\": -0.25");
  const std::string path = write("bad.json", text);
  for (const char* command : {"fk", "ik", "robot", "workspace --samples 1"}) {
    const Result r = run(std::string(command) + " --robot '" + path + "'", "0,0,0\n");
    EXPECT_EQ(r.status, 2) << command;
    EXPECT_NE(r.err.find("pcr: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("bad.json"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("limbs[2].l"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("-0.25"), std::string::npos) << r.err;
  }
}

TEST_F(Cli, BadCsvNamesFileLineAndColumn) {
  const std::string path = write("q.csv", "q1,q2,q3\n0,0,0\n0,x,0\n");
  Result r = run("fk --input '" + path + "'");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("q.csv:3:2"), std::string::npos) << r.err;
  r = run("ik", "0,0\n");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("<stdin>:1"), std::string::npos) << r.err;
  r = run("fk --force 1,y", "0,0,0\n");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
}

TEST_F(Cli, RobotCommandWritesTheCanonicalFile) {
  const std::string path = (dir_ / "robot.json").string();
  const Result r = run("robot --output '" + path + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("femto-3pf"), std::string::npos);
  const pcr::RobotDescription a = pcr::load_robot(path), b = pcr::default_robot();
  // Equal bit for bit (spot checks; test_robot_io checks every field of the shipped file).
  EXPECT_EQ(a.params.limb(2).B, b.params.limb(2).B);
  EXPECT_EQ(a.params.limb(1).alpha, b.params.limb(1).alpha);
  EXPECT_EQ(slurp(path), slurp(std::string(PCR_SOURCE_DIR) + "/robots/femto-3pf.json"));
}

// A pre-stressed 4-limb robot (two rods 300 um and 200 um longer) has several homes: `pcr robot
// --home-pose` writes it saying which one it is in, the home with every rod bowed to its left.
TEST_F(Cli, RobotCommandSaysWhichHomeFromItsPose) {
  pcr::RobotDescription robot;
  robot.name = "pre-stressed-4";
  robot.young_modulus = pcr::default_robot().young_modulus;
  robot.params = pcr::testing::regular_robot(4);
  robot.params.limb(1).rod.length += 300e-6;
  robot.params.limb(3).rod.length += 200e-6;
  const std::string path = (dir_ / "pre.json").string(), out = (dir_ / "homed.json").string();
  pcr::save_robot(robot, path);
  pcr::RobotParams<double> left = robot.params;
  for (int i = 0; i < 4; ++i) left.limb(i).home_bow = 1;
  const pcr::ForwardSolution home = pcr::home_solution(left);
  ASSERT_TRUE(home.summary.converged());
  const pcr::ForwardSolution unsaid = pcr::home_solution(robot.params);
  ASSERT_GT(std::hypot(home.pose.x - unsaid.pose.x, home.pose.y - unsaid.pose.y), 1e-6);
  const std::string pose = pcr::format_double(home.pose.x) + "," + pcr::format_double(home.pose.y) +
                           "," + pcr::format_double(home.pose.theta);
  Result r = run("robot --robot '" + path + "' --home-pose " + pose + " --output '" + out + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("home: rods bowed"), std::string::npos) << r.err;
  const pcr::ForwardSolution homed = pcr::home_solution(pcr::load_robot(out).params);
  ASSERT_TRUE(homed.summary.converged());
  EXPECT_LT(std::hypot(homed.pose.x - home.pose.x, homed.pose.y - home.pose.y), 1e-12);
  r = run("robot --robot '" + path + "' --home-pose 0,nan,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--home-pose: y = nan"), std::string::npos) << r.err;
}

// The default robot with a +-40 mm stroke along a line at 75 degrees: past 22.8 mm the branch
// warm-started IK follows would not hold (rod 0 buckles); pcr ik reports the stable equilibrium
// at the same pose instead, with the stability columns.
TEST_F(Cli, IkReportsStableEquilibria) {
  pcr::RobotDescription robot = pcr::default_robot();
  for (int i = 0; i < 3; ++i) {
    robot.params.limb(i).q_min = -0.040;
    robot.params.limb(i).q_max = 0.040;
  }
  const std::string path = (dir_ / "long.json").string();
  pcr::save_robot(robot, path);
  std::string poses = "x,y,theta\n";
  const double direction = 75 * M_PI / 180;
  for (double t : {0.0, 0.01, 0.02, 0.022, 0.023, 0.024, 0.025}) {
    poses += pcr::format_double(t * std::cos(direction)) + "," +
             pcr::format_double(t * std::sin(direction)) + ",0\n";
  }
  const Result r = run("ik --robot '" + path + "'", poses);
  ASSERT_EQ(r.status, 0) << r.err;
  const pcr::CsvTable t =
      parse(r.out, {"q1", "converged", "stable", "stability_margin", "singularity"});
  ASSERT_EQ(t.rows.size(), 7u);
  for (const auto& row : t.rows) {
    EXPECT_EQ(row[1], 1.0);
    EXPECT_EQ(row[2], 1.0);
    EXPECT_GT(row[3], 0.0);
    EXPECT_GT(row[4], 0.0);
  }
  EXPECT_GT(t.rows[6][0], 0.030);  // rod 0 buckled: its joint ~10 mm past the straight branch's
  // Without the search (a robot whose stroke ends before the stable solution), the rows past the
  // fold are unstable, reported, and fail unless --allow-unstable.
}

TEST_F(Cli, IkRefusesMoreThanThreeLimbs) {
  pcr::RobotDescription robot = pcr::default_robot();
  robot.uncertainty.reset();
  robot.params.num_limbs = 4;
  robot.params.limb(3) = robot.params.limb(0);
  robot.params.limb(3).A *= -1.0;
  const std::string path = (dir_ / "four.json").string();
  pcr::save_robot(robot, path);
  const Result r = run("ik --robot '" + path + "'", "0,0,0\n");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("4 limbs"), std::string::npos) << r.err;
}

TEST_F(Cli, WorkspaceSummarises) {
  const Result r = run("workspace --samples 6 --seed 3");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("# FK (cold from home): "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("# max round-trip error"), std::string::npos) << r.out;
  // The table part parses (the summary lines are '#' comments).
  const pcr::CsvTable t = parse(r.out, {"q1", "q2", "q3"});
  EXPECT_EQ(t.rows.size(), 6u);
}

}  // namespace
