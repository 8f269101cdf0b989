// Staged, bounded identification with Ceres (see pcr/calib/calibrator.hpp for the design).

#include "pcr/calib/calibrator.hpp"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/normal_prior.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

namespace pcr {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The ways a robot may have reached the equilibria of a dataset's rows at their joints (its
/// readings): each row on its own from home, the rows as a path in their order from home, and as
/// a path through folds (a robot that snapped through one).
std::vector<std::pair<SolverOptions, SequenceMode>> dataset_readings(const SolverOptions& fk) {
  SolverOptions through = fk;
  through.through_folds = true;
  std::vector<std::pair<SolverOptions, SequenceMode>> out{{fk, SequenceMode::kIndependent},
                                                          {fk, SequenceMode::kPath}};
  if (!fk.through_folds) out.emplace_back(through, SequenceMode::kPath);
  return out;
}

/// The rows' equilibria in one reading.
std::vector<ForwardSolution> solve_rows(const RobotParams<double>& robot,
                                        const std::vector<CalibrationSample>& data,
                                        const SolverOptions& options, SequenceMode mode,
                                        const PlatformLoad<double>& load) {
  ForwardSequence sequence(robot, options, load, mode);
  std::vector<ForwardSolution> out;
  out.reserve(data.size());
  for (const CalibrationSample& row : data) out.push_back(sequence.solve(row.q));
  return out;
}

/// The equilibria of `robot` at the joints of `at` other than `at` itself, found from its buckled
/// seeds (buckled_seed) and `reached` (equilibria at those joints the robot may have
/// come to otherwise, dataset_readings): the one whose platform pose lies nearest `target`, if
/// any.
std::optional<ForwardSolution> nearest_other_equilibrium(
    const RobotParams<double>& robot, const ForwardSolution& at,
    const std::vector<const ForwardSolution*>& reached, const Pose2<double>& target,
    const SolverOptions& fk, const PlatformLoad<double>& load) {
  std::optional<ForwardSolution> best;
  double best_distance = HUGE_VAL;
  const auto consider = [&](const ForwardSolution& s) {
    if (!is_equilibrium(s.summary)) return;
    const double from_at = pose_distance(s.pose, at.pose, kDefaultOrientationWeight);
    if (!(from_at > kDistinctEquilibrium)) return;  // `at` again
    const double distance = std::hypot(s.pose.x - target.x, s.pose.y - target.y);
    if (distance < best_distance) {
      best_distance = distance;
      best = s;
    }
  };
  for (const ForwardSolution* r : reached) consider(*r);
  for (int k = 0; k < kBuckledSeedsPerRod * robot.num_limbs; ++k) {
    consider(forward_kinematics(robot, at.q, buckled_seed(robot, at, k), fk, load));
  }
  return best;
}

/// The branch-mismatch rule: a row whose equilibrium `predicted[j]` misses its measurement by
/// kMismatchFactor times the rows' median position error or more, and whose measurement lies
/// kMismatchFactor times nearer another equilibrium at the same joints (nearest_other_equilibrium,
/// with the rows' readings, solved once a row needs them), was measured on that one: the robot
/// came to it another way than the one predicted. Per row, that equilibrium or none (also for a
/// row without a converged prediction, or a null one). `predicted_reading`: the mode in which
/// `predicted` is itself the reading of `fk` (that reading is not solved again: it gives each row
/// its prediction, which is not another equilibrium), or none.
std::vector<std::optional<ForwardSolution>> equilibria_measured_instead(
    const RobotParams<double>& robot, const std::vector<CalibrationSample>& data,
    const std::vector<const ForwardSolution*>& predicted, const SolverOptions& fk,
    const PlatformLoad<double>& load, std::optional<SequenceMode> predicted_reading) {
  std::vector<std::optional<ForwardSolution>> out(data.size());
  std::vector<double> errors(data.size(), kNaN), finite;
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (predicted[j] == nullptr || !is_equilibrium(predicted[j]->summary)) continue;
    const Pose2<double> measured = robot.extrinsics.platform_from_measurement(data[j].measured);
    errors[j] = std::hypot(predicted[j]->pose.x - measured.x, predicted[j]->pose.y - measured.y);
    if (std::isfinite(errors[j])) finite.push_back(errors[j]);
  }
  if (finite.empty()) return out;
  std::nth_element(finite.begin(), finite.begin() + finite.size() / 2, finite.end());
  const double median = finite[finite.size() / 2];
  std::vector<std::vector<ForwardSolution>> readings;
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (!(errors[j] > kMismatchFactor * median)) continue;
    if (readings.empty()) {
      for (const auto& [options, mode] : dataset_readings(fk)) {
        if (mode == predicted_reading && options.through_folds == fk.through_folds) continue;
        readings.push_back(solve_rows(robot, data, options, mode, load));
      }
    }
    std::vector<const ForwardSolution*> reached;
    for (const std::vector<ForwardSolution>& reading : readings) reached.push_back(&reading[j]);
    const Pose2<double> measured = robot.extrinsics.platform_from_measurement(data[j].measured);
    std::optional<ForwardSolution> other =
        nearest_other_equilibrium(robot, *predicted[j], reached, measured, fk, load);
    if (other &&
        kMismatchFactor * std::hypot(other->pose.x - measured.x, other->pose.y - measured.y) <
            errors[j]) {
      out[j] = std::move(other);
    }
  }
  return out;
}

/// gauge_generators' order.
enum GaugeIndex {
  kProximalX,
  kProximalY,
  kProximalRotation,
  kDistalX,
  kDistalY,
  kDistalRotation,
  kStiffness,
};

/// The scale of the load parameters (their "half-widths"; they carry no bound): for each
/// component, the load that moves the nominal platform (in Eq. 6's metric, root mean square over
/// the rows) as far as a clamp's position tolerance (the mean half-width of A and B) does, so that
/// its columns weigh like the geometry's. The platform is stiff (inextensible rods, and at home
/// nearly rigid): a millinewton moves it by about 0.1 um on the paper's robot, where EI / L^2 is a
/// millinewton. Where no row solves: the load that bends a rod by the tolerance.
std::array<double, kLoadParameters> load_scales(const RobotParams<double>& robot,
                                                const std::vector<double>& half_widths,
                                                const std::vector<CalibrationSample>& rows,
                                                const CalibrationOptions& options) {
  double tolerance = 0;
  int terms = 0;
  for (std::size_t k = 0; k < half_widths.size(); ++k) {
    const ParameterKind kind = parameter_id(static_cast<int>(k), robot.num_limbs).kind;
    const bool position = kind == ParameterKind::kAx || kind == ParameterKind::kAy ||
                          kind == ParameterKind::kBx || kind == ParameterKind::kBy;
    if (position && half_widths[k] > 0) {
      tolerance += half_widths[k];
      ++terms;
    }
  }
  const ShootingScale scale = shooting_scale(robot);
  tolerance = terms > 0 ? tolerance / terms : 1e-3 * scale.length;
  const double bend = tolerance / scale.length;
  std::array<double, kLoadParameters> out = {bend * scale.force, bend * scale.force,
                                             bend * scale.moment()};
  double square[kLoadParameters] = {0, 0, 0};
  int solved = 0;
  ForwardSequence sequence(robot, options.fk);
  for (const CalibrationSample& row : rows) {
    const ForwardSolution& solution = sequence.solve(row.q);
    double dpose[3 * kMaxParameters], dload[3 * kLoadParameters];
    if (!is_equilibrium(solution.summary) ||
        !platform_pose_jacobian(robot, PlatformLoad<double>(), solution, options.fk, dpose,
                                dload)) {
      continue;
    }
    for (int j = 0; j < kLoadParameters; ++j) {  // per N or N m
      const double w = options.orientation_weight * dload[6 + j];
      square[j] += dload[j] * dload[j] + dload[3 + j] * dload[3 + j] + w * w;
    }
    ++solved;
  }
  for (int j = 0; j < kLoadParameters && solved > 0; ++j) {
    const double moved = std::sqrt(square[j] / solved);
    if (moved > 0 && std::isfinite(moved)) out[static_cast<std::size_t>(j)] = tolerance / moved;
  }
  return out;
}

/// Flat indices of a stage's kind name: a per-limb kind of kParameterKinds ("l", "A_x",
/// "precurvature" ...) on every limb, or a group ("A" covers A_x and A_y, "camera" three values,
/// "all", "load"); empty for an unknown name.
std::vector<int> indices_of_kind(const std::string& kind, int n) {
  std::vector<int> out;
  const int extrinsics = kLimbParameters * n;
  if (kind == "all") {
    for (int k = 0; k < num_parameters(n); ++k) out.push_back(k);
    return out;
  }
  if (kind == "load") {  // after the flat parameters, in the cost's block
    for (int k = 0; k < kLoadParameters; ++k) out.push_back(num_parameters(n) + k);
    return out;
  }
  if (kind == "camera" || kind == "extrinsics") {
    for (int k = 0; k < 3; ++k) out.push_back(extrinsics + k);
  }
  if (kind == "pattern" || kind == "extrinsics") {
    for (int k = 3; k < 6; ++k) out.push_back(extrinsics + k);
  }
  if (!out.empty()) return out;
  std::vector<ParameterKind> limb_kinds;
  if (kind == "A") limb_kinds = {ParameterKind::kAx, ParameterKind::kAy};
  if (kind == "B") limb_kinds = {ParameterKind::kBx, ParameterKind::kBy};
  for (int k = 0; k < kLimbParameters; ++k) {
    if (kind == kParameterKinds[k].name) limb_kinds.push_back(kParameterKinds[k].kind);
  }
  for (int i = 0; i < n; ++i) {
    for (ParameterKind pk : limb_kinds) out.push_back(parameter_index(ParameterId{pk, i}, n));
  }
  return out;
}

/// Free flat indices of a stage: its kinds, restricted to non-zero half-widths (an index past
/// `half_widths`, the load's when its scales are not known yet, counts as free).
std::vector<int> stage_free_indices(const CalibrationStage& stage,
                                    const std::vector<double>& half_widths, int n) {
  std::set<int> free;
  for (const std::string& kind : stage.free) {
    for (int k : indices_of_kind(kind, n)) {
      const std::size_t at = static_cast<std::size_t>(k);
      if (at >= half_widths.size() || half_widths[at] > 0) free.insert(k);
    }
  }
  return std::vector<int>(free.begin(), free.end());
}

bool known_kind(const std::string& kind) { return !indices_of_kind(kind, 1).empty(); }

