// `pcr render`, `pcr measure` and `pcr camera` run as programs: one rendered robot measured end to
// end against the render's ground truth, every bad input docs/vision.md lists ("Command-line
// checks") exiting non-zero with a message naming the mount, the file or the id and writing no
// output, and a camera calibrated from rendered chessboards.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "pcr/robot_io.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/mounts.hpp"
#include "pcr/vision/render.hpp"
#include "scratch_directory.hpp"

namespace {

namespace fs = std::filesystem;
using namespace pcr;
using namespace pcr::vision;

struct Result {
  int status = -1;
  std::string out, err;
  std::string all() const { return out + err; }
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string kMounts = std::string(PCR_SOURCE_DIR) + "/data/mounts-femto-3pf.json";

// 1700 x 1700 px, 100 um/px at 0.5 m, mild barrel distortion.
CameraModel test_camera() {
  CameraModel cam;
  cam.width = cam.height = 1700;
  cam.K << 5000, 0, 851.5, 0, 5010, 847.0, 0, 0, 1;
  cam.distortion << -0.05, 0.02, 0, 0, 0;
  return cam;
}

class VisionCli : public ::testing::Test {
 protected:
  static std::unique_ptr<pcr::test::ScratchDirectory> scratch_;
  static const fs::path& dir() { return scratch_->path(); }

  static void SetUpTestSuite() {
    scratch_ = std::make_unique<pcr::test::ScratchDirectory>("vision_cli");
    save_camera(test_camera(), path("camera.yaml"));
    // The shared good scene: rods and wafer outline drawn, noise, blur, gradient, a small tilt.
    const Result r = run("render --mounts '" + kMounts + "' --camera '" + path("camera.yaml") +
                         "' --output '" + path("home.png") + "' --truth '" + path("truth.json") +
                         "' --tilt-x 0.01 --tilt-y -0.008 --noise 0.01 --blur 0.8 --gradient 0.1 "
                         "--supersampling 3 --seed 7");
    ASSERT_EQ(r.status, 0) << r.all();
  }
  static void TearDownTestSuite() { scratch_.reset(); }

  static std::string path(const std::string& name) { return scratch_->file(name); }

  static Result run(const std::string& args) {
    static int count = 0;
    const std::string tag = std::to_string(count++);
    const fs::path out = dir() / ("stdout" + tag + ".txt"), err = dir() / ("stderr" + tag + ".txt");
    const std::string command = std::string("'") + PCR_CLI_PATH + "' " + args + " > '" +
                                out.string() + "' 2> '" + err.string() + "'";
    const int raw = std::system(command.c_str());
    Result r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    fs::remove(out);
    fs::remove(err);
    return r;
  }

  /// The femto-3pf layout with `edit` applied to its JSON, written to `name`.
  static std::string mounts_with(const std::string& name,
                                 const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = nlohmann::json::parse(slurp(kMounts));
    edit(j);
    std::ofstream(path(name)) << j.dump(2);
    return path(name);
  }

