// pcr: command-line tool for planar parallel continuum robots.
// Thin: parse the arguments, call the library, print.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>

#include "commands.hpp"

namespace {

#ifdef PCR_FULL_TOOL
/// Replaces this process by PCR_FULL_TOOL, found next to it, with the same arguments (argv[0]
/// included, so its usage names what the user typed). Returns only when it cannot.
void exec_full_tool(char** argv) {
  std::error_code error;
  std::filesystem::path path = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    path.replace_filename(PCR_FULL_TOOL);
    ::execv(path.c_str(), argv);
  }
  std::cerr << "pcr: warning: cannot run " << (error ? PCR_FULL_TOOL : path.string()) << ": "
            << (error ? error.message() : std::strerror(errno))
            << "; only the kinematics subcommands are available\n";
}
#endif

/// Every subcommand's --output: an empty name (`--output ""`, an unset shell variable) is neither
/// stdout (that is "-") nor the current directory; refused by CLI11, naming the option.
void refuse_empty_outputs(CLI::App& app) {
  for (CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; })) {
    CLI::Option* output = command->get_option_no_throw("--output");
    if (output == nullptr) continue;
    const std::string what = command->get_name() == "demo"
                                 ? "give the report directory"
                                 : "give a file name, or - for stdout where the command allows it";
    output->check(CLI::Validator(
        [what](std::string& value) {
          return value.empty() ? "the option is empty: " + what : std::string();
        },
        "", "NONEMPTY"));
  }
}

/// A first argument that is no option nor subcommand: named, with the subcommands (CLI11 would
/// only say that a subcommand is required).
void refuse_unknown_subcommand(CLI::App& app, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return;
  const std::string name = argv[1];
  std::string names;
  bool known = false;
  for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; })) {
    known = known || command->check_name(name);
    names += (names.empty() ? "" : ", ") + command->get_name();
  }
  if (!known) {
    throw CLI::ValidationError("unknown subcommand '" + name + "'; the subcommands are " + names);
  }
}

}  // namespace

int main(int argc, char** argv) {
  pcr::protect_inputs();  // no output of a command is written over one of its inputs
  CLI::App app{"pcr: planar parallel continuum robots (kinematics, description files)"};
  app.require_subcommand(1);
  register_fk_command(app);
  register_ik_command(app);
  register_robot_command(app);
  register_workspace_command(app);
#ifdef PCR_HAS_CALIB
  register_simulate_command(app);
  register_sample_command(app);
  register_sensitivity_command(app);
  register_accuracy_command(app);
  register_demo_command(app);
  register_map_command(app);
#endif
#ifdef PCR_HAS_VISION
  register_measure_command(app);
  register_render_command(app);
  register_camera_command(app);
#endif
#if defined(PCR_HAS_VISION) && defined(PCR_HAS_CALIB)
  register_measure_poses_command(app);
#endif
#ifdef PCR_FULL_TOOL
  // This binary links only pcr::io, so its subcommands start in milliseconds; the others, and the
  // help that lists them all, are the full tool's, which loads Ceres, OpenCV and what they need.
  const bool own_command = argc > 1 && !app.get_subcommands([&](const CLI::App* command) {
                                             return command->check_name(argv[1]);
                                           })
                                            .empty();
  if (!own_command) exec_full_tool(argv);
#endif
  refuse_empty_outputs(app);
  try {
    refuse_unknown_subcommand(app, argc, argv);
    app.parse(argc, argv);  // the chosen subcommand runs inside parse()
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "pcr: error: " << e.what() << "\n";
    return 2;
  }
  // What went to stdout must have arrived (a full disk, a closed pipe, > /dev/full).
  std::cout.flush();
  if (!std::cout) {
    std::cerr << "pcr: error: <stdout>: write error\n";
    return 2;
  }
  return pcr::cli::exit_status();
}
