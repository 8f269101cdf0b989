// The rod integrators (RK4 core and CVODE reference) against closed-form elastica solutions:
// the cantilever under a dead tip force perpendicular to its axis (Bisshopp and Drucker, 1945,
// in elliptic integrals) and the circular arc under a pure tip moment.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <vector>

#include "pcr/reference.hpp"
#include "pcr/rod.hpp"

namespace {

// ---- Elliptic integrals by Carlson's symmetric forms (Carlson 1995, duplication theorem) ------

double carlson_rf(double x, double y, double z) {
  for (;;) {
    const double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z);
    const double lambda = sx * (sy + sz) + sy * sz;
    x = 0.25 * (x + lambda);
    y = 0.25 * (y + lambda);
    z = 0.25 * (z + lambda);
    const double mean = (x + y + z) / 3.0;
    const double dx = (mean - x) / mean, dy = (mean - y) / mean, dz = (mean - z) / mean;
    // Series truncation error ~ delta^6: 1e-4 leaves it far below rounding.
    if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) < 1e-4) {
      const double e2 = dx * dy - dz * dz, e3 = dx * dy * dz;
      return (1.0 + (e2 / 24.0 - 0.1 - 3.0 / 44.0 * e3) * e2 + e3 / 14.0) / std::sqrt(mean);
    }
  }
}

double carlson_rd(double x, double y, double z) {
  double sum = 0.0, factor = 1.0;
  for (;;) {
    const double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z);
    const double lambda = sx * (sy + sz) + sy * sz;
    sum += factor / (sz * (z + lambda));
    factor *= 0.25;
    x = 0.25 * (x + lambda);
    y = 0.25 * (y + lambda);
    z = 0.25 * (z + lambda);
    const double mean = 0.2 * (x + y + 3.0 * z);
    const double dx = (mean - x) / mean, dy = (mean - y) / mean, dz = (mean - z) / mean;
    if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) < 1e-4) {
      const double c1 = 3.0 / 14.0, c2 = 1.0 / 6.0, c3 = 9.0 / 22.0, c4 = 3.0 / 26.0;
      const double c5 = 0.25 * c3, c6 = 1.5 * c4;
      const double ea = dx * dy, eb = dz * dz, ec = ea - eb, ed = ea - 6.0 * eb, ee = ed + 2.0 * ec;
      return 3.0 * sum + factor *
                             (1.0 + ed * (-c1 + c5 * ed - c6 * dz * ee) +
                              dz * (c2 * ee + dz * (-c3 * ec + dz * c4 * ea))) /
                             (mean * std::sqrt(mean));
    }
  }
}

/// Incomplete integral of the first kind F(phi, k), 0 <= phi <= pi/2, modulus k.
double ellint_f(double phi, double k) {
  const double s = std::sin(phi), c = std::cos(phi);
  return s * carlson_rf(c * c, 1.0 - k * k * s * s, 1.0);
}

/// Incomplete integral of the second kind E(phi, k).
double ellint_e(double phi, double k) {
  const double s = std::sin(phi), c = std::cos(phi), delta2 = 1.0 - k * k * s * s;
  return s * carlson_rf(c * c, delta2, 1.0) -
         k * k * s * s * s / 3.0 * carlson_rd(c * c, delta2, 1.0);
}

