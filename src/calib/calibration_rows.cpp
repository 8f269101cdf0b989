// The rows the nominal geometry reaches, those set aside or dropped, and the warnings on them.

#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr::calib_internal {
namespace {

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

}  // namespace

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

}  // namespace pcr::calib_internal
