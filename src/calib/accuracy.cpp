#include "pcr/calib/accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "accuracy_internal.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/input_error.hpp"

namespace pcr {
namespace {

std::string format_pose(const Pose2<double>& p) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << p.x << " m, " << p.y << " m, " << p.theta << " rad)";
  return s.str();
}

bool finite(const Pose2<double>& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

}  // namespace

std::vector<Pose2<double>> square_path(const SquarePath& spec) {
  return path_poses(spec, "square_path");
}

std::vector<Pose2<double>> circle_path(const CirclePath& spec) {
  return path_poses(spec, "circle_path");
}

std::vector<Pose2<double>> load_path_csv(const std::string& path) {
  CsvReadOptions options;
  options.columns = {"x", "y", "theta"};
  const CsvTable table = read_csv(path, options);
  if (table.rows.empty()) throw InputError(path + ": the path has no pose (columns x,y,theta)");
  std::vector<Pose2<double>> poses;
  poses.reserve(table.rows.size());
  for (const CsvRow row : table.rows) poses.push_back({row[0], row[1], row[2]});
  return poses;
}

PathCommand command_path(const RobotParams<double>& model, const std::vector<Pose2<double>>& path,
                         const PathCommandOptions& options) {
  if (path.empty()) throw InputError("command_path: the path has no pose");
  require_valid(options, "command_path");
  if (model.num_limbs < 2 || model.num_limbs > 3) {
    throw InputError("command_path: the robot has " + std::to_string(model.num_limbs) +
                     " limbs; inverse kinematics needs 2 or 3");
  }
  PathCommand command;
  command.poses.reserve(path.size());
  InverseSolution previous;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const Pose2<double>& pose = path[k];
    if (!finite(pose)) {
      throw InputError("pose " + std::to_string(k) + " " + format_pose(pose) + ": not finite");
    }
    const PathStep step = k == 0 ? path_ik_start(model, pose, options.step)
                                 : path_ik_step(model, pose, previous, options.step);
    if (!step.ok()) {
      std::ostringstream msg;
      msg << "pose " << k << " " << format_pose(pose) << ": ";
      const SolverSummary& s = step.solution.summary;
      switch (step.status) {
        case PathPoseStatus::kNoSolution:
          msg << "no inverse-kinematics solution (solver status " << to_string(s.status)
              << "): outside the workspace";
          break;
        case PathPoseStatus::kOutOfRange: {
          msg << "a joint leaves its stroke: q = (";
          for (int i = 0; i < step.solution.q.size(); ++i) {
            msg << (i ? ", " : "") << step.solution.q(i);
          }
          msg << ") m";
          break;
        }
        case PathPoseStatus::kInaccurate:
          msg << inaccuracy_message(s);
          break;
        case PathPoseStatus::kStrainExceeded:
          msg << "bending strain " << s.max_strain << " exceeds the limit "
              << options.step.strain_limit;
          break;
        case PathPoseStatus::kOk:
          break;
      }
      throw InputError(msg.str());
    }
    previous = step.solution;
    command.q.push_back(step.solution.q);
    command.poses.push_back(step.solution.pose);
    command.max_strain.push_back(step.solution.summary.max_strain);
    command.iterations.push_back(step.iterations);
  }
  return command;
}

