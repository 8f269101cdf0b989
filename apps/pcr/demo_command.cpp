// pcr demo: the paper's whole method on the built-in virtual robot, in one seeded command (the
// paper's Sections 2.3 to 6; README.md, "The main job"): the measurement of the nominal robot in
// rendered images, then the library's method (pcr::run_method: sensitivity -> sampling and
// simulated measurements -> calibration -> validation -> trajectories and ISO 9283 accuracy ->
// maps), and its report.
#ifdef PCR_HAS_CALIB
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "pcr/calib/method.hpp"
#include "pcr/calib/named_effects.hpp"
#include "pcr/calib/spatial_method.hpp"
#include "pcr/spatial/robot_io.hpp"
#ifdef PCR_HAS_VISION
#include "pcr/vision/camera.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/render.hpp"
#endif

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

struct DemoArgs {
  std::string robot;  ///< empty: the built-in planar robot
  std::string output = "pcr-demo";
  std::uint64_t seed = 1;
  int calibration_count = pcr::kDefaultCalibrationCount;
  int validation_count = pcr::kDefaultValidationCount;
  int repeat = 30;
  int path_poses = 40;
  bool vision = true;
  bool quiet = false;
  std::vector<std::string> effects;  ///< unmodelled effects of the virtual robot, by name
  bool identify_load = false;        ///< spatial: the last stage also frees a platform load
};

/// Stage-by-stage progress on stderr, with the time each stage took. The stages are named once,
/// in order, when it is made: their count is the list's.
class Progress {
 public:
  Progress(std::vector<std::string> stages, bool quiet)
      : stages_(std::move(stages)), quiet_(quiet) {}
  /// Starts the next stage of the list.
  void begin() {
    if (stage_ >= stages_.size()) throw std::logic_error("demo: more stages than listed");
    start_ = std::chrono::steady_clock::now();
    say("[" + std::to_string(stage_ + 1) + "/" + std::to_string(stages_.size()) + "] " +
        stages_[stage_]);
    ++stage_;
  }
  void end() {
    char buf[64];
    std::snprintf(buf, sizeof buf, "      done in %.1f s", seconds_since(start_));
    say(buf);
  }
  void say(const std::string& line) const {
    if (!quiet_) std::cerr << line << "\n";
  }
  static double seconds_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  }

 private:
  std::vector<std::string> stages_;
  std::size_t stage_ = 0;
  bool quiet_;
  std::chrono::steady_clock::time_point start_;
};

/// The output directory: created, or reused only when a previous demo made it (never someone
/// else's files).
fs::path prepare_output(const std::string& dir) {
  if (dir.empty())
    throw pcr::InputError("--output: the option is empty: give the report directory");
  const fs::path out(dir);
  const fs::path marker = out / ".pcr-demo";
  if (fs::exists(out)) {
    if (!fs::is_directory(out)) throw pcr::InputError("--output: " + dir + " is not a directory");
    if (!fs::is_empty(out) && !fs::exists(marker)) {
      throw pcr::InputError("--output: " + dir +
                            " exists and was not written by pcr demo; refusing to overwrite it");
    }
  }
  fs::create_directories(out);
  pcr::write_file_atomically(marker.string(), "written by pcr demo\n");
  return out;
}

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