std::string format_number(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

std::string origin_of(const std::vector<CalibrationSample>& data, std::size_t j) {
  return data[j].origin.empty() ? "configuration " + std::to_string(j + 1) : data[j].origin;
}

std::string joints_text(const JointVector& q) {
  std::string out = "q = (";
  for (Eigen::Index i = 0; i < q.size(); ++i) out += (i ? ", " : "") + format_number(q[i]);
  return out + ") m";
}

/// "a, b, c and 4 more" of the first `shown` items.
std::string listing(const std::vector<std::string>& items, std::size_t shown = 5) {
  std::string out;
  for (std::size_t k = 0; k < items.size() && k < shown; ++k) out += (k ? "; " : "") + items[k];
  if (items.size() > shown) out += "; and " + std::to_string(items.size() - shown) + " more";
  return out;
}

/// Measured poses vary like the nominal model's platform poses, give or take the model's errors
/// (tens of micrometres, milliradians on a workspace of millimetres and tens of milliradians): a
/// column that varies ten times more is in another unit (57.3: degrees; 1000: millimetres).
void warn_of_units(const std::vector<CalibrationSample>& rows,
                   const std::vector<Pose2<double>>& nominal, CalibrationResult* result) {
  const std::size_t m = rows.size();
  if (m < 3) return;
  const auto spread = [m](const auto& value) {  // standard deviation and the farthest row
    double mean = 0, square = 0;
    for (std::size_t j = 0; j < m; ++j) mean += value(j) / static_cast<double>(m);
    std::size_t farthest = 0;
    for (std::size_t j = 0; j < m; ++j) {
      square += (value(j) - mean) * (value(j) - mean);
      if (std::abs(value(j) - mean) > std::abs(value(farthest) - mean)) farthest = j;
    }
    return std::make_pair(std::sqrt(square / static_cast<double>(m)), farthest);
  };
  const auto check = [&](const char* what, const char* unit, const auto& measured,
                         const auto& model) {
    const auto [measured_spread, farthest] = spread(measured);
    const double model_spread = spread(model).first;
    if (model_spread > 0 && measured_spread > 10 * model_spread) {
      result->warnings.push_back(std::string("the measured ") + what + " varies " +
                                 format_number(measured_spread / model_spread) +
                                 " times more than the nominal model's (" +
                                 origin_of(rows, farthest) + ": " +
                                 format_number(measured(farthest)) + "): " + unit + "?");
    }
  };
  check(
      "platform angle (theta)", "degrees instead of radians",
      [&](std::size_t j) { return rows[j].measured.theta; },
      [&](std::size_t j) { return nominal[j].theta; });
  check(
      "position (x)", "millimetres instead of metres",
      [&](std::size_t j) { return rows[j].measured.x; },
      [&](std::size_t j) { return nominal[j].x; });
  check(
      "position (y)", "millimetres instead of metres",
      [&](std::size_t j) { return rows[j].measured.y; },
      [&](std::size_t j) { return nominal[j].y; });
}

/// Rows that repeat an earlier row to the last digit, joints and measurement: two measurements of
/// one configuration never agree to every digit, so such a row is a copy (pasted twice, a file
/// appended to itself), which counts one measurement as two. A repeated configuration with its own
/// measurement is a repeatability measurement, and no warning.
void warn_of_copies(const std::vector<CalibrationSample>& rows, CalibrationResult* result) {
  const auto key = [](const CalibrationSample& row) {
    std::vector<double> k(row.q.data(), row.q.data() + row.q.size());
    k.insert(k.end(), {row.measured.x, row.measured.y, row.measured.theta});
    return k;
  };
  std::map<std::vector<double>, std::size_t> first;
  std::vector<std::string> copies;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const auto [at, inserted] = first.emplace(key(rows[j]), j);
    if (!inserted) copies.push_back(origin_of(rows, j) + " = " + origin_of(rows, at->second));
  }
  if (!copies.empty()) {
    result->warnings.push_back(std::to_string(copies.size()) +
                               " rows repeat an earlier row to the last digit, joints and "
                               "measurement (a copy counts one measurement twice): " +
                               listing(copies));
  }
}

/// The rows the nominal geometry reaches. Ceres cannot start from a failed evaluation. A row whose
/// joints lie within their stroke and that the nominal geometry does not reach may lie past a fold
/// of the design that the robot itself does not have: it is set aside (`set_aside`), to be brought
/// back when the identified geometry reaches it. One with joints outside the stroke is a typo, a
/// wrong unit or another robot's: an InputError, or with drop_unreachable left out and listed in
/// result->dropped; joints outside their stroke are warned of. `used`: the reachable rows' places
/// in `data`.
std::vector<CalibrationSample> reachable_rows(const RobotParams<double>& nominal,
                                              const std::vector<CalibrationSample>& data,
                                              const CalibrationOptions& options,
                                              const std::string& source, CalibrationResult* result,
                                              std::vector<Pose2<double>>* poses,
                                              std::vector<std::size_t>* used,
                                              std::vector<std::size_t>* set_aside) {
  std::vector<CalibrationSample> reachable;
  std::vector<std::string> unreachable, outside, aside;
  ForwardSequence sequence(nominal, options.fk);
  for (std::size_t j = 0; j < data.size(); ++j) {
    const JointVector& q = data[j].q;
    const bool in_stroke = within_stroke(nominal, q);
    std::string joints_outside;  // one entry per row
    for (int i = 0; i < nominal.num_limbs && !in_stroke; ++i) {
      const auto& limb = nominal.limb(i);
      if (limb.within_stroke(q[i])) continue;
      joints_outside += (joints_outside.empty() ? "" : ", ") + std::string("q") +
                        std::to_string(i + 1) + " = " + format_number(q[i]) + " m outside [" +
                        format_number(limb.q_min) + ", " + format_number(limb.q_max) + "]";
    }
    if (!in_stroke) outside.push_back(origin_of(data, j) + ": " + joints_outside);
    const ForwardSolution& solution = sequence.solve(q);
    const SolveStatus status = solution.summary.status;
    const std::string row = origin_of(data, j) + " (" + joints_text(q) + "): " + to_string(status);
    if (is_equilibrium(solution.summary)) {
      reachable.push_back(data[j]);
      reachable.back().origin = origin_of(data, j);  // its place in `data`, not in `reachable`
      poses->push_back(solution.pose);
      used->push_back(j);
    } else if (in_stroke) {
      set_aside->push_back(j);
      aside.push_back(row);
    } else {
      unreachable.push_back(row);
    }
  }
  warn_of_units(reachable, *poses, result);
  warn_of_copies(data, result);
  if (!outside.empty()) {
    result->warnings.push_back(
        std::to_string(outside.size()) +
        " rows have joints outside the stroke (a wrong unit?): " + listing(outside));
  }
  if (!unreachable.empty() && !options.drop_unreachable) {
    throw InputError(source + ": " + std::to_string(unreachable.size()) + " of " +
                     std::to_string(data.size()) +
                     " rows have joints outside the stroke and no forward-kinematics solution on "
                     "the nominal geometry (a wrong unit, a typo, another robot's data?): " +
                     listing(unreachable) + ". Leave them out with drop_unreachable " +
                     "(pcr_calibrate --drop-unreachable)");
  }
  if (!aside.empty()) {
    result->warnings.push_back(
        std::to_string(aside.size()) +
        " rows within the stroke have no forward-kinematics solution on the nominal geometry "
        "(past a fold of the design?): set aside, brought back if the identified geometry "
        "reaches them: " +
        listing(aside));
  }
  result->dropped = unreachable;
  if (reachable.empty())
    throw InputError(source + ": no row has a solution on the nominal geometry");
  return reachable;
}

/// The extrinsics of Eq. 5, P_j = C M_j Pm, from the platform poses P_j of the nominal geometry
/// and the measurements M_j, whatever the guess: a 2D registration. C's rotation (c, s) and
/// translation solve a linear least-squares problem, p_j = t_C + R_C (t_Mj + R_Mj t_Pm), with Pm's
/// translation held at its guess (the platform turns by milliradians, so the data hardly tell it
/// from C's translation: the stages do); Pm's rotation is the mean of theta_Pj - theta_Mj -
/// theta_C. Too few distinct measurements to fix the rotation: the guess.
Extrinsics<double> registered_extrinsics(const std::vector<Pose2<double>>& platform,
                                         const std::vector<CalibrationSample>& rows,
                                         const Extrinsics<double>& guess) {
  const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd a(2 * m, 4);
  Eigen::VectorXd b(2 * m);
  const Vector2<double> g = guess.pattern.translation();
  for (Eigen::Index j = 0; j < m; ++j) {
    const Pose2<double>& measured = rows[static_cast<std::size_t>(j)].measured;
    const Vector2<double> v = measured.transform(g);  // t_Mj + R_Mj t_Pm
    a.row(2 * j) << 1, 0, v.x(), -v.y();
    a.row(2 * j + 1) << 0, 1, v.y(), v.x();
    b(2 * j) = platform[static_cast<std::size_t>(j)].x;
    b(2 * j + 1) = platform[static_cast<std::size_t>(j)].y;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::Vector4d x = qr.solve(b);
  if (qr.rank() < 4 || !x.allFinite() || x.tail<2>().norm() == 0) return guess;
  Extrinsics<double> out = guess;
  out.camera = Pose2<double>{x(0), x(1), std::atan2(x(3), x(2))};
  double sin_sum = 0, cos_sum = 0;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const double d = platform[j].theta - rows[j].measured.theta - out.camera.theta;
    sin_sum += std::sin(d);
    cos_sum += std::cos(d);
  }
  out.pattern.theta = std::atan2(sin_sum, cos_sum);
  return out;
}

/// RMS distance (m) between the platform positions the measurements give through `extrinsics`
/// (Eq. 5) and `platform`.
double registration_rms(const std::vector<Pose2<double>>& platform,
                        const std::vector<CalibrationSample>& rows,
                        const Extrinsics<double>& extrinsics) {
  double square = 0;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const Pose2<double> p = extrinsics.platform_from_measurement(rows[j].measured);
    square += (p.translation() - platform[j].translation()).squaredNorm();
  }
  return std::sqrt(square / static_cast<double>(rows.size()));
}

/// A dataset written in a left-handed frame (an image's, y down) is mirrored: no rigid extrinsics
/// map it onto the model, and the stages end far from the noise, naming the extrinsics. When the
/// measurements register ten times better onto the nominal model's poses with y and theta
/// negated, the warning says so. `registered`: registered_extrinsics of the rows as given.
void warn_of_mirror(const std::vector<Pose2<double>>& platform,
                    const std::vector<CalibrationSample>& rows,
                    const Extrinsics<double>& registered, const Extrinsics<double>& guess,
                    CalibrationResult* result) {
  std::vector<CalibrationSample> mirrored = rows;
  for (CalibrationSample& row : mirrored) {
    row.measured.y = -row.measured.y;
    row.measured.theta = -row.measured.theta;
  }
  const double as_given = registration_rms(platform, rows, registered);
  const double as_mirrored =
      registration_rms(platform, mirrored, registered_extrinsics(platform, mirrored, guess));
  if (as_mirrored * 10 < as_given) {
    result->warnings.push_back(
        "the measured poses register onto the nominal model's " +
        format_number(as_given / as_mirrored) +
        " times better mirrored (y and theta negated): written in a left-handed frame, as an "
        "image's (y down)?");
  }
}

/// Generators whose every moved parameter is in `is_free` (and that move at least one).
std::vector<bool> present_generators(const std::vector<GaugeGenerator>& generators,
                                     const std::vector<bool>& is_free) {
  std::vector<bool> present(generators.size(), false);
  for (std::size_t g = 0; g < generators.size(); ++g) {
    bool ok = true, any = false;
    for (std::size_t k = 0; k < is_free.size(); ++k) {
      if (generators[g].direction[k] != 0.0) {
        ok = ok && is_free[k];
        any = true;
      }
    }
    present[g] = ok && any;
  }
  return present;
}

/// x + B delta on the flat vector: B spans the free parameters (in half-width units) minus the
/// gauge directions, so the step neither moves a held parameter nor drifts along a gauge orbit.
class SubspaceManifold final : public ceres::Manifold {
 public:
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  SubspaceManifold(RowMajor basis, RowMajor inverse)
      : basis_(std::move(basis)), inverse_(std::move(inverse)) {}
  int AmbientSize() const override { return static_cast<int>(basis_.rows()); }
  int TangentSize() const override { return static_cast<int>(basis_.cols()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    Eigen::Map<Eigen::VectorXd>(x_plus_delta, basis_.rows()) =
        Eigen::Map<const Eigen::VectorXd>(x, basis_.rows()) +
        basis_ * Eigen::Map<const Eigen::VectorXd>(delta, basis_.cols());
    return true;
  }
  bool PlusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<RowMajor>(jacobian, basis_.rows(), basis_.cols()) = basis_;
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    Eigen::Map<Eigen::VectorXd>(y_minus_x, inverse_.rows()) =
        inverse_ * (Eigen::Map<const Eigen::VectorXd>(y, basis_.rows()) -
                    Eigen::Map<const Eigen::VectorXd>(x, basis_.rows()));
    return true;
  }
  bool MinusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<RowMajor>(jacobian, inverse_.rows(), inverse_.cols()) = inverse_;
    return true;
  }

 private:
  RowMajor basis_;    // ambient x tangent
  RowMajor inverse_;  // tangent x ambient, inverse_ * basis_ = I
};

