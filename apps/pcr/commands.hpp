#pragma once
// The `pcr` subcommands. Each lives in apps/pcr/<name>_command.cpp and registers itself on the
// top-level app; main.cpp calls every register_<name>_command().

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "pcr/csv_io.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/robot_io.hpp"
#ifdef PCR_HAS_VISION
#include "pcr/vision/tags.hpp"
#endif

void register_fk_command(CLI::App& app);
void register_ik_command(CLI::App& app);
void register_robot_command(CLI::App& app);
void register_workspace_command(CLI::App& app);
#ifdef PCR_HAS_CALIB
void register_simulate_command(CLI::App& app);
void register_sample_command(CLI::App& app);
void register_sensitivity_command(CLI::App& app);
void register_accuracy_command(CLI::App& app);
void register_demo_command(CLI::App& app);
void register_map_command(CLI::App& app);
#endif
#ifdef PCR_HAS_VISION
void register_measure_command(CLI::App& app);
void register_render_command(CLI::App& app);
void register_camera_command(CLI::App& app);
#endif
#if defined(PCR_HAS_VISION) && defined(PCR_HAS_CALIB)
void register_measure_poses_command(CLI::App& app);
#endif

namespace pcr::cli {

/// Exit status of the run: a subcommand sets 1 when some row failed (main exits with it).
inline int& exit_status() {
  static int status = 0;
  return status;
}

/// The library's range of an option (pcr/option_range.hpp): a finite number (CLI11's
/// PositiveNumber and NonNegativeNumber let NaN through) in [lo, hi], its bounds printed as the
/// library prints them; CLI11's error names the option, this the value and the range.
inline CLI::Validator within(const OptionRange& option) {
  const double lo = option.lo, hi = option.hi;
  const std::string range = "[" + OptionRange::text(lo) + ", " + OptionRange::text(hi) + "]" +
                            (*option.unit == '\0' ? "" : std::string(" ") + option.unit);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(value) || value < lo || value > hi) {
          return "'" + text + "' is outside " + range;
        }
        return std::string();
      },
      "in " + range);
}

/// Adds the common `--robot FILE` option (empty: the built-in default robot).
inline CLI::Option* add_robot_option(CLI::App& command, std::string& path) {
  return command.add_option("--robot", path,
                            "pcr-robot JSON description (default: the built-in femto-3pf)");
}

/// Whether `--robot PATH` names a spatial robot file ("kind": "spatial"); an empty path is the
/// built-in planar robot. `pcr fk` and `pcr ik` take either kind; the other commands load planar
/// robots only, and name the file and its kind when given a spatial one.
inline bool is_spatial_robot(const std::string& path) {
  return !path.empty() && load_robot_kind(path) == RobotKind::kSpatial;
}

/// The pose columns of a spatial robot's rows: the platform's position (m, in W) and its
/// orientation P -> W as a rotation vector (rad), angle times axis.
inline const std::vector<std::string>& spatial_pose_columns() {
  static const std::vector<std::string> columns = {"x", "y", "z", "rx", "ry", "rz"};
  return columns;
}

/// The robot of `--robot PATH` (the default robot when empty) for a command that solves inverse
/// kinematics (`what`): an InputError when it has more than 3 limbs.
inline RobotDescription load_robot_for_inverse(const std::string& path, const std::string& what) {
  RobotDescription robot = load_robot_or_default(path);
  const int n = robot.params.num_limbs;
  if (n > 3) {
    throw InputError((path.empty() ? std::string("<default robot>") : path) + ": robot '" +
                     robot.name + "' has " + std::to_string(n) + " limbs; " + what +
                     " solves inverse kinematics, a square problem only for 3 limbs (full pose) "
                     "and 2 limbs (x, y imposed, theta solved)");
  }
  return robot;
}

/// Reads a CSV table from `path`, or from stdin when it is empty or "-"; a table without rows is
/// an input error (nothing to do is more likely a wrong file than a wish).
inline CsvTable read_table(const std::string& path, const CsvReadOptions& options) {
  CsvTable table = path.empty() || path == "-" ? parse_csv(std::cin, "<stdin>", options)
                                               : read_csv(path, options);
  if (table.rows.empty()) throw InputError(table.source + ": no data rows");
  return table;
}