TEST(EllipticIntegrals, CarlsonFormsMatchHighPrecisionValues) {
  // (k, phi, F(phi, k), E(phi, k)) computed with mpmath at 30 digits (ellipf, ellipe; m = k^2).
  struct Value {
    double k, phi, f, e;
  };
  const Value values[] = {
      {0.3, 0.7, 0.70474638317796162748, 0.69530899833306636548},
      {0.75, 1.2, 1.3653473411192320094, 1.066353059888927768},
      {0.9, 1.5707963267948966192, 2.2805491384227703325, 1.1716970527816141047},
      {0.99, 1.5707963267948966192, 3.3566005233611916666, 1.0284758090288040352},
      {0.95, 0.9, 1.0316386650814243646, 0.79627383639823995361},
  };
  for (const Value& v : values) {
    EXPECT_NEAR(ellint_f(v.phi, v.k), v.f, 2e-15 * v.f) << "k " << v.k << " phi " << v.phi;
    EXPECT_NEAR(ellint_e(v.phi, v.k), v.e, 2e-15 * v.e) << "k " << v.k << " phi " << v.phi;
  }
  // Closed forms: K(0) = E(0) = pi/2, E(1) = 1, F(phi, 0) = E(phi, 0) = phi.
  EXPECT_NEAR(ellint_f(M_PI / 2, 0.0), M_PI / 2, 1e-15);
  EXPECT_NEAR(ellint_e(M_PI / 2, 1.0), 1.0, 1e-15);
  EXPECT_NEAR(ellint_f(0.4, 0.0), 0.4, 1e-16);
  EXPECT_NEAR(ellint_e(0.4, 0.0), 0.4, 1e-16);
}

TEST(EllipticIntegrals, CarlsonFormsAgreeWithTheStandardLibrary) {
  // libstdc++'s C++17 special functions, an independent implementation, are good to ~1e-13
  // only (measured: comp_ellint_2(0.99) is 4e-13 off the mpmath value).
  for (double k : {0.0, 0.3, 0.70710678118654752, 0.9, 0.99, 0.999999}) {
    for (double phi : {0.1, 0.7853981633974483, 1.2, M_PI / 2}) {
      EXPECT_NEAR(ellint_f(phi, k), std::ellint_1(k, phi), 1e-12 * std::ellint_1(k, phi))
          << "k " << k << " phi " << phi;
      EXPECT_NEAR(ellint_e(phi, k), std::ellint_2(k, phi), 1e-12 * std::ellint_2(k, phi))
          << "k " << k << " phi " << phi;
    }
  }
}

// ---- Bisshopp and Drucker's cantilever --------------------------------------------------------

struct Tip {
  double x, y, theta;
};

/// Clamped at the origin along +x, dead tip force P along +y, free tip moment; alpha = P L^2 / EI.
/// With EI theta'' = -P cos(theta), theta(0) = 0, theta'(L) = 0, the substitution
/// 1 + sin(theta) = 2 k^2 sin^2(phi) gives sqrt(alpha) = K(k) - F(phi0, k) with
/// sin(phi0) = 1 / (k sqrt 2), and at the tip sin(theta_L) = 2 k^2 - 1,
/// x_L = 2 k cos(phi0) / lambda, y_L = L - 2 (E(k) - E(phi0, k)) / lambda, lambda = sqrt(P / EI).
Tip bisshopp_drucker(double alpha, double length) {
  const auto phi0_of = [](double k) { return std::asin(1.0 / (k * std::sqrt(2.0))); };
  const auto g = [&](double k) {
    return ellint_f(M_PI / 2, k) - ellint_f(phi0_of(k), k) - std::sqrt(alpha);
  };
  // g increases from -sqrt(alpha) at k = 1/sqrt(2) to +infinity at k = 1: bisect to the last bit.
  double lo = 1.0 / std::sqrt(2.0), hi = 1.0 - 1e-15;
  for (int i = 0; i < 200 && hi - lo > 0.0; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (g(mid) < 0.0 ? lo : hi) = mid;
  }
  const double k = 0.5 * (lo + hi);
  const double phi0 = phi0_of(k);
  const double lambda = std::sqrt(alpha) / length;
  const double cos_phi0 = std::sqrt((2.0 * k * k - 1.0) / (2.0 * k * k));
  Tip tip;
  tip.x = 2.0 * k * cos_phi0 / lambda;
  tip.y = length - 2.0 * (ellint_e(M_PI / 2, k) - ellint_e(phi0, k)) / lambda;
  tip.theta = std::atan2(2.0 * k * k - 1.0, 2.0 * k * std::sqrt(1.0 - k * k));
  return tip;
}