/// Everything the stages share: current values, warm-start caches, data.
class Identification {
 public:
  Identification(const RobotDescription& nominal, const std::vector<CalibrationSample>& data,
                 const CalibrationOptions& options)
      : nominal_(nominal.params),
        data_(data),
        options_(options),
        n_(nominal.params.num_limbs),
        count_(num_parameters(n_)),
        identify_load_(frees_load(options.stages)),
        block_(count_ + (identify_load_ ? kLoadParameters : 0)),
        values_(static_cast<std::size_t>(block_)),
        nominal_values_(static_cast<std::size_t>(block_), 0.0),
        caches_(data.size()),
        gross_(data.size(), false),
        lost_(data.size(), false) {
    half_widths_ = parameter_half_widths(*nominal.uncertainty, n_);
    if (identify_load_) {
      const auto scales = load_scales(nominal_, half_widths_, data_, options);
      half_widths_.insert(half_widths_.end(), scales.begin(), scales.end());
    }
    get_parameters(nominal_, nominal_values_.data());  // the nominal load is zero
    values_ = nominal_values_;
  }

  /// The flat parameters.
  int count() const { return count_; }
  /// The values Ceres sees: the flat parameters, then the load when a stage frees it.
  int block() const { return block_; }
  /// The geometry is bounded (Eq. 7); the extrinsics and the load are not: the extrinsics start
  /// from the registration of the data (registered_extrinsics), whatever the guess, and the
  /// report says when they end outside the declared interval.
  bool bounded(int k) const { return k < count_ && parameter_id(k, n_).limb >= 0; }
  const std::vector<double>& values() const { return values_; }
  void set_values(const std::vector<double>& v) { values_ = v; }
  const std::vector<double>& half_widths() const { return half_widths_; }
  const std::vector<double>& nominal_values() const { return nominal_values_; }
  RobotParams<double> robot() const { return with_parameters(nominal_, values_.data()); }
  void set_robot(const RobotParams<double>& robot) { get_parameters(robot, values_.data()); }
  PlatformLoad<double> load() const {
    if (!identify_load_) return PlatformLoad<double>();
    const double* l = values_.data() + count_;
    return PlatformLoad<double>{Vector2<double>(l[0], l[1]), l[2]};
  }
  /// Moves the values along the gauge orbit, the load with them (move_load_along_gauge), and
  /// each row's anchored equilibrium with them by the model's symmetry
  /// (move_equilibrium_along_gauge), then settles there: every robot on the orbit predicts the
  /// same poses, and no continuation is needed to find the same equilibrium (one through robots
  /// off the orbit can fail near a fold).
  void move(const GaugeMotion& m) {
    const PlatformLoad<double> moved = move_load_along_gauge(load(), m.G, m.H, m.stiffness_scale);
    set_robot(move_along_gauge(robot(), m.G, m.H, m.stiffness_scale));
    if (identify_load_) {
      values_[static_cast<std::size_t>(count_)] = moved.force.x();
      values_[static_cast<std::size_t>(count_) + 1] = moved.force.y();
      values_[static_cast<std::size_t>(count_) + 2] = moved.moment;
    }
    for (FkCache& c : caches_) {
      if (!c.valid || !c.anchored) continue;
      c.anchor = move_equilibrium_along_gauge(c.anchor, m.G, m.H, m.stiffness_scale);
      std::copy(values_.begin(), values_.end(), c.anchor_parameters.begin());
    }
    settle();
  }
  /// Starts each row on the equilibrium its experiment reached: of those the rows reach at the
  /// current values in the dataset's readings (dataset_readings: on its own from home, along the
  /// rows' path, through folds), the one whose platform pose lies nearest the row's measurement
  /// (Eq. 6's metric). Rows are measured in their order from home (the formats page), and a robot
  /// that came to a row along its path may hold it on another equilibrium than the one a cold
  /// start from home gives: fitted there, the row would look like a gross outlier, and the model
  /// would be fitted without it. At the start values the model is within its intervals of the
  /// robot, and equilibria at the same joints are millimetres apart.
  void start_on_measured_branches() {
    const RobotParams<double> robot_now = robot();
    std::vector<double> nearest(data_.size(), HUGE_VAL);
    for (const auto& [options, mode] : dataset_readings(options_.fk)) {
      const std::vector<ForwardSolution> reached =
          solve_rows(robot_now, data_, options, mode, load());
      for (std::size_t j = 0; j < data_.size(); ++j) {
        if (!is_equilibrium(reached[j].summary)) continue;
        const Pose2<double> measured =
            robot_now.extrinsics.platform_from_measurement(data_[j].measured);
        const double distance =
            pose_distance(reached[j].pose, measured, options_.orientation_weight);
        if (!(distance < nearest[j])) continue;  // a tie keeps the equilibrium connected to home
        nearest[j] = distance;
        FkCache& c = caches_[j];
        c.solution = reached[j];
        c.valid = true;
        std::copy(values_.begin(), values_.end(), c.parameters.begin());
        c.accept();
      }
    }
  }
  /// Moves each row that the model's equilibrium at the current values misses by far onto the
  /// equilibrium at its joints that its measurement names (equilibria_measured_instead): one the
  /// robot came to in a way the readings at the start values did not follow (a fold the nominal
  /// geometry places elsewhere). The rows moved, by name.
  std::vector<std::string> move_to_measured_equilibria() {
    settle();
    std::vector<const ForwardSolution*> predicted(data_.size(), nullptr);
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if (caches_[j].valid && !lost_[j]) predicted[j] = &caches_[j].solution;
    }
    const std::vector<std::optional<ForwardSolution>> measured =
        equilibria_measured_instead(robot(), data_, predicted, options_.fk, load(), std::nullopt);
    std::vector<std::string> moved;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if (!measured[j]) continue;
      caches_[j].solution = *measured[j];
      caches_[j].accept();
      moved.push_back(origin(j));
    }
    return moved;
  }
  /// Continues every valid cache to the current values and accepts them there (a row that cannot
  /// follow keeps its anchor, and the cost continues it from there when evaluated).
  void settle() {
    const double* values = values_.data();
    double residuals[3];
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if (!caches_[j].valid) continue;
      const std::unique_ptr<ceres::CostFunction> cost(PoseMeasurementError::Create(
          nominal_, data_[j].q, data_[j].measured, options_.orientation_weight,
          options_.residual_scale, &caches_[j], options_.fk, options_.derivatives, identify_load_));
      cost->Evaluate(&values, residuals, nullptr);
    }
    accept_evaluated();
    for (std::size_t j = 0; j < data_.size(); ++j) {
      lost_[j] = caches_[j].valid &&
                 !std::equal(values_.begin(), values_.end(), caches_[j].parameters.begin());
    }
  }
  /// The rows whose residuals add_residuals(problem, false) adds, in its order: all but the lost.
  std::vector<std::size_t> evaluated_rows() const {
    std::vector<std::size_t> out;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if (!lost_[j]) out.push_back(j);
    }
    return out;
  }
  /// The rows left out because their equilibrium does not follow the current values.
  std::vector<std::string> lost_rows() const {
    std::vector<std::string> out;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if (lost_[j]) out.push_back(origin(j));
    }
    return out;
  }
  /// Accepts the caches solved at the current values (a point Ceres kept).
  void accept_evaluated() {
    for (FkCache& c : caches_) {
      if (c.valid && std::equal(values_.begin(), values_.end(), c.parameters.begin())) c.accept();
    }
  }
  /// Whether `is_free` (over the block) frees a load parameter.
  bool load_free(const std::vector<bool>& is_free) const {
    for (int k = count_; k < block_; ++k) {
      if (is_free[static_cast<std::size_t>(k)]) return true;
    }
    return false;
  }

  /// The gauge generators at the current values, over the block (with the load's components when
  /// it is identified).
  std::vector<GaugeGenerator> generators() const {
    return identify_load_ ? gauge_generators(robot(), load()) : gauge_generators(robot());
  }
  /// Which of `generators` are gauges of a problem whose free parameters are `is_free`: every
  /// parameter they move is free, and, with the load free, not a distal translation (under a
  /// force it changes the predictions, by the arm that turns with the platform).
  std::vector<bool> gauges(const std::vector<GaugeGenerator>& generators,
                           const std::vector<bool>& is_free) const {
    std::vector<bool> present = present_generators(generators, is_free);
    if (load_free(is_free)) present[kDistalX] = present[kDistalY] = false;
    return present;
  }

  /// Free flat indices of a stage (stage_free_indices).
  std::vector<int> free_indices(const CalibrationStage& stage) const {
    return stage_free_indices(stage, half_widths_, n_);
  }

  /// Adds every residual block on values_.data(). With `robust`, each configuration's block goes
  /// through the Huber loss at loss_scale_ (whitened units); the problem owns it.
  /// With `robust`, the gross outliers of the stage (exclude_gross_outliers) are left out.
  void add_residuals(ceres::Problem& problem, bool robust = true) {
    ceres::LossFunction* loss =
        robust && loss_scale_ > 0 ? new ceres::HuberLoss(loss_scale_) : nullptr;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      if ((robust && gross_[j]) || lost_[j]) continue;
      problem.AddResidualBlock(PoseMeasurementError::Create(
                                   nominal_, data_[j].q, data_[j].measured,
                                   options_.orientation_weight, options_.residual_scale,
                                   &caches_[j], options_.fk, options_.derivatives, identify_load_),
                               loss, values_.data());
    }
  }

  /// Levenberg-Marquardt with dense QR, stopping on `function_tolerance` (relative) or the
  /// gradient.
  ceres::Solver::Options solver_options(double function_tolerance) const {
    ceres::Solver::Options solver;
    solver.linear_solver_type = ceres::DENSE_QR;
    solver.max_num_iterations = options_.max_iterations;
    solver.num_threads = 1;
    solver.function_tolerance = function_tolerance;
    solver.gradient_tolerance = 1e-12;
    // Off: Ceres compares the step with |x|, which E (~7e10 Pa) dominates, so any step would
    // look negligible. The function and gradient tolerances (whitened residuals) decide.
    solver.parameter_tolerance = 0.0;
    solver.logging_type = ceres::SILENT;
    // With bounds, Ceres runs an Armijo line search on every step; cubic interpolation (its
    // default) asks for the gradient at each trial point, a whole Jacobian evaluation of the
    // rows. Quadratic interpolation needs the trial costs only.
    solver.line_search_interpolation_type = ceres::QUADRATIC;
    return solver;
  }

  /// Fits the stage's free parameters; `last`: the final stage (the tighter function tolerance);
  /// `rescale`: how many times the stage has been solved again for a smaller Huber scale.
  StageReport run_stage(const CalibrationStage& stage, bool last = true, int rescale = 0) {
    StageReport report;
    report.name = stage.name;
    const std::vector<int> free = free_indices(stage);
    for (int k : free) report.free_parameters.push_back(parameter_name(parameter_id(k, n_)));
    const double to_m2 = options_.residual_scale * options_.residual_scale;
    if (free.empty()) {
      report.initial_cost = report.final_cost = cost() * to_m2;
      report.termination = "no free parameter";
      report.usable = true;
      return report;
    }
    std::vector<bool> stage_free(static_cast<std::size_t>(block_), false);
    for (int k : free) stage_free[static_cast<std::size_t>(k)] = true;
    const bool subspace = options_.stage_gauge == StageGauge::kSubspace;
    const auto at_bound = [&](int k) {
      const std::size_t uk = static_cast<std::size_t>(k);
      return bounded(k) && std::abs(values_[uk] - nominal_values_[uk]) >=
                               stage.bounds_scale * half_widths_[uk] * (1 - 1e-9);
    };

    ceres::Solver::Options solver = solver_options(last ? options_.function_tolerance
                                                        : options_.intermediate_function_tolerance);
    ProgressCallback callback(stage.name, to_m2, options_.progress);
    if (options_.progress) solver.callbacks.push_back(&callback);
    // Ceres projects the unconstrained step onto the box: once a step has put a free parameter
    // on its bound, the following ones keep a fraction of the decrease their model predicts and
    // crawl. The solve stops there instead, and the parameter is held at the bound (below).
    std::vector<bool> is_free;
    BoundCallback stop_at_bound([&] {
      for (int k : free) {
        if (is_free[static_cast<std::size_t>(k)] && at_bound(k)) return true;
      }
      return false;
    });
    AcceptCallback accept(this);
    solver.callbacks.push_back(&accept);
    solver.callbacks.push_back(&stop_at_bound);
    solver.update_state_every_iteration = true;  // the callbacks read values_
    ceres::Solver::Summary summary;
    const auto start = std::chrono::steady_clock::now();
    for (FkCache& c : caches_) c.evaluations = c.warm_start_failures = c.newton_iterations = 0;

    // Rounds: each starts from the representative of the gauge orbit deepest inside the box
    // (recentre_in_gauge) with every parameter of the stage free. A round that ends with
    // parameters at a bound is followed by another while the rounds still lower the cost by 1%:
    // a bound met in the gauge a round started in may not be met in the next one's, and a
    // parameter held at a bound is released. A truth inside the box has a representative inside
    // it, which the rounds reach (the sweep in tests/test_calibration.cpp).
    // A round whose start (recentred, clamped) the model cannot evaluate, a row past a fold
    // there, goes on from the last values it evaluated instead: the stage's start, or the end
    // of the last round.
    constexpr int kMaxRounds = 4;
    std::vector<double> last_evaluated = values_;
    std::vector<FkCache> caches_evaluated = caches_;  // the equilibria at last_evaluated
    ceres::Solver::Summary last_summary;
    bool solved = false, restored = false;
    recentre_in_gauge(stage_free, stage.bounds_scale);
    double previous_round_cost = std::numeric_limits<double>::infinity();
    for (int round = 0; round < kMaxRounds; ++round) {
      for (int k : free) {  // a previous stage with wider bounds may have left a value outside
        if (!bounded(k)) continue;
        const double h = stage.bounds_scale * half_widths_[static_cast<std::size_t>(k)];
        const double c = nominal_values_[static_cast<std::size_t>(k)];
        double& v = values_[static_cast<std::size_t>(k)];
        v = std::min(std::max(v, c - h), c + h);
      }
      settle();
      if (round == 0) {
        update_loss_scale();
        exclude_gross_outliers();
      }
      ceres::Problem problem;
      add_residuals(problem);
      is_free = stage_free;
      problem.SetManifold(values_.data(), make_manifold(is_free, subspace));
      if (!subspace && options_.gauge_prior_weight > 0) {
        // Weak pull towards the nominal values, in half-width units: it only matters along the
        // gauge directions (where the data says nothing), which it fixes to the representative
        // closest to the nominal, away from the bounds.
        Eigen::MatrixXd a = Eigen::MatrixXd::Zero(block_, block_);
        for (int k : free) {
          a(k, k) = options_.gauge_prior_weight / half_widths_[static_cast<std::size_t>(k)];
        }
        const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(nominal_values_.data(), block_);
        problem.AddResidualBlock(new ceres::NormalPrior(a, b), nullptr, values_.data());
      }
      for (int k : free) {
        if (!bounded(k)) continue;
        const double h = stage.bounds_scale * half_widths_[static_cast<std::size_t>(k)];
        const double c = nominal_values_[static_cast<std::size_t>(k)];
        problem.SetParameterLowerBound(values_.data(), k, c - h);
        problem.SetParameterUpperBound(values_.data(), k, c + h);
      }
      solve(solver, &problem, &summary, stage.name);
      const bool failed_at_start = summary.termination_type == ceres::FAILURE &&
                                   (summary.iterations.empty() || summary.initial_cost < 0);
      if (failed_at_start && !restored) {
        values_ = last_evaluated;
        for (std::size_t j = 0; j < caches_.size(); ++j) {  // the counters go on counting
          caches_[j].solution = caches_evaluated[j].solution;
          caches_[j].valid = caches_evaluated[j].valid;
          caches_[j].parameters = caches_evaluated[j].parameters;
        }
        restored = true;
        if (solved) {
          summary = last_summary;
          break;
        }
        --round;  // round 0 again, from the stage's own start
        continue;
      }
      if (round == 0) report.initial_cost = summary.initial_cost * to_m2;
      report.iterations += static_cast<int>(summary.iterations.size()) - 1;
      add_counters(summary, &report);
      // Active set: hold the free parameters at a bound the cost pushes against, release the
      // held ones it pulls back inside, solve again; until neither changes.
      constexpr int kMaxPasses = 12;
      for (int pass = 0;
           pass < kMaxPasses &&
           update_active_set(free, at_bound, summary.termination_type == ceres::USER_SUCCESS,
                             &is_free);
           ++pass) {
        if (std::none_of(free.begin(), free.end(),
                         [&](int k) { return is_free[static_cast<std::size_t>(k)]; })) {
          break;
        }
        problem.SetManifold(values_.data(), make_manifold(is_free, subspace));
        solve(solver, &problem, &summary, stage.name + " (active set)");
        report.iterations += static_cast<int>(summary.iterations.size()) - 1;
        add_counters(summary, &report);
      }
      const bool any_at_bound = std::any_of(free.begin(), free.end(), at_bound);
      if (!any_at_bound || !(summary.final_cost < (1 - 1e-2) * previous_round_cost)) break;
      previous_round_cost = summary.final_cost;
      last_evaluated = values_;
      caches_evaluated = caches_;
      last_summary = summary;
      solved = summary.IsSolutionUsable();
      recentre_in_gauge(stage_free, stage.bounds_scale);
    }
    report.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const FkCache& c : caches_) {
      report.fk_solves += c.evaluations;
      report.fk_warm_start_failures += c.warm_start_failures;
      report.fk_newton_iterations += c.newton_iterations;
    }
    report.final_cost = summary.final_cost * to_m2;
    report.termination = summary.BriefReport();
    report.usable = summary.IsSolutionUsable();
    last_free_ = free;
    last_bounds_scale_ = stage.bounds_scale;
    // The Huber scale follows the residuals down (a stage that starts far from the data first
    // fits with a wide one): while it shrinks by half, the stage is solved again with it.
    const double used = loss_scale_;
    if (rescale < 8 && used > 0) {
      update_loss_scale();
      if (loss_scale_ < 0.5 * used) {
        const StageReport again = run_stage(stage, last, rescale + 1);
        report.final_cost = again.final_cost;
        report.termination = again.termination;
        report.usable = again.usable;
        report.iterations += again.iterations;
        report.time_s += again.time_s;
        report.residual_evaluations += again.residual_evaluations;
        report.jacobian_evaluations += again.jacobian_evaluations;
        report.residual_time_s += again.residual_time_s;
        report.jacobian_time_s += again.jacobian_time_s;
        report.linear_solver_time_s += again.linear_solver_time_s;
        report.fk_solves += again.fk_solves;
        report.fk_warm_start_failures += again.fk_warm_start_failures;
        report.fk_newton_iterations += again.fk_newton_iterations;
      }
    }
    return report;
  }

  /// Solves, accepts the equilibria at the result, and names a failure on the progress stream:
  /// Ceres' message and the rows whose FK failed during the solve.
  void solve(const ceres::Solver::Options& solver, ceres::Problem* problem,
             ceres::Solver::Summary* summary, const std::string& what) {
    std::vector<int> failures_before(caches_.size());
    for (std::size_t j = 0; j < caches_.size(); ++j) failures_before[j] = caches_[j].failures;
    ceres::Solve(solver, problem, summary);
    settle();
    if (summary->termination_type != ceres::FAILURE || !options_.progress) return;
    std::vector<std::string> rows;
    for (std::size_t j = 0; j < caches_.size(); ++j) {
      if (caches_[j].failures > failures_before[j]) rows.push_back(origin(j));
    }
    options_.progress("stage " + what + ": " + summary->message + " FK failed on " +
                      std::to_string(rows.size()) + " rows" +
                      (rows.empty() ? std::string() : ": " + listing(rows, 5)));
  }
  std::string origin(std::size_t j) const {
    return data_[j].origin.empty() ? "configuration " + std::to_string(j + 1) : data_[j].origin;
  }

  static void add_counters(const ceres::Solver::Summary& summary, StageReport* report) {
    report->residual_evaluations += summary.num_residual_evaluations;
    report->jacobian_evaluations += summary.num_jacobian_evaluations;
    report->residual_time_s += summary.residual_evaluation_time_in_seconds;
    report->jacobian_time_s += summary.jacobian_evaluation_time_in_seconds;
    report->linear_solver_time_s += summary.linear_solver_time_in_seconds;
  }

  /// Moves the values along the gauge orbit (which changes no prediction), by the generators of
  /// `is_free` whose parameters are all free, to the representative that lies deepest inside the
  /// box nominal +- bounds_scale half-widths: the minimum over the motion of
  /// sum_k (dev_k / h_k)^16 on the bounded free parameters, a smooth stand-in for the largest
  /// |dev_k| / h_k (convex: the deviations are affine in the generators' coefficients, then
  /// mapped onto the exact finite motions). A stage restricted to the complement of the gauge
  /// keeps its start's gauge component, so a start near a bound would pin it there; a truth
  /// inside the box has a representative inside it, and this start reaches it.
  void recentre_in_gauge(const std::vector<bool>& is_free, double bounds_scale) {
    const std::vector<GaugeGenerator> generators = this->generators();
    const std::vector<bool> present = gauges(generators, is_free);
    std::vector<int> rows, cols;
    for (int k = 0; k < count_; ++k) {
      if (is_free[static_cast<std::size_t>(k)] && bounded(k)) rows.push_back(k);
    }
    for (std::size_t j = 0; j < generators.size(); ++j) {
      if (present[j]) cols.push_back(static_cast<int>(j));
    }
    if (rows.empty() || cols.empty()) return;
    const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
    const Eigen::Index c = static_cast<Eigen::Index>(cols.size());
    Eigen::MatrixXd a(m, c);
    Eigen::VectorXd e0(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      const std::size_t k = static_cast<std::size_t>(rows[static_cast<std::size_t>(i)]);
      const double h = bounds_scale * half_widths_[k];
      e0(i) = (values_[k] - nominal_values_[k]) / h;
      for (Eigen::Index j = 0; j < c; ++j)
        a(i, j) =
            generators[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])].direction[k] /
            h;
    }
    // Newton on f(g) = sum e^p, e = e0 + a g, from the least-squares (p = 2) minimum.
    constexpr int p = 16;
    const auto f = [&](const Eigen::VectorXd& g) { return (e0 + a * g).array().pow(p).sum(); };
    Eigen::VectorXd g = a.colPivHouseholderQr().solve(-e0);
    if (!g.allFinite()) g.setZero();
    double fg = f(g);
    for (int iter = 0; iter < 50; ++iter) {
      const Eigen::ArrayXd e = (e0 + a * g).array();
      const Eigen::VectorXd gradient = a.transpose() * (p * e.pow(p - 1)).matrix();
      const Eigen::MatrixXd hessian =
          a.transpose() * (p * (p - 1) * e.pow(p - 2)).matrix().asDiagonal() * a;
      const Eigen::VectorXd step = -hessian.ldlt().solve(gradient);
      if (!step.allFinite()) break;
      double t = 1.0, ft = f(g + step);
      for (int ls = 0; ls < 30 && !(ft < fg); ++ls) ft = f(g + (t *= 0.5) * step);
      if (!(ft < fg)) break;
      g += t * step;
      const bool done = fg - ft <= 1e-12 * fg;
      fg = ft;
      if (done) break;
    }
    double coefficient[7] = {0, 0, 0, 0, 0, 0, 0};  // in gauge_generators' order
    for (Eigen::Index j = 0; j < c; ++j) {
      coefficient[cols[static_cast<std::size_t>(j)]] = g(j);
    }
    move(GaugeMotion{
        Pose2<double>{coefficient[kProximalX], coefficient[kProximalY],
                      coefficient[kProximalRotation]},
        Pose2<double>{coefficient[kDistalX], coefficient[kDistalY], coefficient[kDistalRotation]},
        1.0 + coefficient[kStiffness]});
  }

  /// The stage's manifold: the free parameters in half-width units, minus (with `remove_gauge`)
  /// the gauge directions whose parameters are all free, taken at the current values.
  ceres::Manifold* make_manifold(const std::vector<bool>& is_free, bool remove_gauge) const {
    std::vector<int> free;
    for (int k = 0; k < block_; ++k) {
      if (is_free[static_cast<std::size_t>(k)]) free.push_back(k);
    }
    const Eigen::Index f = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd g(f, 0);
    if (remove_gauge) {
      const std::vector<GaugeGenerator> generators = this->generators();
      const std::vector<bool> present = gauges(generators, is_free);
      for (std::size_t j = 0; j < generators.size(); ++j) {
        if (!present[j]) continue;
        g.conservativeResize(f, g.cols() + 1);
        for (Eigen::Index c = 0; c < f; ++c) {
          const std::size_t k = static_cast<std::size_t>(free[static_cast<std::size_t>(c)]);
          g(c, g.cols() - 1) = generators[j].direction[k] / half_widths_[k];
        }
      }
    }
    // Orthonormal complement of the (scaled) gauge generators among the free parameters.
    Eigen::MatrixXd q = Eigen::MatrixXd::Identity(f, f);
    if (g.cols() > 0) q = Eigen::HouseholderQR<Eigen::MatrixXd>(g).householderQ();
    const Eigen::Index t = f - g.cols();
    SubspaceManifold::RowMajor basis = SubspaceManifold::RowMajor::Zero(block_, t);
    SubspaceManifold::RowMajor inverse = SubspaceManifold::RowMajor::Zero(t, block_);
    for (Eigen::Index c = 0; c < f; ++c) {
      const int k = free[static_cast<std::size_t>(c)];
      const double h = half_widths_[static_cast<std::size_t>(k)];
      basis.row(k) = h * q.block(c, g.cols(), 1, t);
      inverse.col(k) = q.block(c, g.cols(), 1, t).transpose() / h;
    }
    return new SubspaceManifold(std::move(basis), std::move(inverse));
  }

  /// Refits the last stage's free parameters with `held` constant: after a gauge fix that changes
  /// the predictions slightly (a distal translation under a load). Holding the gauge references
  /// leaves a full-rank problem, a few iterations from the fixed values. No bounds: the box is
  /// the stages' gauge's, the fixed gauge may put values outside it.
  void refit_holding(const std::vector<int>& held) {
    std::vector<bool> is_free(static_cast<std::size_t>(block_), false);
    for (int k : last_free_) is_free[static_cast<std::size_t>(k)] = true;
    for (int k : held) is_free[static_cast<std::size_t>(k)] = false;
    ceres::Problem problem;
    add_residuals(problem);
    problem.SetManifold(values_.data(), make_manifold(is_free, false));
    const ceres::Solver::Options solver = solver_options(options_.function_tolerance);
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    settle();
  }

  /// The smallest singular value of the scaled Jacobian on `columns` at the current values,
  /// relative to the largest (the rank test of the covariance); NaN when the model cannot be
  /// evaluated.
  double smallest_singular_value(const std::vector<int>& columns) {
    Eigen::MatrixXd J;
    Eigen::VectorXd r;
    if (columns.empty() || !jacobian(&J, &r) || !J.allFinite()) return kNaN;
    Eigen::MatrixXd Js(J.rows(), static_cast<Eigen::Index>(columns.size()));
    for (std::size_t c = 0; c < columns.size(); ++c) {
      Js.col(static_cast<Eigen::Index>(c)) =
          J.col(columns[c]) * half_widths_[static_cast<std::size_t>(columns[c])];
    }
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(Js).singularValues();
    if (sv.size() < static_cast<Eigen::Index>(columns.size())) return 0.0;  // fewer rows
    return sv(sv.size() - 1) / sv(0);
  }

  /// Ceres cost (whitened) at the current values.
  double cost() {
    ceres::Problem problem;
    add_residuals(problem);
    double c = 0;
    problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, nullptr, nullptr, nullptr);
    return c;
  }

  /// Whitened residuals and the dense Jacobian over every flat parameter at the current values;
  /// their 3-row blocks are those of evaluated_rows().
  bool jacobian(Eigen::MatrixXd* J, Eigen::VectorXd* r) {
    ceres::Problem problem;
    add_residuals(problem, false);  // raw residuals: the loss is the stages' business
    double c = 0;
    std::vector<double> residuals;
    ceres::CRSMatrix crs;
    if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, &residuals, nullptr, &crs)) {
      return false;
    }
    J->setZero(crs.num_rows, crs.num_cols);
    for (int row = 0; row < crs.num_rows; ++row) {
      for (int p = crs.rows[static_cast<std::size_t>(row)];
           p < crs.rows[static_cast<std::size_t>(row) + 1]; ++p) {
        (*J)(row, crs.cols[static_cast<std::size_t>(p)]) = crs.values[static_cast<std::size_t>(p)];
      }
    }
    *r = Eigen::Map<Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
    return true;
  }

  /// The Huber scale: robust_scale declared noise units, or as many times the rows' typical
  /// residual when the model is still far (a stage that starts from the nominal geometry sees
  /// micrometres on every row): a row is an outlier against the others, not against a floor the
  /// model has not reached. The median norm of a whitened 3-vector at the noise is 1.538.
  void update_loss_scale() {
    loss_scale_ = options_.robust_scale;
    row_norms_.clear();
    if (!(loss_scale_ > 0)) return;
    ceres::Problem problem;
    add_residuals(problem, false);
    double c = 0;
    std::vector<double> r;
    if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, &r, nullptr, nullptr)) return;
    // Per data row; a lost row has no residual (NaN), and exclude_gross_outliers leaves it out.
    const std::vector<std::size_t> in = evaluated_rows();
    if (r.size() != 3 * in.size() || in.empty()) return;
    row_norms_.assign(data_.size(), kNaN);
    std::vector<double> norms;
    for (std::size_t b = 0; b < in.size(); ++b) {
      norms.push_back(std::sqrt(r[3 * b] * r[3 * b] + r[3 * b + 1] * r[3 * b + 1] +
                                r[3 * b + 2] * r[3 * b + 2]));
      row_norms_[in[b]] = norms.back();
    }
    std::nth_element(norms.begin(), norms.begin() + norms.size() / 2, norms.end());
    const double median = norms[norms.size() / 2];
    if (std::isfinite(median)) loss_scale_ *= std::max(1.0, median / 1.538);
  }

  /// Leaves out of the stage the rows whose residual at its start exceeds kGrossOutlier times the
  /// Huber scale (a measurement of another equilibrium branch, a row millimetres off). The
  /// Huber cost grows linearly in the residual: one such row outweighs all the others together,
  /// and Ceres' relative convergence test then stops on decreases many noise units large (a row
  /// 10 mm off: the validation mean at 0.073 um instead of the floor). They remain among the
  /// rows whose residuals the result reports, and the next stage looks at them again.
  void exclude_gross_outliers() {
    constexpr double kGrossOutlier = 100;
    std::fill(gross_.begin(), gross_.end(), false);
    if (!(loss_scale_ > 0) || row_norms_.size() != gross_.size()) return;
    for (std::size_t j = 0; j < gross_.size(); ++j)
      gross_[j] = !(row_norms_[j] <= kGrossOutlier * loss_scale_);
  }
  double loss_scale() const { return loss_scale_; }

  const std::vector<int>& last_free() const { return last_free_; }
  std::size_t rows() const { return data_.size(); }
  double last_bounds_scale() const { return last_bounds_scale_; }

 private:
  /// Ends a solve (successfully: the values are the last accepted step's) when `stop` says so
  /// after an accepted step.
  /// Accepts the caches at every point Ceres keeps (the start and each successful step): the
  /// solves of the next trial points start from there (FkCache::anchor). Needs
  /// update_state_every_iteration.
  class AcceptCallback : public ceres::IterationCallback {
   public:
    explicit AcceptCallback(Identification* id) : id_(id) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      if (s.iteration == 0 || s.step_is_successful) id_->accept_evaluated();
      return ceres::SOLVER_CONTINUE;
    }

   private:
    Identification* id_;
  };

  class BoundCallback : public ceres::IterationCallback {
   public:
    explicit BoundCallback(std::function<bool()> stop) : stop_(std::move(stop)) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      return s.iteration > 0 && s.step_is_successful && stop_()
                 ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                 : ceres::SOLVER_CONTINUE;
    }

   private:
    std::function<bool()> stop_;
  };

  /// One update of the active set of the bounds. After a solve stopped by a step onto a bound,
  /// the free parameters at a bound are held. After a solve that ran its course, the sign of the
  /// cost's gradient at a bound (its Lagrange multiplier's) decides: a parameter of `free` the
  /// cost pushes against its bound is held, one it pulls back inside is free. Returns whether
  /// any changed.
  template <class AtBound>
  bool update_active_set(const std::vector<int>& free, const AtBound& at_bound,
                         bool stopped_at_bound, std::vector<bool>* is_free) {
    if (stopped_at_bound) {
      bool changed = false;
      for (int k : free) {
        if ((*is_free)[static_cast<std::size_t>(k)] && at_bound(k)) {
          (*is_free)[static_cast<std::size_t>(k)] = false;
          changed = true;
        }
      }
      return changed;
    }
    ceres::Problem problem;
    add_residuals(problem);
    double c = 0;
    std::vector<double> gradient;
    if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &c, nullptr, &gradient, nullptr)) {
      return false;
    }
    bool changed = false;
    for (int k : free) {
      const std::size_t uk = static_cast<std::size_t>(k);
      if (!at_bound(k)) continue;
      const bool pulled_inside = gradient[uk] * (values_[uk] - nominal_values_[uk]) > 0;
      if ((*is_free)[uk] != pulled_inside) {
        (*is_free)[uk] = pulled_inside;
        changed = true;
      }
    }
    return changed;
  }

  class ProgressCallback : public ceres::IterationCallback {
   public:
    ProgressCallback(std::string stage, double to_m2,
                     const std::function<void(const std::string&)>& sink)
        : stage_(std::move(stage)), to_m2_(to_m2), sink_(sink) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      if (sink_) {
        sink_("stage " + stage_ + ": iteration " + std::to_string(s.iteration) + ", cost " +
              format_number(s.cost * to_m2_) + " m^2");
      }
      return ceres::SOLVER_CONTINUE;
    }

   private:
    std::string stage_;
    double to_m2_;
    const std::function<void(const std::string&)>& sink_;
  };

  RobotParams<double> nominal_;
  const std::vector<CalibrationSample>& data_;
  const CalibrationOptions& options_;
  int n_;
  int count_;
  bool identify_load_;
  int block_;
  std::vector<double> values_;
  std::vector<double> nominal_values_;
  std::vector<double> half_widths_;
  std::vector<FkCache> caches_;
  std::vector<int> last_free_;
  double last_bounds_scale_ = 1.0;
  double loss_scale_ = 0;          ///< Huber scale of the current stage (whitened units; 0: none)
  std::vector<double> row_norms_;  ///< whitened residual norms at the last update_loss_scale
  std::vector<bool> gross_;        ///< rows left out of the stage (exclude_gross_outliers)
  /// Rows whose equilibrium did not follow the values (settle): left out of the solves until it
  /// does, so that one row past a fold of the current geometry does not end a solve at its start.
  std::vector<bool> lost_;
};

