#include "pcr/calib/sensitivity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "pcr/calib/cost.hpp"
#include "pcr/csv_io.hpp"

namespace pcr {
namespace {

/// Table 2 rows: kind name and the per-limb parameter it differentiates; E and D sum all limbs.
/// A kind the paper's table does not have is a row when the robot declares it uncertain.
struct RowSpec {
  const char* name;
  ParameterKind kind;
  bool all_limbs;
  bool when_declared = false;
};

const RowSpec kRows[] = {
    {"E", ParameterKind::kYoungModulus, true},
    {"D", ParameterKind::kDiameter, true},
    {"d", ParameterKind::kDiameter, false},
    {"alpha", ParameterKind::kAlpha, false},
    {"beta", ParameterKind::kBeta, false},
    {"gamma", ParameterKind::kGamma, false},
    {"l", ParameterKind::kLength, false},
    {"A_x", ParameterKind::kAx, false},
    {"A_y", ParameterKind::kAy, false},
    {"B_x", ParameterKind::kBx, false},
    {"B_y", ParameterKind::kBy, false},
    {"precurvature", ParameterKind::kPrecurvature, false, true},
};

std::string format_q(const JointVector& q) {
  std::ostringstream out;
  out << "(";
  for (int i = 0; i < q.size(); ++i) out << (i ? ", " : "") << q(i);
  out << ")";
  return out.str();
}

}  // namespace

std::vector<JointVector> sensitivity_configurations(const RobotParams<double>& robot, double step,
                                                    const JointVector& centre) {
  const int n = robot.num_limbs;
  std::string error;
  if (!SensitivityOptions::kStep.check(step, &error)) throw InputError("sensitivity: " + error);
  JointVector c(n);
  if (centre.size() == 0) {
    for (int i = 0; i < n; ++i) c(i) = 0.5 * (robot.limb(i).q_min + robot.limb(i).q_max);
  } else if (centre.size() != n) {
    throw InputError("sensitivity: centre has " + std::to_string(centre.size()) +
                     " joints, robot has " + std::to_string(n));
  } else {
    c = centre;
  }
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    if (!limb.within_stroke(c(i))) {
      std::ostringstream msg;
      msg << "sensitivity: centre: joint q" << i + 1 << " at " << c(i)
          << " m is outside its stroke q_range [" << limb.q_min << ", " << limb.q_max << "] m";
      throw InputError(msg.str());
    }
  }
  std::vector<JointVector> out;
  int total = 1;
  for (int i = 0; i < n; ++i) total *= 3;
  for (int index = 0; index < total; ++index) {
    JointVector q = c;
    int rest = index;
    bool is_centre = true;
    for (int i = 0; i < n; ++i) {
      const int offset = rest % 3 - 1;
      rest /= 3;
      q(i) += offset * step;
      is_centre = is_centre && offset == 0;
    }
    if (!is_centre) out.push_back(q);
  }
  return out;
}

bool pose_parameter_jacobian(const RobotParams<double>& robot, const ForwardSolution& solution,
                             PoseParameterJacobian* jacobian, const PlatformLoad<double>& load,
                             const SolverOptions& solver) {
  static_assert(kMaxPoseJacobianColumns == kMaxParameters + kLoadParameters,
                "the load columns are the calibration's");
  const int count = num_parameters(robot.num_limbs);
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor, 3, kMaxParameters> flat(3, count);
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> by_load;
  if (!platform_pose_jacobian(robot, load, solution, solver, flat.data(), by_load.data())) {
    return false;
  }
  jacobian->resize(3, count + kLoadParameters);
  jacobian->leftCols(count) = flat;
  jacobian->rightCols(kLoadParameters) = by_load;
  return true;
}

bool platform_parameter_jacobian(const RobotParams<double>& robot, const JointVector& q,
                                 Eigen::MatrixXd* jacobian, const PlatformLoad<double>& load,
                                 const SolverOptions& solver) {
  const ForwardSolution fk = forward_kinematics(robot, q, solver, load);
  if (!is_equilibrium(fk.summary)) return false;
  PoseParameterJacobian J;
  if (!pose_parameter_jacobian(robot, fk, &J, load, solver)) return false;
  *jacobian = J.leftCols(kLimbParameters * robot.num_limbs);
  return true;
}