#ifdef PCR_HAS_VISION
/// Step 1: photograph the true robot's mounts (rendered) and measure the nominal description.
/// The mounts are machined with errors inside the layout's offset uncertainty; the paper's close-up
/// image brings the 840 um along the tag's x axis down to 160 um, used here as the layout's.
pcr::RobotDescription measure_nominal(const pcr::RobotDescription& design,
                                      const pcr::RobotDescription& truth, std::uint64_t seed,
                                      const fs::path& out, json& report, std::string& markdown,
                                      const Progress& progress) {
  using namespace pcr::vision;
  MountLayout layout = default_mounts();
  for (Mount& m : layout.mounts) m.clamp_offset_uncertainty.x() = 160e-6;
  MountLayout machined = layout;
  std::mt19937_64 rng(seed ^ 0x6d6f756e74ULL);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Mount& m : machined.mounts) {
    m.clamp_offset += Eigen::Vector2d(u(rng) * m.clamp_offset_uncertainty.x(),
                                      u(rng) * m.clamp_offset_uncertainty.y());
    m.rod_angle += u(rng) * m.rod_angle_uncertainty;
  }

  Scene scene;  // 1700 x 1700 px, 100 um/px at 0.5 m, with distortion
  scene.camera.width = scene.camera.height = 1700;
  scene.camera.K << 5000, 0, 851.3, 0, 5000, 848.9, 0, 0, 1;
  scene.camera.distortion[0] = -0.15;
  scene.camera.distortion[1] = 0.1;
  scene.plane = PlanePose::looking_down(0.5, 0.01, -0.02);
  RenderOptions render;
  render.supersampling = 3;
  render.blur_sigma_px = 0.8;
  render.noise_sigma = 0.02;
  render.gradient = 0.3;
  // Exposed for the brightest corner (1.2x the centre's light): whites stay below full scale, as
  // pcr measure requires (clipped edges bias the tag size).
  render.white = 0.75f;
  render.seed = static_cast<unsigned>(seed);

  const int n = truth.params.num_limbs;
  const pcr::JointVector home_q = pcr::JointVector::Zero(n);
  const pcr::ForwardSolution home = pcr::forward_kinematics(truth.params, home_q);
  if (!home.summary.converged()) throw std::runtime_error("demo: the true robot has no home pose");
  scene.tags = mount_tags(machined, truth.params, home.pose, {}, &scene.segments);
  const GrayImage image = render_scene(scene, render);
  fs::create_directories(out / "images");
  write_png(image, (out / "images" / "home.png").string());
  save_camera(scene.camera, (out / "camera.yaml").string());
  RobotMeasurement m = measure_robot(image, "home.png", layout, scene.camera, design.params);

  // Actuator directions: each limb's proximal mount over a 1 mm stroke in 125 um steps.
  for (int limb = 0; limb < n; ++limb) {
    std::vector<GrayImage> images;
    std::vector<std::string> names;
    const int proximal_id = machined.mounts[machined.find(limb, MountRole::kProximal)].id;
    for (int k = 0; k <= 8; ++k) {
      std::vector<double> q(n, 0.0);
      q[limb] = -0.5e-3 + 125e-6 * k;
      Scene sweep = scene;
      sweep.segments.clear();
      sweep.tags.clear();
      for (const RenderTag& t : mount_tags(machined, truth.params, home.pose, q)) {
        if (t.id == proximal_id) sweep.tags.push_back(t);
      }
      render.seed = static_cast<unsigned>(seed * 1000 + 10 * limb + k);
      images.push_back(render_scene(sweep, render));
      names.push_back("sweep limb " + std::to_string(limb) + " step " + std::to_string(k));
    }
    const SweepResult r = measure_sweep(images, names, limb, layout, scene.camera, m);
    progress.say(
        fmt("      limb %.0f: actuator direction line rms %.2f um", limb, r.line_rms * 1e6));
  }
  write_annotated(image, m, layout, scene.camera, (out / "images" / "home-annotated.png").string());
  const pcr::RobotDescription nominal = measured_description(design, m);

  markdown += "## 1. Measurement (rendered images, AprilTag)\n\n";
  markdown += fmt("Plane fit: corner rms %.4f px; registration rms A %.1f um, B %.1f um.\n\n",
                  m.fit.corner_rms_px, m.registration_rms_A * 1e6, m.registration_rms_B * 1e6);
  markdown +=
      "| limb | A_x err (um) | A_y err (um) | +- (um) | alpha err (mrad) | +- (mrad) | "
      "gamma err (mrad) | +- (mrad) |\n|---|---|---|---|---|---|---|---|\n";
  json limbs = json::array();
  // The measured A_i are in the design's W (best-fit registration onto the design's A_i): compare
  // them with the truth's A_i registered the same way, so the errors are the measurement's own.
  std::vector<Eigen::Vector2d> true_a, design_a;
  for (int i = 0; i < n; ++i) {
    true_a.push_back(truth.params.limb(i).A);
    design_a.push_back(design.params.limb(i).A);
  }
  const pcr::Pose2<double> registration = rigid_fit(true_a, design_a);
  for (int i = 0; i < n; ++i) {
    const pcr::LimbParams<double>& t = truth.params.limb(i);
    const LimbMeasurement& l = m.limbs[i];
    const Eigen::Vector2d a_error = l.A - registration.transform(t.A);
    const double alpha_error = pcr::wrap_angle(l.alpha - (t.alpha + registration.theta));
    const double gamma_err = l.gamma ? *l.gamma - t.gamma : std::nan("");
    markdown += "| " + std::to_string(i) +
                fmt(" | %.1f | %.1f | %.1f", a_error.x() * 1e6, a_error.y() * 1e6,
                    l.A_halfwidth.maxCoeff() * 1e6) +
                fmt(" | %.3f | %.3f | %.3f | %.3f |\n", alpha_error * 1e3, l.alpha_halfwidth * 1e3,
                    gamma_err * 1e3, l.gamma_halfwidth ? *l.gamma_halfwidth * 1e3 : std::nan(""));
    limbs.push_back({{"A_m", {l.A.x(), l.A.y()}},
                     {"A_halfwidth_m", {l.A_halfwidth.x(), l.A_halfwidth.y()}},
                     {"alpha_rad", l.alpha},
                     {"B_m", {l.B.x(), l.B.y()}},
                     {"beta_rad", l.beta},
                     {"gamma_rad", l.gamma ? *l.gamma : std::nan("")}});
  }
  markdown +=
      "\n(measured minus true, both registered onto the design's proximal clamps; the "
      "+- columns are the measured half-widths)\n\n";
  report["measurement"] = {{"images", "images/home.png"},
                           {"annotated", "images/home-annotated.png"},
                           {"camera", "camera.yaml"},
                           {"corner_rms_px", m.fit.corner_rms_px},
                           {"registration_rms_A_m", m.registration_rms_A},
                           {"registration_rms_B_m", m.registration_rms_B},
                           {"limbs", limbs}};
  return nominal;
}
#endif