/// What makes `result` doubtful, in words: extrinsics outside their declared interval, residuals
/// inconsistent with the declared noise, parameters held at a bound.
void add_warnings(const Identification& id, CalibrationResult* result) {
  for (int k = 0; k < id.count(); ++k) {
    const ParameterEstimate& p = result->parameters[static_cast<std::size_t>(k)];
    if (id.bounded(k) || !(p.half_width > 0)) continue;
    const double deviation = std::abs(p.value - p.nominal) / p.half_width;
    if (deviation > 1) {
      result->warnings.push_back(p.name + " = " + format_number(p.value) + " lies " +
                                 format_number(deviation) + " half-widths from its declared " +
                                 format_number(p.nominal) + " +- " + format_number(p.half_width) +
                                 ": the extrinsics guess or its uncertainty is wrong");
    }
  }
  // Whitened residuals have unit variance at the declared noise; 5 standard deviations of the
  // chi-square estimate of the variance above it is an inconsistency, not chance.
  const double dof = 3.0 * static_cast<double>(id.rows() - result->outliers.size()) -
                     static_cast<double>(result->jacobian_rank);
  const double v = result->residual_variance;
  result->residuals_exceed_noise = std::isfinite(v) && dof > 0 && v > 1 + 5 * std::sqrt(2 / dof);
  if (result->residuals_exceed_noise) {
    result->warnings.push_back(
        "the residuals are " + format_number(std::sqrt(v)) +
        " times the declared noise (residual_scale): an unmodelled effect, outliers, wrong "
        "extrinsics or more noise than declared");
  }
  std::vector<std::string> at_bound;
  for (const ParameterEstimate& p : result->parameters)
    if (p.at_bound) at_bound.push_back(p.name);
  if (!at_bound.empty()) {
    result->warnings.push_back(
        std::to_string(at_bound.size()) +
        " parameters ended at a bound of their interval: " + listing(at_bound, 10));
  }
}

}  // namespace

