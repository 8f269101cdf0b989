// The RK4 rod integrator against closed forms and finite differences.
#include <gtest/gtest.h>

#include <cmath>

#include "pcr/robot.hpp"
#include "pcr/rod.hpp"

namespace pcr {
namespace {

constexpr double kLength = 0.03;
const Rod<double> kRod{kLength, 125e-6, 69e9};  // straight
const double kEI = kRod.bending_stiffness();

TEST(Rod, BendingStiffnessOfCircularSection) {
  const double expected = 69e9 * M_PI * std::pow(125e-6, 4) / 64.0;
  EXPECT_NEAR(bending_stiffness(69e9, 125e-6), expected, 1e-14 * expected);
}

TEST(Rod, UnloadedRodIsStraight) {
  const RodState<double> start{0.01, -0.02, 0.3, 0, 0, 0};
  const RodState<double> tip = integrate_rod(start, kRod, 8);
  EXPECT_NEAR(tip.x, 0.01 + kLength * std::cos(0.3), 1e-17);
  EXPECT_NEAR(tip.y, -0.02 + kLength * std::sin(0.3), 1e-17);
  EXPECT_NEAR(tip.theta, 0.3, 1e-16);
}

// A pure moment bends the rod into a circular arc of radius EI / M (exact: m' = 0 when n = 0).
TEST(Rod, PureMomentGivesCircularArc) {
  const double curvature = 100.0;  // 1/m, strain 0.6%
  const RodState<double> start{0, 0, 0, 0, 0, kEI * curvature};
  const double angle = curvature * kLength;
  for (int steps : {32, 64}) {
    const RodState<double> tip = integrate_rod(start, kRod, steps);
    EXPECT_NEAR(tip.theta, angle, 1e-14);
    EXPECT_NEAR(tip.m, kEI * curvature, 1e-20);
    // The carried (cos, sin) pair has an RK4 error of order (kappa h)^4 / 120.
    const double h = kLength / steps;
    const double bound = kLength * std::pow(curvature * h, 4);
    EXPECT_NEAR(tip.x, std::sin(angle) / curvature, bound) << steps;
    EXPECT_NEAR(tip.y, (1 - std::cos(angle)) / curvature, bound) << steps;
  }
}

TEST(Rod, ErrorFallsSixteenfoldPerStepDoubling) {
  const RodState<double> start{0, 0, 0.2, 4e-4, -9e-4, 2e-5};
  const RodState<double> fine = integrate_rod(start, kRod, 4096);
  const auto error = [&](int steps) {
    const RodState<double> tip = integrate_rod(start, kRod, steps);
    return std::hypot(tip.x - fine.x, tip.y - fine.y);
  };
  const double ratio = error(16) / error(32);
  EXPECT_GT(ratio, 12.0);
  EXPECT_LT(ratio, 20.0);
}

TEST(Rod, SensitivityMatchesCentralDifferences) {
  const RodState<double> start{0.001, 0.002, 1.1, 3e-4, -5e-4, 1.5e-5};
  const RodTip<double> tip = integrate_rod_with_sensitivity(start, kRod, 64);
  const double steps[3] = {1e-9, 1e-9, 1e-11};
  for (int j = 0; j < 3; ++j) {
    RodState<double> plus = start, minus = start;
    double* p = j == 0 ? &plus.nx : j == 1 ? &plus.ny : &plus.m;
    double* m = j == 0 ? &minus.nx : j == 1 ? &minus.ny : &minus.m;
    *p += steps[j];
    *m -= steps[j];
    const RodState<double> a = integrate_rod(plus, kRod, 64);
    const RodState<double> b = integrate_rod(minus, kRod, 64);
    const double fd[4] = {(a.x - b.x) / (2 * steps[j]), (a.y - b.y) / (2 * steps[j]),
                          (a.theta - b.theta) / (2 * steps[j]), (a.m - b.m) / (2 * steps[j])};
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(tip.sensitivity(k, j), fd[k], 1e-6 * std::abs(fd[k]) + 1e-9)
          << "row " << k << " column " << j;
    }
  }
  EXPECT_EQ(tip.state.x, integrate_rod(start, kRod, 64).x);
}

TEST(Rod, SampledShapeVisitsEveryNode) {
  const RodState<double> start{0, 0, 0, 0, 0, kEI * 50.0};
  int count = 0;
  double last_s = -1;
  sample_rod(start, kRod, 16, [&](double s, const RodState<double>& state) {
    EXPECT_GT(s, last_s);
    EXPECT_NEAR(state.theta, 50.0 * s, 1e-14);
    last_s = s;
    ++count;
  });
  EXPECT_EQ(count, 17);
  EXPECT_NEAR(last_s, kLength, 1e-18);
}

// Rods stepped together in SIMD lanes (shooting_residual's path in double) against each rod stepped
// alone: the lanes do the same operations in the same order, so the results are the same to the
// bit. Every robot size (bundles of 2, 4 and 8 lanes, some lanes idle), rods of different lengths,
// EI, laws, angles and wrenches.
template <bool Sens>
void expect_lanes_match_rods_alone() {
  // A compiler free to fuse a * b + c into an FMA (-march=native) may fuse in one path and not in
  // the other: then the tangents differ by a few 1e-15 relative where their terms cancel.
#ifdef __FMA__
  const double tolerance = 1e-13;
#else
  const double tolerance = 0.0;
#endif
  const auto expect_same = [&](double lanes, double alone, const char* what, int n, int i) {
    EXPECT_NEAR(lanes, alone, tolerance * std::abs(alone))
        << what << ", rod " << i << " of " << n << (Sens ? ", with tangents" : "");
  };
  constexpr int kSteps = 24;
  for (int n = 2; n <= kMaxLimbs; ++n) {
    internal::RodStepper<double, Sens> lanes[kMaxLimbs], alone[kMaxLimbs];
    for (int i = 0; i < n; ++i) {
      const RodState<double> start{0.01 * i,         -0.003 * i,
                                   -2.0 + 1.1 * i,   (i - 2.5) * 4e-4,
                                   (1.5 - i) * 3e-4, (i % 2 ? 1 : -1) * (1e-5 + 4e-5 * i)};
      // EI (0.5 + 0.3 i), lengths apart, half of them pre-curved, a third tapered (their tips
      // 1.5, 0.7, 1.3 times as thick): bundles mix the three laws
      const double length = kLength * (0.7 + 0.15 * i);
      const double tip_ratio[] = {1.5, 0.7, 1.3};
      const Rod<double> rod{length,
                            kRod.diameter,
                            kRod.young_modulus * (0.5 + 0.3 * i),
                            i % 2 ? 40.0 - 9.0 * i : 0.0,
                            i % 3 ? 0.0 : 1500.0 * (i - 1),
                            i % 3 == 1 ? kRod.diameter * (tip_ratio[i / 3] - 1.0) / length : 0.0};
      lanes[i].init(start, rod, kSteps);
      alone[i] = lanes[i];
      for (int k = 0; k < kSteps; ++k) alone[i].step();
    }
    internal::integrate_rods_in_lanes(lanes, n, kSteps);
    for (int i = 0; i < n; ++i) {
      const auto& a = lanes[i];
      const auto& b = alone[i];
      expect_same(a.x, b.x, "x", n, i);
      expect_same(a.y, b.y, "y", n, i);
      expect_same(a.th, b.th, "theta", n, i);
      expect_same(a.c, b.c, "cos theta", n, i);
      expect_same(a.s, b.s, "sin theta", n, i);
      expect_same(a.m, b.m, "m", n, i);
      expect_same(a.nx, b.nx, "n_x", n, i);
      expect_same(a.ny, b.ny, "n_y", n, i);
      expect_same(a.max_abs_moment, b.max_abs_moment, "max |m|", n, i);
      if constexpr (Sens) {
        for (int j = 0; j < 3; ++j) {
          expect_same(a.tx[j], b.tx[j], "dx/dwrench", n, i);
          expect_same(a.ty[j], b.ty[j], "dy/dwrench", n, i);
          expect_same(a.tth[j], b.tth[j], "dtheta/dwrench", n, i);
          expect_same(a.tc[j], b.tc[j], "dc/dwrench", n, i);
          expect_same(a.ts[j], b.ts[j], "ds/dwrench", n, i);
          expect_same(a.tm[j], b.tm[j], "dm/dwrench", n, i);
        }
      }
    }
    // The rods are really different, so a lane mix-up would show.
    EXPECT_GT(std::abs(lanes[1].th - lanes[0].th), 0.5);
  }
}

TEST(Rod, LanesMatchRodsSteppedAlone) { expect_lanes_match_rods_alone<false>(); }

TEST(Rod, LanesMatchRodsSteppedAloneWithTangents) { expect_lanes_match_rods_alone<true>(); }

}  // namespace
}  // namespace pcr