std::string table2_markdown(const pcr::SensitivityReport& s) {
  std::string md =
      "| rank | parameter | max abs dx/dp | max abs dy/dp | max abs dtheta/dp | half-width | "
      "position error (um) | orientation error (urad) |\n|---|---|---|---|---|---|---|---|\n";
  int rank = 0;
  for (int index : s.ranking) {
    const pcr::SensitivityRow& r = s.rows[index];
    md += "| " + std::to_string(++rank) + " | " + r.kind +
          fmt(" | %.3e | %.3e | %.3e | %.3e", r.dx, r.dy, r.dtheta, r.half_width) +
          fmt(" | %.2f | %.2f |\n", r.position_error * 1e6, r.orientation_error * 1e6);
  }
  return md;
}

std::string table3_row(const std::string& label, const pcr::PoseErrorStats& s) {
  return "| " + label + fmt(" | %.4f | %.4f | %.4f", s.max_p * 1e6, s.mean_p * 1e6, s.min_p * 1e6) +
         fmt(" | %.3f | %.3f | %.3f |\n", s.max_theta * 1e6, s.mean_theta * 1e6, s.min_theta * 1e6);
}

/// One set's errors per configuration under one model: position (m) and angle (rad).
struct ErrorColumns {
  const char* set;
  const char* model;
  const std::vector<double>& position;
  const std::vector<double>& angle;
};

/// Per-configuration errors for the plots (Figures 8 and 9), those behind Table 3:
/// `set,configuration,model,e_p,<angle>` (the planar e_theta, the spatial e_angle).
std::string errors_csv(const char* angle, const std::vector<ErrorColumns>& columns) {
  std::ostringstream csv;
  csv.precision(10);
  csv << "set,configuration,model,e_p," << angle << "\n";
  for (const ErrorColumns& c : columns) {
    for (std::size_t j = 0; j < c.position.size(); ++j)
      csv << c.set << "," << j << "," << c.model << "," << c.position[j] << "," << c.angle[j]
          << "\n";
  }
  return csv.str();
}

std::string errors_csv(const pcr::CalibrationTable& t) {
  return errors_csv("e_theta", {{"calibration", "nominal", t.nominal_calibration_errors.e_p,
                                 t.nominal_calibration_errors.e_theta},
                                {"calibration", "identified", t.identified_calibration_errors.e_p,
                                 t.identified_calibration_errors.e_theta},
                                {"validation", "nominal", t.nominal_validation_errors.e_p,
                                 t.nominal_validation_errors.e_theta},
                                {"validation", "identified", t.identified_validation_errors.e_p,
                                 t.identified_validation_errors.e_theta}});
}

/// The spatial Table 3's errors per configuration; e_angle: the angle of the rotation between
/// the predicted and the measured marker orientation.
std::string errors_csv(const pcr::SpatialCalibrationTable& t) {
  std::vector<ErrorColumns> columns = {
      {"calibration", "nominal", t.nominal_calibration.position, t.nominal_calibration.angle},
      {"calibration", "identified", t.identified_calibration.position,
       t.identified_calibration.angle}};
  if (t.has_validation) {
    columns.push_back(
        {"validation", "nominal", t.nominal_validation.position, t.nominal_validation.angle});
    columns.push_back({"validation", "identified", t.identified_validation.position,
                       t.identified_validation.angle});
  }
  return errors_csv("e_angle", columns);
}

