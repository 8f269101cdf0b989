// pcr sample: joint configurations by Poisson-disc sampling of the reachable joint box, or (with
// --design d-optimal) calibration configurations chosen for identifiability among Poisson-disc
// candidates (pcr/calib/sampling.hpp). With --validation-output, count + validation-count points
// are drawn together and split, so the calibration and validation sets are disjoint and spaced
// by the same radius; the D-optimal design keeps that validation set and chooses the calibration
// set among candidates away from it. A spatial robot file samples its joint box (default 0 to
// 10 mm per rod) as pcr/calib/spatial_sampling.hpp describes.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/spatial_sampling.hpp"
#include "pcr/csv_io.hpp"

namespace {

struct SampleArguments {
  std::string robot, output, validation_output, design = "poisson-disc";
  int count = pcr::kDefaultCalibrationCount;
  int validation_count = pcr::kDefaultValidationCount;
  int candidates = 0;
  std::uint64_t seed = 1;
  double min_distance = 0;
  double strain_limit = pcr::kDefaultStrainLimit;
  std::vector<double> box;
};

/// --box into box_min, box_max (each of n joints); nothing when not given.
template <class Vector>
void apply_box(const std::vector<double>& box, int n, Vector* box_min, Vector* box_max) {
  if (box.empty()) return;
  box_min->resize(n);
  box_max->resize(n);
  if (box.size() == 2) {
    box_min->setConstant(box[0]);
    box_max->setConstant(box[1]);
  } else if (box.size() == static_cast<std::size_t>(2 * n)) {
    for (int i = 0; i < n; ++i) {
      (*box_min)(i) = box[static_cast<std::size_t>(2 * i)];
      (*box_max)(i) = box[static_cast<std::size_t>(2 * i + 1)];
    }
  } else {
    throw pcr::InputError("--box: expected 2 numbers (min,max for every joint) or " +
                          std::to_string(2 * n) + " (min1,max1,...), got " +
                          std::to_string(box.size()));
  }
}

void write_spatial_configurations(const std::vector<pcr::SpatialJointVector>& configurations, int n,
                                  const std::string& path) {
  std::vector<std::string> header;
  for (int i = 0; i < n; ++i) header.push_back("q" + std::to_string(i + 1));
  std::string text = pcr::csv_line(header);
  for (const pcr::SpatialJointVector& q : configurations) {
    std::vector<std::string> row;
    for (int i = 0; i < n; ++i) row.push_back(pcr::format_double(q(i)));
    text += pcr::csv_line(row);
  }
  pcr::write_file_atomically(path, text);
}

void run_spatial_sample(const SampleArguments& args) {
  using namespace pcr;
  const SpatialRobotDescription robot = load_spatial_robot(args.robot);
  const int n = robot.params.num_rods;
  SpatialSamplingOptions options;
  options.count = args.count;
  options.design = parse_sampling_design(args.design);
  options.candidates = args.candidates;
  options.seed = args.seed;
  options.min_distance = args.min_distance;
  options.strain_limit = args.strain_limit;
  apply_box(args.box, n, &options.box_min, &options.box_max);
  const SpatialConfigurationSets sets = spatial_sample_configurations(
      robot, options, args.validation_output.empty() ? 0 : args.validation_count);
  OutputTransaction outputs;  // all or none
  write_spatial_configurations(sets.calibration, n, args.output);
  if (!args.validation_output.empty())
    write_spatial_configurations(sets.validation, n, args.validation_output);
  outputs.commit();
  std::cerr << "pcr sample: " << sets.calibration.size() << " configurations";
  if (options.design == SamplingDesign::kDOptimal) {
    std::cerr << " (d-optimal among " << sets.candidates.configurations.size()
              << " candidates pairwise >= " << sets.candidates.min_distance * 1e3
              << " mm; identifiable dimension " << sets.design.dimension << " of "
              << sets.design.parameters << ", rank " << sets.design.rank << ", log det "
              << sets.design.log_det << ")";
  }
  if (!args.validation_output.empty())
    std::cerr << " + " << sets.validation.size() << " validation";
  const SpatialSamplingResult& last =
      sets.spread.configurations.empty() ? sets.candidates : sets.spread;
  if (!sets.spread.configurations.empty()) {
    std::cerr << ", pairwise >= " << sets.spread.min_distance * 1e3 << " mm";
  }
  const AdmissionCounts& c = last.counts;
  std::cerr << "; " << c.candidates << " FK solves in the last run (" << c.rejected_fk
            << " without solution, " << c.rejected_strain << " over the strain limit, "
            << c.rejected_unstable << " unstable)\n";
}

void run_sample(const SampleArguments& args) {
  using namespace pcr;
  check_distinct_outputs(
      {{"--output", args.output}, {"--validation-output", args.validation_output}});
  if (cli::is_spatial_robot(args.robot)) {
    run_spatial_sample(args);
    return;
  }
  const RobotDescription robot = load_robot_or_default(args.robot);
  const int n = robot.params.num_limbs;
  SamplingOptions options;
  options.count = args.count;
  options.design = parse_sampling_design(args.design);
  options.candidates = args.candidates;
  options.seed = args.seed;
  options.min_distance = args.min_distance;
  options.strain_limit = args.strain_limit;
  apply_box(args.box, n, &options.box_min, &options.box_max);
  const ConfigurationSets sets = sample_configurations(
      robot, options, args.validation_output.empty() ? 0 : args.validation_count);
  OutputTransaction outputs;  // all or none
  write_configurations(sets.calibration, args.output);
  if (!args.validation_output.empty())
    write_configurations(sets.validation, args.validation_output);
  outputs.commit();
  std::cerr << "pcr sample: " << sets.calibration.size() << " configurations";
  if (options.design == SamplingDesign::kDOptimal) {
    std::cerr << " (d-optimal among " << sets.candidates.configurations.size()
              << " candidates pairwise >= " << sets.candidates.min_distance * 1e3
              << " mm; identifiable dimension " << sets.design.dimension << ", rank "
              << sets.design.rank << ", log det " << sets.design.log_det << ")";
  }
  if (!args.validation_output.empty())
    std::cerr << " + " << sets.validation.size() << " validation";
  const SamplingResult& last = sets.spread.configurations.empty() ? sets.candidates : sets.spread;
  if (!sets.spread.configurations.empty()) {
    std::cerr << ", pairwise >= " << sets.spread.min_distance * 1e3 << " mm";
  }
  std::cerr << "; " << last.candidates << " FK solves in the last run (" << last.rejected_fk
            << " without solution, " << last.rejected_strain << " over the strain limit)\n";
}

}  // namespace

