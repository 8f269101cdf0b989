// pcr: command-line tool for planar parallel continuum robots.
// Thin: parse the arguments, call the library, print.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "commands.hpp"

int main(int argc, char** argv) {
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
#endif
#ifdef PCR_HAS_VISION
  register_measure_command(app);
  register_render_command(app);
  register_camera_command(app);
#endif
  try {
    app.parse(argc, argv);  // the chosen subcommand runs inside parse()
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "pcr: error: " << e.what() << "\n";
    return 2;
  }
  return pcr::cli::exit_status();
}
