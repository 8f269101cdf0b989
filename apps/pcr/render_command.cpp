// pcr render: a synthetic image of the robot's rod-mount tags (tests, end-to-end demo).
#ifdef PCR_HAS_VISION
#include <cstdio>
#include <fstream>
#include <sstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "pcr/vision/render.hpp"

namespace {

std::vector<double> parse_list(const std::string& text, std::size_t n, const std::string& option) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    out.push_back(std::strtod(item.c_str(), &end));
    if (item.empty() || *end != '\0') throw pcr::InputError(option + ": '" + text + "' is not a list of numbers");
  }
  if (n && out.size() != n) throw pcr::InputError(option + ": expected " + std::to_string(n) + " numbers, got '" + text + "'");
  return out;
}

}  // namespace

void register_render_command(CLI::App& app) {
  struct Args {
    std::string robot, mounts, camera, camera_out, output, truth, q, platform = "0,0,0";
    double height = 0.5, tilt_x = 0, tilt_y = 0;
    pcr::vision::RenderOptions render;
    int bits = 8;
    bool rods = true;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("render", "render the rod-mount tags seen by a camera (PNG + JSON truth)");
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option("--mounts", args->mounts, "mount layout JSON (e.g. data/mounts-femto-3pf.json)")->required();
  cmd->add_option("--camera", args->camera, "OpenCV camera YAML (default: 4000 x 4000 px, f = 8000 px)");
  cmd->add_option("--camera-out", args->camera_out, "write the camera used as OpenCV YAML");
  cmd->add_option("--output", args->output, "PNG to write")->required();
  cmd->add_option("--truth", args->truth, "JSON ground truth to write");
  cmd->add_option("--height", args->height, "camera height above the work plane (m)")->capture_default_str();
  cmd->add_option("--tilt-x", args->tilt_x, "camera tilt about its x axis (rad)");
  cmd->add_option("--tilt-y", args->tilt_y, "camera tilt about its y axis (rad)");
  cmd->add_option("--q", args->q, "actuator positions q1,...,qn (m, default 0)");
  cmd->add_option("--platform", args->platform, "platform pose x,y,theta in W (m, rad) for the distal tags");
  cmd->add_option("--supersampling", args->render.supersampling, "samples per pixel per axis")->capture_default_str();
  cmd->add_option("--blur", args->render.blur_sigma_px, "Gaussian blur sigma (px)");
  cmd->add_option("--noise", args->render.noise_sigma, "Gaussian noise sigma (fraction of full scale)");
  cmd->add_option("--gradient", args->render.gradient, "illumination change across the image (fraction)");
  cmd->add_option("--seed", args->render.seed, "noise seed");
  cmd->add_option("--bits", args->bits, "PNG bits per pixel (8 or 16)")->check(CLI::IsMember({8, 16}));
  cmd->add_flag("!--no-rods", args->rods, "do not draw the rods");
  cmd->callback([args]() {
    using namespace pcr;
    using namespace pcr::vision;
    const RobotDescription robot = load_robot_or_default(args->robot);
    const MountLayout layout = load_mounts(args->mounts);
    Scene scene;
    if (args->camera.empty()) {
      scene.camera.width = scene.camera.height = 4000;
      scene.camera.K << 8000, 0, 1999.5, 0, 8000, 1999.5, 0, 0, 1;
    } else {
      scene.camera = load_camera(args->camera);
    }
    scene.plane = PlanePose::looking_down(args->height, args->tilt_x, args->tilt_y);
    const std::vector<double> q = args->q.empty() ? std::vector<double>{} : parse_list(args->q, robot.params.num_limbs, "--q");
    const std::vector<double> pl = parse_list(args->platform, 3, "--platform");
    const Pose2<double> platform{pl[0], pl[1], pl[2]};
    scene.tags = mount_tags(layout, robot.params, platform, q, args->rods ? &scene.segments : nullptr);
    const GrayImage image = render_scene(scene, args->render);
    write_png(image, args->output, args->bits);
    if (!args->camera_out.empty()) save_camera(scene.camera, args->camera_out);
    if (!args->truth.empty()) {
      nlohmann::json j;
      j["format"] = "pcr-render-truth";
      j["image"] = args->output;
      j["plane_in_camera"] = {{"rotation", std::vector<double>(scene.plane.rotation.data(), scene.plane.rotation.data() + 9)},
                              {"translation", {scene.plane.translation.x(), scene.plane.translation.y(), scene.plane.translation.z()}},
                              {"note", "rotation column-major; plane frame = W"}};
      for (const RenderTag& t : scene.tags) {
        j["tags"].push_back({{"family", t.family}, {"id", t.id}, {"size", t.size_m}, {"pose", {t.pose.x, t.pose.y, t.pose.theta}},
                             {"corners_px", [&] {
                                nlohmann::json c;
                                for (const auto& p : tag_corner_pixels(scene, t)) c.push_back({p.x(), p.y()});
                                return c;
                              }()}});
      }
      for (int i = 0; i < robot.params.num_limbs; ++i) {
        const LimbParams<double>& l = robot.params.limb(i);
        const double qi = i < static_cast<int>(q.size()) ? q[i] : 0.0;
        const Eigen::Vector2d A = l.proximal_position(qi), B = platform.transform(l.B);
        j["limbs"].push_back({{"A_W", {A.x(), A.y()}}, {"alpha_W", l.alpha}, {"B_W", {B.x(), B.y()}},
                              {"beta_W", l.beta + platform.theta}, {"q", qi}});
      }
      const std::string tmp = args->truth + ".tmp";
      {
        std::ofstream out(tmp);
        out << j.dump(2) << "\n";
        if (!out) throw std::runtime_error(args->truth + ": cannot write");
      }
      if (std::rename(tmp.c_str(), args->truth.c_str()) != 0) throw std::runtime_error(args->truth + ": cannot rename");
    }
    std::cout << "wrote " << args->output << " (" << image.width << " x " << image.height << " px, "
              << scene.tags.size() << " tags)\n";
  });
}
#endif