std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot) {
  const int n = robot.num_limbs;
  const int count = num_parameters(n);
  auto idx = [n](ParameterKind kind, int limb) {
    return parameter_index(ParameterId{kind, limb}, n);
  };
  auto blank = [count]() { return std::vector<double>(static_cast<std::size_t>(count), 0.0); };
  std::vector<GaugeGenerator> out;
  const Pose2<double>& camera = robot.extrinsics.camera;
  const Pose2<double>& pattern = robot.extrinsics.pattern;
  for (int axis = 0; axis < 2; ++axis) {
    GaugeGenerator g{std::string("proximal clamps + camera: translation ") + (axis ? "y" : "x"),
                     std::string(axis ? "A_y[*] + camera_y" : "A_x[*] + camera_x"), blank()};
    for (int i = 0; i < n; ++i)
      g.direction[idx(axis ? ParameterKind::kAy : ParameterKind::kAx, i)] = 1;
    g.direction[idx(axis ? ParameterKind::kCameraY : ParameterKind::kCameraX, -1)] = 1;
    out.push_back(g);
  }
  {
    GaugeGenerator g{"proximal clamps + camera: rotation",
                     "(A_x, A_y)[*] rotated about W + alpha[*] + camera", blank()};
    for (int i = 0; i < n; ++i) {
      g.direction[idx(ParameterKind::kAx, i)] = -robot.limb(i).A.y();
      g.direction[idx(ParameterKind::kAy, i)] = robot.limb(i).A.x();
      g.direction[idx(ParameterKind::kAlpha, i)] = 1;
    }
    g.direction[idx(ParameterKind::kCameraX, -1)] = -camera.y;
    g.direction[idx(ParameterKind::kCameraY, -1)] = camera.x;
    g.direction[idx(ParameterKind::kCameraTheta, -1)] = 1;
    out.push_back(g);
  }
  for (int axis = 0; axis < 2; ++axis) {
    GaugeGenerator g{
        std::string("distal clamps + pattern: translation ") + (axis ? "y" : "x"),
        std::string(axis ? "B_y[*] - R(pattern_theta) e_y" : "B_x[*] - R(pattern_theta) e_x"),
        blank()};
    for (int i = 0; i < n; ++i)
      g.direction[idx(axis ? ParameterKind::kBy : ParameterKind::kBx, i)] = 1;
    const Vector2<double> e = axis ? Vector2<double>(0, 1) : Vector2<double>(1, 0);
    const Vector2<double> d = -pattern.rotate(e);
    g.direction[idx(ParameterKind::kPatternX, -1)] = d.x();
    g.direction[idx(ParameterKind::kPatternY, -1)] = d.y();
    out.push_back(g);
  }
  {
    GaugeGenerator g{"distal clamps + pattern: rotation",
                     "(B_x, B_y)[*] rotated about P + beta[*] - pattern_theta", blank()};
    for (int i = 0; i < n; ++i) {
      g.direction[idx(ParameterKind::kBx, i)] = -robot.limb(i).B.y();
      g.direction[idx(ParameterKind::kBy, i)] = robot.limb(i).B.x();
      g.direction[idx(ParameterKind::kBeta, i)] = 1;
    }
    g.direction[idx(ParameterKind::kPatternTheta, -1)] = -1;
    out.push_back(g);
  }
  {
    GaugeGenerator g{"bending stiffness: common scale", "d[*] scaled together", blank()};
    for (int i = 0; i < n; ++i)
      g.direction[idx(ParameterKind::kDiameter, i)] = robot.limb(i).rod.diameter;
    out.push_back(g);
  }
  return out;
}