SensitivityReport sensitivity_analysis(const RobotDescription& description,
                                       const SensitivityOptions& options) {
  const RobotParams<double>& robot = description.params;
  const int n = robot.num_limbs;
  require_valid(options, "sensitivity");
  SensitivityReport report;
  report.step = options.step;
  report.configurations = sensitivity_configurations(robot, options.step, options.centre);

  RobotUncertainty u;
  if (description.uncertainty) u = *description.uncertainty;
  if (u.limbs.size() != static_cast<std::size_t>(n))
    u.limbs.assign(static_cast<std::size_t>(n), u.global);

  std::vector<RowSpec> specs;
  for (const RowSpec& spec : kRows) {
    SensitivityRow row;
    row.kind = spec.name;
    if (spec.all_limbs) {
      row.half_width = limb_parameter(u.global, spec.kind);
    } else {
      for (LimbUncertainty& limb : u.limbs)
        row.half_width = std::max(row.half_width, limb_parameter(limb, spec.kind));
    }
    if (spec.when_declared && !(row.half_width > 0)) continue;
    specs.push_back(spec);
    report.rows.push_back(row);
  }

  Eigen::MatrixXd J;
  for (const JointVector& q : report.configurations) {
    if (!platform_parameter_jacobian(robot, q, &J, options.load, options.solver)) {
      throw std::runtime_error("sensitivity: robot '" + description.name +
                               "': no forward-kinematics solution at q = " + format_q(q) +
                               " (a smaller step keeps the configurations closer to the centre)");
    }
    for (std::size_t r = 0; r < report.rows.size(); ++r) {
      const RowSpec& spec = specs[r];
      SensitivityRow& row = report.rows[r];
      const int k = static_cast<int>(spec.kind);
      auto accumulate = [&](const Eigen::Vector3d& d, double h) {
        row.dx = std::max(row.dx, std::abs(d(0)));
        row.dy = std::max(row.dy, std::abs(d(1)));
        row.dtheta = std::max(row.dtheta, std::abs(d(2)));
        row.position_error = std::max(row.position_error, std::hypot(d(0), d(1)) * h);
        row.orientation_error = std::max(row.orientation_error, std::abs(d(2)) * h);
      };
      if (spec.all_limbs) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (int i = 0; i < n; ++i) sum += J.col(i * kLimbParameters + k);
        accumulate(sum, row.half_width);
      } else {
        for (int i = 0; i < n; ++i) {
          accumulate(J.col(i * kLimbParameters + k),
                     limb_parameter(u.limbs[static_cast<std::size_t>(i)], spec.kind));
        }
      }
    }
  }

  report.ranking.resize(report.rows.size());
  for (std::size_t r = 0; r < report.rows.size(); ++r) report.ranking[r] = static_cast<int>(r);
  std::stable_sort(report.ranking.begin(), report.ranking.end(), [&](int a, int b) {
    const SensitivityRow& ra = report.rows[static_cast<std::size_t>(a)];
    const SensitivityRow& rb = report.rows[static_cast<std::size_t>(b)];
    if (ra.position_error != rb.position_error) return ra.position_error > rb.position_error;
    return ra.orientation_error > rb.orientation_error;
  });
  return report;
}

std::string sensitivity_table_text(const SensitivityReport& report) {
  std::ostringstream out;
  char line[256];
  out << "Sensitivity of the platform pose to the parameters (Table 2), max over "
      << report.configurations.size() << " configurations (3^n grid, step " << report.step * 1e3
      << " mm, minus its centre) and the limbs; SI units\n";
  int width = 6;  // the paper's names; a longer one widens the column
  for (const SensitivityRow& row : report.rows)
    width = std::max(width, static_cast<int>(row.kind.size()));
  std::snprintf(line, sizeof(line), "%-*s %12s %12s %12s\n", width, "param", "|dx/dp|", "|dy/dp|",
                "|dtheta/dp|");
  out << line;
  for (const SensitivityRow& row : report.rows) {
    std::snprintf(line, sizeof(line), "%-*s %12.3g %12.3g %12.3g\n", width, row.kind.c_str(),
                  row.dx, row.dy, row.dtheta);
    out << line;
  }
  out << "\nRanking: pose error each parameter can cause = sensitivity x uncertainty half-width\n";
  std::snprintf(line, sizeof(line), "%-4s %-*s %14s %14s %14s\n", "rank", width, "param",
                "half-width", "e_p (um)", "e_theta (urad)");
  out << line;
  int rank = 1;
  for (int r : report.ranking) {
    const SensitivityRow& row = report.rows[static_cast<std::size_t>(r)];
    std::snprintf(line, sizeof(line), "%-4d %-*s %14.3g %14.4g %14.4g\n", rank++, width,
                  row.kind.c_str(), row.half_width, row.position_error * 1e6,
                  row.orientation_error * 1e6);
    out << line;
  }
  return out.str();
}

std::string sensitivity_csv(const SensitivityReport& report) {
  std::string out = csv_line({"param", "dx_dp", "dy_dp", "dtheta_dp", "half_width",
                              "position_error_m", "orientation_error_rad", "rank"});
  for (std::size_t r = 0; r < report.rows.size(); ++r) {
    const SensitivityRow& row = report.rows[r];
    const auto it = std::find(report.ranking.begin(), report.ranking.end(), static_cast<int>(r));
    out += csv_line({row.kind, format_double(row.dx), format_double(row.dy),
                     format_double(row.dtheta), format_double(row.half_width),
                     format_double(row.position_error), format_double(row.orientation_error),
                     std::to_string(it - report.ranking.begin() + 1)});
  }
  return out;
}

std::string sensitivity_json(const SensitivityReport& report) {
  nlohmann::ordered_json root;
  root["step_m"] = report.step;
  nlohmann::ordered_json configs = nlohmann::ordered_json::array();
  for (const JointVector& q : report.configurations) {
    configs.push_back(std::vector<double>(q.data(), q.data() + q.size()));
  }
  root["configurations"] = configs;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const SensitivityRow& row : report.rows) {
    nlohmann::ordered_json j;
    j["param"] = row.kind;
    j["dx_dp"] = row.dx;
    j["dy_dp"] = row.dy;
    j["dtheta_dp"] = row.dtheta;
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