/// Root of f in [a, b] (f(a) < 0 < f(b)) by secant steps kept inside the bracket (bisection
/// otherwise); returns the best point found.
double solve_bracketed(const std::function<double(double)>& f, double a, double b,
                       double f_tolerance) {
  double fa = f(a), fb = f(b);
  if (!(fa < 0.0 && fb > 0.0)) throw std::runtime_error("solve_bracketed: not a bracket");
  double x0 = a, f0 = fa, x1 = b, f1 = fb;
  double best = std::abs(fa) < std::abs(fb) ? a : b, best_f = std::min(std::abs(fa), std::abs(fb));
  for (int i = 0; i < 100; ++i) {
    double x = x1 - f1 * (x1 - x0) / (f1 - f0);
    if (!(x > a && x < b)) x = 0.5 * (a + b);
    const double fx = f(x);
    if (std::abs(fx) < best_f) {
      best_f = std::abs(fx);
      best = x;
    }
    if (best_f <= f_tolerance ||
        b - a <= 4 * std::numeric_limits<double>::epsilon() * std::abs(x)) {
      break;
    }
    (fx < 0.0 ? a : b) = x;
    x0 = x1;
    f0 = f1;
    x1 = x;
    f1 = fx;
  }
  return best;
}

constexpr double kLength = 0.030;                    // m
const pcr::Rod<double> kRod{kLength, 125e-6, 69e9};  // straight
const double kEi = kRod.bending_stiffness();         // N m^2
constexpr int kFineSteps = 2000;

using Integrator = std::function<pcr::RodState<double>(const pcr::RodState<double>&)>;

pcr::RodState<double> rk4(const pcr::RodState<double>& start) {
  return pcr::integrate_rod(start, kRod, kFineSteps);
}
pcr::RodState<double> cvode(const pcr::RodState<double>& start) {
  return pcr::integrate_rod_reference(start, kRod);
}

/// Shoots on m(0) so that the free tip has m(L) = 0 under the tip force (0, P).
pcr::RodState<double> cantilever_tip(double force, const Integrator& integrate) {
  // n(L) is the force of the load on the rod's end; n is constant along the rod.
  const auto tip_moment = [&](double m0) {
    return integrate(pcr::RodState<double>{0, 0, 0, 0.0, force, m0}).m;
  };
  // m(L) = m0 - P int cos(theta) ds: negative at m0 = 0, non-negative at m0 = P L.
  const double m0 =
      solve_bracketed(tip_moment, 0.0, 1.0001 * force * kLength, 1e-15 * force * kLength);
  return integrate(pcr::RodState<double>{0, 0, 0, 0.0, force, m0});
}

class CantileverTest : public ::testing::TestWithParam<double> {};

