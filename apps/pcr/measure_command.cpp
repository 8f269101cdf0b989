// pcr measure: rod-mount tags in a camera image -> a measured pcr-robot description.
#ifdef PCR_HAS_VISION
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/tags.hpp"

void register_measure_command(CLI::App& app) {
  struct Args {
    std::string design, mounts, camera, image, output, annotated;
    std::string family = pcr::vision::kDefaultTagFamily;
    std::vector<std::string> sweeps;
    pcr::vision::MeasureOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd =
      app.add_subcommand("measure", "measure A, alpha, B, beta (and gamma) from camera images");
  cmd->add_option("--design", args->design, "design pcr-robot JSON (empty: built-in femto-3pf)");
  cmd->add_option("--mounts", args->mounts, "mount layout JSON")->required();
  cmd->add_option("--camera", args->camera, "OpenCV camera YAML")->required();
  cmd->add_option("--image", args->image, "image of the robot at home (q = 0)")->required();
  cmd->add_option("--sweep", args->sweeps,
                  "LIMB:IMAGE_DIR, images of limb LIMB (0-based) stepping its actuator, "
                  "in name order of increasing q");
  cmd->add_option("--output", args->output, "measured pcr-robot JSON to write")->required();
  cmd->add_option("--annotated", args->annotated, "annotated PNG for a visual check");
  cmd->add_option("--family", args->family, "tag family of the mounts whose layout file names none")
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
