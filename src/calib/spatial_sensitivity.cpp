#include "pcr/calib/spatial_sensitivity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/csv_io.hpp"

namespace pcr {
namespace {

std::string format_q(const SpatialJointVector& q) {
  std::ostringstream out;
  out << "(";
  for (Eigen::Index i = 0; i < q.size(); ++i) out << (i ? ", " : "") << q(i);
  out << ")";
  return out.str();
}

const char* pose_name(SpatialSensitivityPose pose) {
  return pose == SpatialSensitivityPose::kMeasured ? "measured" : "platform";
}

}  // namespace

std::vector<SpatialJointVector> spatial_sensitivity_configurations(
    int num_rods, double step, const SpatialJointVector& centre) {
  std::string error;
  if (!SpatialSensitivityOptions::kStep.check(step, &error)) {
    throw InputError("spatial sensitivity: " + error);
  }
  if (num_rods < 1 || num_rods > kMaxSpatialRods) {
    throw InputError("spatial sensitivity: invalid number of rods " + std::to_string(num_rods));
  }
  SpatialJointVector c = SpatialJointVector::Constant(
      num_rods, 0.5 * (kSpatialDefaultJointMin + kSpatialDefaultJointMax));
  if (centre.size() != 0) {
    if (centre.size() != num_rods) {
      throw InputError("spatial sensitivity: centre has " + std::to_string(centre.size()) +
                       " joints, robot has " + std::to_string(num_rods) + " rods");
    }
    c = centre;
  }
  std::vector<SpatialJointVector> out;
  int total = 1;
  for (int i = 0; i < num_rods; ++i) total *= 3;
  for (int index = 0; index < total; ++index) {
    SpatialJointVector q = c;
    int rest = index;
    bool is_centre = true;
    for (int i = 0; i < num_rods; ++i) {
      const int offset = rest % 3 - 1;
      rest /= 3;
      q(i) += offset * step;
      is_centre = is_centre && offset == 0;
    }
    if (!is_centre) out.push_back(q);
  }
  return out;
}

bool spatial_pose_parameter_jacobian(const SpatialRobotDescription& robot,
                                     const SpatialJointVector& q, SpatialSensitivityPose pose,
                                     Eigen::MatrixXd* jacobian, const SolverOptions& solver) {
  SpatialRobotDescription nominal = robot;
  // With identity extrinsics the measured marker pose is ^W T_P itself.
  if (pose == SpatialSensitivityPose::kPlatform) nominal.params.extrinsics = {};
  const std::vector<double> zero(
      static_cast<std::size_t>(num_spatial_parameters(robot.params.num_rods)), 0.0);
  // The measured pose is the residual's reference only: its derivative does not depend on it.
  Eigen::Matrix<double, 6, 1> residual;
  if (!spatial_measurement_jacobian(nominal, zero, q, SpatialPose<double>(), 1.0, 1.0, &residual,
                                    jacobian, solver) ||
      !jacobian->allFinite()) {
    return false;
  }
  // The residual's rotation rows differentiate phi = log(R_hat), R_hat the pose itself (the
  // reference passed is the identity): d phi = J_r(phi)^-1 d theta for a turn d theta of R_hat in
  // its own frame. Back to d theta, the rotation vector of R_hat0^T R_hat (a frame-free angle):
  // J_r(phi) = I - (1 - cos a) / a^2 [phi]x + (a - sin a) / a^3 [phi]x^2, a = |phi|.
  const Eigen::Vector3d phi = residual.tail<3>();
  const double a = phi.norm();
  Eigen::Matrix3d hat;
  hat << 0, -phi(2), phi(1), phi(2), 0, -phi(0), -phi(1), phi(0), 0;
  const double c1 = a < 1e-4 ? 0.5 - a * a / 24 : (1 - std::cos(a)) / (a * a);
  const double c2 = a < 1e-4 ? 1.0 / 6 - a * a / 120 : (a - std::sin(a)) / (a * a * a);
  const Eigen::Matrix3d right = Eigen::Matrix3d::Identity() - c1 * hat + c2 * hat * hat;
  jacobian->bottomRows<3>() = (right * jacobian->bottomRows<3>()).eval();
  // The extrinsics do not move the platform (here they moved the identity's measurement).
  if (pose == SpatialSensitivityPose::kPlatform) {
    jacobian->rightCols(kSpatialExtrinsicParameters).setZero();
  }
  return true;
}

SpatialSensitivityReport spatial_sensitivity(const SpatialRobotDescription& description,
                                             const SpatialSensitivityOptions& options) {
  require_valid(options, "spatial sensitivity");
  const int n = description.params.num_rods;
  SpatialSensitivityReport report;
  report.step = options.step;
  report.pose = options.pose;
  report.configurations = spatial_sensitivity_configurations(n, options.step, options.centre);

  const SpatialUncertainty u =
      description.uncertainty ? *description.uncertainty : SpatialUncertainty{};
  const bool measured = options.pose == SpatialSensitivityPose::kMeasured;
  const int kinds = kSpatialRodParameters + (measured ? kSpatialExtrinsicParameters : 0);
  for (int k = 0; k < kinds; ++k) {
    SpatialSensitivityRow row;
    row.kind = kSpatialParameterKinds[k].name;
    const auto kind = static_cast<SpatialParameterKind>(k);
    if (k < kSpatialRodParameters) {
      for (int i = 0; i < n; ++i) {
        row.half_width = std::max(row.half_width, spatial_half_width(u, {kind, i}));
      }
    } else {
      row.half_width = spatial_half_width(u, {kind, -1});
    }
    report.rows.push_back(row);
  }

  const auto start = std::chrono::steady_clock::now();
  Eigen::MatrixXd J;
  for (const SpatialJointVector& q : report.configurations) {
    if (!spatial_pose_parameter_jacobian(description, q, options.pose, &J, options.solver)) {
      throw std::runtime_error("spatial sensitivity: robot '" + description.name +
                               "': no forward-kinematics solution at q = " + format_q(q) +
                               " (a smaller step keeps the configurations closer to the centre)");
    }
    for (int c = 0; c < J.cols(); ++c) {
      const SpatialParameterId id = spatial_parameter_id(c, n);
      const int k = static_cast<int>(id.kind);
      if (k >= kinds) continue;
      SpatialSensitivityRow& row = report.rows[static_cast<std::size_t>(k)];
      const Eigen::Vector3d dp = J.block<3, 1>(0, c), dphi = J.block<3, 1>(3, c);
      const double h = spatial_half_width(u, id);
      row.dx = std::max(row.dx, std::abs(dp(0)));
      row.dy = std::max(row.dy, std::abs(dp(1)));
      row.dz = std::max(row.dz, std::abs(dp(2)));
      row.dposition = std::max(row.dposition, dp.norm());
      row.dangle = std::max(row.dangle, dphi.norm());
      row.position_error = std::max(row.position_error, dp.norm() * h);
      row.orientation_error = std::max(row.orientation_error, dphi.norm() * h);
    }
  }
  report.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  report.ranking.resize(report.rows.size());
  for (std::size_t r = 0; r < report.rows.size(); ++r) report.ranking[r] = static_cast<int>(r);
  std::stable_sort(report.ranking.begin(), report.ranking.end(), [&](int a, int b) {
    const SpatialSensitivityRow& ra = report.rows[static_cast<std::size_t>(a)];
    const SpatialSensitivityRow& rb = report.rows[static_cast<std::size_t>(b)];
    if (ra.position_error != rb.position_error) return ra.position_error > rb.position_error;
    return ra.orientation_error > rb.orientation_error;
  });
  return report;
}

std::string spatial_sensitivity_table_text(const SpatialSensitivityReport& report) {
  std::ostringstream out;
  char line[256];
  const bool measured = report.pose == SpatialSensitivityPose::kMeasured;
  out << "Sensitivity of the "
      << (measured ? "measured marker pose ^S T_M (position in S)" : "platform pose ^W T_P")
      << " to the parameters (Table 2 in 3-D), max over " << report.configurations.size()
      << " configurations (3^n grid, step " << report.step * 1e3
      << " mm, minus its centre) and the rods; SI units (m, rad, Pa)\n";
  std::snprintf(line, sizeof(line), "%-10s %11s %11s %11s %11s %11s\n", "param", "|dx/dp|",
                "|dy/dp|", "|dz/dp|", "|dpos/dp|", "|dphi/dp|");
  out << line;
  for (const SpatialSensitivityRow& row : report.rows) {
    std::snprintf(line, sizeof(line), "%-10s %11.3g %11.3g %11.3g %11.3g %11.3g\n",
                  row.kind.c_str(), row.dx, row.dy, row.dz, row.dposition, row.dangle);
    out << line;
  }
  out << "\nRanking: pose error each parameter can cause = sensitivity x uncertainty half-width\n";
  std::snprintf(line, sizeof(line), "%-4s %-10s %12s %14s %14s\n", "rank", "param", "half-width",
                "e_p (um)", "e_phi (urad)");
  out << line;
  int rank = 1;
  for (int r : report.ranking) {
    const SpatialSensitivityRow& row = report.rows[static_cast<std::size_t>(r)];
    std::snprintf(line, sizeof(line), "%-4d %-10s %12.3g %14.4g %14.4g\n", rank++, row.kind.c_str(),
                  row.half_width, row.position_error * 1e6, row.orientation_error * 1e6);
    out << line;
  }
  return out.str();
}

std::string spatial_sensitivity_csv(const SpatialSensitivityReport& report) {
  std::string out = csv_line({"param", "dx_dp", "dy_dp", "dz_dp", "dposition_dp", "dangle_dp",
                              "half_width", "position_error_m", "orientation_error_rad", "rank"});
  for (std::size_t r = 0; r < report.rows.size(); ++r) {
    const SpatialSensitivityRow& row = report.rows[r];
    const auto it = std::find(report.ranking.begin(), report.ranking.end(), static_cast<int>(r));
    out += csv_line({row.kind, format_double(row.dx), format_double(row.dy), format_double(row.dz),
                     format_double(row.dposition), format_double(row.dangle),
                     format_double(row.half_width), format_double(row.position_error),
                     format_double(row.orientation_error),
                     std::to_string(it - report.ranking.begin() + 1)});
  }
  return out;
}

std::string spatial_sensitivity_json(const SpatialSensitivityReport& report) {
  nlohmann::ordered_json root;
  root["step_m"] = report.step;
  root["pose"] = pose_name(report.pose);
  nlohmann::ordered_json configs = nlohmann::ordered_json::array();
  for (const SpatialJointVector& q : report.configurations) {
    configs.push_back(std::vector<double>(q.data(), q.data() + q.size()));
  }
  root["configurations"] = configs;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const SpatialSensitivityRow& row : report.rows) {
    nlohmann::ordered_json j;
    j["param"] = row.kind;
    j["dx_dp"] = row.dx;
    j["dy_dp"] = row.dy;
    j["dz_dp"] = row.dz;
    j["dposition_dp"] = row.dposition;
    j["dangle_dp"] = row.dangle;
    j["half_width"] = row.half_width;
    j["position_error_m"] = row.position_error;
    j["orientation_error_rad"] = row.orientation_error;
    rows.push_back(j);
  }
  root["table"] = rows;
  nlohmann::ordered_json ranking = nlohmann::ordered_json::array();
  for (int r : report.ranking) ranking.push_back(report.rows[static_cast<std::size_t>(r)].kind);
  root["ranking"] = ranking;
  return root.dump(2) + "\n";
}

}  // namespace pcr