/// Table 4: the paper's square and circle commanded with the nominal and the identified model. The
/// attained poses are what the camera measures, mapped to W with the commanding model's
/// extrinsics, as on the real robot: each model defines its own W (the gauge of the calibration),
/// so this is the frame its commands are in.
std::string accuracy_section(const pcr::MethodResult& result, const DemoArgs& args,
                             const fs::path& out, json& report) {
  std::vector<std::pair<std::string, const pcr::Iso9283Result*>> rows;
  for (const pcr::PathAccuracy& a : result.accuracy) {
    const std::string name = a.path + "-" + a.model;
    pcr::write_file_atomically((out / ("attained-" + name + ".csv")).string(),
                               pcr::measured_to_csv(a.evaluation.commanded, a.evaluation.attained));
    pcr::write_file_atomically((out / ("accuracy-" + name + ".csv")).string(),
                               pcr::iso9283_poses_csv(a.evaluation.iso));
    rows.emplace_back(a.path + ", " + a.model + " model", &a.evaluation.iso);
  }
  report["accuracy"] = json::parse(pcr::iso9283_json(rows));
  report["accuracy"]["repeat"] = args.repeat;
  report["accuracy"]["poses_per_path"] = args.path_poses;
  return pcr::iso9283_table_markdown(rows) + "\nEach pose repeated " + std::to_string(args.repeat) +
         " times, approached from the previous pose; attained poses measured by the camera (with "
         "its noise) and mapped to W with each model's identified extrinsics, as in the paper.\n";
}

/// Where the identified robot can work at theta = 0: the map of `pcr map` (CSV). Its figures are
/// drawn from the CSV by Python (`python -m pcr.plot`, into figures.md): data here, not pictures.
std::string workspace_section(const pcr::MethodResult& result, const fs::path& out, json& report) {
  const pcr::WorkspaceMap& map = *result.map;
  const int n = result.identified.params.num_limbs;
  {
    pcr::OutputFile file((out / "map-identified.csv").string());
    pcr::write_workspace_map_csv(map, n, file.stream());
    file.commit();
  }
  int reachable = 0, unstable = 0;
  double min_singularity = HUGE_VAL, max_3sigma = 0;
  for (const pcr::WorkspaceMapPoint& p : map.points) {
    if (!p.reachable) continue;
    ++reachable;
    unstable += p.stable ? 0 : 1;
    min_singularity = std::min(min_singularity, p.singularity);
    if (p.stable) max_3sigma = std::max(max_3sigma, p.position_3sigma);
  }
  const pcr::RotationRange& rotation = result.rotation_range;
  report["workspace"] = {{"theta", map.theta},
                         {"grid", map.nx},
                         {"range_m", {map.x_min, map.x_max, map.y_min, map.y_max}},
                         {"reachable_area_m2", map.reachable_area},
                         {"stable_area_m2", map.stable_area},
                         {"reachable_points", reachable},
                         {"unstable_reachable_points", unstable},
                         {"min_singularity", reachable ? min_singularity : NAN},
                         {"max_position_3sigma_m", max_3sigma},
                         {"rotation_range_at_centre_rad", {rotation.theta_min, rotation.theta_max}},
                         {"seconds", map.seconds},
                         {"files", {"map-identified.csv"}}};
  char text[1024];
  std::snprintf(
      text, sizeof text,
      "Identified robot at theta = 0, %d x %d positions over x [%.2f, %.2f] mm, y [%.2f, %.2f] "
      "mm (map-identified.csv, %.2f s): reachable within the stroke %.2f mm^2, of which stable "
      "%.2f mm^2 (%d of %d reachable points on an unstable equilibrium); smallest "
      "reciprocal condition number of the scaled FK Jacobian there %.3g. Rotation range at the "
      "centre: [%.4f, %.4f] rad. Predicted 3-sigma position error of what the camera measures, "
      "from "
      "the calibration's covariance: at most %.3g nm over the stable points.\n",
      map.nx, map.ny, map.x_min * 1e3, map.x_max * 1e3, map.y_min * 1e3, map.y_max * 1e3,
      map.seconds, map.reachable_area * 1e6, map.stable_area * 1e6, unstable, reachable,
      min_singularity, rotation.theta_min, rotation.theta_max, max_3sigma * 1e9);
  return std::string(text) +
         "\nThe maps (predicted error, stability margin, singularity, strain, with the workspace "
         "border and the robot's home): [figures.md](figures.md).\n";
}

