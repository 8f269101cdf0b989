#include "pcr/calib/spatial_accuracy.hpp"

#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "accuracy_internal.hpp"
#include "pcr/csv_io.hpp"
#include "pcr/input_error.hpp"
#include "pcr/spatial/sequence.hpp"

namespace pcr {
namespace {

/// The rotation vector of a pose's orientation (rad), as pcr fk writes it.
Vector3<double> rotation_vector(const SpatialPose<double>& p) {
  return quaternion_log<double>(p.orientation);
}

std::string format_pose(const SpatialPose<double>& p) {
  const Vector3<double> r = rotation_vector(p);
  std::ostringstream s;
  s.precision(9);
  s << "(" << p.position.x() << " m, " << p.position.y() << " m, " << p.position.z() << " m, "
    << r.x() << " rad, " << r.y() << " rad, " << r.z() << " rad)";
  return s.str();
}

/// h^-1 (x) g for unit quaternions: the turn from h to g in h's frame.
Vector4<double> relative_turn(const Vector4<double>& h, const Vector4<double>& g) {
  const Vector4<double> conjugate(h[0], -h[1], -h[2], -h[3]);
  return quaternion_product<double>(conjugate, g);
}

Vector4<double> unit(const Vector4<double>& h) { return h / h.norm(); }

/// The Karcher mean of unit quaternions (see the header): R_bar <- R_bar exp(mean log(R_bar^T R_j))
/// from the first, until the mean turn is below rounding. Its deviations from the result go to
/// `deviations`. False when one reaches pi / 2 (the mean need not be unique) or the iteration
/// does not settle.
bool karcher_mean(const std::vector<Vector4<double>>& h, Vector4<double>& mean,
                  std::vector<Vector3<double>>& deviations) {
  constexpr int kMaxIterations = 50;
  constexpr double kSettled = 1e-15;  // rad
  const double n = static_cast<double>(h.size());
  mean = h.front();
  deviations.resize(h.size());
  for (int iter = 0; iter < kMaxIterations; ++iter) {
    Vector3<double> sum = Vector3<double>::Zero();
    double largest = 0;
    for (std::size_t j = 0; j < h.size(); ++j) {
      deviations[j] = quaternion_log<double>(relative_turn(mean, h[j]));
      sum += deviations[j];
      largest = std::max(largest, deviations[j].norm());
    }
    const Vector3<double> step = sum / n;
    if (step.norm() <= kSettled) return largest < 0.5 * M_PI;
    mean = unit(quaternion_product<double>(mean, quaternion_exp<double>(step)));
  }
  return false;
}

}  // namespace

std::vector<SpatialPose<double>> spatial_square_path(const SpatialSquarePath& spec) {
  return path_poses(spec, "spatial_square_path");
}

std::vector<SpatialPose<double>> spatial_circle_path(const SpatialCirclePath& spec) {
  return path_poses(spec, "spatial_circle_path");
}

std::vector<SpatialPose<double>> spatial_helix_path(const SpatialHelixPath& spec) {
  return path_poses(spec, "spatial_helix_path");
}

SpatialPathCommand spatial_command_path(const SpatialRobotParams<double>& model,
                                        const std::vector<SpatialPose<double>>& path,
                                        const SpatialPathCommandOptions& options) {
  if (path.empty()) throw InputError("spatial_command_path: the path has no pose");
  require_valid(options, "spatial_command_path");
  if (spatial_inverse_free_angles(model.num_rods) < 0) {
    throw InputError("spatial_command_path: the robot has " + std::to_string(model.num_rods) +
                     " rods; spatial inverse kinematics needs 3, 5 or 6");
  }
  SpatialInverseSequence sequence(model, options.solver, SequenceMode::kPath);
  if (options.start) {
    SpatialInverseSolution from;  // its factorisation is the forward problem's: none carried
    from.pose = options.start->pose;
    from.q = options.start->q;
    from.wrenches = options.start->wrenches;
    from.summary = options.start->summary;
    sequence.set_warm_start(from);
  }
  SpatialPathCommand command;
  command.poses.reserve(path.size());
  for (std::size_t k = 0; k < path.size(); ++k) {
    const SpatialPose<double>& pose = path[k];
    const auto fail = [&](const std::string& reason) {
      throw InputError("pose " + std::to_string(k) + " " + format_pose(pose) + ": " + reason);
    };
    if (!internal::spatial_pose_valid(pose)) fail("not finite (or a zero quaternion)");
    const SpatialInverseSolution& solution = sequence.solve(pose);
    const SolverSummary& s = solution.summary;
    if (s.status == SolveStatus::kUnstable) {
      fail("the only equilibrium inverse kinematics found would not hold (unstable)");
    }
    if (s.status == SolveStatus::kInaccurate) fail(inaccuracy_message(s));
    if (!s.converged()) {
      fail("no inverse-kinematics solution (solver status " + std::string(to_string(s.status)) +
           "): outside the workspace");
    }
    if (!(s.max_strain <= options.strain_limit)) {
      std::ostringstream msg;
      msg << "bending strain " << s.max_strain << " exceeds the limit " << options.strain_limit;
      fail(msg.str());
    }
    command.q.push_back(solution.q);
    command.poses.push_back(solution.pose);
    command.max_strain.push_back(s.max_strain);
    command.iterations.push_back(s.iterations);
    command.residual_evaluations.push_back(s.residual_evaluations);
  }
  return command;
}

SpatialAccuracyEvaluation evaluate_on_spatial_virtual_robot(
    const SpatialRobotParams<double>& model, SpatialVirtualRobot& robot,
    const std::vector<SpatialPose<double>>& path, const SpatialAccuracyOptions& options) {
  require_valid(options, "evaluate_on_spatial_virtual_robot");
  if (robot.truth().params.num_rods != model.num_rods) {
    throw InputError("evaluate_on_spatial_virtual_robot: the model has " +
                     std::to_string(model.num_rods) + " rods, the virtual robot " +
                     std::to_string(robot.truth().params.num_rods));
  }
  SpatialAccuracyEvaluation out;
  out.command = spatial_command_path(model, path, options.command);
  out.commanded = out.command.poses;  // free angles solved (3 or 5 rods)
  const SpatialExtrinsics<double>& map = options.frame == AttainedFrame::kTrueExtrinsics
                                             ? robot.truth().params.extrinsics
                                             : model.extrinsics;
  out.attained = calib_internal::attained_in_cycles<SpatialPose<double>>(
      options.repeat, path.size(),
      [&](std::size_t k, SpatialPose<double>* attained) -> std::string {
        const SpatialVirtualMeasurement m = robot.measure(out.command.q[k]);
        if (!m.ok) return to_string(m.summary.status);
        *attained = map.platform_from_measurement(m.measured);
        return "";
      },
      [&](std::size_t k) { return format_pose(path[k]); });
  out.iso = iso9283_spatial(out.commanded, out.attained);
  return out;
}

SpatialIso9283Result iso9283_spatial(
    const std::vector<SpatialPose<double>>& commanded,
    const std::vector<std::vector<SpatialPose<double>>>& attained) {
  if (commanded.size() != attained.size()) {
    throw InputError("iso9283_spatial: " + std::to_string(commanded.size()) +
                     " commanded poses but " + std::to_string(attained.size()) +
                     " sets of attained poses");
  }
  if (commanded.empty()) throw InputError("iso9283_spatial: no commanded pose");
  SpatialIso9283Result result;
  result.poses.reserve(commanded.size());
  std::vector<Vector4<double>> orientations;
  std::vector<Vector3<double>> deviations;
  std::vector<double> l;
  for (std::size_t k = 0; k < commanded.size(); ++k) {
    const SpatialPose<double>& c = commanded[k];
    const std::vector<SpatialPose<double>>& a = attained[k];
    if (a.size() < 2) {
      throw InputError("iso9283_spatial: pose " + std::to_string(k) + " has " +
                       std::to_string(a.size()) +
                       " attained poses (at least 2 needed, ISO 9283 asks for 30)");
    }
    if (!internal::spatial_pose_valid(c)) {
      throw InputError("iso9283_spatial: commanded pose " + std::to_string(k) +
                       " is not finite (or has a zero quaternion)");
    }
    const double n = static_cast<double>(a.size());
    SpatialIso9283Pose p;
    p.commanded = c;
    p.cycles = static_cast<int>(a.size());
    Vector3<double> sum = Vector3<double>::Zero();
    orientations.resize(a.size());
    for (std::size_t j = 0; j < a.size(); ++j) {
      if (!internal::spatial_pose_valid(a[j])) {
        throw InputError("iso9283_spatial: attained pose " + std::to_string(j) + " of pose " +
                         std::to_string(k) + " is not finite (or has a zero quaternion)");
      }
      sum += a[j].position;
      orientations[j] = unit(a[j].orientation);
    }
    p.barycentre.position = sum / n;
    if (!karcher_mean(orientations, p.barycentre.orientation, deviations)) {
      throw InputError("iso9283_spatial: the attained orientations of pose " + std::to_string(k) +
                       " spread over pi / 2 or more about their mean: no unique mean");
    }
    p.ap_xyz = p.barycentre.position - c.position;
    p.ap_p = p.ap_xyz.norm();
    p.ap_abc = quaternion_log<double>(relative_turn(unit(c.orientation), p.barycentre.orientation));
    l.resize(a.size());
    double sl = 0;
    Vector3<double> v_abc = Vector3<double>::Zero();
    for (std::size_t j = 0; j < a.size(); ++j) {
      l[j] = (a[j].position - p.barycentre.position).norm();
      sl += l[j];
      v_abc += deviations[j].cwiseProduct(deviations[j]);
    }
    p.l_bar = sl / n;
    double vl = 0;
    for (double lj : l) vl += (lj - p.l_bar) * (lj - p.l_bar);
    p.s_l = std::sqrt(vl / (n - 1));
    p.rp_l = p.l_bar + 3.0 * p.s_l;
    p.s_abc = (v_abc / (n - 1)).cwiseSqrt();
    p.rp_abc = 3.0 * p.s_abc;
    result.poses.push_back(p);
  }
  using Pose = SpatialIso9283Pose;
  result.ap_p = iso9283_stats(result.poses, [](const Pose& p) { return p.ap_p; });
  result.rp_l = iso9283_stats(result.poses, [](const Pose& p) { return p.rp_l; });
  for (int i = 0; i < 3; ++i) {
    result.ap_abc_abs[i] =
        iso9283_stats(result.poses, [i](const Pose& p) { return std::abs(p.ap_abc[i]); });
    result.rp_abc[i] = iso9283_stats(result.poses, [i](const Pose& p) { return p.rp_abc[i]; });
  }
  return result;
}

std::string iso9283_spatial_table_markdown(
    const std::vector<std::pair<std::string, const SpatialIso9283Result*>>& rows) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(4);
  // One row per statistic: three angles' max, mean and min would make 17 columns.
  // "abs(AP_a)": a '|' inside a cell would break the Markdown table.
  s << "| path | statistic | max | mean | min |\n|---|---|---:|---:|---:|\n";
  const auto row = [&](const std::string& path, const char* name, const Iso9283Stats& st,
                       double scale) {
    s << "| " << path << " | " << name << " | " << st.max * scale << " | " << st.mean * scale
      << " | " << st.min * scale << " |\n";
  };
  static constexpr const char* kAp[3] = {"abs(AP_a) (mrad)", "abs(AP_b) (mrad)",
                                         "abs(AP_c) (mrad)"};
  static constexpr const char* kRp[3] = {"RP_a (+- mrad)", "RP_b (+- mrad)", "RP_c (+- mrad)"};
  for (const auto& [name, r] : rows) {
    row(name, "AP_p (um)", r->ap_p, 1e6);
    for (int i = 0; i < 3; ++i) row(name, kAp[i], r->ap_abc_abs[i], 1e3);
    row(name, "RP_l (um)", r->rp_l, 1e6);
    for (int i = 0; i < 3; ++i) row(name, kRp[i], r->rp_abc[i], 1e3);
  }
  return s.str();
}

