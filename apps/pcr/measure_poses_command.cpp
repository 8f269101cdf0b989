// pcr measure-poses: a spatial robot's tag board in camera images -> the measured poses ^S T_M of
// the spatial calibration dataset (docs/vision.md, "Spatial robots").
#if defined(PCR_HAS_VISION) && defined(PCR_HAS_CALIB)
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/spatial/robot_io.hpp"
#include "pcr/vision/tag_board.hpp"

void register_measure_poses_command(CLI::App& app) {
  struct Args {
    std::string robot, board, camera, input, output, covariance;
    pcr::vision::MeasureOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "measure-poses",
      "measure a spatial robot's platform pose (its tag board in camera images): the dataset "
      "pcr_calibrate reads");
  cmd->add_option("--robot", args->robot, "spatial pcr-robot JSON (its rods: the joints per row)")
      ->required();
  cmd->add_option("--board", args->board, "tag board JSON (pcr-tag-board)")->required();
  cmd->add_option("--camera", args->camera, "OpenCV camera YAML")->required();
  cmd->add_option("--input", args->input,
                  "CSV q1,...,qn,image: the joints (m) and the image of each configuration, in "
                  "measurement order (a relative image path is relative to this file's directory)")
      ->required();
  cmd->add_option("--output", args->output, "spatial dataset CSV to write (q1..qn,x,y,z,rx,ry,rz)")
      ->required();
  cmd->add_option("--covariance", args->covariance,
                  "CSV to write: each row's pose covariance (dp in S, dtheta in M) and fit");
  pcr::cli::add_detector_options(*cmd, args->options.detector);
  cmd->callback([args]() {
    using namespace pcr;
    using namespace pcr::vision;
    namespace fs = std::filesystem;
    check_distinct_outputs({{"--output", args->output}, {"--covariance", args->covariance}});
    if (!cli::is_spatial_robot(args->robot)) {
      throw InputError(args->robot +
                       ": a planar robot; pcr measure-poses measures a spatial robot's platform "
                       "(pcr measure measures a planar robot)");
    }
    const SpatialRobotDescription robot = load_spatial_robot(args->robot);
    const int n = robot.params.num_rods;
    const TagBoard board = load_tag_board(args->board);
    const CameraModel camera = load_camera(args->camera);
    CsvReadOptions csv;
    csv.columns = cli::joint_names(n);
    csv.text_columns = {"image"};
    const CsvTable table = cli::read_table(args->input, csv);
    for (int i = 0; i < n; ++i) cli::check_column_range(table, i, -1.0, 1.0, "m");
    const fs::path base = args->input == "-" ? fs::path() : fs::path(args->input).parent_path();

    SpatialDataset data;
    data.num_joints = n;
    std::vector<BoardPose> poses;
    for (std::size_t r = 0; r < table.rows.size(); ++r) {
      const fs::path named = table.texts[r][0];
      const std::string image_path = (named.is_absolute() ? named : base / named).string();
      const std::string row = table.source + ":" + std::to_string(table.line_numbers[r]) + ": ";
      GrayImage image;
      try {
        image = read_image(image_path);
        check_image_size(camera, image.width, image.height, args->camera, image_path);
      } catch (const InputError& e) {
        throw InputError(row + e.what());
      }
      poses.push_back(measure_board_pose(image, row + image_path, board, camera, args->options));
      SpatialJointVector q(n);
      for (int i = 0; i < n; ++i) q(i) = table.rows[r][static_cast<std::size_t>(i)];
      data.add(q, poses.back().camera_T_board);
    }

    OutputTransaction outputs;  // the dataset and the covariances: all or none
    write_spatial_dataset(data, args->output);
    if (!args->covariance.empty()) {
      OutputFile file(args->covariance);
      CsvWriter out(file.stream());
      const char* const names[6] = {"x", "y", "z", "rx", "ry", "rz"};
      for (const std::string& q : cli::joint_names(n)) out.add(q);
      for (int a = 0; a < 6; ++a)
        for (int b = a; b < 6; ++b) out.add(std::string("cov_") + names[a] + "_" + names[b]);
      out.add("corner_rms_px");
      out.add("tags_seen");
      out.end_row();
      for (std::size_t r = 0; r < poses.size(); ++r) {
        for (int i = 0; i < n; ++i) out.add(data.q[r](i));
        for (int a = 0; a < 6; ++a)
          for (int b = a; b < 6; ++b) out.add(poses[r].covariance(a, b));
        out.add(poses[r].corner_rms_px);
        out.add(static_cast<int>(poses[r].detections.size()));
        out.end_row();
      }
      out.flush();
      file.commit();
    }
    outputs.commit();
    Eigen::Matrix<double, 6, 1> variance = Eigen::Matrix<double, 6, 1>::Zero();
    for (const BoardPose& p : poses) variance += p.covariance.diagonal() / poses.size();
    const Eigen::Matrix<double, 6, 1> sigma = variance.cwiseSqrt();
    std::printf(
        "%zu poses; predicted sigma (rms over the rows): position %.2f, %.2f, %.2f um (in S), "
        "rotation %.1f, %.1f, %.1f urad (in M)\n",
        poses.size(), sigma[0] * 1e6, sigma[1] * 1e6, sigma[2] * 1e6, sigma[3] * 1e6,
        sigma[4] * 1e6, sigma[5] * 1e6);
    std::cout << "wrote " << args->output << "\n";
  });
}
#endif