/// Table 3 and the stages, with the fit not chosen when both were tried.
std::string calibration_section(const pcr::MethodResult& result) {
  const pcr::CalibrationResult& calibrated = result.calibration;
  const pcr::CalibrationTable& table3 = result.table;
  const char* header =
      "| model, set | e_p max (um) | e_p mean (um) | e_p min (um) | e_theta max (urad) | e_theta "
      "mean (urad) | e_theta min (urad) |\n|---|---|---|---|---|---|---|\n";
  std::string md = std::string("## 3. Calibration (Table 3)\n\n") + header;
  md += table3_row("nominal, calibration", table3.nominal_calibration);
  md += table3_row("nominal, validation", table3.nominal_validation);
  md += table3_row("identified, calibration", table3.identified_calibration);
  md += table3_row("identified, validation", table3.identified_validation);
  md +=
      "\nNominal model: the measured geometry with identified extrinsics (the paper's first "
      "stage). Stages:\n\n";
  for (const pcr::StageReport& s : calibrated.stages) {
    md += "- " + s.name + ": " + std::to_string(s.free_parameters.size()) + " free parameters, " +
          std::to_string(s.iterations) + " iterations, " +
          fmt("cost %.3e -> %.3e m^2, %.2f s\n", s.initial_cost, s.final_cost, s.time_s);
  }
  const pcr::ModelSelection& selection = *result.selection;
  md += "\nModel: " + selection.decision + ".\n";
  if (selection.tried_load) {
    const pcr::CalibrationTable& other_table = selection.other_table();
    md += std::string("\nThe fit not chosen (") +
          (selection.load_chosen ? "the paper's stages" : "the load model") +
          "), for comparison:\n\n" + header +
          table3_row("identified, calibration", other_table.identified_calibration) +
          table3_row("identified, validation", other_table.identified_validation);
  }
  if (calibrated.load_identified) {
    md += fmt("\nIdentified platform load: f = (%.4g, %.4g) mN, m_z = %.4g uN m.\n",
              calibrated.load.force.x() * 1e3, calibrated.load.force.y() * 1e3,
              calibrated.load.moment * 1e6);
  }
  return md +
         "\nFull report (identified values with standard deviations, bounds, gauge): "
         "calibration-report.txt.\n\n";
}

/// What each stage of the method found, as progress lines.
void say_what_was_found(pcr::MethodStage stage, const pcr::MethodResult& r,
                        const Progress& progress) {
  switch (stage) {
    case pcr::MethodStage::kMeasurement:
      progress.say(fmt("      %.0f + %.0f configurations, Poisson-disc radius %.3f mm",
                       r.calibration_data.size(), r.validation_data.size(),
                       r.configurations.spread.min_distance * 1e3));
      if (r.unmeasured > 0) {
        progress.say(
            fmt("      %.0f configurations not measured: the robot holds no stable "
                "equilibrium there",
                r.unmeasured));
      }
      break;
    case pcr::MethodStage::kValidation:
      progress.say(fmt("      validation mean e_p: nominal %.3f um, identified %.4f um",
                       r.table.nominal_validation.mean_p * 1e6,
                       r.table.identified_validation.mean_p * 1e6));
      break;
    case pcr::MethodStage::kAccuracy:
      for (const pcr::PathAccuracy& a : r.accuracy) {
        progress.say("      " + a.path + ", " + a.model +
                     fmt(" model: AP_p max %.4f um, mean %.4f um", a.evaluation.iso.ap_p.max * 1e6,
                         a.evaluation.iso.ap_p.mean * 1e6));
      }
      break;
    case pcr::MethodStage::kWorkspaceMap:
      progress.say(fmt("      %.0f x %.0f map in %.2f s: reachable %.2f mm^2", r.map->nx, r.map->ny,
                       r.map->seconds, r.map->reachable_area * 1e6) +
                   fmt(", stable %.2f mm^2", r.map->stable_area * 1e6));
      break;
    default:
      break;
  }
}

/// The report's last lines: the total time, report.json and report.md written, every file put
/// in place at once, the Markdown on stdout.
void finish_report(const fs::path& out, std::chrono::steady_clock::time_point start, json& report,
                   std::string& md, pcr::OutputTransaction& outputs, const Progress& progress) {
  report["time_s"] = Progress::seconds_since(start);
  md += fmt("\nTotal time %.1f s.\n", Progress::seconds_since(start));
  pcr::write_file_atomically((out / "report.json").string(), report.dump(2) + "\n");
  pcr::write_file_atomically((out / "report.md").string(), md);
  outputs.commit();
  std::cout << md;
  progress.say("wrote " + (out / "report.md").string());
}