bool measurement_jacobian(const RobotParams<double>& robot, const JointVector& q,
                          double orientation_weight, double residual_scale,
                          Eigen::MatrixXd* jacobian, const SolverOptions& fk) {
  const int count = num_parameters(robot.num_limbs);
  FkCache cache;
  const std::unique_ptr<ceres::CostFunction> cost(
      PoseMeasurementError::Create(robot, q, Pose2<double>(), orientation_weight, residual_scale,
                                   &cache, fk, DerivativeMode::kImplicit));
  std::vector<double> values(static_cast<std::size_t>(count));
  get_parameters(robot, values.data());
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> J(3, count);
  double residuals[3];
  const double* parameters[] = {values.data()};
  double* jacobians[] = {J.data()};
  if (!cost->Evaluate(parameters, residuals, jacobians)) return false;
  *jacobian = J;
  return true;
}

std::vector<CalibrationStage> default_stages() {
  return {
      {"extrinsics", {"camera", "pattern"}, 1.0},
      {"influential", {"l", "A", "B", "alpha", "camera", "pattern"}, 1.0},
      {"all", {"all"}, 1.0},
  };
}

bool frees_load(const std::vector<CalibrationStage>& stages) {
  for (const CalibrationStage& stage : stages) {
    if (std::find(stage.free.begin(), stage.free.end(), "load") != stage.free.end()) return true;
  }
  return false;
}

std::vector<CalibrationStage> with_load_stage(std::vector<CalibrationStage> stages) {
  if (!stages.empty() && !frees_load(stages)) stages.back().free.push_back("load");
  return stages;
}

void validate_stages(const std::vector<CalibrationStage>& stages, const std::string& source) {
  if (stages.empty()) throw InputError(source + ": no stage");
  for (std::size_t s = 0; s < stages.size(); ++s) {
    const std::string where = source + ": stages[" + std::to_string(s) + "]";
    for (const std::string& kind : stages[s].free) {
      if (!known_kind(kind)) throw InputError(where + ".free: unknown kind \"" + kind + "\"");
    }
    if (!(stages[s].bounds_scale > 0) || !std::isfinite(stages[s].bounds_scale)) {
      throw InputError(where + ".bounds_scale: must be positive, got " +
                       format_number(stages[s].bounds_scale));
    }
  }
}

std::vector<double> parameter_half_widths(const RobotUncertainty& u, int num_limbs) {
  std::vector<double> h(static_cast<std::size_t>(num_parameters(num_limbs)), 0.0);
  for (int k = 0; k < num_parameters(num_limbs); ++k) {
    const ParameterId id = parameter_id(k, num_limbs);
    double& v = h[static_cast<std::size_t>(k)];
    if (id.limb >= 0) {
      const LimbUncertainty& l = static_cast<std::size_t>(id.limb) < u.limbs.size()
                                     ? u.limbs[static_cast<std::size_t>(id.limb)]
                                     : u.global;
      v = limb_parameter(l, id.kind);
    } else {
      const int e = static_cast<int>(id.kind) - static_cast<int>(ParameterKind::kCameraX);
      v = e < 3 ? u.camera(e) : u.pattern(e - 3);
    }
  }
  return h;
}

RobotParams<double> move_along_gauge(const RobotParams<double>& params, const Pose2<double>& G,
                                     const Pose2<double>& H, double stiffness_scale) {
  RobotParams<double> out = params;
  for (int i = 0; i < params.num_limbs; ++i) {
    LimbParams<double>& limb = out.limb(i);
    limb.A = G.transform(params.limb(i).A);
    limb.alpha = params.limb(i).alpha + G.theta;
    limb.B = H.transform(params.limb(i).B);
    limb.beta = params.limb(i).beta + H.theta;
    limb.rod.diameter = params.limb(i).rod.diameter * stiffness_scale;
  }
  out.extrinsics.camera = G * params.extrinsics.camera;
  out.extrinsics.pattern = params.extrinsics.pattern * H.inverse();
  return out;
}

PlatformLoad<double> move_load_along_gauge(const PlatformLoad<double>& load, const Pose2<double>& G,
                                           const Pose2<double>& H, double stiffness_scale) {
  const double stiffness = std::pow(stiffness_scale, 4);  // EI ~ d^4
  PlatformLoad<double> out;
  out.force = stiffness * G.rotate(load.force);
  // The new platform origin lies at H^-1(0) in the old platform frame: the moment about it
  // loses that arm's cross product with the force (platform angle taken as 0).
  const Vector2<double> arm = H.inverse().translation();
  out.moment = stiffness * (load.moment - (arm.x() * load.force.y() - arm.y() * load.force.x()));
  return out;
}

ForwardSolution move_equilibrium_along_gauge(const ForwardSolution& solution,
                                             const Pose2<double>& G, const Pose2<double>& H,
                                             double stiffness_scale) {
  const double stiffness = std::pow(stiffness_scale, 4);  // EI ~ d^4
  ForwardSolution out = solution;
  out.pose = G * solution.pose * H.inverse();
  for (Wrench<double>& w : out.wrenches) {
    const Vector2<double> n = stiffness * G.rotate(Vector2<double>(w.nx, w.ny));
    w = Wrench<double>{n.x(), n.y(), stiffness * w.m};  // m(0), about the rod's start: not turned
  }
  out.jacobian.clear();
  return out;
}

std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot,
                                             const PlatformLoad<double>& load) {
  std::vector<GaugeGenerator> out = gauge_generators(robot);
  const double fx = load.force.x(), fy = load.force.y(), m = load.moment;
  // d load / d coefficient of each generator, in gauge_generators' order (see
  // move_load_along_gauge): proximal x, y, rotation; distal x, y, rotation; stiffness.
  const double components[7][kLoadParameters] = {
      {0, 0, 0},   {0, 0, 0}, {-fy, fx, 0},           {0, 0, fy},
      {0, 0, -fx}, {0, 0, 0}, {4 * fx, 4 * fy, 4 * m}};
  for (std::size_t j = 0; j < out.size(); ++j) {
    out[j].direction.insert(out[j].direction.end(), components[j], components[j] + kLoadParameters);
  }
  return out;
}

GaugeMotion gauge_fix_motion(const RobotParams<double>& params,
                             const RobotParams<double>& reference, bool proximal_translation,
                             bool proximal_rotation, bool distal_translation, bool distal_rotation,
                             bool stiffness) {
  // The motion that maps limb 0's estimated clamp frame onto its reference one; a rotation alone
  // turns about the origin.
  const auto onto_reference = [](bool translation, bool rotation, const Vector2<double>& estimated,
                                 double estimated_angle, const Vector2<double>& wanted,
                                 double wanted_angle) {
    const double rot = rotation ? wanted_angle - estimated_angle : 0.0;
    if (!translation) return Pose2<double>{0, 0, rot};
    const Vector2<double> t = wanted - Pose2<double>{0, 0, rot}.rotate(estimated);
    return Pose2<double>{t.x(), t.y(), rot};
  };
  const LimbParams<double>& limb = params.limb(0);
  const LimbParams<double>& ref = reference.limb(0);
  return GaugeMotion{
      onto_reference(proximal_translation, proximal_rotation, limb.A, limb.alpha, ref.A, ref.alpha),
      onto_reference(distal_translation, distal_rotation, limb.B, limb.beta, ref.B, ref.beta),
      stiffness ? ref.rod.diameter / limb.rod.diameter : 1.0};
}

