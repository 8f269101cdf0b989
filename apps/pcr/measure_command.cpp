// pcr measure: rod-mount tags in a camera image -> a measured pcr-robot description; on a
// spatial design, the tags next to its holes and attachment points in an image of the base and
// one of the platform -> the measured spatial description.
#ifdef PCR_HAS_VISION
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/vision/attachment_points.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/tags.hpp"

namespace {

struct MeasureArguments {
  std::string design, mounts, camera, image, output, annotated;
  std::string points, base_image, platform_image;
  std::string family = pcr::vision::kDefaultTagFamily;
  std::vector<std::string> sweeps;
  pcr::vision::MeasureOptions options;
};

/// A spatial design: A_i from --base-image, B_i from --platform-image, registered onto the
/// design's (pcr::vision::measure_attachment_points).
void run_spatial_measure(const MeasureArguments& args) {
  using namespace pcr;
  using namespace pcr::vision;
  if (!args.mounts.empty() || !args.image.empty() || !args.sweeps.empty() ||
      !args.annotated.empty()) {
    throw InputError("pcr measure: " + args.design +
                     " is a spatial robot: give --points, --base-image and --platform-image (no "
                     "--mounts, --image, --sweep or --annotated, which are a planar robot's)");
  }
  for (const auto& [option, value] : {std::pair<const char*, std::string>{"--points", args.points},
                                      {"--base-image", args.base_image},
                                      {"--platform-image", args.platform_image}}) {
    if (value.empty()) {  // a usage error, as CLI11's for the options every robot needs
      throw CLI::RequiredError(
          std::string(option) + " is required: " + args.design + " is a spatial robot",
          CLI::ExitCodes::RequiredError);
    }
  }
  const SpatialRobotDescription design = load_spatial_robot(args.design);
  const AttachmentLayout layout = load_attachment_layout(args.points, args.family);
  const CameraModel camera = load_camera(args.camera);
  const GrayImage base = read_image(args.base_image);
  check_image_size(camera, base.width, base.height, args.camera, args.base_image);
  const GrayImage platform = read_image(args.platform_image);
  check_image_size(camera, platform.width, platform.height, args.camera, args.platform_image);
  const AttachmentMeasurement m = measure_attachment_points(
      base, args.base_image, platform, args.platform_image, layout, camera, design, args.options);
  save_spatial_robot(measured_spatial_description(design, m), args.output);
  std::printf("registration rms: A %.1f um (W), B %.1f um (P)\n", m.A.rms * 1e6, m.B.rms * 1e6);
  std::printf("%-4s %-6s %12s %12s %10s\n", "rod", "param", "design mm", "measured mm", "+- mm");
  for (int i = 0; i < design.params.num_rods; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    for (int end = 0; end < 2; ++end) {
      const PointRegistration& r = end ? m.B : m.A;
      const Eigen::Vector3d& d = end ? design.params.limb(i).B : design.params.limb(i).A;
      for (int axis = 0; axis < 3; ++axis) {
        const std::string param = std::string(end ? "B" : "A") + "xyz"[axis];
        std::printf("%-4d %-6s %12.4f %12.4f %10.4f\n", i + 1, param.c_str(), d[axis] * 1e3,
                    r.points[k][axis] * 1e3, r.half_widths[k][axis] * 1e3);
      }
    }
  }
  std::cout << "wrote " << args.output << "\n";
}

}  // namespace