void run_demo(const DemoArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  if (args.identify_load) {
    throw pcr::InputError(
        "--identify-load: for a spatial robot (the planar demo chooses the load model on its "
        "validation set)");
  }
  const fs::path out = prepare_output(args.output);
  // Every file goes in place at the end, when all were written: a failed or interrupted demo
  // leaves the files of the previous run as they were.
  pcr::OutputTransaction outputs;
  Progress progress(
      {"measurement: render the mounts, detect the tags, measure the nominal robot",
       "sensitivity analysis (Table 2)", "Poisson-disc sampling",
       "simulated measurements of both sets", "three-stage calibration", "validation (Table 3)",
       "square and circle trajectories, ISO 9283 accuracy (Table 4)",
       "workspace maps of the identified robot (reachability, stability, singularity)"},
      args.quiet);
  json report;
  report["seed"] = args.seed;
  report["unmodelled_effects"] = args.effects;
  std::string md = "# pcr demo: the method of Mauze et al. (2021) on " +
                   (args.robot.empty() ? std::string("the built-in virtual robot")
                                       : "a virtual robot drawn from " + args.robot) +
                   "\n\n";
  md += "Seed " + std::to_string(args.seed) + ", unmodelled effects: " +
        (args.effects.empty() ? std::string("none") : CLI::detail::join(args.effects, ", ")) +
        ". Units: um and urad in the tables, SI in every file. Files: see report.json. Figures: "
        "[figures.md](figures.md), drawn from these files by `python -m pcr.plot DIR` (which "
        "`scripts/run.sh demo` runs).\n\n";

  // The virtual robot: a truth drawn from the design inside the paper's uncertainty intervals,
  // true extrinsics, the paper's repeatability as measurement noise.
  const pcr::RobotDescription design =
      args.robot.empty() ? pcr::default_robot() : pcr::load_robot(args.robot);
  pcr::VirtualRobotOptions vr_options;
  vr_options.seed = args.seed;
  vr_options.effects = pcr::planar_effects_named(args.effects, "--effects");
  pcr::VirtualRobot robot(design, vr_options);
  pcr::save_robot(design, (out / "design.json").string());
  pcr::save_robot(robot.truth(), (out / "truth.json").string());

  // 1. Nominal description.
  progress.begin();
  pcr::RobotDescription nominal = design;
  bool measured = false;
#ifdef PCR_HAS_VISION
  if (args.vision && args.robot.empty()) {  // the built-in robot's mounts are the ones rendered
    nominal = measure_nominal(design, robot.truth(), args.seed, out, report, md, progress);
    measured = true;
  }
#endif
  if (!measured) {
    const std::string why =
        args.robot.empty()
            ? "measurement skipped (vision not built or --no-vision): starting from the design "
              "with the paper's uncertainties"
            : "measurement skipped: starting from " + args.robot + " as the nominal description";
    progress.say("      " + why);
    md += "## 1. Measurement\n\n" + why + ".\n\n";
    report["measurement"] = why;
  }
  if (args.robot.empty()) nominal.name = "femto-3pf (measured)";
  pcr::save_robot(nominal, (out / "nominal.json").string());
  progress.end();

  // 2. The rest of the method: the paper's stages and, when their residuals say the model misses
  // an effect, the load model, kept only when the validation set supports it.
  pcr::MethodOptions method;
  method.sampling.count = args.calibration_count;
  method.sampling.seed = args.seed;
  method.validation_count = args.validation_count;
  method.model = pcr::CalibratedModel::kSelected;
  if (!args.quiet)
    method.calibration.progress = [](const std::string& l) { std::cerr << "      " << l << "\n"; };
  method.square.num_poses = method.circle.num_poses = args.path_poses;
  method.accuracy.repeat = args.repeat;
  method.map.grid = 200;
  method.on_stage_begin = [&](pcr::MethodStage) { progress.begin(); };
  method.on_stage_end = [&](pcr::MethodStage stage, const pcr::MethodResult& r) {
    say_what_was_found(stage, r, progress);
    progress.end();
  };
  const pcr::MethodResult result = pcr::run_method(nominal, robot, method);

  pcr::write_file_atomically((out / "sensitivity.csv").string(),
                             pcr::sensitivity_csv(*result.sensitivity));
  report["sensitivity"] = json::parse(pcr::sensitivity_json(*result.sensitivity));
  md += "## 2. Sensitivity analysis (Table 2), most influential first\n\n" +
        table2_markdown(*result.sensitivity) + "\n";

  pcr::write_dataset(result.calibration_data, (out / "calibration.csv").string());
  pcr::write_dataset(result.validation_data, (out / "validation.csv").string());
  report["configurations"] = {{"calibration", result.calibration_data.size()},
                              {"validation", result.validation_data.size()},
                              {"min_distance_m", result.configurations.spread.min_distance},
                              {"files", {"calibration.csv", "validation.csv"}}};

  pcr::RobotDescription identified = result.identified;
  identified.name =
      (args.robot.empty() ? std::string("femto-3pf") : nominal.name) + " (identified)";
  pcr::save_robot(identified, (out / "identified.json").string());
  pcr::write_file_atomically((out / "calibration-report.txt").string(),
                             pcr::calibration_report_text(result.calibration, result.table));
  pcr::write_file_atomically((out / "calibration-errors.csv").string(), errors_csv(result.table));
  report["calibration"] =
      json::parse(pcr::calibration_report_json(result.calibration, result.table));
  report["calibration"]["model_selection"] =
      json::parse(pcr::model_selection_json(*result.selection));
  md += calibration_section(result);

  md += "## 4. Trajectory accuracy, ISO 9283 (Table 4)\n\n" +
        accuracy_section(result, args, out, report);
  md += "\n## 5. Where the identified robot can work\n\n" + workspace_section(result, out, report);

  report["files"] = {"report.md",
                     "report.json",
                     "design.json",
                     "truth.json",
                     "nominal.json",
                     "identified.json",
                     "sensitivity.csv",
                     "calibration.csv",
                     "validation.csv",
                     "calibration-report.txt",
                     "calibration-errors.csv",
                     "accuracy-{square,circle}-{nominal,identified}.csv",
                     "attained-{square,circle}-{nominal,identified}.csv",
                     "map-identified.csv",
                     "images/"};
  finish_report(out, start, report, md, outputs, progress);
}