/// Refuses a table whose column `column` (0-based) holds a value outside [lo, hi], naming the
/// source, the line, the column and the value: a value no robot can mean (a typo, another unit)
/// is an input error, not a row to solve.
inline void check_column_range(const CsvTable& table, std::size_t column, double lo, double hi,
                               const std::string& unit) {
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const double value = table.rows[r][column];
    if (!(value >= lo && value <= hi)) {
      throw InputError(table.source + ":" + std::to_string(table.line_numbers[r]) + ": " +
                       table.columns[column] + " = " + format_double(value) + " " + unit +
                       " is outside [" + format_double(lo) + ", " + format_double(hi) + "] " +
                       unit);
    }
  }
}

/// Names q1, ..., qn.
inline std::vector<std::string> joint_names(int n) {
  std::vector<std::string> names;
  for (int i = 1; i <= n; ++i) names.push_back("q" + std::to_string(i));
  return names;
}

/// A table of joint values q1..qn (m) from `path` (read_table), each within [-1, 1] m.
inline CsvTable read_joint_table(const std::string& path, int n) {
  CsvReadOptions csv;
  csv.columns = joint_names(n);
  const CsvTable table = read_table(path, csv);
  for (std::size_t c = 0; c < csv.columns.size(); ++c) check_column_range(table, c, -1.0, 1.0, "m");
  return table;
}

/// `option`'s text: as many comma-separated finite numbers as `names`, which name them in errors.
inline std::vector<double> parse_list(const std::string& text,
                                      const std::vector<std::string>& names,
                                      const std::string& option) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0')
      throw InputError(option + ": '" + text + "' is not a list of numbers");
    if (out.size() < names.size() && !std::isfinite(value)) {
      throw InputError(option + ": " + names[out.size()] + " = " + item +
                       " is not a finite number");
    }
    out.push_back(value);
  }
  if (out.size() != names.size() || (!text.empty() && text.back() == ','))
    throw InputError(option + ": expected " + std::to_string(names.size()) + " numbers (" +
                     CLI::detail::join(names, ",") + "), got '" + text + "'");
  return out;
}

/// The solver options and platform load shared by fk and ik.
struct SolveArguments {
  std::string force;  ///< "fx,fy" in N
  double moment = 0;  ///< N m
  int steps = SolverOptions().rod_steps;

  void add_to(CLI::App& command) {
    command.add_option("--force", force, "external force on the platform, fx,fy (N, in W)");
    command.add_option("--moment", moment, "external moment on the platform, mz (N m)")
        ->check(within(PlatformLoad<double>::kMoment));
    command
        .add_option(
            "--steps", steps,
            "RK4 steps per rod (0: chosen from the solution's error estimate, 1 nm / 1 urad)")
        ->check(within(SolverOptions::kRodSteps))
        ->capture_default_str();
  }

  PlatformLoad<double> load() const {
    PlatformLoad<double> load;
    if (!force.empty()) {
      const std::string bad = "--force: expected two numbers fx,fy (N), got '" + force + "'";
      const std::size_t comma = force.find(',');
      if (comma == std::string::npos) throw InputError(bad);
      char* end = nullptr;
      const std::string fx = force.substr(0, comma), fy = force.substr(comma + 1);
      load.force.x() = std::strtod(fx.c_str(), &end);
      if (fx.empty() || *end != '\0') throw InputError(bad);
      load.force.y() = std::strtod(fy.c_str(), &end);
      if (fy.empty() || *end != '\0') throw InputError(bad);
    }
    load.moment = moment;
    if (!load.force.allFinite() || !std::isfinite(load.moment)) {
      throw InputError("--force/--moment: non-finite load");
    }
    return load;
  }

  SolverOptions options() const {
    SolverOptions options;
    options.rod_steps = steps;
    return options;
  }

  /// A spatial robot's file carries its load (gravity, external_force, external_moment): the
  /// planar load options would be ignored, so they are refused.
  void require_no_planar_load(const std::string& robot_path) const {
    if (!force.empty() || moment != 0) {
      throw InputError("--force/--moment: " + robot_path +
                       " is a spatial robot, whose file carries its load (external_force, "
                       "external_moment, gravity)");
    }
  }
};