void register_measure_command(CLI::App& app) {
  auto args = std::make_shared<MeasureArguments>();
  CLI::App* cmd = app.add_subcommand(
      "measure",
      "measure A, alpha, B, beta (and gamma) from camera images; a spatial robot's A_i and B_i");
  cmd->add_option("--design", args->design,
                  "design pcr-robot JSON (empty: built-in femto-3pf); a spatial one is measured "
                  "from --points, --base-image and --platform-image");
  cmd->add_option("--mounts", args->mounts, "mount layout JSON (a planar robot: required)");
  cmd->add_option("--camera", args->camera, "OpenCV camera YAML")->required();
  cmd->add_option("--image", args->image,
                  "image of the robot at home (q = 0) (a planar robot: required)");
  cmd->add_option("--points", args->points,
                  "attachment layout JSON (pcr-attachment-points): the tags next to a spatial "
                  "robot's A_i and B_i");
  cmd->add_option("--base-image", args->base_image,
                  "image of the base: the tags next to the holes A_i (a spatial robot)");
  cmd->add_option("--platform-image", args->platform_image,
                  "image of the platform, at any pose: the tags next to the points B_i (a "
                  "spatial robot)");
  cmd->add_option("--sweep", args->sweeps,
                  "LIMB:IMAGE_DIR, images of limb LIMB (0-based) stepping its actuator, "
                  "in name order of increasing q");
  cmd->add_option("--output", args->output, "measured pcr-robot JSON to write")->required();
  cmd->add_option("--annotated", args->annotated, "annotated PNG for a visual check");
  cmd->add_option("--family", args->family,
                  "tag family of the mounts (points) whose layout file names none")
      ->capture_default_str();
  pcr::cli::add_detector_options(*cmd, args->options.detector);
  cmd->callback([args]() {
    using namespace pcr;
    using namespace pcr::vision;
    if (!is_known_family(args->family)) {
      throw InputError("--family: unknown tag family '" + args->family +
                       "'; the accepted families are " + known_families());
    }
    check_distinct_outputs({{"--output", args->output}, {"--annotated", args->annotated}});
    if (cli::is_spatial_robot(args->design)) return run_spatial_measure(*args);
    if (!args->points.empty() || !args->base_image.empty() || !args->platform_image.empty()) {
      throw InputError(
          "pcr measure: --points, --base-image and --platform-image measure a "
          "spatial robot; " +
          (args->design.empty() ? std::string("the built-in design") : args->design) +
          " is planar (give --mounts and --image)");
    }
    for (const auto& [option, value] :
         {std::pair<const char*, std::string>{"--mounts", args->mounts},
          {"--image", args->image}}) {
      if (value.empty()) throw CLI::RequiredError(option);  // as when they were required options
    }
    const RobotDescription design = load_robot_or_default(args->design);
    const MountLayout layout = load_mounts(args->mounts, args->family);
    const CameraModel camera = load_camera(args->camera);
    const GrayImage image = read_image(args->image);
    check_image_size(camera, image.width, image.height, args->camera, args->image);
    RobotMeasurement m =
        measure_robot(image, args->image, layout, camera, design.params, args->options);
    for (const std::string& sweep : args->sweeps) {
      const std::size_t colon = sweep.find(':');
      if (colon == std::string::npos)
        throw InputError("--sweep: expected LIMB:IMAGE_DIR, got '" + sweep + "'");
      int limb = -1;
      try {
        limb = std::stoi(sweep.substr(0, colon));
      } catch (const std::exception&) {
        throw InputError("--sweep: bad limb index in '" + sweep + "'");
      }
      const std::string dir = sweep.substr(colon + 1);
      if (!std::filesystem::is_directory(dir))
        throw InputError("--sweep: " + dir + " is not a directory");
      std::vector<std::string> files;
      for (const auto& e : std::filesystem::directory_iterator(dir)) {
        const std::string ext = e.path().extension().string();
        if (e.is_regular_file() &&
            (ext == ".png" || ext == ".tif" || ext == ".tiff" || ext == ".jpg"))
          files.push_back(e.path().string());
      }
      std::sort(files.begin(), files.end());
      std::vector<GrayImage> images;
      for (const auto& f : files) images.push_back(read_image(f));
      const SweepResult r = measure_sweep(images, files, limb, layout, camera, m, args->options);
      std::printf(
          "sweep limb %d: %zu images, line rms %.2f um, direction %.4f +- %.4f mrad (1 sigma)\n",
          limb, images.size(), r.line_rms * 1e6, r.direction_plane, r.direction_sigma * 1e3);
    }
    const RobotDescription out = measured_description(design, m);
    OutputTransaction outputs;  // all or none
    save_robot(out, args->output);
    if (!args->annotated.empty()) write_annotated(image, m, layout, camera, args->annotated);
    outputs.commit();
    std::printf(
        "plane fit: corner rms %.4f px (sigma used %.4f px); registration rms A %.1f um, B %.1f "
        "um\n",
        m.fit.corner_rms_px, m.fit.corner_sigma_px, m.registration_rms_A * 1e6,
        m.registration_rms_B * 1e6);
    std::printf("%-5s %-6s %14s %14s %12s\n", "limb", "param", "design", "measured", "+-");
    for (int i = 0; i < static_cast<int>(m.limbs.size()); ++i) {
      const LimbMeasurement& l = m.limbs[i];
      const LimbParams<double>& d = design.params.limb(i);
      const auto row = [&](const char* name, double dv, double mv, double hw, double unit) {
        std::printf("%-5d %-6s %14.6f %14.6f %12.6f\n", i, name, dv * unit, mv * unit, hw * unit);
      };
      row("Ax mm", d.A.x(), l.A.x(), l.A_halfwidth.x(), 1e3);
      row("Ay mm", d.A.y(), l.A.y(), l.A_halfwidth.y(), 1e3);
      row("alpha", d.alpha, l.alpha, l.alpha_halfwidth, 1.0);
      row("Bx mm", d.B.x(), l.B.x(), l.B_halfwidth.x(), 1e3);
      row("By mm", d.B.y(), l.B.y(), l.B_halfwidth.y(), 1e3);
      row("beta", d.beta, l.beta, l.beta_halfwidth, 1.0);
      if (l.gamma) row("gamma", d.gamma, *l.gamma, *l.gamma_halfwidth, 1.0);
    }
    std::cout << "wrote " << args->output << "\n";
  });
}
#endif