/// The method on a virtual spatial robot drawn from the --robot file (pcr::run_spatial_method):
/// the same report directory, its tables for a spatial robot; figures.md as the planar one's.
void run_spatial_demo(const DemoArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  const pcr::SpatialRobotDescription nominal = pcr::load_spatial_robot(args.robot);
  if (!nominal.uncertainty) {
    throw pcr::InputError(args.robot +
                          ": no uncertainty section: the virtual robot draws its truth inside it "
                          "and the calibration identifies within it");
  }
  const fs::path out = prepare_output(args.output);
  pcr::OutputTransaction outputs;
  Progress progress(
      {"sensitivity analysis (Table 2)", "Poisson-disc sampling",
       "simulated measurements of both sets", "two-stage calibration", "validation (Table 3)",
       "square, circle and helix trajectories, ISO 9283 accuracy (Table 4)"},
      args.quiet);
  pcr::SpatialVirtualRobotOptions vr_options;
  vr_options.seed = args.seed;
  vr_options.effects = pcr::spatial_effects_named(args.effects, "--effects");
  pcr::SpatialVirtualRobot robot(nominal, vr_options);
  pcr::save_spatial_robot(nominal, (out / "nominal.json").string());
  pcr::save_spatial_robot(robot.truth(), (out / "truth.json").string());

  pcr::SpatialMethodOptions method;
  method.sampling.count = args.calibration_count;
  method.sampling.seed = args.seed;
  method.validation_count = args.validation_count;
  method.accuracy.repeat = args.repeat;
  method.square.num_poses = method.circle.num_poses = method.helix.num_poses = args.path_poses;
  if (args.identify_load)
    method.calibration.stages = pcr::with_load_stage(method.calibration.stages);
  if (!args.quiet)
    method.calibration.progress = [](const std::string& l) { std::cerr << "      " << l << "\n"; };
  method.on_stage_begin = [&](pcr::MethodStage) { progress.begin(); };
  method.on_stage_end = [&](pcr::MethodStage, const pcr::SpatialMethodResult&) { progress.end(); };
  const pcr::SpatialMethodResult result = pcr::run_spatial_method(nominal, robot, method);

  json report;
  report["robot"] = args.robot;
  report["seed"] = args.seed;
  report["unmodelled_effects"] = args.effects;
  report["unmodelled_effect_sizes"] = {
      {"payload_kg", vr_options.effects.payload},
      {"misalignment_half_width_rad", vr_options.effects.misalignment_half_width},
      {"diameter_half_width_m", vr_options.effects.diameter_half_width}};
  report["identify_load"] = args.identify_load;
  report["noise"] = {{"position_m", robot.noise_position()}, {"angle_rad", vr_options.noise_angle}};
  std::string md =
      "# pcr demo: the method of Mauze et al. (2021) on a virtual spatial robot "
      "drawn from " +
      args.robot + "\n\nSeed " + std::to_string(args.seed) + ". Unmodelled effects: " +
      (args.effects.empty() ? std::string("none")
                            : CLI::detail::join(args.effects, ", ") + " (" +
                                  pcr::describe(vr_options.effects) + ")") +
      (args.identify_load ? "; the last calibration stage also identifies a platform load" : "") +
      fmt(". Measurement noise %.3g nm and %.3g urad per axis (the noise floor of "
          "an rms error: %.3g nm, %.3g urad). Units: um and mrad in Table 4, SI in "
          "every file. Figures: [figures.md](figures.md), drawn from these files by "
          "`python -m pcr.plot DIR` (which `scripts/run.sh demo` runs).\n\n",
          robot.noise_position() * 1e9, vr_options.noise_angle * 1e6,
          std::sqrt(3.0) * robot.noise_position() * 1e9,
          std::sqrt(3.0) * vr_options.noise_angle * 1e6);

  pcr::write_file_atomically((out / "sensitivity.csv").string(),
                             pcr::spatial_sensitivity_csv(*result.sensitivity));
  report["sensitivity"] = json::parse(pcr::spatial_sensitivity_json(*result.sensitivity));
  md += "## 1. Sensitivity analysis (Table 2), most influential first\n\n```\n" +
        pcr::spatial_sensitivity_table_text(*result.sensitivity) + "```\n\n";

  pcr::write_spatial_dataset(result.calibration_data, (out / "calibration.csv").string());
  pcr::write_spatial_dataset(result.validation_data, (out / "validation.csv").string());
  report["configurations"] = {{"calibration", result.calibration_data.size()},
                              {"validation", result.validation_data.size()},
                              {"unmeasured", result.unmeasured},
                              {"files", {"calibration.csv", "validation.csv"}}};

  pcr::SpatialRobotDescription identified = result.identified;
  identified.name =
      (args.robot.empty() ? std::string("femto-3pf") : nominal.name) + " (identified)";
  pcr::save_spatial_robot(identified, (out / "identified.json").string());
  const std::string text = pcr::spatial_calibration_report_text(result.calibration, result.table);
  pcr::write_file_atomically((out / "calibration-report.txt").string(), text);
  pcr::write_file_atomically((out / "calibration-errors.csv").string(), errors_csv(result.table));
  report["calibration"] =
      json::parse(pcr::spatial_calibration_report_json(result.calibration, result.table));
  md += "## 2. Calibration and validation (Table 3)\n\n```\n" + text + "```\n\n";

  std::vector<std::pair<std::string, const pcr::SpatialIso9283Result*>> rows;
  for (const pcr::SpatialPathAccuracy& a : result.accuracy) {
    const std::string name = a.path + "-" + a.model;
    pcr::write_file_atomically((out / ("accuracy-" + name + ".csv")).string(),
                               pcr::iso9283_spatial_poses_csv(a.evaluation.iso));
    rows.emplace_back(a.path + ", " + a.model, &a.evaluation.iso);
  }
  report["accuracy"] = json::parse(pcr::iso9283_spatial_json(rows));
  md += fmt("## 3. Trajectory accuracy, ISO 9283 in 3-D (Table 4), %.0f cycles\n\n", args.repeat) +
        "The paths about the nominal robot's platform at the middle of the joint box; the "
        "nominal model is the nominal geometry with its extrinsics fitted.\n\n" +
        pcr::iso9283_spatial_table_markdown(rows) + "\n";

  report["files"] = {"report.md",
                     "report.json",
                     "nominal.json",
                     "truth.json",
                     "identified.json",
                     "sensitivity.csv",
                     "calibration.csv",
                     "validation.csv",
                     "calibration-report.txt",
                     "calibration-errors.csv",
                     "accuracy-{square,circle,helix}-{nominal,identified}.csv"};
  finish_report(out, start, report, md, outputs, progress);
}
}  // namespace