TEST_P(CantileverTest, Rk4AndCvodeMatchBisshoppDrucker) {
  const double alpha = GetParam();
  const Tip exact = bisshopp_drucker(alpha, kLength);
  // Sanity of the closed form itself: the tip bends towards +y, within the rod's reach.
  ASSERT_GT(exact.y, 0.0);
  ASSERT_LT(std::hypot(exact.x, exact.y), kLength);
  const double force = alpha * kEi / (kLength * kLength);
  const double tolerance = 1e-9 * kLength;
  for (const auto& [name, integrator] :
       {std::pair<const char*, Integrator>{"rk4", rk4}, {"cvode", cvode}}) {
    const pcr::RodState<double> tip = cantilever_tip(force, integrator);
    EXPECT_NEAR(tip.x, exact.x, tolerance) << name << " alpha " << alpha;
    EXPECT_NEAR(tip.y, exact.y, tolerance) << name << " alpha " << alpha;
    EXPECT_NEAR(tip.theta, exact.theta, tolerance / kLength) << name << " alpha " << alpha;
    EXPECT_NEAR(tip.m, 0.0, 1e-12 * force * kLength) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Elastica, CantileverTest, ::testing::Values(0.5, 1.0, 2.0, 5.0, 10.0));

TEST(Elastica, SmallLoadApproachesLinearBeamTheory) {
  // Independent check of the closed form: as alpha -> 0, y_L -> alpha L / 3 and
  // theta_L -> alpha / 2 (Euler-Bernoulli); the next terms are O(alpha^3).
  const double alpha = 1e-3;
  const Tip exact = bisshopp_drucker(alpha, kLength);
  EXPECT_NEAR(exact.y, alpha * kLength / 3.0, 1e-6 * alpha * kLength);
  EXPECT_NEAR(exact.theta, alpha / 2.0, 1e-6 * alpha);
}

TEST(Elastica, PureTipMomentGivesCircularArc) {
  for (double turn : {0.5, 2.0, 6.0}) {  // total bending angle M L / EI (rad)
    const double moment = turn * kEi / kLength;
    const double radius = kEi / moment;
    const pcr::RodState<double> start{0, 0, 0, 0, 0, moment};
    for (const auto& [name, integrator] :
         {std::pair<const char*, Integrator>{"rk4", rk4}, {"cvode", cvode}}) {
      const pcr::RodState<double> tip = integrator(start);
      EXPECT_NEAR(tip.x, radius * std::sin(turn), 1e-9 * kLength) << name << " turn " << turn;
      EXPECT_NEAR(tip.y, radius * (1.0 - std::cos(turn)), 1e-9 * kLength) << name;
      EXPECT_NEAR(tip.theta, turn, 1e-9) << name;
      EXPECT_NEAR(tip.m, moment, 1e-12 * moment) << name;
    }
    // Dense output along the arc, at arbitrary arc lengths.
    const std::vector<double> arc = {0.0, 0.1 * kLength, 0.37 * kLength, 0.9 * kLength, kLength};
    const auto shape = pcr::sample_rod_reference(start, kRod, arc);
    ASSERT_EQ(shape.size(), arc.size());
    for (std::size_t i = 0; i < arc.size(); ++i) {
      const double angle = arc[i] / radius;
      EXPECT_NEAR(shape[i].x, radius * std::sin(angle), 1e-9 * kLength) << "s " << arc[i];
      EXPECT_NEAR(shape[i].y, radius * (1.0 - std::cos(angle)), 1e-9 * kLength) << "s " << arc[i];
      EXPECT_NEAR(shape[i].theta, angle, 1e-9) << "s " << arc[i];
    }
  }
}

TEST(ReferenceRod, RejectsBadInput) {
  const pcr::RodState<double> start{0, 0, 0, 0, 0, 0};
  EXPECT_THROW(pcr::integrate_rod_reference(start, pcr::Rod<double>{kLength, 125e-6, -1.0}),
               std::invalid_argument);
  EXPECT_THROW(pcr::integrate_rod_reference(start, pcr::Rod<double>{0.0, 125e-6, 69e9}),
               std::invalid_argument);
  pcr::RodState<double> nan_start = start;
  nan_start.m = std::nan("");
  EXPECT_THROW(pcr::integrate_rod_reference(nan_start, kRod), std::invalid_argument);
  EXPECT_THROW(pcr::sample_rod_reference(start, kRod, {0.5 * kLength, 0.1 * kLength}),
               std::invalid_argument);
  EXPECT_THROW(pcr::sample_rod_reference(start, kRod, {2 * kLength}), std::invalid_argument);
  // A step budget too small for the tolerance is a CVODE failure, reported as runtime_error.
  pcr::ReferenceOptions tiny;
  tiny.max_steps = 3;
  EXPECT_THROW(pcr::integrate_rod_reference(pcr::RodState<double>{0, 0, 0, 0, 0, 5 * kEi / kLength},
                                            kRod, tiny),
               std::runtime_error);
}

}  // namespace