Iso9283Result iso9283(const std::vector<Pose2<double>>& commanded,
                      const std::vector<std::vector<Pose2<double>>>& attained) {
  if (commanded.size() != attained.size()) {
    throw InputError("iso9283: " + std::to_string(commanded.size()) + " commanded poses but " +
                     std::to_string(attained.size()) + " sets of attained poses");
  }
  if (commanded.empty()) throw InputError("iso9283: no commanded pose");
  Iso9283Result result;
  result.poses.reserve(commanded.size());
  for (std::size_t k = 0; k < commanded.size(); ++k) {
    const Pose2<double>& c = commanded[k];
    const std::vector<Pose2<double>>& a = attained[k];
    if (a.size() < 2) {
      throw InputError("iso9283: pose " + std::to_string(k) + " has " + std::to_string(a.size()) +
                       " attained poses (at least 2 needed, ISO 9283 asks for 30)");
    }
    if (!finite(c))
      throw InputError("iso9283: commanded pose " + std::to_string(k) + " is not finite");
    const double n = static_cast<double>(a.size());
    Iso9283Pose p;
    p.commanded = c;
    p.cycles = static_cast<int>(a.size());
    // Angles are averaged as deviations from the command, so a path near +-pi does not wrap.
    double sx = 0, sy = 0, sdt = 0;
    for (std::size_t j = 0; j < a.size(); ++j) {
      if (!finite(a[j])) {
        throw InputError("iso9283: attained pose " + std::to_string(j) + " of pose " +
                         std::to_string(k) + " is not finite");
      }
      sx += a[j].x;
      sy += a[j].y;
      sdt += wrap_angle(a[j].theta - c.theta);
    }
    p.barycentre = Pose2<double>{sx / n, sy / n, c.theta + sdt / n};
    p.ap_x = p.barycentre.x - c.x;
    p.ap_y = p.barycentre.y - c.y;
    p.ap_p = std::hypot(p.ap_x, p.ap_y);
    p.ap_theta = sdt / n;
    std::vector<double> l(a.size());
    double sl = 0;
    for (std::size_t j = 0; j < a.size(); ++j) {
      l[j] = std::hypot(a[j].x - p.barycentre.x, a[j].y - p.barycentre.y);
      sl += l[j];
    }
    p.l_bar = sl / n;
    double vl = 0, vt = 0;
    for (std::size_t j = 0; j < a.size(); ++j) {
      vl += (l[j] - p.l_bar) * (l[j] - p.l_bar);
      const double dt = wrap_angle(a[j].theta - p.barycentre.theta);
      vt += dt * dt;
    }
    p.s_l = std::sqrt(vl / (n - 1));
    p.rp_l = p.l_bar + 3.0 * p.s_l;
    p.s_theta = std::sqrt(vt / (n - 1));
    p.rp_theta = 3.0 * p.s_theta;
    result.poses.push_back(p);
  }
  result.ap_p = iso9283_stats(result.poses, [](const Iso9283Pose& p) { return p.ap_p; });
  result.ap_theta_abs =
      iso9283_stats(result.poses, [](const Iso9283Pose& p) { return std::abs(p.ap_theta); });
  result.rp_l = iso9283_stats(result.poses, [](const Iso9283Pose& p) { return p.rp_l; });
  result.rp_theta = iso9283_stats(result.poses, [](const Iso9283Pose& p) { return p.rp_theta; });
  return result;
}

AccuracyEvaluation evaluate_on_virtual_robot(const RobotParams<double>& model, VirtualRobot& robot,
                                             const std::vector<Pose2<double>>& path,
                                             const AccuracyOptions& options) {
  require_valid(options, "evaluate_on_virtual_robot");
  if (robot.truth().params.num_limbs != model.num_limbs) {
    throw InputError("evaluate_on_virtual_robot: the model has " + std::to_string(model.num_limbs) +
                     " limbs, the virtual robot " + std::to_string(robot.truth().params.num_limbs));
  }
  AccuracyEvaluation out;
  out.command = command_path(model, path, options.command);
  // For n = 2 theta is solved for by IK: the commanded orientation is the solved one.
  out.commanded = out.command.poses;
  const Extrinsics<double>& map = options.frame == AttainedFrame::kTrueExtrinsics
                                      ? robot.truth().params.extrinsics
                                      : model.extrinsics;
  out.attained = calib_internal::attained_in_cycles<Pose2<double>>(
      options.repeat, path.size(),
      [&](std::size_t k, Pose2<double>* attained) -> std::string {
        const VirtualMeasurement m = robot.measure(out.command.q[k]);
        if (!m.ok) return to_string(m.summary.status);
        *attained = map.platform_from_measurement(m.measured);
        return "";
      },
      [&](std::size_t k) { return format_pose(path[k]); });
  out.iso = iso9283(out.commanded, out.attained);
  return out;
}

MeasuredPath load_measured_csv(const std::string& path) {
  CsvReadOptions options;
  options.columns = {"pose", "x_c", "y_c", "theta_c", "x", "y", "theta"};
  const CsvTable table = read_csv(path, options);
  if (table.rows.empty()) throw InputError(path + ": no measured pose");
  MeasuredPath out;
  std::vector<int> first_line;
  const double tol_length = 1e-12, tol_angle = 1e-12;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const CsvRow row = table.rows[r];
    const std::string where = path + ":" + std::to_string(table.line_numbers[r]);
    const double index = row[0];
    if (!(index >= 0) || index != std::floor(index) || index > 1e7) {
      std::ostringstream msg;
      msg << where << ": column 'pose': expected a pose index (integer >= 0), got " << index;
      throw InputError(msg.str());
    }
    const std::size_t k = static_cast<std::size_t>(index);
    const Pose2<double> commanded{row[1], row[2], row[3]};
    if (k >= out.commanded.size()) {
      out.commanded.resize(k + 1, Pose2<double>{NAN, NAN, NAN});
      out.attained.resize(k + 1);
      first_line.resize(k + 1, 0);
    }
    if (first_line[k] == 0) {
      out.commanded[k] = commanded;
      first_line[k] = table.line_numbers[r];
    } else {
      const Pose2<double>& c = out.commanded[k];
      if (std::abs(c.x - commanded.x) > tol_length || std::abs(c.y - commanded.y) > tol_length ||
          std::abs(wrap_angle(c.theta - commanded.theta)) > tol_angle) {
        throw InputError(where + ": pose " + std::to_string(k) + " commanded as " +
                         format_pose(commanded) + " but as " + format_pose(c) + " on line " +
                         std::to_string(first_line[k]));
      }
    }
    out.attained[k].push_back(Pose2<double>{row[4], row[5], row[6]});
  }
  for (std::size_t k = 0; k < out.commanded.size(); ++k) {
    if (first_line[k] == 0) {
      throw InputError(path + ": pose index " + std::to_string(k) +
                       " has no row (indices must run from 0 to " +
                       std::to_string(out.commanded.size() - 1) + ")");
    }
  }
  return out;
}