void register_demo_command(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "the whole method on a virtual robot (the built-in one, or drawn from --robot): measure, "
      "sensitivity, sampling, "
      "calibration, trajectory accuracy; writes a report directory");
  cmd->add_option("--robot", args->robot,
                  "a robot file (planar, or spatial: \"kind\": \"spatial\") with an uncertainty "
                  "section, instead of the built-in robot: the virtual robot is drawn from it");
  cmd->add_option("--output", args->output, "output directory")->capture_default_str();
  cmd->add_option("--seed", args->seed, "seed of the virtual robot, images, sampling, noise")
      ->capture_default_str();
  cmd->add_option("--calibration", args->calibration_count, "calibration configurations")
      ->check(pcr::cli::within(pcr::SamplingOptions::kCount))
      ->capture_default_str();
  cmd->add_option("--validation", args->validation_count, "validation configurations")
      ->check(pcr::cli::within(pcr::MethodOptions::kValidationCount))
      ->capture_default_str();
  cmd->add_option("--repeat", args->repeat, "ISO 9283 cycles per pose")
      ->check(pcr::cli::within(pcr::AccuracyOptions::kRepeat))
      ->capture_default_str();
  cmd->add_option("--poses", args->path_poses, "poses per trajectory")
      ->check(pcr::cli::within(pcr::SquarePath::kNumPoses))
      ->capture_default_str();
  cmd->add_option("--effects", args->effects,
                  "unmodelled effects of the virtual robot (pcr/calib/named_effects.hpp): "
                  "misalignments (holes turned beyond their intervals), diameters (unequal rods), "
                  "load (unknown to the model: planar 5 mN, spatial a 100 g payload), all")
      ->delimiter(',')
      ->check(CLI::IsMember(pcr::unmodelled_effect_names()));
  cmd->add_flag("--identify-load", args->identify_load,
                "spatial robot: the last calibration stage also identifies a constant platform "
                "load (the load stage)");
  cmd->add_flag("!--no-vision", args->vision, "start from the design instead of measuring");
  cmd->add_flag("--quiet", args->quiet, "no progress on stderr");
  cmd->callback([args]() {
    if (pcr::cli::is_spatial_robot(args->robot)) {
      run_spatial_demo(*args);
    } else {
      run_demo(*args);
    }
  });
}
#endif
