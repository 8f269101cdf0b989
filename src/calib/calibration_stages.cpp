// The stages: the parameters their kinds free, the paper's three, checks, half-widths (Eq. 7).

#include "pcr/calib/calibration_stages.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr {
namespace {

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

bool known_kind(const std::string& kind) { return !indices_of_kind(kind, 1).empty(); }

}  // namespace

namespace calib_internal {

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

}  // namespace calib_internal

using calib_internal::format_number;
using calib_internal::stage_free_indices;

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
  calib_internal::validate_stage_list(stages, source, known_kind, "");
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

namespace calib_internal {

void validate_stage_list(const std::vector<CalibrationStage>& stages, const std::string& source,
                         bool (*known)(const std::string&), const std::string& unknown_hint) {
  if (stages.empty()) throw InputError(source + ": no stage");
  for (std::size_t s = 0; s < stages.size(); ++s) {
    const std::string where = source + ": stages[" + std::to_string(s) + "]";
    for (const std::string& kind : stages[s].free) {
      if (!known(kind)) {
        throw InputError(where + ".free: unknown kind \"" + kind + "\"" + unknown_hint);
      }
    }
    if (!(stages[s].bounds_scale > 0) || !std::isfinite(stages[s].bounds_scale)) {
      throw InputError(where + ".bounds_scale: must be positive, got " +
                       format_number(stages[s].bounds_scale));
    }
  }
}

}  // namespace calib_internal

}  // namespace pcr