std::string measured_to_csv(const std::vector<Pose2<double>>& commanded,
                            const std::vector<std::vector<Pose2<double>>>& attained) {
  if (commanded.size() != attained.size()) {
    throw InputError("measured_to_csv: commanded and attained sizes differ");
  }
  std::string out = csv_line({"pose", "x_c", "y_c", "theta_c", "x", "y", "theta"});
  for (std::size_t k = 0; k < commanded.size(); ++k) {
    const Pose2<double>& c = commanded[k];
    for (const Pose2<double>& a : attained[k]) {
      out += csv_line({std::to_string(k), format_double(c.x), format_double(c.y),
                       format_double(c.theta), format_double(a.x), format_double(a.y),
                       format_double(a.theta)});
    }
  }
  return out;
}

std::string iso9283_table_markdown(
    const std::vector<std::pair<std::string, const Iso9283Result*>>& rows) {
  std::ostringstream s;
  s << std::fixed;
  // "abs(AP_theta)": a '|' inside a cell would break the Markdown table.
  s << "| path | AP_p max (um) | AP_p mean (um) | AP_p min (um) | abs(AP_theta) max (mrad) | "
       "abs(AP_theta) mean (mrad) | abs(AP_theta) min (mrad) | RP_l max (um) | "
       "RP_theta max (mrad) |\n";
  s << "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& [name, r] : rows) {
    s << "| " << name << std::setprecision(4) << " | " << r->ap_p.max * 1e6 << " | "
      << r->ap_p.mean * 1e6 << " | " << r->ap_p.min * 1e6 << " | " << r->ap_theta_abs.max * 1e3
      << " | " << r->ap_theta_abs.mean * 1e3 << " | " << r->ap_theta_abs.min * 1e3 << " | "
      << r->rp_l.max * 1e6 << " | +-" << r->rp_theta.max * 1e3 << " |\n";
  }
  return s.str();
}

std::string iso9283_poses_csv(const Iso9283Result& result) {
  std::string out =
      csv_line({"pose", "x_c", "y_c", "theta_c", "x_bar", "y_bar", "theta_bar", "cycles", "ap_x",
                "ap_y", "ap_p", "ap_theta", "l_bar", "s_l", "rp_l", "s_theta", "rp_theta"});
  for (std::size_t k = 0; k < result.poses.size(); ++k) {
    const Iso9283Pose& p = result.poses[k];
    out += csv_line({std::to_string(k), format_double(p.commanded.x), format_double(p.commanded.y),
                     format_double(p.commanded.theta), format_double(p.barycentre.x),
                     format_double(p.barycentre.y), format_double(p.barycentre.theta),
                     std::to_string(p.cycles), format_double(p.ap_x), format_double(p.ap_y),
                     format_double(p.ap_p), format_double(p.ap_theta), format_double(p.l_bar),
                     format_double(p.s_l), format_double(p.rp_l), format_double(p.s_theta),
                     format_double(p.rp_theta)});
  }
  return out;
}

std::string iso9283_json(const std::vector<std::pair<std::string, const Iso9283Result*>>& rows) {
  using nlohmann::ordered_json;
  const auto stats = [](const Iso9283Stats& s) {
    return ordered_json{{"max", s.max}, {"mean", s.mean}, {"min", s.min}};
  };
  ordered_json paths = ordered_json::array();
  for (const auto& [name, r] : rows) {
    ordered_json poses = ordered_json::array();
    for (const Iso9283Pose& p : r->poses) {
      poses.push_back(
          ordered_json{{"commanded", {p.commanded.x, p.commanded.y, p.commanded.theta}},
                       {"barycentre", {p.barycentre.x, p.barycentre.y, p.barycentre.theta}},
                       {"cycles", p.cycles},
                       {"ap_p", p.ap_p},
                       {"ap_theta", p.ap_theta},
                       {"rp_l", p.rp_l},
                       {"rp_theta", p.rp_theta}});
    }
    paths.push_back(ordered_json{{"path", name},
                                 {"units", "m, rad"},
                                 {"ap_p", stats(r->ap_p)},
                                 {"ap_theta_abs", stats(r->ap_theta_abs)},
                                 {"rp_l", stats(r->rp_l)},
                                 {"rp_theta", stats(r->rp_theta)},
                                 {"poses", poses}});
  }
  return ordered_json{{"iso9283", paths}}.dump(2) + "\n";
}

}  // namespace pcr
