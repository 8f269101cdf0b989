// pcr accuracy: ISO 9283 accuracy of a path commanded through inverse kinematics (the paper's
// Section 6 and Table 4). Runs against a virtual robot (truth from a file, or drawn
// with a seed), or computes the table from poses measured on a real robot (--measured).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/calib/accuracy.hpp"
#include "pcr/calib/named_effects.hpp"

namespace {

struct AccuracyArguments {
  std::string robot, path = "square", truth, nominal, measured, poses, output;
  std::string format = "text", frame = "model";
  double size = 0;  // 0: the paper's (side 2 mm, diameter 3 mm)
  std::vector<double> centre;
  double theta = 0;
  int count = 0;  // 0: 40 (square), 36 (circle)
  int repeat = 30;
  std::uint64_t seed = 1;
  double noise_position = pcr::kDefaultNoisePosition;
  double noise_angle = pcr::kDefaultNoiseAngle;
  double strain_limit = pcr::kDefaultStrainLimit;
  std::vector<std::string> effects;
  pcr::cli::SolveArguments solve;
};

std::vector<pcr::Pose2<double>> make_path(const AccuracyArguments& args, std::string* name) {
  using namespace pcr;
  Vector2<double> centre(0, 0);
  if (!args.centre.empty()) {
    if (args.centre.size() != 2) throw InputError("--centre: expected x,y (m)");
    centre = Vector2<double>(args.centre[0], args.centre[1]);
  }
  if (args.path == "square") {
    SquarePath spec;
    spec.centre = centre;
    spec.theta = args.theta;
    if (args.size > 0) spec.side = args.size;
    if (args.count > 0) spec.num_poses = args.count;
    *name = "square";
    return square_path(spec);
  }
  if (args.path == "circle") {
    CirclePath spec;
    spec.centre = centre;
    spec.theta = args.theta;
    if (args.size > 0) spec.diameter = args.size;
    if (args.count > 0) spec.num_poses = args.count;
    *name = "circle";
    return circle_path(spec);
  }
  *name = args.path;
  return load_path_csv(args.path);
}

void run_accuracy(const AccuracyArguments& args) {
  using namespace pcr;
  check_distinct_outputs({{"--poses", args.poses},
                          {"--output", args.output.empty() ? std::string("-") : args.output}});
  OutputTransaction outputs;  // the poses and the table: all or none
  if (args.format != "text" && args.format != "json" && args.format != "csv") {
    throw InputError("--format: expected text, json or csv, got '" + args.format + "'");
  }
  std::string name;
  Iso9283Result iso;
  if (!args.measured.empty()) {
    const MeasuredPath measured = load_measured_csv(args.measured);
    iso = iso9283(measured.commanded, measured.attained);
    name = args.measured;
    std::cerr << "pcr accuracy: " << measured.commanded.size() << " poses measured in "
              << args.measured << "\n";
  } else {
    const RobotDescription model = load_robot_or_default(args.robot);
    const std::vector<Pose2<double>> path = make_path(args, &name);
    VirtualRobotOptions vr;
    vr.seed = args.seed;
    vr.noise_position = args.noise_position;
    vr.noise_angle = args.noise_angle;
    vr.solver = args.solve.options();
    vr.effects = planar_effects_named(args.effects, "--effects");
    if (!args.solve.force.empty() || args.solve.moment != 0) {
      // A known load: the model commands with it and the virtual robot carries it.
      vr.effects.external_load = true;
      vr.effects.load = args.solve.load();
    }
    RobotDescription source;
    std::string truth_note;
    if (!args.truth.empty()) {
      source = load_robot(args.truth);
      source.uncertainty.reset();  // zero half-widths: the virtual robot is exactly this file
      truth_note = "truth " + args.truth;
    } else {
      source = args.nominal.empty() ? model : load_robot(args.nominal);
      truth_note = "truth drawn from " +
                   (args.nominal.empty() ? std::string("the model") : args.nominal) +
                   " with seed " + std::to_string(args.seed);
    }
    VirtualRobot robot(source, vr);
    AccuracyOptions options;
    options.repeat = args.repeat;
    options.command.step.strain_limit = args.strain_limit;
    options.command.step.solver = args.solve.options();
    options.command.step.load = args.solve.load();
    if (args.frame == "true")
      options.frame = AttainedFrame::kTrueExtrinsics;
    else if (args.frame == "model")
      options.frame = AttainedFrame::kModelExtrinsics;
    else
      throw InputError("--frame: expected true or model, got '" + args.frame + "'");
    std::cerr << "pcr accuracy: " << name << ", " << path.size() << " poses x " << args.repeat
              << " cycles on the virtual robot (" << truth_note << ")\n";
    const AccuracyEvaluation e = evaluate_on_virtual_robot(model.params, robot, path, options);
    if (!args.poses.empty()) {
      write_file_atomically(args.poses, measured_to_csv(e.commanded, e.attained));
    }
    iso = e.iso;
  }
  const std::vector<std::pair<std::string, const Iso9283Result*>> rows = {{name, &iso}};
  OutputFile out(args.output);
  if (args.format == "json")
    out.stream() << iso9283_json(rows);
  else if (args.format == "csv")
    out.stream() << iso9283_poses_csv(iso);
  else
    out.stream() << iso9283_table_markdown(rows);
  out.commit();
  outputs.commit();
}

}  // namespace