std::string iso9283_spatial_poses_csv(const SpatialIso9283Result& result) {
  std::string out = csv_line(
      {"pose",   "x_c",    "y_c",    "z_c",    "rx_c", "ry_c", "rz_c", "x_bar", "y_bar", "z_bar",
       "rx_bar", "ry_bar", "rz_bar", "cycles", "ap_x", "ap_y", "ap_z", "ap_p",  "ap_a",  "ap_b",
       "ap_c",   "l_bar",  "s_l",    "rp_l",   "s_a",  "s_b",  "s_c",  "rp_a",  "rp_b",  "rp_c"});
  std::vector<std::string> fields;
  const auto add = [&](const auto& vector) {
    for (int i = 0; i < vector.size(); ++i) fields.push_back(format_double(vector[i]));
  };
  for (std::size_t k = 0; k < result.poses.size(); ++k) {
    const SpatialIso9283Pose& p = result.poses[k];
    fields.assign({std::to_string(k)});
    add(p.commanded.position);
    add(rotation_vector(p.commanded));
    add(p.barycentre.position);
    add(rotation_vector(p.barycentre));
    fields.push_back(std::to_string(p.cycles));
    add(p.ap_xyz);
    fields.push_back(format_double(p.ap_p));
    add(p.ap_abc);
    for (double v : {p.l_bar, p.s_l, p.rp_l}) fields.push_back(format_double(v));
    add(p.s_abc);
    add(p.rp_abc);
    out += csv_line(fields);
  }
  return out;
}