void register_sample_command(CLI::App& app) {
  auto args = std::make_shared<SampleArguments>();
  CLI::App* cmd = app.add_subcommand(
      "sample",
      "joint configurations by Poisson-disc sampling (FK converged, strain-limited; spatial: "
      "stable too) or D-optimal design");
  pcr::cli::add_robot_option(*cmd, args->robot);
  using pcr::cli::within;
  cmd->add_option("--count", args->count, "calibration configurations")
      ->check(within(pcr::SamplingOptions::kCount))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "sampling seed")->capture_default_str();
  cmd->add_option("--output", args->output, "configurations CSV to write (q1,...,qn)")->required();
  cmd->add_option("--validation-output", args->validation_output,
                  "also write a disjoint validation set (drawn together, then split)");
  cmd->add_option("--validation-count", args->validation_count, "validation configurations")
      ->check(within(pcr::SamplingOptions::kCount))
      ->capture_default_str();
  cmd->add_option("--design", args->design,
                  "calibration configurations: poisson-disc (spread) or d-optimal (greedy max "
                  "log det of the scaled information on the identifiable subspace, among "
                  "Poisson-disc candidates; the validation set stays Poisson-disc)")
      ->check(CLI::IsMember({"poisson-disc", "d-optimal"}))
      ->capture_default_str();
  cmd->add_option("--candidates", args->candidates,
                  "d-optimal: Poisson-disc candidates to choose from (default: 10 x count)")
      ->check(within(pcr::SamplingOptions::kCandidates));
  cmd->add_option("--min-distance", args->min_distance,
                  "Poisson-disc radius in joint space (m; default: chosen from the count)")
      ->check(within(pcr::SamplingOptions::kMinDistance));
  cmd->add_option("--box", args->box,
                  "joint sub-box: min,max for all joints, or min1,max1,...,minn,maxn (m; spatial "
                  "robot: default 0,0.01)")
      ->delimiter(',')
      ->check(within(pcr::SamplingOptions::kBox));
  cmd->add_option("--strain-limit", args->strain_limit, "max bending strain")
      ->check(within(pcr::kStrainLimitRange))
      ->capture_default_str();
  cmd->callback([args] { run_sample(*args); });
}
