#pragma once
// The RK4 step counts a solve chooses among when SolverOptions::rod_steps is 0, planar and
// spatial alike: a ladder from min_rod_steps (16, 24, 32, 48, 64, 96, ... for the default) up to
// max_rod_steps, each rung even so that its half is a whole count (the error estimate's), and
// about 4/3 or 3/2 of the one below, so that RK4's error (~ N^-4) falls by 3 to 5 per rung.

#include <algorithm>
#include <cmath>

#include "pcr/solver.hpp"

namespace pcr::internal {

inline int next_rod_steps_rung(int steps) { return steps % 3 == 0 ? steps / 3 * 4 : steps / 2 * 3; }

/// The step count for a solution of `steps` steps whose estimated error is `ratio` times its
/// target: the smallest on the ladder that meets the target (error ~ N^-4), but a lower count only
/// when it meets half the target, so that a sequence does not flip between two.
inline int rod_steps_for_error(const SolverOptions& options, int steps, double ratio) {
  if (options.rod_steps > 0) return options.rod_steps;
  if (!std::isfinite(ratio)) return options.max_rod_steps;
  const auto rung_at_least = [&](double wanted) {
    int ladder = options.min_rod_steps;
    while (ladder < wanted && ladder < options.max_rod_steps) ladder = next_rod_steps_rung(ladder);
    return std::min(ladder, options.max_rod_steps);
  };
  if (ratio > 1.0) return std::max(steps, rung_at_least(steps * std::pow(ratio, 0.25)));
  return std::min(steps, rung_at_least(steps * std::pow(2.0 * ratio, 0.25)));
}

/// The step count after `steps` on the ladder towards `target` (which is on the ladder): one rung
/// at a time, for a solve that the whole change of model was too much for (near a fold).
inline int rod_steps_rung_towards(const SolverOptions& options, int steps, int target) {
  if (options.rod_steps > 0 || steps == target) return target;
  int ladder = options.min_rod_steps, below = ladder;
  while (ladder < std::max(steps, target) && ladder < options.max_rod_steps) {
    if (ladder < steps) below = ladder;
    ladder = next_rod_steps_rung(ladder);
    if (target > steps && ladder > steps) return std::min(ladder, target);
  }
  return std::max(below, target);
}

/// The step count a solve starts with: options.rod_steps when fixed, else `preferred` (a warm
/// start's count; min_rod_steps cold) within [min_rod_steps, max_rod_steps].
inline int starting_rod_steps(const SolverOptions& options, int preferred) {
  if (options.rod_steps > 0) return options.rod_steps;
  return std::min(std::max(preferred, options.min_rod_steps), options.max_rod_steps);
}

}  // namespace pcr::internal
