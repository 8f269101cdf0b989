// Bad input: each gives an InputError naming the mount, the file or the id. And the camera files.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <utility>
#include <vector>

#include "pcr/robot_io.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/render.hpp"

namespace pcr::vision {
namespace {

// One scratch file per test and name: ctest runs this binary's tests as parallel processes.
std::string tmp(const std::string& name) {
  return std::string(PCR_BINARY_DIR) + "/test_vision_inputs_" +
         ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + name;
}

MountLayout layout() {
  return load_mounts(std::string(PCR_SOURCE_DIR) + "/data/mounts-femto-3pf.json");
}

Scene small_scene() {
  Scene scene;
  scene.camera.width = scene.camera.height = 1100;
  scene.camera.K << 2800, 0, 550, 0, 2800, 550, 0, 0, 1;  // 179 um/px at 0.5 m
  scene.plane = PlanePose::looking_down(0.5);
  scene.tags = mount_tags(layout(), femto_3pf(), Pose2<double>{});
  return scene;
}

GrayImage render(const Scene& s) {
  RenderOptions opt;
  opt.supersampling = 2;
  opt.blur_sigma_px = 0.6;
  return render_scene(s, opt);
}

// Runs the measurement and returns the InputError message ("" when none was thrown).
std::string measure_error(const Scene& s, const MountLayout& l) {
  try {
    measure_robot(render(s), "home.png", l, s.camera, femto_3pf());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(VisionInputs, GoodSceneMeasures) {
  const Scene s = small_scene();
  const RobotMeasurement m = measure_robot(render(s), "home.png", layout(), s.camera, femto_3pf());
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR((m.limbs[i].A - femto_3pf().limb(i).A).norm(), 0.0, 20e-6);
}

TEST(VisionInputs, MissingMarkerNamesTheMount) {
  Scene s = small_scene();
  s.tags.erase(s.tags.begin() + 4);  // B2, id 4
  const std::string e = measure_error(s, layout());
  EXPECT_NE(e.find("home.png"), std::string::npos) << e;
  EXPECT_NE(e.find("mount B2"), std::string::npos) << e;
  EXPECT_NE(e.find("id 4"), std::string::npos) << e;
}

TEST(VisionInputs, DuplicatedIdNamesTheId) {
  Scene s = small_scene();
  RenderTag extra = s.tags[2];
  extra.pose = Pose2<double>{0.0, 0.0, 0.3};
  s.tags.push_back(extra);
  const std::string e = measure_error(s, layout());
  EXPECT_NE(e.find("tag id 2"), std::string::npos) << e;
  EXPECT_NE(e.find("2 times"), std::string::npos) << e;
}

TEST(VisionInputs, WrongFamilyNamesTheMount) {
  Scene s = small_scene();
  for (RenderTag& t : s.tags) t.family = "tag25h9";
  const std::string e = measure_error(s, layout());
  EXPECT_NE(e.find("mount A1 (tag36h11 id 0) not found"), std::string::npos) << e;
}

TEST(VisionInputs, MarkerCutByTheBorder) {
  Scene s = small_scene();
  // Shift the view so that A1's quiet zone crosses the bottom border (black border still inside).
  const Eigen::Vector2d c = s.tags[0].pose.translation();
  const double metres_per_px = 0.5 / 2800;
  const double half_visible = 0.5 * 0.010 + 0.4 * 0.00125;  // to the middle of the white ring
  s.plane.translation.x() = -c.x();
  s.plane.translation.y() = (550 - 0.5 - half_visible / metres_per_px) * metres_per_px + c.y();
  const std::string e = measure_error(s, layout());
  EXPECT_NE(e.find("mount A1"), std::string::npos) << e;
  EXPECT_NE(e.find("is cut by the image border"), std::string::npos) << e;
}

TEST(VisionInputs, UnreadableAndBlankImagesNameTheFile) {
  const std::string garbage = tmp("garbage.png");
  std::ofstream(garbage) << "not an image";
  try {
    read_image(garbage);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(garbage), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_image(tmp("does-not-exist.png")), InputError);
  const std::string blank = tmp("blank.png");
  write_png(GrayImage(200, 100, 0.5f), blank);
  try {
    read_image(blank);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("blank"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(blank), std::string::npos) << e.what();
  }
}

std::vector<unsigned char> bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The size is read from every format's header as OpenCV's encoders wrote it, and every truncated
// header is an InputError naming the file, never a read past the end (ASan) nor a wrong size.
TEST(VisionInputs, HeaderSizeIsReadBeforeDecoding) {
  cv::Mat grey(23, 37, CV_8U), wide(23, 37, CV_16U), colour(23, 37, CV_8UC3);
  cv::randu(grey, 0, 255);
  cv::randu(wide, 0, 65535);
  cv::randu(colour, 0, 255);
  const std::vector<std::pair<std::string, cv::Mat>> files = {
      {"grey.png", grey}, {"wide.png", wide}, {"grey.jpg", grey},    {"colour.jpg", colour},
      {"grey.tif", grey}, {"wide.tif", wide}, {"grey.bmp", grey},    {"colour.bmp", colour},
      {"grey.pgm", grey}, {"wide.pgm", wide}, {"colour.ppm", colour}};
  for (const auto& [name, mat] : files) {
    const std::string path = tmp(name);
    ASSERT_TRUE(cv::imwrite(path, mat)) << name;
    const std::vector<unsigned char> bytes = bytes_of(path);
    EXPECT_EQ(image_header_size(bytes, name), std::make_pair(37, 23)) << name;
    const GrayImage image = read_image(path);
    EXPECT_EQ(image.width, 37) << name;
    EXPECT_EQ(image.height, 23) << name;
    for (std::size_t size = 0; size < std::min<std::size_t>(bytes.size(), 300); ++size) {
      const std::vector<unsigned char> prefix(bytes.begin(), bytes.begin() + size);
      try {
        EXPECT_EQ(image_header_size(prefix, name), std::make_pair(37, 23)) << name << size;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      }
    }
  }
  const std::string webp = tmp("other.webp");
  std::ofstream(webp) << "RIFF\x10\0\0\0WEBPVP8 ";
  try {
    read_image(webp);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not an image pcr reads"), std::string::npos) << e.what();
  }
}

TEST(VisionInputs, CameraFileRoundTripAndErrors) {
  const Scene s = small_scene();
  CameraModel cam = s.camera;
  cam.distortion << -0.1, 0.05, 1e-4, -2e-4, 0.01;
  const std::string path = tmp("camera.yaml");
  save_camera(cam, path);
  const CameraModel back = load_camera(path);
  EXPECT_EQ(back.width, 1100);
  EXPECT_DOUBLE_EQ(back.K(0, 0), 2800);
  EXPECT_DOUBLE_EQ(back.distortion[3], -2e-4);
  // normalize() inverts project_normalized().
  const Eigen::Vector2d xn(0.12, -0.09);
  EXPECT_LT((back.normalize(back.project_normalized(xn)) - xn).norm(), 1e-12);

  // Wrong dimensions for the image.
  CameraModel wrong = cam;
  wrong.width = 1000;
  wrong.K(0, 2) = 500;
  try {
    measure_robot(render(s), "home.png", layout(), wrong, femto_3pf());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1100 x 1100"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("home.png"), std::string::npos) << e.what();
  }
  // A missing field and a malformed matrix, named with the file.
  const std::string missing = tmp("missing.yaml");
  std::ofstream(missing) << "%YAML:1.0\n---\nimage_width: 100\nimage_height: 100\n";
  try {
    load_camera(missing);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("camera_matrix"), std::string::npos) << e.what();
  }
  const std::string bad = tmp("bad.yaml");
  std::ofstream(bad)
      << "%YAML:1.0\n---\nimage_width: 100\nimage_height: 100\ncamera_matrix: !!opencv-matrix\n"
         "   rows: 2\n   cols: 2\n   dt: d\n   data: [ 1., 0., 0., 1. ]\n"
         "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
         "   data: [ 0., 0., 0., 0., 0. ]\n";
  try {
    load_camera(bad);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("must be 3x3"), std::string::npos) << e.what();
  }
}

// Whatever OpenCV's FileStorage writes around a camera (the fields of its calibration sample:
// strings, counts, comments, per-view matrices of any element type and size, NaN) passes the
// shape check that keeps malformed text from OpenCV's reader.
TEST(VisionInputs, CameraFilesAsOpenCVWritesThemAreRead) {
  cv::RNG rng(20261124);
  for (int trial = 0; trial < 20; ++trial) {
    const std::string path = tmp("opencv" + std::to_string(trial) + ".yaml");
    const int views = 1 + trial;
    const int n_distortion = std::vector<int>{0, 4, 5, 8}[trial % 4];
    {
      cv::FileStorage fs(path, cv::FileStorage::WRITE);
      fs << "calibration_time"
         << "Tue 24 Nov 2026 18:43:14 UTC";
      fs << "nr_of_frames" << views << "image_width" << 1920 << "image_height" << 1080;
      fs << "board_width" << 9 << "board_height" << 6 << "square_size" << 0.008;
      fs.writeComment("flags: +fix_k3 +zero_tangent_dist", false);
      fs << "flags" << 4096 << "fisheye_model" << 0;
      fs << "camera_matrix"
         << (cv::Mat_<double>(3, 3) << rng.uniform(500., 3000.), 0, 960.3, 0,
             rng.uniform(500., 3000.), 540.7, 0, 0, 1);
      cv::Mat distortion(1, n_distortion, CV_64F);
      if (n_distortion > 0) rng.fill(distortion, cv::RNG::NORMAL, 0, 0.1);
      fs << "distortion_coefficients" << distortion;
      fs << "avg_reprojection_error" << rng.uniform(0.05, 0.5);
      cv::Mat errors(views, 1, CV_32F), extrinsics(views, 6, CV_64F), points(views, 54, CV_32FC2);
      rng.fill(errors, cv::RNG::UNIFORM, 0, 1);
      rng.fill(extrinsics, cv::RNG::NORMAL, 0, std::pow(10.0, rng.uniform(-300, 300)));
      rng.fill(points, cv::RNG::UNIFORM, 0, 1920);
      extrinsics.at<double>(0, 0) = std::numeric_limits<double>::quiet_NaN();
      extrinsics.at<double>(0, 1) = -std::numeric_limits<double>::infinity();
      fs << "per_view_reprojection_errors" << errors << "extrinsic_parameters" << extrinsics
         << "image_points" << points << "mask" << cv::Mat(2, 3, CV_8U, cv::Scalar(255));
    }
    const CameraModel camera = load_camera(path);
    EXPECT_EQ(camera.width, 1920);
    EXPECT_EQ(camera.height, 1080);
    EXPECT_DOUBLE_EQ(camera.K(1, 2), 540.7);
  }
}

// OpenCV 5's FileStorage begins its YAML with `%YAML 1.2` (OpenCV 4's with `%YAML:1.0`), may
// write booleans as true/false, and a YAML tool may end the document with `...`: the same camera
// in each writer's shape reads the same. Written by hand: the OpenCV here is 4.6.
TEST(VisionInputs, CameraFilesOfOpenCV4And5AreRead) {
  const std::string body =
      "calibration_time: \"Tue 24 Nov 2026 18:43:14 UTC\"\nimage_width: 1920\n"
      "image_height: 1080\nfix_aspect_ratio: false\ncamera_matrix: !!opencv-matrix\n"
      "   rows: 3\n   cols: 3\n   dt: d\n"
      "   data: [ 2.8001e+03, 0., 9.603e+02, 0., 2.7995e+03,\n       5.407e+02, 0., 0., 1. ]\n"
      "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
      "   data: [ -1.5e-01, 1.0e-01, 0., 0., 0. ]\n";
  const std::string heads[] = {"%YAML:1.0\n---\n",
                               "%YAML 1.2\n---\n",
                               "%YAML 1.1\n---\n",
                               "%YAML 1.0\n---\n",
                               "%YAML:1.2\n---\n",
                               "---\n",
                               ""};
  for (const std::string& head : heads) {
    for (const std::string& tail :
         {std::string(), std::string("...\n"), std::string("...\n# end\n")}) {
      const std::string path = tmp("writers.yaml");
      std::ofstream(path, std::ios::binary) << head << body << tail;
      try {
        const CameraModel camera = load_camera(path);
        EXPECT_EQ(camera.width, 1920);
        EXPECT_DOUBLE_EQ(camera.K(0, 0), 2800.1);
        EXPECT_DOUBLE_EQ(camera.K(1, 2), 540.7);
        EXPECT_DOUBLE_EQ(camera.distortion[0], -0.15);
      } catch (const InputError& e) {
        ADD_FAILURE() << e.what() << "\nin:\n" << head << body << tail;
      }
    }
  }
  // What is not the shape of either writer stays refused, naming the line.
  const std::pair<std::string, std::string> refused[] = {
      {"%YAML 2.0\n---\n" + body, "bad.yaml:1: '%YAML 2.0': only line 1 may be a YAML directive"},
      {"%YAML 1.3\n---\n" + body, "bad.yaml:1: '%YAML 1.3'"},
      {"%YAML  1.2\n---\n" + body, "bad.yaml:1: '%YAML  1.2'"},
      {"---\n%YAML 1.2\n" + body, "bad.yaml:2: '%YAML 1.2'"},
      {"%YAML 1.2\n%TAG ! tag:opencv.org,2026:\n---\n" + body, "bad.yaml:2: '%TAG"},
      {"%YAML 1.2\n---\n...\n" + body, "bad.yaml:3: '...'"},
      {"%YAML 1.2\n---\n" + body + "...\nimage_width: 1\n", "bad.yaml:19: 'image_width: 1' after"},
      {"%YAML 1.2\n---\n" + body + "...\n---\n", "bad.yaml:19: '---' after"},
  };
  for (const auto& [text, message] : refused) {
    const std::string path = tmp("bad.yaml");
    std::ofstream(path, std::ios::binary) << text;
    try {
      load_camera(path);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
          << e.what() << "\nexpected: " << message;
    }
  }
}

// Text OpenCV's writer would never give is refused, naming the line, before OpenCV reads it.
TEST(VisionInputs, CameraFilesOutOfShapeAreRefusedByLine) {
  const std::string head = "%YAML:1.0\n---\nimage_width: 100\nimage_height: 100\n";
  const std::string matrix =
      "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
      "   data: [ 80., 0., 50., 0., 80.,\n       50., 0., 0., 1. ]\n";
  const auto load_text = [](const std::string& text) {
    const std::string path = tmp("bad.yaml");
    std::ofstream(path, std::ios::binary) << text;
    return load_camera(path);
  };
  const std::string distortion =
      "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 0\n   dt: d\n   data: []\n";
  ASSERT_NO_THROW(load_text(head + matrix + distortion));
  const std::pair<std::string, std::string> cases[] = {
      {head + "\tcols: 3\n", "bad.yaml:5: a control character"},
      {head + "---\n" + matrix, "bad.yaml:5: '---': only line 1"},
      {"%YAML:1.0\n---%YAML:1.0\n--`-\n", "bad.yaml:2: '---%YAML:1.0': only line 1"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 3\n   data: [ 1.,\n",
       "bad.yaml:8: the 'data'"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 3\n   step: 3\n",
       "bad.yaml:7: 'step' is not"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 3\n   rows: 3\n",
       "bad.yaml:7: 'rows' given"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
              "   data: [ 1., 2. ] x\n",
       "bad.yaml:9: a line of the 'data' list"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
              "   data: [ 1., 2e ]\n",
       "bad.yaml:9: '2e' is not a number"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 3\nimage_width: 1\n",
       "bad.yaml:7: the opencv-matrix above lacks"},
      {head + "image_width:100\n", "bad.yaml:5: 'image_width:100' is not a 'key: value' line"},
      {head + "image_width: [1, 2]\n", "bad.yaml:5: 'image_width' is neither"},
      {head + "  rows: 3\n", "bad.yaml:5: an indented line outside"},
      {head + "camera_matrix: !!opencv-matrix\n   rows: 99999999999\n", "bad.yaml:6: 'rows: 9"},
      {head + "camera_matrix: !!opencv-matrix\n   dt: q\n", "bad.yaml:6: 'dt: q' is not"},
  };
  for (const auto& [text, message] : cases) {
    try {
      load_text(text);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
          << e.what() << "\nexpected: " << message;
    }
  }
}

TEST(VisionInputs, MountLayoutErrors) {
  const std::string base = R"({"mounts": [
    {"name": "A1", "role": "proximal", "limb": 0, "id": 0, "tag_size": 0.01, "clamp_offset": [0.014, 0],
     "clamp_offset_uncertainty": [0, 0], "rod_angle": 0, "rod_angle_uncertainty": 0},
    {"name": "B1", "role": "distal", "limb": 0, "id": ID, "tag_size": 0.01, "clamp_offset": [0.014, 0],
     "clamp_offset_uncertainty": [0, 0], "rod_angle": 3.14, "rod_angle_uncertainty": 0}]})";
  auto with = [&](const std::string& id) {
    std::string t = base;
    t.replace(t.find("ID"), 2, id);
    return t;
  };
  EXPECT_NO_THROW(parse_mounts(with("1"), "m.json"));
  try {
    parse_mounts(with("0"), "m.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("duplicated tag id 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("B1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_mounts(with("100000"), "m.json"), InputError);  // not in tag36h11
  // The family of mounts that name none: the caller's (pcr measure --family), unless the file's
  // root names one; an unknown one is refused by name.
  for (const Mount& m : parse_mounts(with("1"), "m.json", "tag25h9").mounts) {
    EXPECT_EQ(m.family, "tag25h9");
  }
  std::string rooted = with("1");
  rooted.insert(1, R"("family": "tag16h5", )");
  for (const Mount& m : parse_mounts(rooted, "m.json", "tag25h9").mounts) {
    EXPECT_EQ(m.family, "tag16h5");
  }
  try {
    parse_mounts(with("1"), "m.json", "tag99h1");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.json: unknown default tag family 'tag99h1'"),
              std::string::npos)
        << e.what();
  }
  // A megabyte in a field is shown as its first characters, not echoed whole.
  try {
    parse_mounts(with("\"" + std::string(1 << 20, '7') + "\""), "m.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_LT(std::string(e.what()).size(), 200u) << std::string(e.what()).substr(0, 200);
    EXPECT_NE(std::string(e.what()).find("7777..."), std::string::npos) << e.what();
  }
  // A field that is not in the format is named with the closest known one.
  std::string misspelt = with("1");
  misspelt.replace(misspelt.rfind("\"clamp_offset\""), 14, "\"clamp_ofset\"");
  std::string angel = with("1");
  angel.replace(angel.rfind("\"rod_angle\""), 11, "\"rod_angel\"");
  const std::pair<std::string, std::string> unknown[] = {
      {misspelt,
       "m.json: mounts[1] (B1).clamp_ofset: unknown field; did you mean \"clamp_offset\"?"},
      {angel,
       "m.json: mounts[1] (B1).rod_angel: unknown field; did you mean \"rod_angle\"? "
       "(known here: name, role, limb, id, family"},
      {"{\"tagsize\": 0.01, " + with("1").substr(1),
       "m.json: tagsize: unknown field; did you mean \"tag_size\"?"},
  };
  for (const auto& [text, message] : unknown) {
    try {
      parse_mounts(text, "m.json");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST(VisionInputs, BoardSizeIsColsXRowsAndNothingElse) {
  EXPECT_EQ(parse_board_size("9x6", "--board"), std::make_pair(9, 6));
  EXPECT_EQ(parse_board_size("2x100", "--board"), std::make_pair(2, 100));
  for (const char* bad : {"9x6x", "9x6 ", " 9x6", "9x", "x6", "9X6", "+9x6", "9x-6", "1x6", "9x101",
                          "9x6.5", "0009x6", "9", ""}) {
    try {
      parse_board_size(bad, "--board");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--board: expected COLSxROWS"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("got '" + std::string(bad) + "'"), std::string::npos)
          << e.what();
    }
  }
}

TEST(VisionInputs, ACircleBeyondItsRangeIsRefusedByName) {
  std::string error;
  EXPECT_TRUE(RenderCircle().is_valid(&error)) << error;  // the paper's 100 mm wafer
  const RenderCircle huge{Eigen::Vector2d::Zero(), 1.0};  // a radius of a metre: 2 m across
  EXPECT_FALSE(huge.is_valid(&error));
  EXPECT_EQ(error, "diameter: expected a number from 0 to 1 (m), got 2");
  Scene scene;
  scene.circles.push_back(huge);
  try {
    render_scene(scene, RenderOptions());
    ADD_FAILURE() << "rendered a 2 m circle";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "render_scene: circle: diameter: expected a number from 0 to 1 (m), got 2");
  }
}

// cv::calibrateCamera on rendered chessboards recovers the camera that rendered them.
TEST(VisionInputs, ChessboardCalibrationRecoversTheCamera) {
  CameraModel cam;
  cam.width = 800;
  cam.height = 600;
  cam.K << 900, 0, 402, 0, 905, 297, 0, 0, 1;
  cam.distortion << -0.2, 0.1, 0, 0, 0;
  std::vector<std::string> paths;
  const double tilts[][2] = {{0.0, 0.0},  {0.3, 0.0},   {-0.3, 0.1},
                             {0.1, 0.35}, {0.0, -0.35}, {0.25, 0.25}};
  for (int k = 0; k < 6; ++k) {
    Scene s;
    s.camera = cam;
    s.plane = PlanePose::looking_down(0.12, tilts[k][0], tilts[k][1]);
    s.chessboard = RenderChessboard{9, 6, 0.008, Pose2<double>{-0.032, -0.02, 0.05 * k}};
    RenderOptions opt;
    opt.supersampling = 3;
    opt.blur_sigma_px = 0.7;
    paths.push_back(tmp("board" + std::to_string(k) + ".png"));
    write_png(render_scene(s, opt), paths.back());
  }
  const CalibrationResult r = calibrate_camera(paths, ChessboardSpec{9, 6, 0.008});
  EXPECT_EQ(r.used.size(), 6u);
  EXPECT_LT(r.rms_px, 0.2);
  EXPECT_NEAR(r.camera.K(0, 0), 900, 9);
  EXPECT_NEAR(r.camera.K(1, 1), 905, 9);
  EXPECT_NEAR(r.camera.K(0, 2), 402, 8);
  EXPECT_NEAR(r.camera.K(1, 2), 297, 8);
  EXPECT_NEAR(r.camera.distortion[0], -0.2, 0.05);
}

}  // namespace
}  // namespace pcr::vision
