// calibrate(): the staged identification, step by step (design: pcr/calib/calibrator.hpp).

#include "pcr/calib/calibrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "calibration_internal.hpp"
#include "identification.hpp"

namespace pcr {
namespace {

using calib_internal::add_warnings;
using calib_internal::Identification;
using calib_internal::joints_text;
using calib_internal::kDistalRotation;
using calib_internal::kDistalX;
using calib_internal::kDistalY;
using calib_internal::kNaN;
using calib_internal::kProximalRotation;
using calib_internal::kProximalX;
using calib_internal::kProximalY;
using calib_internal::kStiffness;
using calib_internal::leave_out_outliers;
using calib_internal::listing;
using calib_internal::origin_of;
using calib_internal::present_generators;
using calib_internal::rank_and_gauge_directions;
using calib_internal::reachable_rows;
using calib_internal::registered_extrinsics;
using calib_internal::standard_deviations;
using calib_internal::warn_of_mirror;

/// Throws InputError, naming `source`, when `nominal` has no uncertainty section or an invalid
/// limb count, `data` is empty or does not match it, the options or a stage are invalid, or the
/// rows measure fewer values than a stage frees.
void check_calibration_inputs(const RobotDescription& nominal,
                              const std::vector<CalibrationSample>& data,
                              const CalibrationOptions& options, const std::string& source) {
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
}

/// The stages, from the registered start; before them, unless the first stage frees the
/// extrinsics alone, Table 3's "nominal model" from the same start.
void identify_in_stages(Identification* identification, const CalibrationOptions& options, int n,
                        CalibrationResult& result) {
  const std::vector<double> registered = identification->values();
  const int count = identification->count();

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
}

/// The rows set aside that the identified geometry reaches join the last stage, run again.
void bring_back_set_aside(const RobotDescription& nominal,
                          const std::vector<CalibrationSample>& data,
                          const CalibrationOptions& options,
                          const std::vector<std::size_t>& set_aside, std::vector<std::size_t>& used,
                          std::vector<CalibrationSample>& rows,
                          std::unique_ptr<Identification>& identification,
                          CalibrationResult& result) {
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

/// Rows measured on another equilibrium at their joints than the readings at the start values
/// gave (a fold the nominal geometry places elsewhere, a robot pushed onto a buckled shape):
/// named by the identified model, fitted there in the last stage, run again.
void refit_on_measured_equilibria(Identification* identification, const CalibrationOptions& options,
                                  CalibrationResult& result) {
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
}

/// result.parameters before the gauge fix: names, nominal values, half-widths, which are free in
/// the last stage, and where those lie in its box (at a bound or not).
void describe_parameters(const Identification& id, int n, int block,
                         const std::vector<bool>& is_free, CalibrationResult& result) {
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
}

/// The gauge: which generators only move free parameters (`present`: the gauges; `movable`: those
/// whose parameters are all free) and, with fix_gauge, the values moved to the limb-0 gauge
/// (refitted with the references held where a free load leaves a distal translation no gauge).
/// Returns the parameters the gauge fix holds.
std::vector<int> fix_identified_gauge(Identification& id, const RobotDescription& nominal,
                                      const CalibrationOptions& options, int n,
                                      const std::vector<int>& free,
                                      const std::vector<bool>& is_free, std::vector<bool>& present,
                                      std::vector<bool>& movable, CalibrationResult& result) {
  present = id.gauges(id.generators(), is_free);
  const auto flat = [n](ParameterKind kind, int limb) {
    return parameter_index(ParameterId{kind, limb}, n);
  };
  const bool prox_t = present[kProximalX] && present[kProximalY];
  const bool prox_r = prox_t && present[kProximalRotation];
  const bool dist_t = present[kDistalX] && present[kDistalY];
  const bool dist_r = present[kDistalRotation];
  const bool stiff = present[kStiffness];
  result.load_identified = id.load_free(is_free);
  movable = present_generators(id.generators(), is_free);
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
  return held;
}

}  // namespace

CalibrationResult calibrate(const RobotDescription& nominal,
                            const std::vector<CalibrationSample>& data,
                            const CalibrationOptions& options) {
  const std::string source = "calibration of \"" + nominal.name + "\"";
  check_calibration_inputs(nominal, data, options, source);
  const int n = nominal.params.num_limbs;

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
  const int block = identification->block();
  identify_in_stages(identification.get(), options, n, result);

  if (!set_aside.empty()) {
    bring_back_set_aside(nominal, data, options, set_aside, used, rows, identification, result);
  }
  refit_on_measured_equilibria(identification.get(), options, result);
  Identification& id = *identification;

  // Parameters at a bound (before the gauge fix, in the last stage's box).
  const std::vector<int>& free = id.last_free();
  std::vector<bool> is_free(static_cast<std::size_t>(block), false);
  for (int k : free) is_free[static_cast<std::size_t>(k)] = true;
  describe_parameters(id, n, block, is_free, result);

  // Gauge: which generators only move free parameters.
  std::vector<bool> present, movable;
  const std::vector<int> held =
      fix_identified_gauge(id, nominal, options, n, free, is_free, present, movable, result);
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
  leave_out_outliers(id, rows, evaluated, J, r, result);
  if (evaluated) rank_and_gauge_directions(id, free, present, movable, J, r, result);
  standard_deviations(id, options, block, free, held, evaluated, J, result);
  for (int k = 0; k < block; ++k) {
    result.parameters[static_cast<std::size_t>(k)].value = id.values()[static_cast<std::size_t>(k)];
  }
  add_warnings(id, &result);
  return result;
}

}  // namespace pcr