void register_accuracy_command(CLI::App& app) {
  auto args = std::make_shared<AccuracyArguments>();
  CLI::App* cmd = app.add_subcommand(
      "accuracy",
      "ISO 9283 accuracy of a path commanded by IK (Table 4), on a virtual robot or "
      "from measured poses");
  using pcr::cli::within;
  pcr::cli::add_robot_option(*cmd, args->robot);
  cmd->add_option("--path", args->path, "square, circle, or a CSV file of poses (x,y,theta)")
      ->capture_default_str();
  // The square's ranges are the circle's (CirclePath::kDiameter is kSide's).
  cmd->add_option("--size", args->size, "square side or circle diameter (m; default 2 mm / 3 mm)")
      ->check(within(pcr::SquarePath::kSide));
  cmd->add_option("--centre", args->centre, "path centre x,y (m, in W; default 0,0)")
      ->delimiter(',')
      ->check(within(pcr::SquarePath::kCentre));
  cmd->add_option("--theta", args->theta, "constant platform orientation (rad)")
      ->check(within(pcr::SquarePath::kTheta))
      ->capture_default_str();
  cmd->add_option("--count", args->count, "poses on the path (default 40 square, 36 circle)")
      ->check(within(pcr::SquarePath::kNumPoses));
  cmd->add_option("--repeat", args->repeat, "ISO 9283 cycles per pose")
      ->check(within(pcr::AccuracyOptions::kRepeat))
      ->capture_default_str();
  auto* truth = cmd->add_option("--truth", args->truth,
                                "the virtual robot's true description (JSON, used as is)");
  cmd->add_option("--nominal", args->nominal,
                  "draw the truth from this description's uncertainties (default: --robot)")
      ->excludes(truth);
  cmd->add_option("--seed", args->seed, "seed of the truth draw and of the noise")
      ->capture_default_str();
  cmd->add_option("--noise-position", args->noise_position, "camera noise std on x and y (m)")
      ->check(within(pcr::VirtualRobotOptions::kNoisePosition))
      ->capture_default_str();
  cmd->add_option("--noise-angle", args->noise_angle, "camera noise std on theta (rad)")
      ->check(within(pcr::VirtualRobotOptions::kNoiseAngle))
      ->capture_default_str();
  cmd->add_option("--effects", args->effects,
                  "unmodelled effects of the virtual robot: misalignments, diameters, load, all "
                  "(pcr/calib/named_effects.hpp)")
      ->delimiter(',');
  cmd->add_option("--frame", args->frame,
                  "map camera measurements to W with the 'model' extrinsics (the paper's way, "
                  "valid for an identified model) or the virtual robot's 'true' ones (the error "
                  "of a nominal model's robot parameters alone)")
      ->capture_default_str();
  cmd->add_option("--strain-limit", args->strain_limit, "max bending strain of a commanded pose")
      ->check(within(pcr::kStrainLimitRange))
      ->capture_default_str();
  cmd->add_option("--poses", args->poses,
                  "write the commanded and attained poses (the --measured CSV format)");
  cmd->add_option("--measured", args->measured,
                  "compute the table from measured poses instead: CSV "
                  "pose,x_c,y_c,theta_c,x,y,theta (m, rad, in W)")
      ->excludes(truth);
  cmd->add_option("--format", args->format,
                  "text (Table 4, Markdown), json (summary + per pose), csv (per pose)")
      ->capture_default_str();
  cmd->add_option("--output", args->output, "output file (default: stdout)");
  args->solve.add_to(*cmd);
  cmd->callback([args] { run_accuracy(*args); });
}