  /// Runs `pcr measure` expecting a failure; checks the exit status, that every `needle` is in the
  /// message and that no output file (nor a temporary one) was left.
  static void expect_measure_error(const std::string& mounts, const std::string& camera,
                                   const std::string& image,
                                   const std::vector<std::string>& needles) {
    const std::string output = path("bad_out.json");
    const Result r =
        run("measure --mounts '" + mounts + "' --camera '" + camera + "' --image '" + image +
            "' --output '" + output + "' --annotated '" + path("bad_out.png") + "'");
    EXPECT_NE(r.status, 0) << r.all();
    for (const std::string& n : needles)
      EXPECT_NE(r.err.find(n), std::string::npos) << "'" << n << "' not in: " << r.err;
    for (const auto& e : fs::directory_iterator(dir()))
      EXPECT_EQ(e.path().filename().string().rfind("bad_out", 0), std::string::npos)
          << "left " << e.path();
  }
};

std::unique_ptr<pcr::test::ScratchDirectory> VisionCli::scratch_;

// The measured robot file's A, alpha, B, beta contain the rendered truth within the written
// half-widths, and (the layout's offsets being exact here) lie close to it: the image part alone.
TEST_F(VisionCli, RenderThenMeasureRecoversTheTruth) {
  const Result r = run("measure --mounts '" + kMounts + "' --camera '" + path("camera.yaml") +
                       "' --image '" + path("home.png") + "' --output '" + path("nominal.json") +
                       "' --annotated '" + path("annotated.png") + "'");
  ASSERT_EQ(r.status, 0) << r.all();
  EXPECT_TRUE(fs::file_size(path("annotated.png")) > 0);
  const RobotDescription measured = load_robot(path("nominal.json"));
  ASSERT_TRUE(measured.uncertainty.has_value());
  const nlohmann::json truth = nlohmann::json::parse(slurp(path("truth.json")));
  ASSERT_EQ(truth["limbs"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const nlohmann::json& t = truth["limbs"][i];
    const LimbParams<double>& m = measured.params.limb(i);
    const LimbUncertainty& u = measured.uncertainty->limbs[i];
    // Platform at (0, 0, 0) and q = 0: P = W, so the truth's B_W, beta_W are B, beta.
    const Eigen::Vector2d A(t["A_W"][0], t["A_W"][1]), B(t["B_W"][0], t["B_W"][1]);
    const double alpha = t["alpha_W"], beta = t["beta_W"];
    for (int k = 0; k < 2; ++k) {
      EXPECT_LE(std::abs(m.A[k] - A[k]), u.A[k]) << "limb " << i << " A" << k;
      EXPECT_LE(std::abs(m.B[k] - B[k]), u.B[k]) << "limb " << i << " B" << k;
      EXPECT_LT(std::abs(m.A[k] - A[k]), 60e-6) << "limb " << i << " A" << k;  // < 0.6 px
      EXPECT_LT(std::abs(m.B[k] - B[k]), 60e-6) << "limb " << i << " B" << k;
      // Intervals dominated by the 840 um / 15 um machining tolerances, not uselessly wide.
      EXPECT_GT(u.A[k], 15e-6);
      EXPECT_LT(u.A[k], 2e-3);
      EXPECT_LT(u.B[k], 2e-3);
    }
    const double da = std::remainder(m.alpha - alpha, 2 * M_PI),
                 db = std::remainder(m.beta - beta, 2 * M_PI);
    EXPECT_LE(std::abs(da), u.alpha) << "limb " << i;
    EXPECT_LE(std::abs(db), u.beta) << "limb " << i;
    EXPECT_LT(std::abs(da), 3e-3) << "limb " << i;
    EXPECT_LT(std::abs(db), 3e-3) << "limb " << i;
    EXPECT_LT(u.alpha, 0.05);
    EXPECT_LT(u.beta, 0.05);
  }
  EXPECT_NE(r.out.find("registration rms"), std::string::npos) << r.out;
}

TEST_F(VisionCli, MissingMarkerNamesTheMountAndId) {
  const std::string mounts =
      mounts_with("missing.json", [](nlohmann::json& j) { j["mounts"][4]["id"] = 7; });
  expect_measure_error(mounts, path("camera.yaml"), path("home.png"),
                       {"mount B2", "id 7", "home.png"});
}

TEST_F(VisionCli, DuplicatedIdInTheImageNamesTheId) {
  // B2 (id 4) printed with A2's id 1: id 1 is seen twice.
  Scene scene;
  scene.camera = test_camera();
  scene.plane = PlanePose::looking_down(0.5);
  scene.tags = mount_tags(load_mounts(kMounts), femto_3pf(), Pose2<double>{});
  scene.tags[4].id = 1;
  RenderOptions opt;
  opt.supersampling = 2;
  opt.blur_sigma_px = 0.7;
  write_png(render_scene(scene, opt), path("duplicated.png"));
  expect_measure_error(kMounts, path("camera.yaml"), path("duplicated.png"),
                       {"tag id 1", "2 times", "mount A2", "duplicated.png"});
}

TEST_F(VisionCli, DuplicatedIdInTheLayoutNamesTheIdAndFile) {
  const std::string mounts =
      mounts_with("dup_layout.json", [](nlohmann::json& j) { j["mounts"][3]["id"] = 0; });
  expect_measure_error(mounts, path("camera.yaml"), path("home.png"),
                       {"dup_layout.json", "tag id 0", "B1"});
}

TEST_F(VisionCli, WrongFamilyNamesTheMount) {
  const std::string mounts =
      mounts_with("family.json", [](nlohmann::json& j) { j["family"] = "tag25h9"; });
  expect_measure_error(mounts, path("camera.yaml"), path("home.png"),
                       {"mount A1 (tag25h9 id 0) not found", "home.png"});
  // An unknown family is a layout error naming the file.
  const std::string unknown =
      mounts_with("unknown.json", [](nlohmann::json& j) { j["family"] = "tag99h99"; });
  expect_measure_error(unknown, path("camera.yaml"), path("home.png"),
                       {"unknown.json", "tag99h99"});
}

TEST_F(VisionCli, UnreadableOrBlankImageNamesTheFile) {
  std::ofstream(path("garbage.png")) << "not an image";
  expect_measure_error(kMounts, path("camera.yaml"), path("garbage.png"), {"garbage.png"});
  expect_measure_error(kMounts, path("camera.yaml"), path("nowhere.png"), {"nowhere.png"});
  write_png(GrayImage(1700, 1700, 0.45f), path("blank.png"));
  expect_measure_error(kMounts, path("camera.yaml"), path("blank.png"), {"blank.png", "blank"});
}

TEST_F(VisionCli, MarkerCutByTheBorderNamesTheMount) {
  // Shift the principal point so that A1's white quiet zone crosses the image border, its black
  // border still inside (so it is detected, then refused).
  CameraModel cam = test_camera();
  cam.distortion.setZero();  // pixel shifts are then exact translations of the image
  Scene scene;
  scene.camera = cam;
  scene.plane = PlanePose::looking_down(0.5);
  scene.tags = mount_tags(load_mounts(kMounts), femto_3pf(), Pose2<double>{});
  const std::vector<Eigen::Vector2d> c = tag_corner_pixels(scene, scene.tags[0]);
  double vmax = -1e9;
  for (const auto& p : c) vmax = std::max(vmax, p.y());
  const double side_px = (c[1] - c[0]).norm(), ring_px = side_px / 8.0;
  cam.K(1, 2) += (cam.height - 0.5) - (vmax + 0.5 * ring_px);
  scene.camera = cam;
  for (std::size_t k = 1; k < scene.tags.size(); ++k)  // the others stay well inside
    for (const auto& p : tag_corner_pixels(scene, scene.tags[k]))
      ASSERT_TRUE(p.x() > 2 * ring_px && p.y() > 2 * ring_px && p.x() < cam.width - 2 * ring_px &&
                  p.y() < cam.height - 2 * ring_px);
  save_camera(cam, path("shifted.yaml"));
  const Result r = run("render --mounts '" + kMounts + "' --camera '" + path("shifted.yaml") +
                       "' --output '" + path("cut.png") + "' --blur 0.7 --supersampling 2");
  ASSERT_EQ(r.status, 0) << r.all();
  expect_measure_error(kMounts, path("shifted.yaml"), path("cut.png"),
                       {"mount A1", "cut by the image border", "cut.png"});
}

TEST_F(VisionCli, CameraOfAnotherSizeNamesTheFiles) {
  CameraModel cam = test_camera();
  cam.width = cam.height = 1600;
  save_camera(cam, path("small.yaml"));
  expect_measure_error(kMounts, path("small.yaml"), path("home.png"), {"home.png", "1600"});
  // A camera file missing its matrix names the file and the field.
  std::ofstream(path("broken.yaml")) << "%YAML:1.0\n---\nimage_width: 1700\nimage_height: 1700\n";
  expect_measure_error(kMounts, path("broken.yaml"), path("home.png"),
                       {"broken.yaml", "camera_matrix"});
}

// The wafer outline is drawn (dark on the circle of 50 mm radius) unless --no-rods, and the tags'
// ground truth does not depend on it.
TEST_F(VisionCli, RenderDrawsTheWaferOutline) {
  const std::string common =
      "render --mounts '" + kMounts + "' --camera '" + path("camera.yaml") + "' --supersampling 1";
  ASSERT_EQ(run(common + " --output '" + path("plain.png") + "' --truth '" + path("plain.json") +
                "' --no-rods")
                .status,
            0);
  ASSERT_EQ(
      run(common + " --output '" + path("wafer.png") + "' --truth '" + path("wafer.json") + "'")
          .status,
      0);
  const GrayImage plain = read_image(path("plain.png")), wafer = read_image(path("wafer.png"));
  const CameraModel cam = test_camera();
  const PlanePose plane = PlanePose::looking_down(0.5);
  int dark = 0, n = 0;
  for (int k = 0; k < 36; ++k) {
    const double a = 2 * M_PI * (k + 0.5) / 36;
    const Eigen::Vector2d px =
        cam.project(plane.to_camera(0.05 * Eigen::Vector2d(std::cos(a), std::sin(a))));
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    const float w = wafer.pixels[static_cast<std::size_t>(v) * wafer.width + u];
    const float p = plain.pixels[static_cast<std::size_t>(v) * plain.width + u];
    EXPECT_NEAR(p, 0.45f, 0.01f) << "no outline expected at angle " << a;
    dark += w < 0.35f;
    ++n;
  }
  EXPECT_GE(dark, n - 2);  // a 3 px band: the nearest pixel is on it (rods may cross it elsewhere)
  const nlohmann::json a = nlohmann::json::parse(slurp(path("plain.json"))),
                       b = nlohmann::json::parse(slurp(path("wafer.json")));
  EXPECT_EQ(a["tags"], b["tags"]);
  EXPECT_DOUBLE_EQ(b["wafer_outline"]["diameter"].get<double>(), 0.1);
}

// `pcr camera` on rendered chessboards recovers the camera that rendered them.
TEST_F(VisionCli, CameraFromRenderedChessboards) {
  CameraModel cam;
  cam.width = 800;
  cam.height = 600;
  cam.K << 900, 0, 402, 0, 905, 297, 0, 0, 1;
  cam.distortion << -0.2, 0.1, 0, 0, 0;
  save_camera(cam, path("board_camera.yaml"));
  const double poses[][3] = {{0.0, 0.0, 0.0},   {0.3, 0.0, 0.05},  {-0.3, 0.1, 0.1},
                             {0.1, 0.35, 0.15}, {0.0, -0.35, 0.2}, {0.25, 0.25, 0.25}};
  std::string images;
  for (int k = 0; k < 6; ++k) {
    const std::string image = path("board" + std::to_string(k) + ".png");
    std::ostringstream args;
    args << "render --chessboard 9x6 --square 0.008 --camera '" << path("board_camera.yaml")
         << "' --height 0.12 --tilt-x " << poses[k][0] << " --tilt-y " << poses[k][1]
         << " --board-pose 0,0," << poses[k][2] << " --supersampling 3 --blur 0.7 --output '"
         << image << "'";
    const Result r = run(args.str());
    ASSERT_EQ(r.status, 0) << r.all();
    images += " '" + image + "'";
  }
  const Result r = run("camera --board 9x6 --square 0.008 --images" + images + " --output '" +
                       path("calibrated.yaml") + "'");
  ASSERT_EQ(r.status, 0) << r.all();
  const CameraModel c = load_camera(path("calibrated.yaml"));
  EXPECT_EQ(c.width, 800);
  EXPECT_EQ(c.height, 600);
  EXPECT_NEAR(c.K(0, 0), 900, 9);
  EXPECT_NEAR(c.K(1, 1), 905, 9);
  EXPECT_NEAR(c.K(0, 2), 402, 8);
  EXPECT_NEAR(c.K(1, 2), 297, 8);
  EXPECT_NEAR(c.distortion[0], -0.2, 0.05);
  // A blank image: an error naming the file, no output. (Not a large image without a board:
  // cv::findChessboardCorners without CALIB_CB_FAST_CHECK searches it for minutes.)
  write_png(GrayImage(320, 240, 0.5f), path("blank_board.png"));
  const Result bad = run("camera --board 9x6 --square 0.008 --images '" + path("blank_board.png") +
                         "' --output '" + path("bad_out.yaml") + "'");
  EXPECT_NE(bad.status, 0) << bad.all();
  EXPECT_NE(bad.err.find("blank_board.png"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad_out.yaml")));
}

}  // namespace