/// What the rows of `pcr fk` and `pcr ik` are (pcr::SequenceMode).
struct RowsArguments {
  bool path = false;
  bool through_folds = false;

  void add_to(CLI::App& command) {
    CLI::Option* path_flag = command.add_flag(
        "--path", path,
        "the rows are a path the robot follows in this order: each row continued from the one "
        "before (fast along a smooth path). Default: each row on its own, in any order, on the "
        "branch connected to home (as a solve from home gives it)");
    command
        .add_flag("--through-folds", through_folds,
                  "with --path: where the branch ends at a fold, follow it through (the robot "
                  "snaps through), not from home")
        ->needs(path_flag);
  }

  SequenceMode mode() const { return path ? SequenceMode::kPath : SequenceMode::kIndependent; }
  void apply(SolverOptions& options) const { options.through_folds = through_folds; }
};

/// The row loop of `pcr fk` and `pcr ik`: `solve_row(row, out)` solves each input row (as its
/// RowsArguments say), adds its output fields to `out` and returns its summary;
/// the output is written atomically, each failed row is named on stderr by its input line, and the
/// exit status is 1 if any failed.
template <class SolveRow>
void solve_rows(const char* command, const CsvTable& table, const std::string& output,
                const std::vector<std::string>& header, SolveRow&& solve_row,
                bool allow_unstable = false) {
  OutputFile file(output);
  CsvWriter out(file.stream());
  for (const std::string& name : header) out.add(name);
  out.end_row();
  int failures = 0;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const SolverSummary summary = solve_row(table.rows[r], out);
    const SolveStatus status = summary.status;
    out.end_row();
    if (status == SolveStatus::kUnstable && !allow_unstable) {
      ++failures;
      std::cerr << command << ": " << table.source << ":" << table.line_numbers[r]
                << ": unstable: the equilibrium at this pose would not hold, and no stable one "
                   "was found (--allow-unstable accepts it)\n";
    } else if (status == SolveStatus::kInaccurate) {
      ++failures;
      std::cerr << command << ": " << table.source << ":" << table.line_numbers[r] << ": "
                << inaccuracy_message(summary) << "\n";
    } else if (status != SolveStatus::kConverged && status != SolveStatus::kUnstable) {
      ++failures;
      std::cerr << command << ": " << table.source << ":" << table.line_numbers[r]
                << ": not converged (" << to_string(status) << ")\n";
    }
  }
  out.flush();
  file.commit();
  if (failures > 0) {
    std::cerr << command << ": " << failures << " of " << table.rows.size()
              << " rows did not converge\n";
    exit_status() = 1;
  }
}

/// The columns after the inputs (and, for IK, the joints) of both commands' output.
inline const std::vector<std::string>& summary_columns() {
  static const std::vector<std::string> columns = {"converged",        "iterations", "residual",
                                                   "status",           "max_strain", "stable",
                                                   "stability_margin", "singularity"};
  return columns;
}

/// Adds the fields of summary_columns(); max_strain only for a valid equilibrium; stable is 1, 0
/// or empty when not checked (no valid equilibrium).
inline void add_summary_fields(const SolverSummary& s, bool valid, CsvWriter& out) {
  out.add(s.converged() ? 1 : 0);
  out.add(s.iterations);
  out.add(s.final_residual_norm);
  out.add(to_string(s.status));
  out.add(valid ? s.max_strain : std::nan(""));
  if (s.stability == Stability::kUnchecked) {
    out.add("");
  } else {
    out.add(s.stability == Stability::kStable ? 1 : 0);
  }
  out.add(s.stability_margin);
  out.add(s.singularity);
}

#ifdef PCR_HAS_VISION
/// The tag detector's options of the commands that measure tags in images (docs/vision.md, step 1).
inline void add_detector_options(CLI::App& command, vision::DetectorOptions& options) {
  command.add_option("--min-margin", options.min_decision_margin, "minimum decision margin")
      ->check(within(vision::DetectorOptions::kMinDecisionMargin))
      ->capture_default_str();
  command.add_option("--max-hamming", options.max_hamming, "maximum corrected bits")
      ->check(within(vision::DetectorOptions::kMaxHamming))
      ->capture_default_str();
}
#endif

}  // namespace pcr::cli
