// `pcr render`, `pcr measure`, `pcr camera` and `pcr measure-poses` run as programs: one rendered
// robot measured end to end against the render's ground truth (a planar robot's description, a
// spatial robot's platform poses and its attachment points), every bad input docs/vision.md lists
// ("Command-line checks") exiting non-zero with a message naming the mount, the file, the row or
// the id and writing no output, and a camera calibrated from rendered chessboards.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "pcr/csv_io.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/mounts.hpp"
#include "pcr/vision/render.hpp"
#include "scratch_directory.hpp"
#include "umeyama_reference.hpp"

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

  /// Checks that `r` failed, that every `needle` is in its message and that no output file named
  /// bad_out* (nor a temporary one) was left.
  static void expect_failure(const Result& r, const std::vector<std::string>& needles) {
    EXPECT_NE(r.status, 0) << r.all();
    for (const std::string& n : needles)
      EXPECT_NE(r.err.find(n), std::string::npos) << "'" << n << "' not in: " << r.err;
    for (const auto& e : fs::directory_iterator(dir()))
      EXPECT_EQ(e.path().filename().string().rfind("bad_out", 0), std::string::npos)
          << "left " << e.path();
  }

  /// Runs `pcr measure` expecting a failure (expect_failure).
  static void expect_measure_error(const std::string& mounts, const std::string& camera,
                                   const std::string& image,
                                   const std::vector<std::string>& needles) {
    const std::string output = path("bad_out.json");
    const Result r =
        run("measure --mounts '" + mounts + "' --camera '" + camera + "' --image '" + image +
            "' --output '" + output + "' --annotated '" + path("bad_out.png") + "'");
    expect_failure(r, needles);
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

// ---- A spatial robot: `pcr measure-poses` -----------------------------------------------------

const std::string kSpatialRobot =
    std::string(PCR_SOURCE_DIR) + "/robots/continuum-stewart-gough.json";

// A rotation matrix as a (w, x, y, z) quaternion, through Eigen.
Eigen::Vector4d quaternion_wxyz(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return {q.w(), q.x(), q.y(), q.z()};
}
Eigen::Matrix3d rotation_wxyz(const Eigen::Vector4d& q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}
struct Frame {  // a rigid pose through Eigen, independent of pcr::SpatialPose
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Frame operator*(const Frame& o) const { return {R * o.R, t + R * o.t}; }
  Frame inverse() const { return {R.transpose(), -(R.transpose() * t)}; }
};
Frame frame_of(const nlohmann::json& j) {
  const nlohmann::json &p = j["position"], &q = j["orientation"];
  return {rotation_wxyz(Eigen::Vector4d(q[0], q[1], q[2], q[3])),
          Eigen::Vector3d(p[0], p[1], p[2])};
}
nlohmann::json frame_json(const Frame& f) {
  const Eigen::Vector4d q = quaternion_wxyz(f.R);
  return {{"position", {f.t.x(), f.t.y(), f.t.z()}}, {"orientation", {q[0], q[1], q[2], q[3]}}};
}

// The platform's board (frame P): four 24 mm tags around a 16 mm one on its top face, 5 mm above
// P, and a 16 mm tag on a 30 degree bevel at its edge (as tests/test_spatial_vision.cpp's).
struct SpatialBoardTag {
  int id;
  double size;
  Frame in_platform;
};
std::vector<SpatialBoardTag> spatial_board() {
  const auto turn = [](double angle, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  };
  std::vector<SpatialBoardTag> tags;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d at((k % 2 ? 0.035 : -0.035), (k / 2 ? 0.035 : -0.035), 0.005);
    tags.push_back({10 + k, 0.024, {turn(0.4 * k, Eigen::Vector3d::UnitZ()), at}});
  }
  tags.push_back({14, 0.016, {turn(-0.3, Eigen::Vector3d::UnitZ()), {0, 0, 0.005}}});
  tags.push_back({15, 0.016, {turn(-M_PI / 6, Eigen::Vector3d::UnitX()), {0, -0.07, 0}}});
  return tags;
}

// The board frame M off P (the file's "marker", ^M T_P): its poses are M's, not P's.
const Frame kMarkerTPlatform{
    Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix(),
    {0.004, -0.003, 0.002}};

