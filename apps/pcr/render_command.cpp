// pcr render: a synthetic image of the robot's rod-mount tags, or of a spatial robot's platform
// tag board (tests, end-to-end demo).
#ifdef PCR_HAS_VISION
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "commands.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/vision/render.hpp"
#include "pcr/vision/tag_board.hpp"

namespace {

nlohmann::json frame_json(const pcr::SpatialPose<double>& pose) {
  const auto& p = pose.position;
  const auto& q = pose.orientation;
  return {{"position", {p.x(), p.y(), p.z()}}, {"orientation", {q[0], q[1], q[2], q[3]}}};
}

}  // namespace

void register_render_command(CLI::App& app) {
  struct Args {
    std::string robot, mounts, board, camera, camera_out, output, truth, q, platform = "0,0,0";
    std::string chessboard, board_pose = "0,0,0";
    double height = 0.5, tilt_x = 0, tilt_y = 0, wafer = 0.100, square = 0.005;
    pcr::vision::RenderOptions render;
    int bits = 8;
    bool rods = true;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd =
      app.add_subcommand("render", "render the rod-mount tags seen by a camera (PNG + JSON truth)");
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option(
      "--mounts", args->mounts,
      "mount layout JSON (e.g. data/mounts-femto-3pf.json); required unless --chessboard");
  cmd->add_option("--board", args->board,
                  "tag board JSON of a spatial robot's platform (with a spatial --robot)");
  cmd->add_option("--camera", args->camera,
                  "OpenCV camera YAML (default: 4000 x 4000 px, f = 8000 px)");
  cmd->add_option("--camera-out", args->camera_out, "write the camera used as OpenCV YAML");
  cmd->add_option("--output", args->output, "PNG to write")->required();
  cmd->add_option("--truth", args->truth, "JSON ground truth to write");
  using pcr::cli::within;
  cmd->add_option("--height", args->height, "camera height above the work plane (m)")
      ->check(within(pcr::vision::PlanePose::kHeight))
      ->capture_default_str();
  cmd->add_option("--tilt-x", args->tilt_x, "camera tilt about its x axis (rad)")
      ->check(within(pcr::vision::PlanePose::kTiltX));
  cmd->add_option("--tilt-y", args->tilt_y, "camera tilt about its y axis (rad)")
      ->check(within(pcr::vision::PlanePose::kTiltY));
  cmd->add_option("--q", args->q, "actuator positions q1,...,qn (m, default 0)");
  cmd->add_option("--platform", args->platform,
                  "platform pose x,y,theta in W (m, rad) for the distal tags");
  cmd->add_option("--supersampling", args->render.supersampling, "samples per pixel per axis")
      ->check(within(pcr::vision::RenderOptions::kSupersampling))
      ->capture_default_str();
  cmd->add_option("--blur", args->render.blur_sigma_px, "Gaussian blur sigma (px)")
      ->check(within(pcr::vision::RenderOptions::kBlur));
  cmd->add_option("--noise", args->render.noise_sigma,
                  "Gaussian noise sigma (fraction of full scale)")
      ->check(within(pcr::vision::RenderOptions::kNoise));
  cmd->add_option("--gradient", args->render.gradient,
                  "illumination change across the image (fraction)")
      ->check(within(pcr::vision::RenderOptions::kGradient));
  cmd->add_option("--seed", args->render.seed, "noise seed");
  cmd->add_option("--bits", args->bits, "PNG bits per pixel (8 or 16)")
      ->check(CLI::IsMember({8, 16}));
  cmd->add_flag("!--no-rods", args->rods, "do not draw the rods nor the platform outline");
  cmd->add_option("--wafer-diameter", args->wafer,
                  "platform outline: wafer circle centred on P (m, 0 = none)")
      ->check(within(pcr::vision::RenderCircle::kDiameter))
      ->capture_default_str();
  cmd->add_option("--chessboard", args->chessboard,
                  "also draw a chessboard of COLSxROWS inner corners (for pcr camera)");
  cmd->add_option("--square", args->square, "chessboard square edge (m)")
      ->check(within(pcr::vision::ChessboardSpec::kSquare))
      ->capture_default_str();
  cmd->add_option("--board-pose", args->board_pose,
                  "chessboard centre pose x,y,theta in the plane (m, rad)");
  cmd->callback([args]() {
    using namespace pcr;
    using namespace pcr::vision;
    check_distinct_outputs(
        {{"--output", args->output}, {"--camera-out", args->camera_out}, {"--truth", args->truth}});
    Scene scene;
    if (args->camera.empty()) {
      scene.camera.width = scene.camera.height = 4000;
      scene.camera.K << 8000, 0, 1999.5, 0, 8000, 1999.5, 0, 0, 1;
    } else {
      scene.camera = load_camera(args->camera);
    }
    scene.plane = PlanePose::looking_down(args->height, args->tilt_x, args->tilt_y);
    nlohmann::json truth;  // what the scene is, for --truth
    if (cli::is_spatial_robot(args->robot)) {
      // The platform by forward kinematics at --q, its board seen from above; the truth is the
      // measurement ^S T_M (S the camera frame) and ^W T_S (the robot file's extrinsics.tracker
      // for this camera).
      if (args->board.empty() || !args->mounts.empty() || !args->chessboard.empty() ||
          args->platform != "0,0,0") {
        throw InputError("pcr render: " + args->robot +
                         " is a spatial robot: give its platform's --board (its pose comes from "
                         "--q; no --mounts, --chessboard or --platform)");
      }
      const SpatialRobotDescription robot = load_spatial_robot(args->robot);
      const int n = robot.params.num_rods;
      SpatialJointVector q = SpatialJointVector::Zero(n);
      if (!args->q.empty()) {
        const std::vector<double> v = cli::parse_list(args->q, cli::joint_names(n), "--q");
        for (int i = 0; i < n; ++i) q(i) = v[static_cast<std::size_t>(i)];
      }
      const SpatialForwardSolution fk = spatial_forward_kinematics(robot.params, q);
      if (!fk.summary.converged()) {
        throw InputError("--q: the forward kinematics of " + args->robot + " at " + args->q +
                         " did not converge (" + to_string(fk.summary.status) + ")");
      }
      const TagBoard board = load_tag_board(args->board);
      scene.tags_3d = board_tags(board, fk.pose * board.marker_T_platform.inverse());
      const SpatialPose<double> camera_T_world{scene.plane.translation,
                                               quaternion_of(scene.plane.rotation)};
      truth["q"] = std::vector<double>(q.data(), q.data() + n);
      truth["world_T_platform"] = frame_json(fk.pose);
      truth["camera_T_marker"] =
          frame_json(camera_T_world * fk.pose * board.marker_T_platform.inverse());
      truth["world_T_camera"] = frame_json(camera_T_world.inverse());
    } else {
      if (args->mounts.empty() && args->chessboard.empty())
        throw InputError("pcr render: give --mounts or --chessboard");
      const RobotDescription robot = load_robot_or_default(args->robot);
      const int n = robot.params.num_limbs;
      const std::vector<double> q = args->q.empty()
                                        ? std::vector<double>{}
                                        : cli::parse_list(args->q, cli::joint_names(n), "--q");
      for (std::size_t i = 0; i < q.size(); ++i) {
        const LimbParams<double>& limb = robot.params.limb(static_cast<int>(i));
        if (!limb.within_stroke(q[i])) {
          throw InputError("--q: q" + std::to_string(i + 1) + " = " + format_double(q[i]) +
                           " m is beyond the stroke of limbs[" + std::to_string(i) +
                           "], q_range [" + format_double(limb.q_min) + ", " +
                           format_double(limb.q_max) + "] m");
        }
      }
      const std::vector<double> pl =
          cli::parse_list(args->platform, {"x", "y", "theta"}, "--platform");
      const Pose2<double> platform{pl[0], pl[1], pl[2]};
      if (!args->mounts.empty()) {
        scene.tags = mount_tags(load_mounts(args->mounts), robot.params, platform, q,
                                args->rods ? &scene.segments : nullptr);
        // The platform is a 100 mm silicon wafer (paper, Sec. 4.1); only an outline, the tags stay
        // on top.
        if (args->rods && args->wafer > 0)
          scene.circles.push_back(RenderCircle{platform.translation(), 0.5 * args->wafer});
      }
      if (!args->chessboard.empty()) {
        RenderChessboard board;
        std::tie(board.cols, board.rows) = parse_board_size(args->chessboard, "--chessboard");
        if (!(args->square > 0))
          throw InputError("--square: must be > 0, got " + std::to_string(args->square));
        board.square_m = args->square;
        const std::vector<double> c =
            cli::parse_list(args->board_pose, {"x", "y", "theta"}, "--board-pose");
        scene.chessboard =
            RenderChessboard::centred(board.cols, board.rows, board.square_m, {c[0], c[1], c[2]});
      }
      if (!args->mounts.empty() && args->rods && args->wafer > 0)
        truth["wafer_outline"] = {{"centre_W", {platform.x, platform.y}},
                                  {"diameter", args->wafer}};
      if (scene.chessboard) {
        const RenderChessboard& b = *scene.chessboard;
        truth["chessboard"] = {{"cols", b.cols},
                               {"rows", b.rows},
                               {"square", b.square_m},
                               {"corner0_pose", {b.pose.x, b.pose.y, b.pose.theta}}};
      }
      truth["plane_in_camera"] = {
          {"rotation",
           std::vector<double>(scene.plane.rotation.data(), scene.plane.rotation.data() + 9)},
          {"translation",
           {scene.plane.translation.x(), scene.plane.translation.y(), scene.plane.translation.z()}},
          {"note", "rotation column-major; plane frame = W"}};
      for (const RenderTag& t : scene.tags) {
        truth["tags"].push_back({{"family", t.family},
                                 {"id", t.id},
                                 {"size", t.size_m},
                                 {"pose", {t.pose.x, t.pose.y, t.pose.theta}},
                                 {"corners_px", [&] {
                                    nlohmann::json c;
                                    for (const auto& p : tag_corner_pixels(scene, t))
                                      c.push_back({p.x(), p.y()});
                                    return c;
                                  }()}});
      }
      for (int i = 0; i < (args->mounts.empty() ? 0 : robot.params.num_limbs); ++i) {
        const LimbParams<double>& l = robot.params.limb(i);
        const double qi = i < static_cast<int>(q.size()) ? q[i] : 0.0;
        const Eigen::Vector2d A = l.proximal_position(qi), B = platform.transform(l.B);
        truth["limbs"].push_back({{"A_W", {A.x(), A.y()}},
                                  {"alpha_W", l.alpha},
                                  {"B_W", {B.x(), B.y()}},
                                  {"beta_W", l.beta + platform.theta},
                                  {"q", qi}});
      }
    }
    const GrayImage image = render_scene(scene, args->render);
    OutputTransaction outputs;  // the image, the camera and the truth: all or none
    write_png(image, args->output, args->bits);
    if (!args->camera_out.empty()) save_camera(scene.camera, args->camera_out);
    if (!args->truth.empty()) {
      truth["format"] = "pcr-render-truth";
      truth["image"] = args->output;
      write_file_atomically(args->truth, truth.dump(2) + "\n");
    }
    outputs.commit();
    std::cout << "wrote " << args->output << " (" << image.width << " x " << image.height << " px, "
              << scene.tags.size() + scene.tags_3d.size() << " tags)\n";
  });
}
#endif
