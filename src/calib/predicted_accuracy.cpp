// Predicted accuracy of a calibrated robot (see predicted_accuracy.hpp): the parameter covariance,
// its reader, and its propagation to the platform pose at a solved configuration.

#include "pcr/calib/predicted_accuracy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>

#include "pcr/calib/cost.hpp"
#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"

namespace pcr {
namespace {

using nlohmann::json;

/// Symmetry and positive semi-definiteness are judged on the correlation matrix, whose entries
/// are O(1) whatever the units: rounding in the calibration's V S^-2 V^T is ~1e-16 of them.
constexpr double kSymmetryTolerance = 1e-9;
constexpr double kEigenvalueTolerance = 1e-9;

/// A value as the file holds it (the shortest text that reads back the same; NaN is null).
std::string number(double value) { return json(value).dump(); }

std::string entry(Eigen::Index row, Eigen::Index col) {
  return "covariance.matrix[" + std::to_string(row) + "][" + std::to_string(col) + "]";
}

/// The limb count and whether the load follows, from the number of names; -1 when no robot has
/// that many parameters.
int limbs_of(std::size_t size, bool* load) {
  const int count = static_cast<int>(size);
  for (int with_load = 0; with_load < 2; ++with_load) {
    const int rest = count - kExtrinsicParameters - 3 * with_load;
    if (rest >= kLimbParameters && rest % kLimbParameters == 0 &&
        rest / kLimbParameters <= kMaxLimbs) {
      *load = with_load == 1;
      return rest / kLimbParameters;
    }
  }
  return -1;
}

/// A report written before rods had a precurvature (ten parameters per limb) held it at its
/// nominal value, a straight rod: its covariance with their rows and columns zero. Any other
/// layout comes back as it is, for the validation to judge.
ParameterCovariance with_held_precurvatures(const ParameterCovariance& in) {
  const auto precurvature = [](const ParameterId& id) {
    return id.kind == ParameterKind::kPrecurvature;
  };
  for (int n = 2; n <= kMaxLimbs; ++n) {
    for (int load = 0; load < 2; ++load) {
      const int count = num_parameters(n) + load * kLoadParameters;
      std::vector<int> kept;  // current flat indices of the report's parameters, in its order
      for (int k = 0; k < count; ++k) {
        if (!precurvature(parameter_id(k, n))) kept.push_back(k);
      }
      if (kept.size() != in.names.size()) continue;
      bool same = true;
      for (std::size_t j = 0; j < kept.size() && same; ++j)
        same = in.names[j] == parameter_name(parameter_id(kept[j], n));
      if (!same) continue;
      ParameterCovariance out;
      for (int k = 0; k < count; ++k) out.names.push_back(parameter_name(parameter_id(k, n)));
      out.matrix = Eigen::MatrixXd::Zero(count, count);
      for (std::size_t r = 0; r < kept.size(); ++r) {
        for (std::size_t c = 0; c < kept.size(); ++c) {
          out.matrix(kept[r], kept[c]) =
              in.matrix(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
        }
      }
      return out;
    }
  }
  return in;
}

/// The farthest point from the origin of the zonotope {sum_k s_k g_k : |s_k| <= 1} in the plane
/// (m generators g_k, zero ones left out). A convex function's maximum over a polytope is at a
/// vertex, and the vertex that maximises u . x is sum_k sign(u . g_k) g_k, constant while u turns
/// between two of the directions where some u . g_k changes sign (g_k's angle +- pi/2): one
/// candidate per arc between consecutive such angles, at its middle.
template <class Generators>
Eigen::Vector2d farthest_vertex(const Generators& g) {
  constexpr int kMax = 2 * kMaxPoseJacobianColumns;
  std::array<double, kMax> angles;
  int count = 0;
  for (Eigen::Index k = 0; k < g.cols(); ++k) {
    if (g(0, k) == 0 && g(1, k) == 0) continue;
    const double phi = std::atan2(g(1, k), g(0, k));
    for (const double side : {-0.5 * M_PI, 0.5 * M_PI}) {
      angles[static_cast<std::size_t>(count++)] = std::remainder(phi + side, 2 * M_PI) + M_PI;
    }
  }
  Eigen::Vector2d best = Eigen::Vector2d::Zero();
  if (count == 0) return best;
  std::sort(angles.begin(), angles.begin() + count);
  for (int a = 0; a < count; ++a) {
    const double next = a + 1 < count ? angles[static_cast<std::size_t>(a + 1)]
                                      : angles[0] + 2 * M_PI;  // the arc across 2 pi
    const double mid = 0.5 * (angles[static_cast<std::size_t>(a)] + next);
    const Eigen::Vector2d u(std::cos(mid), std::sin(mid));
    Eigen::Vector2d v = Eigen::Vector2d::Zero();
    for (Eigen::Index k = 0; k < g.cols(); ++k) {
      const double side = u.dot(g.col(k));
      v += side > 0 ? g.col(k) : side < 0 ? Eigen::Vector2d(-g.col(k)) : Eigen::Vector2d::Zero();
    }
    if (v.squaredNorm() > best.squaredNorm()) best = v;
  }
  return best;
}

}  // namespace

const char* to_string(PredictionStatus status) {
  switch (status) {
    case PredictionStatus::kOk:
      return "ok";
    case PredictionStatus::kNoJacobian:
      return "no_jacobian";
    case PredictionStatus::kNotIdentifiable:
      return "not_identifiable";
    case PredictionStatus::kNoCovariance:
      return "no_covariance";
  }
  return "unknown";
}

PredictedAccuracy predicted_accuracy(const RobotParams<double>& robot,
                                     const ForwardSolution& solution,
                                     const ParameterCovariance& covariance,
                                     const PredictedAccuracyOptions& options) {
  const int n = robot.num_limbs;
  const int count = num_parameters(n);
  const Eigen::MatrixXd& C = covariance.matrix;
  const bool has_covariance = C.size() > 0 || !covariance.names.empty();
  if (has_covariance) {
    if (C.rows() != C.cols() || C.rows() != static_cast<Eigen::Index>(covariance.names.size())) {
      throw InputError("predicted_accuracy: covariance: " + std::to_string(C.rows()) + " x " +
                       std::to_string(C.cols()) + " matrix for " +
                       std::to_string(covariance.names.size()) + " parameter names");
    }
    if (covariance.num_limbs() != n) {
      throw InputError("predicted_accuracy: covariance: " + std::to_string(C.rows()) +
                       " parameters, not those of a robot with " + std::to_string(n) + " limbs (" +
                       std::to_string(count) + ", or " + std::to_string(count + kLoadParameters) +
                       " with the load)");
    }
  }
  const std::vector<double>& h = options.half_widths;
  if (!h.empty()) {
    if (static_cast<int>(h.size()) != count) {
      throw InputError("predicted_accuracy: half_widths: " + std::to_string(h.size()) +
                       " values, expected " + std::to_string(count) + " (the flat parameters)");
    }
    for (std::size_t k = 0; k < h.size(); ++k) {
      if (!(h[k] >= 0) || !std::isfinite(h[k])) {
        throw InputError("predicted_accuracy: half_widths[" + std::to_string(k) + "] (" +
                         parameter_name(parameter_id(static_cast<int>(k), n)) +
                         "): expected a finite value >= 0, got " + number(h[k]));
      }
    }
  }

  PredictedAccuracy out;
  PoseParameterJacobian J;
  if (!pose_parameter_jacobian(robot, solution, &J, options.load, options.solver)) return out;

  if (!h.empty()) {
    // The flat columns only: the load has no interval (the calibration identifies it).
    Eigen::Matrix<double, 2, Eigen::Dynamic, 0, 2, kMaxPoseJacobianColumns> g(2, count);
    out.worst_components.setZero();
    for (int k = 0; k < count; ++k) {
      const double hk = h[static_cast<std::size_t>(k)];
      g.col(k) = J.block<2, 1>(0, k) * hk;
      out.worst_components += J.col(k).cwiseAbs() * hk;
    }
    const Eigen::Vector2d v = farthest_vertex(g);
    out.worst_position = v.norm();
    out.worst_position_direction =
        v.norm() > 0 ? Eigen::Vector2d(v / v.norm()) : Eigen::Vector2d::Zero();
    out.worst_orientation = out.worst_components(2);
  }

  if (!has_covariance) {
    out.status = PredictionStatus::kNoCovariance;
    return out;
  }
  // In the camera's frame: chained through Eq. 5, d meas = D_P d(^W T_P) + D_e d(extrinsics).
  const bool measurement = options.frame == PoseFrame::kMeasurement;
  if (measurement) {
    using J9 = ceres::Jet<double, 9>;
    const Pose2<double>& p = solution.pose;
    const Pose2<J9> platform{J9(p.x, 0), J9(p.y, 1), J9(p.theta, 2)};
    const Pose2<double>& cam = robot.extrinsics.camera;
    const Pose2<double>& pat = robot.extrinsics.pattern;
    const Extrinsics<J9> extrinsics{Pose2<J9>{J9(cam.x, 3), J9(cam.y, 4), J9(cam.theta, 5)},
                                    Pose2<J9>{J9(pat.x, 6), J9(pat.y, 7), J9(pat.theta, 8)}};
    const Pose2<J9> m = extrinsics.measurement_from_platform(platform);
    Eigen::Matrix<double, 3, 9, Eigen::RowMajor> D;
    D << m.x.v.transpose(), m.y.v.transpose(), m.theta.v.transpose();
    J = D.leftCols<3>() * J;  // the extrinsic columns of J are zero
    J.middleCols<kExtrinsicParameters>(kLimbParameters * n) = D.rightCols<6>();
  }
  // The parameters that move the pose: every limb parameter, the extrinsics for the measured
  // pose, and the load when the covariance has it. Those whose variance is NaN are left out, and
  // said so.
  std::array<int, kMaxPoseJacobianColumns> moving;
  int m = 0;
  bool all_known = true;
  const auto take = [&](int k) {
    if (std::isnan(C(k, k))) {
      all_known = all_known && J.col(k).isZero(0.0);
    } else {
      moving[static_cast<std::size_t>(m++)] = k;
    }
  };
  for (int k = 0; k < (measurement ? count : kLimbParameters * n); ++k) take(k);
  if (covariance.has_load()) {
    for (int j = 0; j < kLoadParameters; ++j) take(count + j);
  }
  // Sigma = J_m C_mm J_m^T: the covariance's rows and the Jacobian's columns are both in flat
  // order, then the load's three.
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxPoseJacobianColumns> JC =
      Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxPoseJacobianColumns>::Zero(3, m);
  for (int a = 0; a < m; ++a) {
    const int ka = moving[static_cast<std::size_t>(a)];
    for (int b = 0; b < m; ++b) {
      const int kb = moving[static_cast<std::size_t>(b)];
      JC.col(a) += J.col(kb) * C(kb, ka);
    }
  }
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  for (int a = 0; a < m; ++a)
    sigma += JC.col(a) * J.col(moving[static_cast<std::size_t>(a)]).transpose();
  sigma = 0.5 * (sigma + sigma.transpose()) + options.measurement_covariance;
  out.covariance = sigma;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> position(sigma.topLeftCorner<2, 2>());
  out.position_1sigma = std::sqrt(std::max(position.eigenvalues()(1), 0.0));
  out.position_3sigma = 3 * out.position_1sigma;
  out.position_axis = position.eigenvectors().col(1);
  out.orientation_1sigma = std::sqrt(std::max(sigma(2, 2), 0.0));
  out.orientation_3sigma = 3 * out.orientation_1sigma;
  out.status = all_known ? PredictionStatus::kOk : PredictionStatus::kNotIdentifiable;
  return out;
}

int ParameterCovariance::num_limbs() const {
  bool load = false;
  return limbs_of(names.size(), &load);
}

bool ParameterCovariance::has_load() const {
  bool load = false;
  return limbs_of(names.size(), &load) > 0 && load;
}

ParameterCovariance parameter_covariance(const CalibrationResult& result) {
  ParameterCovariance out;
  if (result.covariance.size() == 0) return out;
  for (const ParameterEstimate& p : result.parameters) out.names.push_back(p.name);
  out.matrix = result.covariance;
  return out;
}

void validate_parameter_covariance(const ParameterCovariance& covariance, const std::string& source,
                                   int num_limbs) {
  const std::vector<std::string>& names = covariance.names;
  const Eigen::MatrixXd& C = covariance.matrix;
  const Eigen::Index size = static_cast<Eigen::Index>(names.size());
  if (C.rows() != size || C.cols() != size) {
    throw InputError(source + ": covariance.matrix: " + std::to_string(C.rows()) + " x " +
                     std::to_string(C.cols()) + " for " + std::to_string(size) +
                     " parameters (expected a square matrix, one row per parameter)");
  }
  bool load = false;
  const int n = limbs_of(names.size(), &load);
  if (n < 0) {
    throw InputError(source + ": covariance.parameters: " + std::to_string(size) +
                     " names are not the flat parameters of a robot (" +
                     std::to_string(kLimbParameters) + " per limb, up to " +
                     std::to_string(kMaxLimbs) + " limbs, then 6 extrinsics, then optionally " +
                     "the load's 3)");
  }
  if (num_limbs > 0 && n != num_limbs) {
    throw InputError(source + ": covariance.parameters: " + std::to_string(size) +
                     " names, the parameters of a robot with " + std::to_string(n) +
                     " limbs; the robot has " + std::to_string(num_limbs));
  }
  for (Eigen::Index k = 0; k < size; ++k) {
    const std::string expected = parameter_name(parameter_id(static_cast<int>(k), n));
    if (names[static_cast<std::size_t>(k)] != expected) {
      throw InputError(source + ": covariance.parameters[" + std::to_string(k) + "]: expected \"" +
                       expected + "\", got \"" + excerpt(names[static_cast<std::size_t>(k)]) +
                       "\" (the flat parameter order of pcr/parameters.hpp)");
    }
  }
  // NaN: on the rows and columns of the parameters whose variance is NaN, nowhere else; but a
  // held parameter (variance 0) has no covariance with any, so its row and column are all zero.
  std::vector<bool> known(static_cast<std::size_t>(size)), held(static_cast<std::size_t>(size));
  for (Eigen::Index k = 0; k < size; ++k) {
    known[static_cast<std::size_t>(k)] = !std::isnan(C(k, k));
    held[static_cast<std::size_t>(k)] = C(k, k) == 0;
  }
  for (Eigen::Index r = 0; r < size; ++r) {
    for (Eigen::Index c = 0; c < size; ++c) {
      const std::size_t ur = static_cast<std::size_t>(r), uc = static_cast<std::size_t>(c);
      const double v = C(r, c);
      if (known[ur] && known[uc]) {
        if (std::isnan(v)) {
          throw InputError(source + ": " + entry(r, c) + ": null (NaN) where the variances of " +
                           names[ur] + " and " + names[uc] +
                           " are known: NaN only on the rows and columns of parameters that are "
                           "not identifiable");
        }
        if (!std::isfinite(v)) {
          throw InputError(source + ": " + entry(r, c) + ": " + number(v) + " is not finite");
        }
        continue;
      }
      // One of them is not identifiable: NaN, or zero against a held parameter.
      const std::size_t unknown = known[ur] ? uc : ur, other = known[ur] ? ur : uc;
      if (held[other] && v != 0) {
        throw InputError(source + ": " + entry(r, c) + ": " + number(v) + " where " + names[other] +
                         " is held (variance 0): its row and column must be 0");
      }
      if (!held[other] && !std::isnan(v)) {
        throw InputError(source + ": " + entry(r, c) + ": " + number(v) +
                         " where the variance of " + names[unknown] +
                         " is null (not identifiable): its row and column must be null (but 0 "
                         "against a held parameter)");
      }
    }
  }
  for (Eigen::Index k = 0; k < size; ++k) {
    if (known[static_cast<std::size_t>(k)] && C(k, k) < 0) {
      throw InputError(source + ": " + entry(k, k) + ": " + number(C(k, k)) + ": the variance of " +
                       names[static_cast<std::size_t>(k)] + " is negative");
    }
  }
  // Symmetry, |correlation| <= 1, then the correlation matrix's eigenvalues, on the known ones
  // with a positive variance (a zero variance with a nonzero covariance fails |correlation| <= 1).
  std::vector<Eigen::Index> positive;
  for (Eigen::Index r = 0; r < size; ++r) {
    if (!known[static_cast<std::size_t>(r)]) continue;
    if (C(r, r) > 0) positive.push_back(r);
    for (Eigen::Index c = r + 1; c < size; ++c) {
      if (!known[static_cast<std::size_t>(c)]) continue;
      const double scale = std::sqrt(C(r, r) * C(c, c));
      if (std::abs(C(r, c) - C(c, r)) > kSymmetryTolerance * scale) {
        throw InputError(source + ": " + entry(r, c) + " = " + number(C(r, c)) + " but " +
                         entry(c, r) + " = " + number(C(c, r)) + ": not symmetric (" +
                         names[static_cast<std::size_t>(r)] + ", " +
                         names[static_cast<std::size_t>(c)] + ")");
      }
      if (std::abs(C(r, c)) > (1 + kSymmetryTolerance) * scale) {
        throw InputError(source + ": " + entry(r, c) + ": " + number(C(r, c)) +
                         ": larger than sqrt(" + number(C(r, r)) + " * " + number(C(c, c)) +
                         "), the variances of " + names[static_cast<std::size_t>(r)] + " and " +
                         names[static_cast<std::size_t>(c)] + ": not positive semi-definite");
      }
    }
  }
  const Eigen::Index m = static_cast<Eigen::Index>(positive.size());
  if (m < 2) return;
  Eigen::MatrixXd R(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) {
      const Eigen::Index r = positive[static_cast<std::size_t>(a)];
      const Eigen::Index c = positive[static_cast<std::size_t>(b)];
      R(a, b) = 0.5 * (C(r, c) + C(c, r)) / std::sqrt(C(r, r) * C(c, c));
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(R);
  const double smallest = eigen.eigenvalues()(0);
  if (eigen.info() == Eigen::Success && smallest >= -kEigenvalueTolerance) return;
  // Name the parameters with the largest shares in the offending direction.
  const Eigen::VectorXd v = eigen.eigenvectors().col(0);
  std::vector<Eigen::Index> order(static_cast<std::size_t>(m));
  std::iota(order.begin(), order.end(), Eigen::Index(0));
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index a, Eigen::Index b) { return std::abs(v(a)) > std::abs(v(b)); });
  std::string along;
  for (std::size_t t = 0; t < order.size() && t < 3; ++t) {
    along += (t ? ", " : "") +
             names[static_cast<std::size_t>(positive[static_cast<std::size_t>(order[t])])];
  }
  throw InputError(source + ": covariance.matrix: not positive semi-definite: its correlation " +
                   "matrix has the eigenvalue " + number(smallest) + " (mostly along " + along +
                   ")");
}

ParameterCovariance parse_parameter_covariance(const std::string& json_text,
                                               const std::string& source, int num_limbs) {
  check_json_nesting(json_text, source);
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {
    throw InputError(source + ": invalid JSON: " + e.what());
  }
  if (!root.is_object() || !root.contains("covariance")) {
    throw InputError(source +
                     ": covariance: missing (a calibration report with the parameters' covariance "
                     "is expected, as pcr calibrate writes it)");
  }
  const json& block = root["covariance"];
  if (!block.is_object()) {
    throw InputError(source + ": covariance: expected an object {parameters, units, matrix}, got " +
                     excerpt(block.dump()));
  }
  for (auto it = block.begin(); it != block.end(); ++it) {
    if (it.key() != "parameters" && it.key() != "units" && it.key() != "matrix") {
      throw InputError(source + ": covariance: unknown field \"" + excerpt(it.key()) + "\"");
    }
  }
  if (block.contains("units") &&
      (!block["units"].is_string() || block["units"].get<std::string>() != "SI, flat order")) {
    throw InputError(source + ": covariance.units: expected \"SI, flat order\", got " +
                     excerpt(block["units"].dump()));
  }
  if (!block.contains("parameters") || !block["parameters"].is_array()) {
    throw InputError(source + ": covariance.parameters: expected a list of parameter names, got " +
                     (block.contains("parameters") ? excerpt(block["parameters"].dump())
                                                   : std::string("nothing")));
  }
  ParameterCovariance out;
  const json& names = block["parameters"];
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!names[k].is_string()) {
      throw InputError(source + ": covariance.parameters[" + std::to_string(k) +
                       "]: expected a string, got " + excerpt(names[k].dump()));
    }
    out.names.push_back(names[k].get<std::string>());
  }
  if (!block.contains("matrix") || !block["matrix"].is_array()) {
    throw InputError(
        source + ": covariance.matrix: expected a list of rows, got " +
        (block.contains("matrix") ? excerpt(block["matrix"].dump()) : std::string("nothing")));
  }
  const json& rows = block["matrix"];
  const std::size_t size = out.names.size();
  if (rows.size() != size) {
    throw InputError(source + ": covariance.matrix: " + std::to_string(rows.size()) + " rows for " +
                     std::to_string(size) +
                     " parameters (expected a square matrix, one row per parameter)");
  }
  out.matrix.resize(static_cast<Eigen::Index>(size), static_cast<Eigen::Index>(size));
  for (std::size_t r = 0; r < size; ++r) {
    const std::string where = source + ": covariance.matrix[" + std::to_string(r) + "]";
    if (!rows[r].is_array() || rows[r].size() != size) {
      throw InputError(where + ": expected a row of " + std::to_string(size) +
                       " numbers (a square matrix), got " + excerpt(rows[r].dump()));
    }
    for (std::size_t c = 0; c < size; ++c) {
      const json& v = rows[r][c];
      double value;
      if (v.is_null()) {
        value = std::numeric_limits<double>::quiet_NaN();  // how nlohmann writes NaN
      } else if (v.is_number()) {
        value = v.get<double>();
      } else {
        throw InputError(where + "[" + std::to_string(c) + "]: expected a number or null, got " +
                         excerpt(v.dump()));
      }
      out.matrix(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = value;
    }
  }
  out = with_held_precurvatures(out);
  validate_parameter_covariance(out, source, num_limbs);
  return out;
}

ParameterCovariance read_parameter_covariance(const std::string& report_path, int num_limbs) {
  return parse_parameter_covariance(
      read_input_file(report_path, kMaxJsonFileBytes, "a calibration report"), report_path,
      num_limbs);
}

}  // namespace pcr
