// pcr camera: intrinsics and distortion from chessboard images (cv::calibrateCamera).
#ifdef PCR_HAS_VISION
#include <cstdio>
#include <iostream>
#include <tuple>

#include "commands.hpp"
#include "pcr/vision/camera.hpp"

void register_camera_command(CLI::App& app) {
  struct Args {
    std::string board = "9x6", output;
    double square = 0.005;
    std::vector<std::string> images;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "camera",
      "calibrate a camera from chessboard images; writes OpenCV YAML (camera_matrix, ...)");
  cmd->add_option("--board", args->board, "inner corners COLSxROWS of the chessboard")
      ->capture_default_str();
  cmd->add_option("--square", args->square, "chessboard square edge (m)")
      ->check(pcr::cli::within(pcr::vision::ChessboardSpec::kSquare))
      ->capture_default_str();
  cmd->add_option("--images", args->images, "images of the board (at least 3, varied poses)")
      ->required();
  cmd->add_option("--output", args->output, "camera YAML to write")->required();
  cmd->callback([args]() {
    pcr::vision::ChessboardSpec spec;
    std::tie(spec.cols, spec.rows) = pcr::vision::parse_board_size(args->board, "--board");
    spec.square_m = args->square;
    const auto result = pcr::vision::calibrate_camera(args->images, spec);
    pcr::vision::save_camera(result.camera, args->output, result.rms_px);
    for (const auto& r : result.rejected)
      std::cerr << "pcr camera: no board found in " << r << "\n";
    std::cout << "calibrated from " << result.used.size() << " images, rms " << result.rms_px
              << " px; fx " << result.camera.K(0, 0) << " fy " << result.camera.K(1, 1) << " cx "
              << result.camera.K(0, 2) << " cy " << result.camera.K(1, 2) << "; wrote "
              << args->output << "\n";
  });
}
#endif