nlohmann::json spatial_board_json() {
  nlohmann::json j = {{"format", "pcr-tag-board"},
                      {"version", 1},
                      {"family", kDefaultTagFamily},
                      {"marker", frame_json(kMarkerTPlatform)}};
  for (const SpatialBoardTag& t : spatial_board())
    j["tags"].push_back({{"id", t.id}, {"tag_size", t.size}, {"pose", frame_json(t.in_platform)}});
  return j;
}

class SpatialVisionCli : public VisionCli {
 protected:
  static constexpr int kRows = 4;
  // ^S T_M of each row, and the camera: 640 x 640 px, f = 750 px, barrel distortion, 0.75 m
  // above W, about 0.35 m above the platform (0.47 mm/px on it).
  static std::vector<Frame> truths_;

  static void SetUpTestSuite() {
    scratch_ = std::make_unique<pcr::test::ScratchDirectory>("spatial_vision_cli");
    Scene scene;
    scene.camera.width = scene.camera.height = 640;
    scene.camera.K << 750, 0, 322.4, 0, 751, 317.9, 0, 0, 1;
    scene.camera.distortion << -0.1, 0.03, 0.0002, -0.0003, 0.0;
    scene.plane = PlanePose::looking_down(0.75, 0.05, -0.03);
    save_camera(scene.camera, path("camera.yaml"));
    const Frame camera_T_world{scene.plane.rotation, scene.plane.translation};
    std::ofstream(path("board.json")) << spatial_board_json().dump(2);
    std::ofstream rows(path("rows.csv"));
    rows << "q1,q2,q3,q4,q5,q6,image\n";
    for (int k = 0; k < kRows; ++k) {
      // Platform poses ^W T_P about 0.4 m above the base, moved by up to 2 cm, tilted by up to
      // 0.1 rad; the joints are only carried through to the dataset.
      const Frame world_T_platform{
          (Eigen::AngleAxisd(0.1 * std::sin(k + 1.0), Eigen::Vector3d::UnitX()) *
           Eigen::AngleAxisd(0.08 * std::cos(2.0 * k), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(0.3 * k - 0.4, Eigen::Vector3d::UnitZ()))
              .toRotationMatrix(),
          {0.02 * std::cos(1.3 * k), 0.015 * std::sin(2.1 * k), 0.4 + 0.01 * k}};
      scene.tags_3d.clear();
      for (const SpatialBoardTag& t : spatial_board()) {
        const Frame w = world_T_platform * t.in_platform;
        scene.tags_3d.push_back(RenderTag3d{kDefaultTagFamily, t.id, t.size,
                                            SpatialPose<double>{w.t, quaternion_wxyz(w.R)}});
      }
      truths_.push_back(camera_T_world * world_T_platform * kMarkerTPlatform.inverse());
      RenderOptions opt;
      opt.supersampling = 3;
      opt.blur_sigma_px = 0.8;
      opt.noise_sigma = 0.02;
      opt.gradient = 0.15;
      opt.white = 0.8;
      opt.seed = 40 + k;
      const std::string image = "pose" + std::to_string(k) + ".png";
      write_png(render_scene(scene, opt), path(image));
      for (int i = 0; i < 6; ++i) rows << 0.001 * (k + 1) * (i - 2) << ",";
      rows << image << "\n";  // relative: to the rows file's directory
    }
  }

  /// Runs `pcr measure-poses` with `board` and `rows` expecting a failure naming every `needle`
  /// and writing no output.
  static void expect_poses_error(const std::string& board, const std::string& rows,
                                 const std::vector<std::string>& needles,
                                 const std::string& robot = kSpatialRobot) {
    const Result r =
        run("measure-poses --robot '" + robot + "' --board '" + board + "' --camera '" +
            path("camera.yaml") + "' --input '" + rows + "' --output '" + path("bad_out.csv") +
            "' --covariance '" + path("bad_out_cov.csv") + "'");
    expect_failure(r, needles);
  }

  static std::string write(const std::string& name, const std::string& text) {
    std::ofstream(path(name)) << text;
    return path(name);
  }
};

std::vector<Frame> SpatialVisionCli::truths_;

// The 0.9999 quantile of chi-square with 6 degrees of freedom.
constexpr double kChiSquare6Quantile9999 = 27.856;

// Each row's measured ^S T_M lies within the command's own predicted covariance of the truth of
// the render: its Mahalanobis distance d2 = e^T S^-1 e (e = (dp in S, dtheta in M)) below
// chi-square(6)'s 0.9999 quantile; the joints are carried through unchanged.
TEST_F(SpatialVisionCli, MeasuredPosesAgreeWithTheRenderedTruthWithinTheirCovariance) {
  const Result r =
      run("measure-poses --robot '" + kSpatialRobot + "' --board '" + path("board.json") +
          "' --camera '" + path("camera.yaml") + "' --input '" + path("rows.csv") + "' --output '" +
          path("dataset.csv") + "' --covariance '" + path("covariance.csv") + "'");
  ASSERT_EQ(r.status, 0) << r.all();
  const CsvTable data = read_csv(path("dataset.csv"));
  const CsvTable cov = read_csv(path("covariance.csv"));
  ASSERT_EQ(data.columns, (std::vector<std::string>{"q1", "q2", "q3", "q4", "q5", "q6", "x", "y",
                                                    "z", "rx", "ry", "rz"}));
  ASSERT_EQ(data.rows.size(), static_cast<std::size_t>(kRows));
  ASSERT_EQ(cov.rows.size(), static_cast<std::size_t>(kRows));
  ASSERT_EQ(cov.columns.size(), 6u + 21u + 2u);
  double worst = 0;
  for (int k = 0; k < kRows; ++k) {
    const CsvRow row = data.rows[static_cast<std::size_t>(k)];
    for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(row[i], 0.001 * (k + 1) * (i - 2));
    const Eigen::Vector3d p(row[6], row[7], row[8]), turn(row[9], row[10], row[11]);
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(turn.norm(), turn.normalized()).toRotationMatrix();  // not a zero turn
    const Frame& truth = truths_[static_cast<std::size_t>(k)];
    const Eigen::AngleAxisd dtheta(truth.R.transpose() * R);
    Eigen::Matrix<double, 6, 1> e;
    e << p - truth.t, dtheta.angle() * dtheta.axis();
    Eigen::Matrix<double, 6, 6> S;
    const CsvRow c = cov.rows[static_cast<std::size_t>(k)];
    std::size_t at = 6;
    for (int a = 0; a < 6; ++a)
      for (int b = a; b < 6; ++b) S(a, b) = S(b, a) = c[at++];
    EXPECT_EQ(c[at + 1], 6) << "row " << k << ": every board tag seen";
    const double d2 = e.dot(S.ldlt().solve(e));
    EXPECT_LT(d2, kChiSquare6Quantile9999) << "row " << k << ": error " << e.transpose();
    // A covariance of this camera's scale (um, sub-mrad), not one so wide any pose would pass.
    EXPECT_LT(std::sqrt(S(0, 0)), 20e-6) << "row " << k;
    EXPECT_LT(std::sqrt(S(4, 4)), 2e-3) << "row " << k;
    worst = std::max(worst, d2);
  }
  std::printf("%d poses, worst d2 %.2f\n", kRows, worst);
}

// The command-line round trip: `pcr render` places the board by the robot's forward kinematics at
// q and writes the truth ^S T_M; `pcr measure-poses` on that image finds it within its covariance.
TEST_F(SpatialVisionCli, RenderedSpatialRobotMeasuredWithinItsCovariance) {
  const std::string q = "0.004,-0.002,0.003,0.001,-0.003,0.002";
  const Result render =
      run("render --robot '" + kSpatialRobot + "' --board '" + path("board.json") + "' --camera '" +
          path("camera.yaml") + "' --q " + q +
          " --height 0.75 --tilt-x 0.05 --tilt-y -0.03 --supersampling 3 --blur 0.8 --noise 0.01 "
          "--seed 9 --output '" +
          path("fk.png") + "' --truth '" + path("fk.json") + "'");
  ASSERT_EQ(render.status, 0) << render.all();
  write("fk_rows.csv", "image,q1,q2,q3,q4,q5,q6\nfk.png," + q + "\n");  // columns in any order
  const Result r = run("measure-poses --robot '" + kSpatialRobot + "' --board '" +
                       path("board.json") + "' --camera '" + path("camera.yaml") + "' --input '" +
                       path("fk_rows.csv") + "' --output '" + path("fk_dataset.csv") +
                       "' --covariance '" + path("fk_covariance.csv") + "'");
  ASSERT_EQ(r.status, 0) << r.all();
  const nlohmann::json truth = nlohmann::json::parse(slurp(path("fk.json")));
  const Frame measured_truth = frame_of(truth["camera_T_marker"]);
  // The truth's frames, from the render's own ^W T_P and the test's camera and ^M T_P.
  const Frame world_T_platform = frame_of(truth["world_T_platform"]);
  const PlanePose plane = PlanePose::looking_down(0.75, 0.05, -0.03);
  const Frame expected =
      Frame{plane.rotation, plane.translation} * world_T_platform * kMarkerTPlatform.inverse();
  EXPECT_LT((expected.t - measured_truth.t).norm(), 1e-12);
  EXPECT_LT((expected.R - measured_truth.R).norm(), 1e-12);
  // The platform on its 0.4 m rods, nearly upright: a little below 0.4 m above the base.
  EXPECT_GT(world_T_platform.t.z(), 0.3);
  EXPECT_LT(world_T_platform.t.z(), 0.4);
  const CsvTable data = read_csv(path("fk_dataset.csv"));
  const CsvTable cov = read_csv(path("fk_covariance.csv"));
  ASSERT_EQ(data.rows.size(), 1u);
  const CsvRow row = data.rows[0];
  const Eigen::Vector3d p(row[6], row[7], row[8]), turn(row[9], row[10], row[11]);
  const Eigen::AngleAxisd dtheta(measured_truth.R.transpose() *
                                 Eigen::AngleAxisd(turn.norm(), turn.normalized()).matrix());
  Eigen::Matrix<double, 6, 1> e;
  e << p - measured_truth.t, dtheta.angle() * dtheta.axis();
  Eigen::Matrix<double, 6, 6> S;
  std::size_t at = 6;
  for (int a = 0; a < 6; ++a)
    for (int b = a; b < 6; ++b) S(a, b) = S(b, a) = cov.rows[0][at++];
  const double d2 = e.dot(S.ldlt().solve(e));
  EXPECT_LT(d2, kChiSquare6Quantile9999) << "error " << e.transpose();
  std::printf("rendered at q: d2 %.2f, |dp| %.1f um\n", d2, e.head<3>().norm() * 1e6);
}

TEST_F(SpatialVisionCli, BadInputsNameTheFileRowAndValue) {
  const std::string rows = path("rows.csv"), board = path("board.json");
  // A missing image: the row's line and the file.
  expect_poses_error(board,
                     write("missing_rows.csv",
                           "q1,q2,q3,q4,q5,q6,image\n0,0,0,0,0,0,pose0.png\n"
                           "0,0,0,0,0,0,nowhere.png\n"),
                     {"missing_rows.csv:3", "nowhere.png"});
  // Rows with the wrong joint count: a header of 5 joints for 6 rods, a row of 5 joints.
  expect_poses_error(board, write("five.csv", "q1,q2,q3,q4,q5,image\n0,0,0,0,0,pose0.png\n"),
                     {"five.csv", "missing column 'q6'"});
  expect_poses_error(board,
                     write("short_row.csv", "q1,q2,q3,q4,q5,q6,image\n0,0,0,0,0,pose0.png\n"),
                     {"short_row.csv:2", "expected 7 columns, got 6"});
  // Joints beyond any robot (a unit slip): the line, the column and the value.
  expect_poses_error(board, write("mm.csv", "q1,q2,q3,q4,q5,q6,image\n0,0,12,0,0,0,pose0.png\n"),
                     {"mm.csv:2", "q3 = 12"});
  // A board whose ids are not in the image: the row and image, the board's ids and those seen.
  nlohmann::json j = spatial_board_json();
  for (auto& t : j["tags"]) t["id"] = t["id"].get<int>() + 40;
  std::ofstream(path("other_ids.json")) << j.dump();
  expect_poses_error(path("other_ids.json"), rows,
                     {"rows.csv:2", "pose0.png", "no tag of the board", "id 50", "id 10"});
  // An id the family lacks: the board file and the tag.
  j = spatial_board_json();
  j["tags"][2]["id"] = 5000;
  std::ofstream(path("bad_id.json")) << j.dump();
  expect_poses_error(path("bad_id.json"), rows, {"bad_id.json", "board tag 2", "id 5000"});
  // Malformed board files: a syntax error (line and column), a misspelt field, a quaternion not
  // of unit norm, a missing size, a tag given twice.
  expect_poses_error(write("syntax.json", "{\n  \"tags\": [\n    {\"id\": 1,}\n  ]\n}\n"), rows,
                     {"syntax.json:3", "JSON syntax error"});
  j = spatial_board_json();
  j["tags"][1]["tag_sise"] = 0.02;
  std::ofstream(path("misspelt.json")) << j.dump();
  expect_poses_error(path("misspelt.json"), rows, {"misspelt.json", "tags[1].tag_sise"});
  j = spatial_board_json();
  j["tags"][0]["pose"]["orientation"] = {1, 0.1, 0, 0};
  std::ofstream(path("norm.json")) << j.dump();
  expect_poses_error(path("norm.json"), rows, {"norm.json", "tags[0].pose.orientation", "norm"});
  j = spatial_board_json();
  j["tags"][3].erase("tag_size");
  std::ofstream(path("no_size.json")) << j.dump();
  expect_poses_error(path("no_size.json"), rows, {"no_size.json", "tags[3].tag_size", "missing"});
  j = spatial_board_json();
  j["tags"][4]["id"] = 10;
  std::ofstream(path("twice.json")) << j.dump();
  expect_poses_error(path("twice.json"), rows, {"twice.json", "id 10", "twice"});
  // A planar robot file.
  expect_poses_error(board, rows, {"femto-3pf.json", "planar"},
                     std::string(PCR_SOURCE_DIR) + "/robots/femto-3pf.json");
  // The output over an input is refused, and the input stays.
  const std::string before = slurp(rows);
  const Result r =
      run("measure-poses --robot '" + kSpatialRobot + "' --board '" + board + "' --camera '" +
          path("camera.yaml") + "' --input '" + rows + "' --output '" + rows + "'");
  EXPECT_NE(r.status, 0) << r.all();
  EXPECT_EQ(slurp(rows), before);
}

// ---- A spatial robot's attachment points: `pcr measure` on a spatial design
// ----------------------

// The truth: the design's holes A_i and points B_i each moved by up to 80 um along each axis
// (within the file's 0.1 mm half-widths). Next to each, a tag face up (40 mm on the base; 30 mm on
// the platform, 5 mm above the point), its centre 25 mm (20 mm) from the point along the ring's
// tangent away from the nearest other point, turned 0.35 rad off it (edges off the pixel grid).
// The layout file gives each point in its tag's frame; the images: the base from 0.4 m, the
// platform at a pose ^W T_P from 0.35 m above it, both with the fixture's camera.
struct AttachmentScene {
  std::vector<Eigen::Vector3d> A, B;  // the truth, in W and P
  nlohmann::json layout;
};

AttachmentScene attachment_scene(const SpatialRobotParams<double>& design, const Frame& platform,
                                 const CameraModel& camera, const std::string& base_png,
                                 const std::string& platform_png) {
  AttachmentScene out;
  const int n = design.num_rods;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d move(std::cos(1.7 * i), std::sin(2.3 * i + 0.4), std::cos(0.9 * i + 1));
    out.A.push_back(design.limb(i).A + 80e-6 * move);
    out.B.push_back(design.limb(i).B - 80e-6 * move.reverse());
  }
  out.layout = {{"format", "pcr-attachment-points"}, {"version", 1}, {"tag_size", 0.03}};
  out.layout["rods"] = nlohmann::json::array();
  for (int i = 0; i < n; ++i) out.layout["rods"].push_back(nlohmann::json::object());
  for (int end = 0; end < 2; ++end) {
    const std::vector<Eigen::Vector3d>& points = end ? out.B : out.A;
    Scene scene;
    scene.camera = camera;
    scene.plane = PlanePose::looking_down(end ? platform.t.z() + 0.35 : 0.4, 0.05, -0.03);
    const Frame world_T_frame = end ? platform : Frame{};
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
      int nearest = i == 0 ? 1 : 0;
      for (int j = 0; j < n; ++j)
        if (j != i && (points[static_cast<std::size_t>(j)] - p).norm() <
                          (points[static_cast<std::size_t>(nearest)] - p).norm())
          nearest = j;
      Eigen::Vector3d away = Eigen::Vector3d::UnitZ().cross(p).normalized();
      if (away.dot(points[static_cast<std::size_t>(nearest)] - p) > 0) away = -away;
      const Frame tag{
          Eigen::AngleAxisd(std::atan2(away.y(), away.x()) + 0.35, Eigen::Vector3d::UnitZ())
              .toRotationMatrix(),
          p + (end ? 0.02 : 0.025) * away + Eigen::Vector3d(0, 0, end ? 0.005 : 0.0)};
      const Frame in_world = world_T_frame * tag;
      scene.tags_3d.push_back(
          RenderTag3d{kDefaultTagFamily, (end ? 30 : 20) + i, end ? 0.03 : 0.04,
                      SpatialPose<double>{in_world.t, quaternion_wxyz(in_world.R)}});
      const Eigen::Vector3d offset = tag.R.transpose() * (p - tag.t);
      out.layout["rods"][static_cast<std::size_t>(i)][end ? "B" : "A"] = {
          {"id", (end ? 30 : 20) + i}, {"offset", {offset.x(), offset.y(), offset.z()}}};
      if (!end) out.layout["rods"][static_cast<std::size_t>(i)]["A"]["tag_size"] = 0.04;
    }
    RenderOptions opt;
    opt.supersampling = 2;
    opt.blur_sigma_px = 0.8;
    opt.noise_sigma = 0.02;
    opt.white = 0.85;
    opt.seed = 60 + end;
    write_png(render_scene(scene, opt), end ? platform_png : base_png);
  }
  return out;
}

