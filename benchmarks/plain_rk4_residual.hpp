#pragma once
// A yardstick of the machine for benchmarks/bench_cli.py: the shooting residual of a three-rod
// robot written as plainly as can be.

namespace pcr::bench {

struct PlainRod {
  double ax, ay, alpha;  ///< proximal clamp in W (m) and the rod's angle there (rad)
  double bx, by, beta;   ///< distal clamp in the platform's frame (m, rad)
  double length, ei;     ///< m, N m^2
};

/// The 12 residuals of three rods integrated from their proximal clamps by RK4 in 64 steps, with
/// std::sin and std::cos at every stage (x' = cos th, y' = sin th, th' = m / EI,
/// m' = nx sin th - ny cos th): each rod's tip against its distal clamp (x, y, angle), then the
/// platform's equilibrium (forces, moment). Unknowns: (nx, ny, m0) of each rod, the platform pose.
void plain_rk4_residual(const PlainRod (&rods)[3], const double (&unknowns)[12],
                        double (&residual)[12]);

}  // namespace pcr::bench
