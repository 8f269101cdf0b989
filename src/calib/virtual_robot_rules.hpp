#pragma once
// The rules every virtual robot follows, planar or spatial: how it draws its truth from a nominal
// value and a half-width, and which equilibria it measures.

#include <random>

#include "pcr/kinematics.hpp"  // is_equilibrium

namespace pcr::internal {

/// nominal + U(-h, h), or nominal +- fraction h with the sign drawn when fraction > 0; h = 0
/// leaves the value unchanged (and still consumes one draw, so the stream does not depend on which
/// half-widths are zero).
inline double draw_within(std::mt19937_64& rng, double nominal, double half_width,
                          double fraction = 0.0) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double x = u(rng);
  if (fraction > 0.0) return nominal + half_width * (x < 0.0 ? -fraction : fraction);
  return nominal + half_width * x;
}

/// Whether a virtual robot measures the equilibrium its truth's FK reports. A real robot does not
/// hold an unstable equilibrium: it snaps to another one, which no statics model can say. Such a
/// configuration is not measured (its status becomes kUnstable), and the robot is homed again, as
/// a lab does after a snap (*home_again).
inline bool measured_equilibrium(SolverSummary& summary, bool* home_again) {
  *home_again = false;
  if (!is_equilibrium(summary)) return false;
  if (summary.stability == Stability::kUnstable) {
    summary.status = SolveStatus::kUnstable;
    *home_again = true;
    return false;
  }
  return true;
}

}  // namespace pcr::internal
