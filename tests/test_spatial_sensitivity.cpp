// The spatial sensitivity analysis (Table 2 in 3-D, pcr/calib/spatial_sensitivity.hpp): its
// derivatives against central differences of FK on the moved description, its table against
// the maxima of those differences over the grid, the extrinsics' known derivatives, the ranking
// and the refusal of bad options.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "pcr/calib/spatial_sensitivity.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/parameters.hpp"

namespace pcr {
namespace {

/// One discrete model for every solve (fixed RK4 steps, Newton to the tolerance): its derivative
/// is what the implicit function theorem gives exactly.
SolverOptions exact_fk() {
  SolverOptions fk;
  fk.rod_steps = 64;
  fk.tolerance = 1e-13;
  fk.chord_output_share = 0;
  fk.check_stability = false;
  return fk;
}

/// The reference robot seen through a tilted tracker and an offset marker, so that the measured
/// pose differs from the platform pose.
SpatialRobotDescription observed_robot() {
  SpatialRobotDescription robot = continuum_stewart_gough_description();
  robot.params.extrinsics.tracker.position = Eigen::Vector3d(0.1, -0.2, 0.9);
  robot.params.extrinsics.tracker.orientation =
      quaternion_of<double>((Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix());
  robot.params.extrinsics.marker.position = Eigen::Vector3d(0.02, 0.01, -0.03);
  robot.params.extrinsics.marker.orientation = quaternion_of<double>(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix());
  return robot;
}

/// The pose `kind` of the description moved by `d`, FK warm from `warm` (its own robot's).
SpatialPose<double> moved_pose(const SpatialRobotDescription& nominal, const std::vector<double>& d,
                               const SpatialJointVector& q, const SpatialForwardSolution& warm,
                               SpatialSensitivityPose kind) {
  const SpatialRobotParams<double> moved =
      spatial_with_deviations<double>(nominal.params, d.data());
  const SpatialForwardSolution fk = spatial_forward_kinematics(moved, q, warm, exact_fk());
  EXPECT_TRUE(fk.summary.converged());
  return kind == SpatialSensitivityPose::kPlatform
             ? fk.pose
             : moved.extrinsics.measurement_from_platform(fk.pose);
}

/// Central difference of the pose (position, then the rotation vector from `centre`) in
/// flat parameter k, step h.
Eigen::Matrix<double, 6, 1> central_difference(const SpatialRobotDescription& nominal,
                                               const SpatialJointVector& q,
                                               const SpatialForwardSolution& warm,
                                               SpatialSensitivityPose kind,
                                               const SpatialPose<double>& centre, int k, double h) {
  std::vector<double> d(static_cast<std::size_t>(num_spatial_parameters(nominal.params.num_rods)),
                        0.0);
  SpatialPose<double> side[2];
  for (int s = 0; s < 2; ++s) {
    d[static_cast<std::size_t>(k)] = s == 0 ? h : -h;
    side[s] = moved_pose(nominal, d, q, warm, kind);
  }
  Eigen::Matrix<double, 6, 1> out;
  out.head<3>() = (side[0].position - side[1].position) / (2 * h);
  out.tail<3>() = (internal::turn_from(centre.orientation, side[0].orientation) -
                   internal::turn_from(centre.orientation, side[1].orientation)) /
                  (2 * h);
  return out;
}

/// 1e-3 of the parameter's half-width: the truncation (h^2) and FK's rounding (1e-13 of the
/// scaled residual over h) both stay well below the tolerance.
double step_for(const SpatialRobotDescription& robot, int k) {
  return 1e-3 *
         spatial_half_width(*robot.uncertainty, spatial_parameter_id(k, robot.params.num_rods));
}

TEST(SpatialSensitivity, DerivativesMatchCentralDifferencesOfFk) {
  const SpatialRobotDescription robot = observed_robot();
  const int n = robot.params.num_rods, count = num_spatial_parameters(n);
  const std::vector<SpatialJointVector> grid =
      spatial_sensitivity_configurations(n, 1e-3, SpatialJointVector());
  double worst = 0;
  for (SpatialSensitivityPose kind :
       {SpatialSensitivityPose::kPlatform, SpatialSensitivityPose::kMeasured}) {
    for (std::size_t g : {std::size_t{0}, grid.size() / 2, grid.size() - 1}) {
      const SpatialJointVector& q = grid[g];
      Eigen::MatrixXd J;
      ASSERT_TRUE(spatial_pose_parameter_jacobian(robot, q, kind, &J, exact_fk()));
      ASSERT_EQ(J.rows(), 6);
      ASSERT_EQ(J.cols(), count);
      const SpatialForwardSolution warm = spatial_forward_kinematics(robot.params, q, exact_fk());
      ASSERT_TRUE(warm.summary.converged());
      const SpatialPose<double> centre =
          kind == SpatialSensitivityPose::kPlatform
              ? warm.pose
              : robot.params.extrinsics.measurement_from_platform(warm.pose);
      for (int k = 0; k < count; ++k) {
        const double h = step_for(robot, k);
        const Eigen::Matrix<double, 6, 1> difference =
            central_difference(robot, q, warm, kind, centre, k, h);
        // Relative to the column, with a floor of FK's rounding over the step (1e-15 m / h).
        const double error =
            (difference - J.col(k)).norm() / (J.col(k).norm() + difference.norm() + 1e-15 / h);
        worst = std::max(worst, error);
        EXPECT_LT(error, 1e-5) << spatial_parameter_name(spatial_parameter_id(k, n))
                               << " at configuration " << g << "\n  exact " << J.col(k).transpose()
                               << "\n  differences " << difference.transpose();
      }
    }
  }
  std::printf("worst relative derivative error over 2 x 3 configurations x %d parameters: %.3g\n",
              count, worst);
}

TEST(SpatialSensitivity, TableIsTheMaximumOverTheGridOfCentralDifferences) {
  // One kind (the free lengths of the six rods) over the whole 3^6 grid, from FK alone.
  const SpatialRobotDescription robot = continuum_stewart_gough_description();
  const int n = robot.params.num_rods;
  SpatialSensitivityOptions options;
  options.solver = exact_fk();
  const SpatialSensitivityReport report = spatial_sensitivity(robot, options);
  ASSERT_EQ(report.configurations.size(), 728u);
  ASSERT_EQ(report.rows.size(), static_cast<std::size_t>(kSpatialRodParameters));
  const int length = static_cast<int>(SpatialParameterKind::kLength);
  const SpatialSensitivityRow& row = report.rows[static_cast<std::size_t>(length)];
  EXPECT_EQ(row.kind, "l");
  double dz = 0, dposition = 0, dangle = 0;
  for (const SpatialJointVector& q : report.configurations) {
    const SpatialForwardSolution warm = spatial_forward_kinematics(robot.params, q, exact_fk());
    ASSERT_TRUE(warm.summary.converged());
    for (int i = 0; i < n; ++i) {
      const int k = spatial_parameter_index({SpatialParameterKind::kLength, i}, n);
      const Eigen::Matrix<double, 6, 1> d = central_difference(
          robot, q, warm, SpatialSensitivityPose::kPlatform, warm.pose, k, step_for(robot, k));
      dz = std::max(dz, std::abs(d(2)));
      dposition = std::max(dposition, d.head<3>().norm());
      dangle = std::max(dangle, d.tail<3>().norm());
    }
  }
  std::printf("l: |dz/dl| %.6g (table %.6g), |dpos/dl| %.6g (%.6g), |dphi/dl| %.6g (%.6g) rad/m\n",
              dz, row.dz, dposition, row.dposition, dangle, row.dangle);
  EXPECT_NEAR(row.dz, dz, 1e-5 * dz);
  EXPECT_NEAR(row.dposition, dposition, 1e-5 * dposition);
  EXPECT_NEAR(row.dangle, dangle, 1e-5 * dangle);
  EXPECT_NEAR(row.position_error, dposition * 0.5e-3, 1e-5 * dposition * 0.5e-3);
}

TEST(SpatialSensitivity, ExtrinsicsMoveTheMeasurementByKnownAmounts) {
  const SpatialRobotDescription robot = observed_robot();
  const int n = robot.params.num_rods;
  const SpatialJointVector q = SpatialJointVector::Constant(n, 4e-3);
  Eigen::MatrixXd J;
  ASSERT_TRUE(spatial_pose_parameter_jacobian(robot, q, SpatialSensitivityPose::kMeasured, &J));
  // ^S p_M = R_S^T (p_P + ... - p_S): moving the tracker by e_x in W moves it by -R_S^T e_x.
  const Eigen::Matrix3d R_S = robot.params.extrinsics.tracker.rotation();
  for (int a = 0; a < 3; ++a) {
    const int k = spatial_parameter_index(
        {static_cast<SpatialParameterKind>(static_cast<int>(SpatialParameterKind::kTrackerX) + a),
         -1},
        n);
    const Eigen::Vector3d expected = -R_S.transpose().col(a);
    const Eigen::Vector3d moved = J.block<3, 1>(0, k), turned = J.block<3, 1>(3, k);
    EXPECT_LT((moved - expected).norm(), 1e-12) << J.col(k).transpose();
    EXPECT_LT(turned.norm(), 1e-12);
  }
  // The platform pose does not see the extrinsics.
  ASSERT_TRUE(spatial_pose_parameter_jacobian(robot, q, SpatialSensitivityPose::kPlatform, &J));
  EXPECT_EQ(J.rightCols(kSpatialExtrinsicParameters).norm(), 0.0);

  // The table: a translation of the tracker moves the measured position by its own length; a
  // turn of the tracker or the marker turns the measurement by its own angle (R_hat = exp(-d)...).
  SpatialSensitivityOptions options;
  options.pose = SpatialSensitivityPose::kMeasured;
  const SpatialSensitivityReport report = spatial_sensitivity(robot, options);
  ASSERT_EQ(report.rows.size(),
            static_cast<std::size_t>(kSpatialRodParameters + kSpatialExtrinsicParameters));
  for (const SpatialSensitivityRow& row : report.rows) {
    if (row.kind == "tracker_x" || row.kind == "tracker_y" || row.kind == "tracker_z") {
      EXPECT_NEAR(row.dposition, 1.0, 1e-12) << row.kind;
      EXPECT_NEAR(row.dangle, 0.0, 1e-12) << row.kind;
      EXPECT_NEAR(row.position_error, 1e-3, 1e-15) << row.kind;
    }
    if (row.kind.find("_r") != std::string::npos &&
        (row.kind.rfind("tracker", 0) == 0 || row.kind.rfind("marker", 0) == 0)) {
      EXPECT_NEAR(row.dangle, 1.0, 1e-12) << row.kind;
      EXPECT_NEAR(row.orientation_error, 50e-3, 1e-14) << row.kind;
    }
  }
}

TEST(SpatialSensitivity, RankingFollowsTheValues) {
  SpatialSensitivityOptions options;
  options.pose = SpatialSensitivityPose::kMeasured;
  const SpatialSensitivityReport report =
      spatial_sensitivity(continuum_stewart_gough_description(), options);
  ASSERT_EQ(report.ranking.size(), report.rows.size());
  std::vector<int> sorted = report.ranking;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t r = 0; r < sorted.size(); ++r) EXPECT_EQ(sorted[r], static_cast<int>(r));
  for (std::size_t r = 0; r + 1 < report.ranking.size(); ++r) {
    const SpatialSensitivityRow& a = report.rows[static_cast<std::size_t>(report.ranking[r])];
    const SpatialSensitivityRow& b = report.rows[static_cast<std::size_t>(report.ranking[r + 1])];
    EXPECT_GE(a.position_error, b.position_error) << a.kind << " before " << b.kind;
    if (a.position_error == b.position_error) {
      EXPECT_GE(a.orientation_error, b.orientation_error) << a.kind << " before " << b.kind;
    }
  }
  // Every rod of the reference robot has the same intervals: error = sensitivity x half-width.
  for (const SpatialSensitivityRow& row : report.rows) {
    EXPECT_NEAR(row.position_error, row.dposition * row.half_width,
                1e-12 * row.dposition * row.half_width)
        << row.kind;
    EXPECT_NEAR(row.orientation_error, row.dangle * row.half_width,
                1e-12 * row.dangle * row.half_width)
        << row.kind;
    EXPECT_LE(std::max({row.dx, row.dy, row.dz}), row.dposition * (1 + 1e-15)) << row.kind;
  }
  std::printf("%s", spatial_sensitivity_table_text(report).c_str());
}

TEST(SpatialSensitivity, BadOptionsAreRefusedByName) {
  const SpatialRobotDescription robot = continuum_stewart_gough_description();
  const auto refused = [&](const SpatialSensitivityOptions& options, const std::string& field) {
    try {
      spatial_sensitivity(robot, options);
      ADD_FAILURE() << "accepted; expected a refusal naming " << field;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  SpatialSensitivityOptions options;
  options.step = 0;
  refused(options, "step");
  options.step = std::nan("");
  refused(options, "step");
  options = SpatialSensitivityOptions();
  options.centre = SpatialJointVector::Constant(3, 1e-3);
  refused(options, "centre");
  options.centre = SpatialJointVector::Constant(6, 5.0);  // mm typed as m
  refused(options, "centre");
  options = SpatialSensitivityOptions();
  options.solver.max_iterations = 0;
  refused(options, "max_iterations");
}

}  // namespace
}  // namespace pcr