// Render, then `pcr measure` on the spatial design: the written file's A_i and B_i contain the
// truth registered onto the design (W and P as the command defines them) within their written
// half-widths, which are those of an image (tens of um), not the design's; everything else is the
// design's. Then the command's own checks: a planar option on a spatial design, an image missing,
// a layout of another rod count, the output over an input.
TEST_F(SpatialVisionCli, MeasuredAttachmentPointsContainTheRenderedTruth) {
  const SpatialRobotDescription design = load_spatial_robot(kSpatialRobot);
  const Frame platform{Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                           Eigen::AngleAxisd(0.04, Eigen::Vector3d::UnitX()).toRotationMatrix(),
                       {0.004, -0.003, 0.38}};
  const AttachmentScene truth = attachment_scene(
      design.params, platform, load_camera(path("camera.yaml")), path("base.png"), path("top.png"));
  std::ofstream(path("points.json")) << truth.layout.dump(2);
  const std::string inputs = "measure --design '" + kSpatialRobot + "' --points '" +
                             path("points.json") + "' --camera '" + path("camera.yaml") +
                             "' --base-image '" + path("base.png") + "' --platform-image '" +
                             path("top.png") + "'";
  const Result r = run(inputs + " --output '" + path("measured.json") + "'");
  ASSERT_EQ(r.status, 0) << r.all();
  EXPECT_NE(r.out.find("registration rms: A"), std::string::npos) << r.out;
  const SpatialRobotDescription measured = load_spatial_robot(path("measured.json"));
  ASSERT_TRUE(measured.uncertainty.has_value());
  const int n = design.params.num_rods;
  std::vector<Eigen::Vector3d> design_A, design_B;
  for (int i = 0; i < n; ++i) {
    design_A.push_back(design.params.limb(i).A);
    design_B.push_back(design.params.limb(i).B);
  }
  const std::vector<Eigen::Vector3d> A = pcr::test::umeyama_registered(truth.A, design_A),
                                     B = pcr::test::umeyama_registered(truth.B, design_B);
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const SpatialLimbParams<double>& m = measured.params.limb(i);
    const SpatialRodUncertainty& u = measured.uncertainty->rods[k];
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(std::abs(m.A[a] - A[k][a]), u.A[a]) << "A" << i + 1 << " axis " << a;
      EXPECT_LE(std::abs(m.B[a] - B[k][a]), u.B[a]) << "B" << i + 1 << " axis " << a;
      worst = std::max(
          {worst, std::abs(m.A[a] - A[k][a]) / u.A[a], std::abs(m.B[a] - B[k][a]) / u.B[a]});
      // An image's: most in depth (one tag's tilt), which an off-axis ray turns partly into x, y.
      EXPECT_LT(u.A[a], 1.5e-3) << "A" << i + 1;
      EXPECT_LT(u.B[a], 1.5e-3) << "B" << i + 1;
    }
    EXPECT_LT(u.A.head<2>().maxCoeff(), 0.5e-3) << "A" << i + 1;
    EXPECT_LT(u.B.head<2>().maxCoeff(), 0.5e-3) << "B" << i + 1;
    // The rest is the design's.
    EXPECT_EQ(m.rod.length, design.params.limb(i).rod.length);
    EXPECT_TRUE(m.base_orientation == design.params.limb(i).base_orientation);
    EXPECT_EQ(u.length, design.uncertainty->rods[k].length);
    EXPECT_TRUE(u.base_rotation == design.uncertainty->rods[k].base_rotation);
  }
  EXPECT_TRUE(measured.params.extrinsics.tracker.position ==
              design.params.extrinsics.tracker.position);
  EXPECT_TRUE(measured.uncertainty->tracker == design.uncertainty->tracker);
  std::printf("worst |error| / half-width %.2f; pcr measure printed:\n%s", worst, r.out.c_str());

  // A planar robot's option, a missing image, another rod count, a planar design, the output
  // over an input (which stays as it was).
  const std::string bad_out = " --output '" + path("bad_out.json") + "'";
  expect_failure(run(inputs + " --image '" + path("base.png") + "'" + bad_out),
                 {"spatial robot", "--image"});
  expect_failure(run("measure --design '" + kSpatialRobot + "' --points '" + path("points.json") +
                     "' --camera '" + path("camera.yaml") + "' --base-image '" + path("base.png") +
                     "'" + bad_out),
                 {"--platform-image is required", "spatial"});
  expect_failure(run("measure --camera '" + path("camera.yaml") + "' --image '" + path("base.png") +
                     "'" + bad_out),
                 {"--mounts is required"});  // the built-in design is planar
  nlohmann::json five = truth.layout;
  five["rods"].erase(5);
  std::ofstream(path("five.json")) << five.dump();
  expect_failure(run("measure --design '" + kSpatialRobot + "' --points '" + path("five.json") +
                     "' --camera '" + path("camera.yaml") + "' --base-image '" + path("base.png") +
                     "' --platform-image '" + path("top.png") + "'" + bad_out),
                 {"five.json", "5 rods", "has 6"});
  nlohmann::json misspelt = truth.layout;
  misspelt["rods"][2]["B"]["ofset"] = misspelt["rods"][2]["B"]["offset"];
  std::ofstream(path("misspelt_points.json")) << misspelt.dump();
  expect_failure(
      run("measure --design '" + kSpatialRobot + "' --points '" + path("misspelt_points.json") +
          "' --camera '" + path("camera.yaml") + "' --base-image '" + path("base.png") +
          "' --platform-image '" + path("top.png") + "'" + bad_out),
      {"misspelt_points.json", "rods[2].B.ofset", "unknown field"});
  expect_failure(run("measure --design '" + std::string(PCR_SOURCE_DIR) +
                     "/robots/femto-3pf.json' --points '" + path("points.json") + "' --camera '" +
                     path("camera.yaml") + "' --base-image '" + path("base.png") +
                     "' --platform-image '" + path("top.png") + "'" + bad_out),
                 {"femto-3pf.json", "planar", "--mounts"});
  const std::string before = slurp(path("points.json"));
  EXPECT_NE(run(inputs + " --output '" + path("points.json") + "'").status, 0);
  EXPECT_EQ(slurp(path("points.json")), before);
}

}  // namespace