GaugeMotion gauge_fix_motion(const RobotParams<double>& params, const PlatformLoad<double>& load,
                             const RobotParams<double>& reference, bool held[2]) {
  const Vector2<double>& B = params.limb(0).B;
  const Vector2<double>& wanted = reference.limb(0).B;
  const double force = load.force.norm();
  if (!(force > 0)) {
    held[0] = held[1] = true;
    return GaugeMotion{Pose2<double>{0, 0, 0},
                       Pose2<double>{wanted.x() - B.x(), wanted.y() - B.y(), 0}, 1.0};
  }
  // The platform origin moves by -t: its moment arm about the old origin, t x f at angle 0, is
  // compensated by move_load_along_gauge; what is left, (R(theta) - I) t x f, is second order in
  // theta when t is perpendicular to f.
  const Vector2<double> u(-load.force.y() / force, load.force.x() / force);
  const int c = std::abs(u.x()) >= std::abs(u.y()) ? 0 : 1;
  held[c] = true;
  held[1 - c] = false;
  const Vector2<double> t = (wanted[c] - B[c]) / u[c] * u;
  return GaugeMotion{Pose2<double>{0, 0, 0}, Pose2<double>{t.x(), t.y(), 0}, 1.0};
}

RobotParams<double> fix_gauge(const RobotParams<double>& params,
                              const RobotParams<double>& reference, bool proximal_translation,
                              bool proximal_rotation, bool distal_translation, bool distal_rotation,
                              bool stiffness) {
  const GaugeMotion m = gauge_fix_motion(params, reference, proximal_translation, proximal_rotation,
                                         distal_translation, distal_rotation, stiffness);
  return move_along_gauge(params, m.G, m.H, m.stiffness_scale);
}

ConfigurationErrors configuration_errors(const RobotParams<double>& robot,
                                         const std::vector<CalibrationSample>& data,
                                         const SolverOptions& fk, const PlatformLoad<double>& load,
                                         SequenceMode order) {
  ConfigurationErrors errors;
  errors.branch_mismatch.assign(data.size(), false);
  errors.other_pose.assign(data.size(), Pose2<double>{kNaN, kNaN, kNaN});
  const std::vector<ForwardSolution> solutions = solve_rows(robot, data, fk, order, load);
  for (std::size_t j = 0; j < data.size(); ++j) {
    const ForwardSolution& s = solutions[j];
    if (!is_equilibrium(s.summary)) {
      errors.e_p.push_back(kNaN);
      errors.e_theta.push_back(kNaN);
      continue;
    }
    const Pose2<double> measured = robot.extrinsics.platform_from_measurement(data[j].measured);
    errors.e_p.push_back(std::hypot(s.pose.x - measured.x, s.pose.y - measured.y));
    errors.e_theta.push_back(std::abs(wrap_angle(s.pose.theta - measured.theta)));
  }
  std::vector<const ForwardSolution*> predicted;
  for (const ForwardSolution& s : solutions) predicted.push_back(&s);
  const std::vector<std::optional<ForwardSolution>> other =
      equilibria_measured_instead(robot, data, predicted, fk, load, order);
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (!other[j]) continue;
    errors.branch_mismatch[j] = true;
    errors.other_pose[j] = other[j]->pose;
  }
  return errors;
}

PoseErrorStats pose_errors(const RobotParams<double>& robot,
                           const std::vector<CalibrationSample>& data, const SolverOptions& fk,
                           const PlatformLoad<double>& load, SequenceMode order) {
  return error_statistics(configuration_errors(robot, data, fk, load, order));
}

PoseErrorStats error_statistics(const ConfigurationErrors& errors) {
  PoseErrorStats stats;
  stats.min_p = stats.min_theta = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < errors.e_p.size(); ++j) {
    const double e_p = errors.e_p[j], e_t = errors.e_theta[j];
    if (std::isnan(e_p)) {
      ++stats.failed;
      continue;
    }
    if (j < errors.branch_mismatch.size() && errors.branch_mismatch[j]) {
      ++stats.branch_mismatches;
      continue;
    }
    stats.max_p = std::max(stats.max_p, e_p);
    stats.min_p = std::min(stats.min_p, e_p);
    stats.mean_p += e_p;
    stats.max_theta = std::max(stats.max_theta, e_t);
    stats.min_theta = std::min(stats.min_theta, e_t);
    stats.mean_theta += e_t;
    ++stats.count;
  }
  if (stats.count > 0) {
    stats.mean_p /= stats.count;
    stats.mean_theta /= stats.count;
  } else {
    stats.min_p = stats.min_theta = kNaN;
    stats.max_p = stats.max_theta = stats.mean_p = stats.mean_theta = kNaN;
  }
  return stats;
}

int free_parameter_count(const CalibrationStage& stage, const RobotDescription& nominal) {
  if (!nominal.uncertainty) throw InputError("free_parameter_count: no uncertainty section");
  const int n = nominal.params.num_limbs;
  return static_cast<int>(
      stage_free_indices(stage, parameter_half_widths(*nominal.uncertainty, n), n).size());
}

void check_enough_measurements(const std::vector<CalibrationStage>& stages,
                               const RobotDescription& nominal, std::size_t rows,
                               const std::string& source) {
  if (!nominal.uncertainty) return;  // calibrate() names the missing section and what needs it
  // The stage with the most free parameters (the last, "all", for the default stages) decides.
  const CalibrationStage* largest = nullptr;
  int free = 0;
  for (const CalibrationStage& stage : stages) {
    const int count = free_parameter_count(stage, nominal);
    if (largest == nullptr || count > free) {
      largest = &stage;
      free = count;
    }
  }
  const std::size_t measured = 3 * rows;
  if (largest == nullptr || measured >= static_cast<std::size_t>(free)) return;
  throw InputError(source + ": " + std::to_string(rows) +
                   (rows == 1 ? " configuration gives " : " configurations give ") +
                   std::to_string(measured) +
                   " measured values (x, y, theta each), fewer than the " + std::to_string(free) +
                   " free parameters of stage '" + largest->name + "': at least " +
                   std::to_string((free + 2) / 3) + " configurations are needed");
}

