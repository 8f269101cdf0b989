// Measurement (pcr::vision): camera models, mount layouts, images as float32 (H, W) NumPy arrays
// in [0, 1], synthetic renders of a robot's mount tags, and the measurement of A, alpha, B, beta
// from one image, actuator directions from sweeps, and chessboard camera calibration (-> a
// measured pcr.Robot).
#include <cmath>
#include <optional>

#include "bindings.hpp"
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/mounts.hpp"
#include "pcr/vision/render.hpp"

namespace pcr::python {
namespace {

using namespace pcr::vision;
using FloatImage = py::array_t<float, py::array::c_style | py::array::forcecast>;

py::array_t<float> to_array(const GrayImage& image) {
  py::array_t<float> out(
      {static_cast<py::ssize_t>(image.height), static_cast<py::ssize_t>(image.width)});
  std::copy(image.pixels.begin(), image.pixels.end(), out.mutable_data());
  return out;
}

GrayImage from_array(const py::object& object, const std::string& what) {
  FloatImage a;
  try {
    a = FloatImage::ensure(object);
  } catch (const py::error_already_set&) {
  }
  if (!a || a.ndim() != 2 || a.shape(0) < 1 || a.shape(1) < 1) {
    throw std::invalid_argument(what + ": expected a 2-D (H, W) array of grey levels in [0, 1]");
  }
  GrayImage image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
  std::copy(a.data(), a.data() + a.size(), image.pixels.begin());
  for (float v : image.pixels) {
    if (!std::isfinite(v)) throw std::invalid_argument(what + ": non-finite pixel value");
  }
  return image;
}

const char* role_name(MountRole r) { return r == MountRole::kProximal ? "proximal" : "distal"; }

py::dict limb_dict(const LimbMeasurement& l) {
  py::dict d;
  d["A"] = l.A;
  d["A_halfwidth"] = l.A_halfwidth;
  d["alpha"] = l.alpha;
  d["alpha_halfwidth"] = l.alpha_halfwidth;
  d["B"] = l.B;
  d["B_halfwidth"] = l.B_halfwidth;
  d["beta"] = l.beta;
  d["beta_halfwidth"] = l.beta_halfwidth;
  d["gamma"] = l.gamma ? py::cast(*l.gamma) : py::none();
  d["gamma_halfwidth"] = l.gamma_halfwidth ? py::cast(*l.gamma_halfwidth) : py::none();
  d["A_plane"] = l.A_plane;
  d["alpha_plane"] = l.alpha_plane;
  d["B_plane"] = l.B_plane;
  d["beta_plane"] = l.beta_plane;
  return d;
}

CameraModel default_render_camera() {
  CameraModel c;  // as `pcr render` without --camera: 4000 x 4000 px, f = 8000 px
  c.width = c.height = 4000;
  c.K << 8000, 0, 1999.5, 0, 8000, 1999.5, 0, 0, 1;
  return c;
}

Scene camera_scene(const std::optional<CameraModel>& camera, double height, double tilt_x,
                   double tilt_y) {
  Scene scene;
  scene.camera = camera ? *camera : default_render_camera();
  scene.plane = PlanePose::looking_down(in_range(height, PlanePose::kHeight),
                                        in_range(tilt_x, PlanePose::kTiltX),
                                        in_range(tilt_y, PlanePose::kTiltY));
  return scene;
}

py::array_t<float> render(const Scene& scene, int supersampling, double blur, double noise,
                          double gradient, unsigned seed) {
  RenderOptions o;
  o.supersampling = supersampling;
  o.blur_sigma_px = blur;
  o.noise_sigma = noise;
  o.gradient = gradient;
  o.seed = seed;
  checked_options(o);
  GrayImage image;
  {
    py::gil_scoped_release release;
    image = render_scene(scene, o);
  }
  return to_array(image);
}

/// pcr.Camera and load_camera: the pinhole camera and its OpenCV YAML.
void bind_camera(py::module_& m) {
  py::class_<CameraModel>(m, "Camera",
                          "Pinhole camera with OpenCV's distortion model (k1 k2 p1 p2 [k3 ...]).")
      .def(py::init([](int width, int height, const Eigen::Matrix3d& K,
                       const std::optional<Eigen::VectorXd>& distortion) {
             const int nd = distortion ? static_cast<int>(distortion->size()) : 5;
             if (width < 1 || height < 1) {
               throw InputError("Camera: width and height must be >= 1 px, got " +
                                std::to_string(width) + " x " + std::to_string(height));
             }
             if (nd != 0 && nd != 4 && nd != 5 && nd != 8) {
               throw InputError("Camera.distortion: expected 0, 4, 5 or 8 coefficients, got " +
                                std::to_string(nd));
             }
             CameraModel c;
             c.width = width;
             c.height = height;
             c.K = K;
             c.distortion = distortion ? *distortion : Eigen::VectorXd::Zero(5);
             return c;
           }),
           py::arg("width"), py::arg("height"), py::arg("K"), py::arg("distortion") = py::none(),
           "width, height (px), K the 3x3 intrinsic matrix (px), distortion (OpenCV order).")
      .def_readwrite("width", &CameraModel::width, "px")
      .def_readwrite("height", &CameraModel::height, "px")
      .def_readwrite("K", &CameraModel::K, "3x3 intrinsic matrix (px)")
      .def_readwrite("distortion", &CameraModel::distortion, "k1 k2 p1 p2 [k3 [k4 k5 k6]]")
      .def(
          "project",
          [](const CameraModel& c, const py::object& p) {
            return c.project(to_vector<3>(p, "point_camera", "x, y, z in m"));
          },
          py::arg("point_camera"), "A camera-frame point (m) -> pixel (u, v).")
      .def(
          "save",
          [](const CameraModel& c, const std::filesystem::path& path) {
            save_camera(c, output_path(path));
          },
          py::arg("path"),
          "Writes OpenCV YAML (camera_matrix, distortion_coefficients, ...) to `path` (str or "
          "os.PathLike).")
      .def("__repr__", [](const CameraModel& c) {
        return "Camera(" + std::to_string(c.width) + " x " + std::to_string(c.height) +
               " px, f = " + std::to_string(c.focal_px()) + " px)";
      });
  m.def(
      "load_camera",
      [](const std::filesystem::path& path) { return load_camera(input_path(path)); },
      py::arg("path"),
      "Reads an OpenCV camera YAML. FileNotFoundError when it does not exist, ValueError naming "
      "the file and the field.");
}

/// pcr.MountLayout, load_mounts, default_mounts: where the tags sit on the rods.
void bind_mount_layout(py::module_& m) {
  py::class_<MountLayout>(m, "MountLayout",
                          "Where each rod mount's tag is and how its clamp sits on it (the "
                          "pcr-mounts JSON format).")
      .def_property_readonly("num_limbs", &MountLayout::num_limbs,
                             "limbs the layout has mounts for")
      .def_property_readonly(
          "mounts",
          [](const MountLayout& l) {
            py::list out;
            for (const Mount& mt : l.mounts) {
              py::dict d;
              d["name"] = mt.name;
              d["role"] = role_name(mt.role);
              d["limb"] = mt.limb;
              d["family"] = mt.family;
              d["id"] = mt.id;
              d["tag_size"] = mt.tag_size;
              d["clamp_offset"] = mt.clamp_offset;
              d["clamp_offset_uncertainty"] = mt.clamp_offset_uncertainty;
              d["rod_angle"] = mt.rod_angle;
              d["rod_angle_uncertainty"] = mt.rod_angle_uncertainty;
              out.append(d);
            }
            return out;
          },
          "list of dicts (a copy): name, role, limb, family, id, tag_size (m), clamp_offset (m), "
          "clamp_offset_uncertainty, rod_angle (rad), rod_angle_uncertainty")
      .def(
          "without_uncertainty",
          [](const MountLayout& l) {
            MountLayout out = l;
            for (Mount& mt : out.mounts) {
              mt.clamp_offset_uncertainty.setZero();
              mt.rod_angle_uncertainty = 0;
            }
            return out;
          },
          "A copy whose offsets are exact (zero half-widths).")
      .def_static("from_json", &parse_mounts, py::arg("text"), py::arg("source") = "<string>",
                  py::arg("family") = kDefaultTagFamily)
      .def("__len__", [](const MountLayout& l) { return l.mounts.size(); });
  m.def(
      "load_mounts",
      [](const std::filesystem::path& path, const std::string& family) {
        return load_mounts(input_path(path), family);
      },
      py::arg("path"), py::arg("family") = kDefaultTagFamily,
      "Reads a pcr-mounts JSON file; `family`: the tag family of the mounts when the file names "
      "none. FileNotFoundError when it does not exist, ValueError naming the file, field and "
      "value.");
  m.def("default_mounts", &default_mounts,
        "The default robot's layout (data/mounts-femto-3pf.json).");
}

/// read_image, write_png: images as float32 (H, W) arrays in [0, 1].
void bind_image_io(py::module_& m) {
  m.def(
      "read_image",
      [](const std::filesystem::path& path) { return to_array(read_image(input_path(path))); },
      py::arg("path"),
      "Reads an 8/16-bit grey or colour image -> float32 (H, W) in [0, 1]. FileNotFoundError "
      "when it does not exist, ValueError naming the file when it cannot be read or is blank.");
  m.def(
      "write_png",
      [](const std::filesystem::path& path, const py::object& image, int bits) {
        if (bits != 8 && bits != 16) {
          throw std::invalid_argument("bits: expected 8 or 16, got " + std::to_string(bits));
        }
        write_png(from_array(image, "image"), output_path(path), bits);
      },
      py::arg("path"), py::arg("image"), py::arg("bits") = 8,
      "Writes a (H, W) array in [0, 1] as an 8- or 16-bit grey PNG (temp file, then renamed).");
}

/// mount_tags, render_robot, render_chessboard: synthetic images, as `pcr render`.
void bind_render(py::module_& m) {
  m.def(
      "mount_tags",
      [](const RobotDescription& robot, const MountLayout& layout, const py::object& platform,
         const std::optional<std::vector<double>>& q) {
        const std::vector<RenderTag> tags = mount_tags(
            layout, robot.params, to_pose(platform, "platform"), q.value_or(std::vector<double>{}));
        py::list out;
        for (const RenderTag& t : tags) {
          py::dict d;
          d["family"] = t.family;
          d["id"] = t.id;
          d["size"] = t.size_m;
          d["pose"] = Eigen::Vector3d(t.pose.x, t.pose.y, t.pose.theta);
          out.append(d);
        }
        return out;
      },
      py::arg("robot"), py::arg("mounts"), py::arg("platform") = py::make_tuple(0.0, 0.0, 0.0),
      py::arg("q") = py::none(),
      "The layout's tags placed on the robot (plane frame = W): a list of dicts family, id, "
      "size (m), pose (x, y, theta of the tag in W).");

  m.def(
      "render_robot",
      [](const RobotDescription& robot, const MountLayout& layout,
         const std::optional<CameraModel>& camera, double height, double tilt_x, double tilt_y,
         const std::optional<std::vector<double>>& q, const py::object& platform, bool rods,
         int supersampling, double blur, double noise, double gradient, unsigned seed) {
        if (q && static_cast<int>(q->size()) != robot.params.num_limbs) {
          throw std::invalid_argument("q: expected " + std::to_string(robot.params.num_limbs) +
                                      " values (m), got " + std::to_string(q->size()));
        }
        Scene scene = camera_scene(camera, height, tilt_x, tilt_y);
        scene.tags =
            mount_tags(layout, robot.params, to_pose(platform, "platform"),
                       q.value_or(std::vector<double>{}), rods ? &scene.segments : nullptr);
        return render(scene, supersampling, blur, noise, gradient, seed);
      },
      py::arg("robot"), py::arg("mounts"), py::kw_only(), py::arg("camera") = py::none(),
      py::arg("height") = 0.5, py::arg("tilt_x") = 0.0, py::arg("tilt_y") = 0.0,
      py::arg("q") = py::none(), py::arg("platform") = py::make_tuple(0.0, 0.0, 0.0),
      py::arg("rods") = true, py::arg("supersampling") = 4, py::arg("blur") = 0.0,
      py::arg("noise") = 0.0, py::arg("gradient") = 0.0, py::arg("seed") = 1u,
      "A synthetic image (float32 (H, W) in [0, 1]) of the robot's mount tags, as `pcr "
      "render`: camera (default 4000 x 4000 px, f = 8000 px) `height` m above the work plane, "
      "tilted by tilt_x, tilt_y (rad); proximal tags at A_i + q_i, distal tags on the platform "
      "at `platform` (^W T_P). blur (px), noise (fraction of full scale), gradient "
      "(illumination change). Releases the GIL.");

  m.def(
      "render_chessboard",
      [](const std::optional<CameraModel>& camera, int cols, int rows, double square,
         const py::object& board_pose, double height, double tilt_x, double tilt_y,
         int supersampling, double blur, double noise, double gradient, unsigned seed) {
        if (cols < 2 || rows < 2) {
          throw std::invalid_argument("chessboard: expected at least 2 x 2 inner corners, got " +
                                      std::to_string(cols) + " x " + std::to_string(rows));
        }
        in_range(square, ChessboardSpec::kSquare);
        Scene scene = camera_scene(camera, height, tilt_x, tilt_y);
        scene.chessboard =
            RenderChessboard::centred(cols, rows, square, to_pose(board_pose, "board_pose"));
        return render(scene, supersampling, blur, noise, gradient, seed);
      },
      py::kw_only(), py::arg("camera") = py::none(), py::arg("cols") = 9, py::arg("rows") = 6,
      py::arg("square") = 0.005, py::arg("board_pose") = py::make_tuple(0.0, 0.0, 0.0),
      py::arg("height") = 0.5, py::arg("tilt_x") = 0.0, py::arg("tilt_y") = 0.0,
      py::arg("supersampling") = 4, py::arg("blur") = 0.0, py::arg("noise") = 0.0,
      py::arg("gradient") = 0.0, py::arg("seed") = 1u,
      "A synthetic image of a chessboard (cols x rows inner corners, `square` m) lying in the "
      "work plane with its centre at board_pose (x, y, theta), as `pcr render --chessboard`; "
      "the camera and the options as render_robot. For calibrate_camera.");
}

/// pcr.RobotMeasurement and measure_robot: A, alpha, B, beta from one image.
void bind_robot_measurement(py::module_& m) {
  py::class_<RobotMeasurement>(m, "RobotMeasurement",
                               "A, alpha, B, beta of each limb measured from one image, in the "
                               "design's W and P (rigid registration), with half-widths.")
      .def_property_readonly(
          "limbs",
          [](const RobotMeasurement& r) {
            py::list out;
            for (const LimbMeasurement& l : r.limbs) out.append(limb_dict(l));
            return out;
          },
          "list of dicts: A, A_halfwidth (m), alpha, alpha_halfwidth (rad), B, B_halfwidth, beta, "
          "beta_halfwidth, gamma/gamma_halfwidth (None without a sweep), and the *_plane values")
      .def_property_readonly(
          "corner_rms_px", [](const RobotMeasurement& r) { return r.fit.corner_rms_px; },
          "rms of the tag corners' reprojection residuals (px)")
      .def_property_readonly(
          "corner_sigma_px", [](const RobotMeasurement& r) { return r.fit.corner_sigma_px; },
          "the corners' standard deviation the covariances assume (px)")
      .def_readonly("world_in_plane", &RobotMeasurement::world_in_plane,
                    "W in the plane frame (the registration), Pose (m, rad)")
      .def_readonly("platform_in_plane", &RobotMeasurement::platform_in_plane,
                    "P in the plane frame, Pose (m, rad)")
      .def_readonly("registration_rms_A", &RobotMeasurement::registration_rms_A, "m")
      .def_readonly("registration_rms_B", &RobotMeasurement::registration_rms_B, "m")
      .def_property_readonly(
          "markers",
          [](const RobotMeasurement& r) {
            py::list out;
            for (const MarkerPose& mk : r.fit.markers) {
              py::dict d;
              d["family"] = mk.family;
              d["id"] = mk.id;
              d["pose"] = Eigen::Vector3d(mk.pose.x, mk.pose.y, mk.pose.theta);
              d["covariance"] = mk.covariance;
              out.append(d);
            }
            return out;
          },
          "fitted tag poses in the plane frame (dicts family, id, pose, covariance)");

  m.def(
      "measure_robot",
      [](const py::object& image, const MountLayout& layout, const CameraModel& camera,
         const RobotDescription& design, const std::string& source, double coverage_factor,
         double min_margin, int max_hamming) {
        const GrayImage gray = from_array(image, source);
        check_image_size(camera, gray.width, gray.height, "camera", source);
        MeasureOptions o;
        o.coverage_factor = checked_number(coverage_factor, "coverage_factor", "", 0.0);
        o.detector.min_decision_margin = in_range(min_margin, DetectorOptions::kMinDecisionMargin);
        o.detector.max_hamming =
            static_cast<int>(in_range(max_hamming, DetectorOptions::kMaxHamming));
        py::gil_scoped_release release;
        return measure_robot(gray, source, layout, camera, design.params, o);
      },
      py::arg("image"), py::arg("mounts"), py::arg("camera"), py::arg("design"), py::kw_only(),
      py::arg("source") = "<image>", py::arg("coverage_factor") = 3.0, py::arg("min_margin") = 30.0,
      py::arg("max_hamming") = 0,
      "Detects the mount tags in `image` ((H, W) array in [0, 1]) in the families of the "
      "layout's mounts, fits their poses and the plane, and registers the clamps onto `design` -> "
      "RobotMeasurement. `source` names the "
      "image in error messages (ValueError for a missing marker, a size mismatch). Releases "
      "the GIL.");
}

/// pcr.SweepResult and measure_sweep: an actuator's direction from a sweep of images.
void bind_sweep(py::module_& m) {
  py::class_<SweepResult>(m, "SweepResult",
                          "One actuator's direction from its proximal tag over a sweep of images.")
      .def_readonly("gamma", &SweepResult::gamma, "actuator misalignment: line angle - alpha (rad)")
      .def_readonly("gamma_halfwidth", &SweepResult::gamma_halfwidth, "rad")
      .def_readonly("direction_plane", &SweepResult::direction_plane,
                    "angle of the fitted line in the plane frame (rad)")
      .def_readonly("direction_sigma", &SweepResult::direction_sigma, "rad")
      .def_property_readonly(
          "centres",
          [](const SweepResult& r) {
            Eigen::MatrixX2d out(r.centres.size(), 2);
            for (std::size_t k = 0; k < r.centres.size(); ++k)
              out.row(k) = r.centres[k].transpose();
            return out;
          },
          "(N, 2) tag centres in the plane frame (m), one per image")
      .def_readonly("line_rms", &SweepResult::line_rms,
                    "rms distance of the centres to the line (m)");

  m.def(
      "measure_sweep",
      [](const std::vector<py::object>& images, int limb, const MountLayout& layout,
         const CameraModel& camera, RobotMeasurement& home,
         const std::optional<std::vector<std::string>>& sources, double coverage_factor) {
        if (sources && sources->size() != images.size()) {
          throw std::invalid_argument("sources: expected " + std::to_string(images.size()) +
                                      " names (one per image), got " +
                                      std::to_string(sources->size()));
        }
        std::vector<GrayImage> grays;
        std::vector<std::string> names;
        for (std::size_t k = 0; k < images.size(); ++k) {
          names.push_back(sources ? (*sources)[k] : "<sweep image " + std::to_string(k) + ">");
          grays.push_back(from_array(images[k], names.back()));
          check_image_size(camera, grays.back().width, grays.back().height, "camera", names.back());
        }
        MeasureOptions o;
        o.coverage_factor = checked_number(coverage_factor, "coverage_factor", "", 0.0);
        py::gil_scoped_release release;
        return measure_sweep(grays, names, limb, layout, camera, home, o);
      },
      py::arg("images"), py::arg("limb"), py::arg("mounts"), py::arg("camera"), py::arg("home"),
      py::kw_only(), py::arg("sources") = py::none(), py::arg("coverage_factor") = 3.0,
      "Actuator direction of `limb` from `images` (in stroke order) of its proximal tag as the "
      "actuator moves, the work plane held where `home` (a RobotMeasurement) found it: a total "
      "least-squares line through the tag centres -> SweepResult. Also stores gamma and its "
      "half-width in home.limbs[limb], which measured_description() then uses. Releases the "
      "GIL.");
}

/// pcr.CameraCalibration and calibrate_camera: intrinsics from chessboard images.
void bind_camera_calibration(py::module_& m) {
  py::class_<CalibrationResult>(m, "CameraCalibration", "cv::calibrateCamera over chessboards.")
      .def_readonly("camera", &CalibrationResult::camera, "the calibrated Camera")
      .def_readonly("rms_px", &CalibrationResult::rms_px, "reprojection error (px)")
      .def_readonly("used", &CalibrationResult::used, "images whose board was found")
      .def_readonly("rejected", &CalibrationResult::rejected, "images without a board");
  m.def(
      "calibrate_camera",
      [](const std::vector<std::filesystem::path>& images, int cols, int rows, double square) {
        std::vector<std::string> paths;
        for (const std::filesystem::path& image : images) paths.push_back(input_path(image));
        ChessboardSpec board;
        board.cols = cols;
        board.rows = rows;
        board.square_m = in_range(square, ChessboardSpec::kSquare);
        py::gil_scoped_release release;
        return calibrate_camera(paths, board);
      },
      py::arg("images"), py::kw_only(), py::arg("cols") = 9, py::arg("rows") = 6,
      py::arg("square") = 0.005,
      "Camera intrinsics and distortion from image files (str or os.PathLike) of a chessboard "
      "with cols x rows inner corners and `square` (m) squares, as `pcr camera` -> "
      "CameraCalibration (at least 3 images with a board; FileNotFoundError for a missing "
      "file, ValueError naming the files otherwise). Releases the GIL.");
}

/// measured_description: a design with its measured values -> Robot.
void bind_measured_description(py::module_& m) {
  m.def("measured_description", &measured_description, py::arg("design"), py::arg("measurement"),
        "`design` with the measured A, alpha, B, beta (gamma when swept) and an uncertainty "
        "section with the measured half-widths -> Robot.");
}

}  // namespace

void wrap_vision(py::module_& m) {
  bind_camera(m);
  bind_mount_layout(m);
  bind_image_io(m);
  bind_render(m);
  bind_robot_measurement(m);
  bind_sweep(m);
  bind_camera_calibration(m);
  bind_measured_description(m);
}

}  // namespace pcr::python