std::string iso9283_spatial_json(
    const std::vector<std::pair<std::string, const SpatialIso9283Result*>>& rows) {
  using nlohmann::ordered_json;
  const auto stats = [](const Iso9283Stats& s) {
    return ordered_json{{"max", s.max}, {"mean", s.mean}, {"min", s.min}};
  };
  const auto per_axis = [&](const std::array<Iso9283Stats, 3>& s) {
    return ordered_json{{"a", stats(s[0])}, {"b", stats(s[1])}, {"c", stats(s[2])}};
  };
  const auto vector = [](const Vector3<double>& v) { return ordered_json{v.x(), v.y(), v.z()}; };
  const auto pose = [&](const SpatialPose<double>& p) {
    return ordered_json{{"position", vector(p.position)},
                        {"rotation_vector", vector(rotation_vector(p))}};
  };
  ordered_json paths = ordered_json::array();
  for (const auto& [name, r] : rows) {
    ordered_json poses = ordered_json::array();
    for (const SpatialIso9283Pose& p : r->poses) {
      poses.push_back(ordered_json{{"commanded", pose(p.commanded)},
                                   {"barycentre", pose(p.barycentre)},
                                   {"cycles", p.cycles},
                                   {"ap_xyz", vector(p.ap_xyz)},
                                   {"ap_p", p.ap_p},
                                   {"ap_abc", vector(p.ap_abc)},
                                   {"rp_l", p.rp_l},
                                   {"rp_abc", vector(p.rp_abc)}});
    }
    paths.push_back(ordered_json{{"path", name},
                                 {"units", "m, rad"},
                                 {"ap_p", stats(r->ap_p)},
                                 {"ap_abc_abs", per_axis(r->ap_abc_abs)},
                                 {"rp_l", stats(r->rp_l)},
                                 {"rp_abc", per_axis(r->rp_abc)},
                                 {"poses", poses}});
  }
  return ordered_json{{"iso9283_spatial", paths}}.dump(2) + "\n";
}

}  // namespace pcr