CalibrationResult calibrate(const RobotDescription& nominal,
                            const std::vector<CalibrationSample>& data,
                            const CalibrationOptions& options) {
  const std::string source = "calibration of \"" + nominal.name + "\"";
  if (!nominal.uncertainty) {
    throw InputError(source +
                     ": the nominal description has no \"uncertainty\" section; the "
                     "bounds of the identification (Eq. 7) come from it");
  }
  const int n = nominal.params.num_limbs;
  if (n < 2 || n > kMaxLimbs)
    throw InputError(source + ": invalid limb count " + std::to_string(n));
  if (data.empty()) throw InputError(source + ": no calibration configuration");
  for (std::size_t j = 0; j < data.size(); ++j) {
    if (data[j].q.size() != n) {
      throw InputError(source + ": configuration " + std::to_string(j + 1) + " has " +
                       std::to_string(data[j].q.size()) + " joint values, the robot " +
                       std::to_string(n) + " limbs");
    }
  }
  require_valid(options, "calibration options");
  validate_stages(options.stages, source);
  check_enough_measurements(options.stages, nominal, data.size(), source);

  CalibrationResult result;
  result.residual_variance = kNaN;
  std::vector<Pose2<double>> nominal_poses;
  std::vector<std::size_t> used, set_aside;
  std::vector<CalibrationSample> rows = reachable_rows(nominal.params, data, options, source,
                                                       &result, &nominal_poses, &used, &set_aside);
  auto identification = std::make_unique<Identification>(nominal, rows, options);
  {
    RobotParams<double> start = nominal.params;
    start.extrinsics = registered_extrinsics(nominal_poses, rows, nominal.params.extrinsics);
    identification->set_robot(start);
    warn_of_mirror(nominal_poses, rows, start.extrinsics, nominal.params.extrinsics, &result);
  }
  identification->start_on_measured_branches();
  const std::vector<double> registered = identification->values();
  const int count = identification->count();
  const int block = identification->block();

  // Table 3's "nominal model": the nominal robot with the extrinsics alone identified.
  bool first_is_extrinsics = true;
  for (int k : identification->free_indices(options.stages.front())) {
    first_is_extrinsics = first_is_extrinsics && k < count && parameter_id(k, n).limb < 0;
  }
  if (!first_is_extrinsics) {
    identification->run_stage(CalibrationStage{"extrinsics (nominal model)", {"extrinsics"}, 1.0});
    result.extrinsics_only = identification->robot();
    identification->set_values(registered);
  }
  for (std::size_t s = 0; s < options.stages.size(); ++s) {
    result.stages.push_back(
        identification->run_stage(options.stages[s], s + 1 == options.stages.size()));
    if (s == 0 && first_is_extrinsics) result.extrinsics_only = identification->robot();
  }

  // The rows set aside that the identified geometry reaches join the last stage, run again.
  if (!set_aside.empty()) {
    const RobotParams<double> identified = identification->robot();
    ForwardSequence sequence(identified, options.fk, identification->load());
    std::vector<std::string> back, still;
    for (std::size_t j : set_aside) {
      const ForwardSolution& s = sequence.solve(data[j].q);
      const std::string row = origin_of(data, j) + " (" + joints_text(data[j].q) + ")";
      if (is_equilibrium(s.summary)) {
        used.push_back(j);
        back.push_back(row);
      } else {
        still.push_back(row + ": " + to_string(s.summary.status));
      }
    }
    if (!back.empty()) {
      const std::vector<double> values = identification->values();
      identification.reset();               // it holds `rows`, which grows
      std::sort(used.begin(), used.end());  // the measurement order: the rows' path
      rows.clear();
      for (std::size_t j : used) {
        rows.push_back(data[j]);
        rows.back().origin = origin_of(data, j);
      }
      identification = std::make_unique<Identification>(nominal, rows, options);
      identification->set_values(values);
      identification->start_on_measured_branches();
      CalibrationStage again = options.stages.back();
      again.name += " (with " + std::to_string(back.size()) + " rows brought back)";
      result.stages.push_back(identification->run_stage(again, true));
      result.warnings.push_back(
          std::to_string(back.size()) +
          " rows set aside reached by the identified geometry, used in stage '" + again.name +
          "': " + listing(back));
    }
    result.dropped.insert(result.dropped.end(), still.begin(), still.end());
  }
  // Rows measured on another equilibrium at their joints than the readings at the start values
  // gave (a fold the nominal geometry places elsewhere, a robot pushed onto a buckled shape):
  // named by the identified model, fitted there in the last stage, run again.
  const std::vector<std::string> moved = identification->move_to_measured_equilibria();
  if (!moved.empty()) {
    CalibrationStage again = options.stages.back();
    again.name += " (with " + std::to_string(moved.size()) + " rows on the equilibria measured)";
    result.stages.push_back(identification->run_stage(again, true));
    result.warnings.push_back(
        std::to_string(moved.size()) +
        " rows were measured on another equilibrium at their joints than the one first fitted "
        "(the robot came to it another way): fitted on it in stage '" +
        again.name + "': " + listing(moved));
  }
  Identification& id = *identification;

  // Parameters at a bound (before the gauge fix, in the last stage's box).
  const std::vector<int>& free = id.last_free();
  std::vector<bool> is_free(static_cast<std::size_t>(block), false);
  for (int k : free) is_free[static_cast<std::size_t>(k)] = true;
  result.parameters.resize(static_cast<std::size_t>(block));
  for (int k = 0; k < block; ++k) {
    ParameterEstimate& p = result.parameters[static_cast<std::size_t>(k)];
    const std::size_t uk = static_cast<std::size_t>(k);
    p.name = parameter_name(parameter_id(k, n));
    p.kind = parameter_id(k, n).kind;
    p.nominal = id.nominal_values()[uk];
    p.half_width = id.half_widths()[uk];
    p.free = is_free[uk];
    if (p.free && id.bounded(k)) {
      p.box_deviation = (id.values()[uk] - p.nominal) / (id.last_bounds_scale() * p.half_width);
      p.at_bound = std::abs(std::abs(p.box_deviation) - 1) <= 1e-6;
    }
  }

  // Gauge: which generators only move free parameters.
  std::vector<bool> present = id.gauges(id.generators(), is_free);
  const auto flat = [n](ParameterKind kind, int limb) {
    return parameter_index(ParameterId{kind, limb}, n);
  };
  const bool prox_t = present[kProximalX] && present[kProximalY];
  const bool prox_r = prox_t && present[kProximalRotation];
  const bool dist_t = present[kDistalX] && present[kDistalY];
  const bool dist_r = present[kDistalRotation];
  const bool stiff = present[kStiffness];
  result.load_identified = id.load_free(is_free);
  const std::vector<bool> movable = present_generators(id.generators(), is_free);
  bool held_distal[2] = {dist_t, dist_t};  // B_0's x and y
  const auto references = [&] {            // the parameters the gauge fix holds
    std::vector<int> held;
    if (prox_t) held.push_back(flat(ParameterKind::kAx, 0));
    if (prox_t) held.push_back(flat(ParameterKind::kAy, 0));
    if (prox_r) held.push_back(flat(ParameterKind::kAlpha, 0));
    if (held_distal[0]) held.push_back(flat(ParameterKind::kBx, 0));
    if (held_distal[1]) held.push_back(flat(ParameterKind::kBy, 0));
    if (dist_r) held.push_back(flat(ParameterKind::kBeta, 0));
    if (stiff) held.push_back(flat(ParameterKind::kDiameter, 0));
    return held;
  };
  if (options.fix_gauge) {
    id.move(gauge_fix_motion(id.robot(), nominal.params, prox_t, prox_r, dist_t, dist_r, stiff));
    // With the load free, a distal translation is a gauge only perpendicular to the force, and
    // to second order in the platform angle: the data leave it unidentified, so one coordinate
    // of B_0 holds it. Along the force it is identified as far as the data see the force: where
    // the free parameters less the references are rank deficient, it is a gauge too (B_0 held
    // whole). The other free parameters are then refitted with the references held.
    if (result.load_identified && movable[kDistalX] && movable[kDistalY]) {
      id.move(gauge_fix_motion(id.robot(), id.load(), nominal.params, held_distal));
      if (!(held_distal[0] && held_distal[1])) {
        const std::vector<int> held = references();
        std::vector<int> estimated;
        for (int k : free) {
          if (std::find(held.begin(), held.end(), k) == held.end()) estimated.push_back(k);
        }
        if (!(id.smallest_singular_value(estimated) > kRankThreshold)) {
          id.move(
              gauge_fix_motion(id.robot(), PlatformLoad<double>(), nominal.params, held_distal));
        }
      }
      present[kDistalX] = held_distal[0];
      present[kDistalY] = held_distal[1];
    }
  }
  const std::vector<int> held = references();
  if (options.fix_gauge && result.load_identified && (held_distal[0] || held_distal[1])) {
    id.refit_holding(held);
  }
  result.identified = id.robot();
  result.load = id.load();
  result.free_count = static_cast<int>(free.size());

  // Rank of the Jacobian (columns scaled by the half-widths) on the free parameters. A model that
  // cannot be evaluated at the result (an FK that fails there) has no rank, variance or std.
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  const std::vector<std::string> lost = id.lost_rows();
  if (!lost.empty()) {
    result.warnings.push_back(std::to_string(lost.size()) +
                              " rows left out: their equilibrium does not continue to the "
                              "identified geometry (past a fold of it?): " +
                              listing(lost));
  }
  const bool evaluated = !free.empty() && id.jacobian(&J, &r) && J.allFinite() && r.allFinite();
  if (!free.empty() && !evaluated) {
    result.warnings.push_back(
        "the model could not be evaluated at the identified values (an FK failed or was not "
        "finite): no rank, residual variance or standard deviations");
  }
  // Outliers: rows whose whitened residual norm exceeds robust_scale. The Huber loss bounded
  // their pull in the stages; the rank, the variance and the covariance are the other rows'.
  id.update_loss_scale();
  result.outlier_threshold = id.loss_scale();
  if (evaluated && id.loss_scale() > 0) {
    const std::vector<std::size_t> in = id.evaluated_rows();
    std::vector<Eigen::Index> kept;
    for (std::size_t b = 0; b < in.size(); ++b) {
      const std::size_t j = in[b];
      const Eigen::Index at = 3 * static_cast<Eigen::Index>(b);
      const double norm = r.segment<3>(at).norm();
      if (norm > id.loss_scale()) {
        result.outliers.push_back(origin_of(rows, j) + " (" + format_number(norm) +
                                  " x the noise)");
      } else {
        kept.insert(kept.end(), {at, at + 1, at + 2});
      }
    }
    if (!result.outliers.empty()) {
      result.warnings.push_back(
          std::to_string(result.outliers.size()) + " rows are outliers (residual beyond " +
          format_number(id.loss_scale()) +
          " x the declared noise), down-weighted: " + listing(result.outliers));
      const Eigen::MatrixXd J_kept = J(kept, Eigen::all);
      const Eigen::VectorXd r_kept = r(kept);
      J = J_kept;
      r = r_kept;
    }
  }
  if (evaluated) {
    Eigen::MatrixXd Js(J.rows(), static_cast<Eigen::Index>(free.size()));
    for (std::size_t c = 0; c < free.size(); ++c) {
      Js.col(static_cast<Eigen::Index>(c)) =
          J.col(free[c]) * id.half_widths()[static_cast<std::size_t>(free[c])];
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js);
    const Eigen::VectorXd sv = svd.singularValues();
    const double smax = sv.size() > 0 ? sv(0) : 0.0;
    for (Eigen::Index k = 0; k < sv.size(); ++k) {
      result.singular_values.push_back(smax > 0 ? sv(k) / smax : 0.0);
      if (smax > 0 && sv(k) > kRankThreshold * smax) ++result.jacobian_rank;
    }
    const std::vector<GaugeGenerator> final_generators = id.generators();
    for (std::size_t g = 0; g < final_generators.size(); ++g) {
      GaugeDirection d;
      d.name = final_generators[g].name;
      d.combination = final_generators[g].combination;
      d.present = present[g];
      d.free = movable[g];
      Eigen::VectorXd scaled(static_cast<Eigen::Index>(free.size()));
      for (std::size_t c = 0; c < free.size(); ++c) {
        const std::size_t k = static_cast<std::size_t>(free[c]);
        scaled(static_cast<Eigen::Index>(c)) =
            final_generators[g].direction[k] / id.half_widths()[k];
      }
      d.relative_gain = (d.free && smax > 0 && scaled.norm() > 0)
                            ? (Js * scaled).norm() / (smax * scaled.norm())
                            : kNaN;
      result.gauge.push_back(d);
    }
    const double m = static_cast<double>(r.size());
    const double dof = m - static_cast<double>(result.jacobian_rank);
    result.residual_variance = dof > 0 ? r.squaredNorm() / dof : kNaN;
  }

  // Standard deviations in the limb-0 gauge: the pseudo-inverse of J^T J on the free parameters
  // that are not gauge references, in half-width units, scaled back and by the residual
  // variance. Directions below the rank threshold are what the data cannot identify: named in
  // words, and every parameter with a share in one is "not identifiable" (std NaN), not 0.
  for (int k : held) result.parameters[static_cast<std::size_t>(k)].gauge_reference = true;
  std::vector<int> estimated;
  for (int k : free) {
    if (!result.parameters[static_cast<std::size_t>(k)].gauge_reference) estimated.push_back(k);
  }
  if (options.compute_covariance) result.covariance = Eigen::MatrixXd::Zero(block, block);
  if (options.compute_covariance && evaluated && !estimated.empty() &&
      std::isfinite(result.residual_variance)) {
    const Eigen::Index p = static_cast<Eigen::Index>(estimated.size());
    Eigen::MatrixXd Je(J.rows(), p);
    for (Eigen::Index c = 0; c < p; ++c) {
      const std::size_t k = static_cast<std::size_t>(estimated[static_cast<std::size_t>(c)]);
      Je.col(c) = J.col(static_cast<Eigen::Index>(k)) * id.half_widths()[k];
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Je, Eigen::ComputeFullV);
    const Eigen::VectorXd sv = svd.singularValues();  // min(rows, p) of them; the rest are 0
    const Eigen::MatrixXd& V = svd.matrixV();         // p x p
    const double smax = sv.size() > 0 ? sv(0) : 0.0;
    result.covariance_ok = smax > 0;
    Eigen::VectorXd inverse_squares = Eigen::VectorXd::Zero(p);
    std::vector<bool> identifiable(static_cast<std::size_t>(p), true);
    for (Eigen::Index d = 0; d < p; ++d) {
      if (d < sv.size() && sv(d) > kRankThreshold * smax) {
        inverse_squares(d) = 1.0 / (sv(d) * sv(d));
        continue;
      }
      std::vector<std::pair<double, Eigen::Index>> terms;
      for (Eigen::Index c = 0; c < p; ++c) {
        if (std::abs(V(c, d)) >= 0.1) {
          terms.emplace_back(V(c, d), c);
          identifiable[static_cast<std::size_t>(c)] = false;
        }
      }
      std::sort(terms.begin(), terms.end(),
                [](const auto& a, const auto& b) { return std::abs(a.first) > std::abs(b.first); });
      std::string words;
      for (std::size_t t = 0; t < terms.size() && t < 6; ++t) {
        char coefficient[16];
        std::snprintf(coefficient, sizeof coefficient, "%s%.2f ", terms[t].first < 0 ? "- " : "+ ",
                      std::abs(terms[t].first));
        words += (t ? " " : "") + std::string(coefficient) +
                 result
                     .parameters[static_cast<std::size_t>(
                         estimated[static_cast<std::size_t>(terms[t].second)])]
                     .name;
      }
      if (terms.size() > 6) words += " ...";
      result.unidentifiable.push_back(words);
    }
    // The covariance in half-width units, then in SI: C_ab = h_a h_b (V S^-2 V^T)_ab sigma^2.
    const Eigen::MatrixXd scaled =
        V * inverse_squares.asDiagonal() * V.transpose() * result.residual_variance;
    for (Eigen::Index a = 0; a < p; ++a) {
      const std::size_t ka = static_cast<std::size_t>(estimated[static_cast<std::size_t>(a)]);
      ParameterEstimate& e = result.parameters[ka];
      e.identifiable = identifiable[static_cast<std::size_t>(a)];
      const bool known = result.covariance_ok && e.identifiable;
      for (Eigen::Index b = 0; b < p; ++b) {
        const std::size_t kb = static_cast<std::size_t>(estimated[static_cast<std::size_t>(b)]);
        const bool both = known && identifiable[static_cast<std::size_t>(b)];
        result.covariance(static_cast<Eigen::Index>(ka), static_cast<Eigen::Index>(kb)) =
            both ? 0.5 * (scaled(a, b) + scaled(b, a)) * e.half_width *
                       result.parameters[kb].half_width
                 : kNaN;
      }
      e.std_dev = known ? e.half_width * std::sqrt(scaled(a, a)) : kNaN;
    }
    if (!result.unidentifiable.empty()) {
      result.warnings.push_back(
          std::to_string(result.unidentifiable.size()) +
          " combinations of parameters (in half-widths) are not identifiable from these data, "
          "beyond the gauge: " +
          listing(result.unidentifiable, 3));
    }
  } else {
    for (int k : estimated) {
      result.parameters[static_cast<std::size_t>(k)].std_dev = kNaN;
      if (!options.compute_covariance) continue;
      for (int j : estimated) result.covariance(k, j) = kNaN;  // zero against the held ones
    }
  }
  for (int k = 0; k < block; ++k) {
    result.parameters[static_cast<std::size_t>(k)].value = id.values()[static_cast<std::size_t>(k)];
  }
  add_warnings(id, &result);
  return result;
}

}  // namespace pcr
