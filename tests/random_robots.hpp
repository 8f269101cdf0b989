#pragma once
// Robots the tests draw at random: n-limb variants of the default design, every parameter drawn
// inside the paper's uncertainty intervals (Mauze et al. 2021, Table 1; robots/femto-3pf.json).

#include <cmath>
#include <random>

#include "pcr/robot.hpp"

namespace pcr::testing {

/// The default robot's limb design repeated n times, limbs 360/n degrees apart (limb 0 at -90
/// degrees, as in femto_3pf): straight and stress-free at q = 0, home pose (0, 0, 0).
inline RobotParams<double> regular_robot(int n) {
  const RobotParams<double> base = femto_3pf();
  const double r_a = base.limb(0).A.norm();
  const double turn = base.limb(0).alpha - std::atan2(base.limb(0).A.y(), base.limb(0).A.x());
  RobotParams<double> robot;
  robot.num_limbs = n;
  for (int i = 0; i < n; ++i) {
    const double phi = -M_PI / 2 + 2 * M_PI * i / n;
    LimbParams<double> limb = base.limb(0);
    limb.A = Vector2<double>(r_a * std::cos(phi), r_a * std::sin(phi));
    limb.alpha = phi + turn;
    limb.B = limb.A + limb.rod.length * Vector2<double>(std::cos(limb.alpha), std::sin(limb.alpha));
    limb.beta = limb.alpha;
    robot.limb(i) = limb;
  }
  return robot;
}

/// The paper's half-widths: A, B 160 um; alpha, beta, gamma 5 mrad; l 126 um; d 20 um. E is not
/// in the paper's table; 2% per limb stands for one material bought twice.
struct Intervals {
  double position = 160e-6, angle = 5e-3, length = 126e-6, diameter = 20e-6;
  double young_modulus_fraction = 0.02;
};

/// `robot` with every limb parameter drawn uniformly inside `intervals` around its value,
/// independently per limb (so d and E differ between limbs).
inline RobotParams<double> perturbed(const RobotParams<double>& robot, std::mt19937_64& rng,
                                     const Intervals& intervals = {}) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Braces, not parentheses, around draws: a braced list is evaluated left to right, a call's
  // arguments in an order that differs between compilers, and one seed must give the same robots
  // under every compiler.
  RobotParams<double> out = robot;
  for (int i = 0; i < out.num_limbs; ++i) {
    LimbParams<double>& limb = out.limb(i);
    limb.A += intervals.position * Vector2<double>{u(rng), u(rng)};
    limb.alpha += intervals.angle * u(rng);
    limb.gamma += intervals.angle * u(rng);
    limb.B += intervals.position * Vector2<double>{u(rng), u(rng)};
    limb.beta += intervals.angle * u(rng);
    limb.rod.length += intervals.length * u(rng);
    limb.rod.diameter += intervals.diameter * u(rng);
    limb.rod.young_modulus *= 1.0 + intervals.young_modulus_fraction * u(rng);
  }
  return out;
}

}  // namespace pcr::testing
