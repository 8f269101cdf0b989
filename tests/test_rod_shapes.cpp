// Shaped rods: pre-curved (Rod's intrinsic curvature u*(s) = u0 + u1 s) and tapered (d(s) = d + d'
// s, so EI(s) varies). The RK4 rod against closed forms and CVODE, the cantilever against the
// energy reference, and robots with pre-curved and tapered rods, drawn at random, solved (FK and
// IK, cold, in shuffled order) within 1 nm of CVODE, their stability agreeing with the energy's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/reference.hpp"
#include "pcr/robot.hpp"
#include "pcr/rod.hpp"
#include "random_robots.hpp"

namespace pcr {
namespace {

constexpr double kLength = 0.030;
constexpr double kPositionPromise = 1e-9;  // m: SolverOptions' default accuracy, with margin
constexpr double kAnglePromise = 1e-6;     // rad

/// A rod of the paper's section, its tip tip_ratio times as thick as its base.
Rod<double> rod(double u0, double u1, double tip_ratio = 1.0) {
  constexpr double kDiameter = 125e-6;
  return Rod<double>{kLength, kDiameter, 69e9, u0, u1, kDiameter * (tip_ratio - 1.0) / kLength};
}

/// CVODE tighter than its default, below RK4's error at 1024 steps on strongly bent rods.
ReferenceOptions tight_reference() {
  ReferenceOptions options;
  options.relative_tolerance = 1e-14;
  options.absolute_tolerance = 1e-16;
  return options;
}

/// int_0^s cos and sin of theta0 + k s + u1 s^2 / 2 by composite Simpson over 20000 panels (error
/// below 1e-16 l for these smooth integrands): the free rod's centreline, whatever u1.
Vector2<double> quadrature_point(double theta0, double k, double u1, double s) {
  constexpr int kPanels = 20000;
  const double h = s / kPanels;
  Vector2<double> sum(0, 0);
  for (int i = 0; i <= kPanels; ++i) {
    const double t = i * h, angle = theta0 + k * t + 0.5 * u1 * t * t;
    const double weight = (i == 0 || i == kPanels) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    sum += weight * Vector2<double>(std::cos(angle), std::sin(angle));
  }
  return sum * h / 3.0;
}

// Unloaded but for a moment, a rod turns by m0 / EI + u*(s): with u1 = 0 a circular arc of
// curvature m0 / EI + u0, otherwise theta(s) = theta0 + (m0 / EI + u0) s + u1 s^2 / 2. RK4
// integrates theta's quadratic exactly and x, y to fourth order (64 -> 128 steps: 16 times
// closer); CVODE (rtol 1e-14) within 1e-11 l everywhere.
TEST(PrecurvedRod, FreeRodTakesItsIntrinsicShape) {
  for (const double u0 : {-60.0, 25.0}) {
    for (const double u1 : {0.0, 4000.0, -2500.0}) {
      for (const double m0 : {0.0, 3e-5}) {
        const Rod<double> r = rod(u0, u1);
        const double theta0 = 0.3, k = m0 / r.bending_stiffness() + u0;
        const RodState<double> start{1e-3, -2e-3, theta0, 0.0, 0.0, m0};
        const auto check = [&](double s, const RodState<double>& state, double tolerance,
                               const char* what) {
          EXPECT_NEAR(state.theta, theta0 + k * s + 0.5 * u1 * s * s, tolerance / kLength)
              << what << " u0 " << u0 << " u1 " << u1 << " s " << s;
          EXPECT_NEAR(state.m, m0, 1e-15) << what;
          Vector2<double> expected = quadrature_point(theta0, k, u1, s);
          if (u1 == 0.0 && k != 0.0) {  // the arc in closed form
            expected = Vector2<double>(std::sin(theta0 + k * s) - std::sin(theta0),
                                       std::cos(theta0) - std::cos(theta0 + k * s)) /
                       k;
          }
          EXPECT_NEAR(state.x - start.x, expected.x(), tolerance) << what << " s " << s;
          EXPECT_NEAR(state.y - start.y, expected.y(), tolerance) << what << " s " << s;
        };
        sample_rod(start, r, 1024, [&](double s, const RodState<double>& state) {
          check(s, state, 1e-11 * kLength, "RK4");
        });
        double errors[2];
        for (int pass = 0; pass < 2; ++pass) {
          const RodState<double> tip = integrate_rod(start, r, 64 << pass);
          Vector2<double> exact = quadrature_point(theta0, k, u1, kLength);
          errors[pass] = (Vector2<double>(tip.x - start.x, tip.y - start.y) - exact).norm();
        }
        if (errors[0] > 1e-13) {  // above the rounding floor: the fourth order shows
          EXPECT_GT(errors[0] / errors[1], 12.0) << "u0 " << u0 << " u1 " << u1;
          EXPECT_LT(errors[0] / errors[1], 20.0) << "u0 " << u0 << " u1 " << u1;
        }
        const std::vector<double> arc = {0.0, 0.2 * kLength, 0.55 * kLength, kLength};
        const std::vector<RodState<double>> reference =
            sample_rod_reference(start, r, arc, tight_reference());
        for (std::size_t i = 0; i < arc.size(); ++i)
          check(arc[i], reference[i], 1e-11 * kLength, "CVODE");
      }
    }
  }
}

// A tapered rod under a moment alone: m(s) = m0, so theta(s) = theta0 + m0 int_0^s dt / EI(t) in
// closed form, (64 m0 / (E pi)) (d^-3 - d(s)^-3) / (3 d'), and its centreline by quadrature: RK4
// within 1e-9 l at 1024 steps (EI varying 16 times costs it accuracy), fourth order in between;
// CVODE within 1e-11 l. The largest strain
// |m| d(s) / (2 EI(s)) sits at the thinner end.
TEST(TaperedRod, MomentBendsItByTheClosedForm) {
  for (const double tip_ratio : {0.5, 0.8, 1.7, 2.0}) {
    const Rod<double> r = rod(0.0, 0.0, tip_ratio);
    const double m0 = 4e-5, theta0 = -0.4;  // N m: 0.6 % strain at the thinnest tip
    const double d = r.diameter, slope = r.diameter_slope;
    const auto theta = [&](double s) {
      const double d3 = d * d * d, ds = r.diameter_at(s), ds3 = ds * ds * ds;
      return theta0 + 64.0 * m0 / (r.young_modulus * M_PI) * (1.0 / d3 - 1.0 / ds3) / (3.0 * slope);
    };
    const auto centreline = [&](double s) {  // composite Simpson, 20000 panels
      constexpr int kPanels = 20000;
      const double h = s / kPanels;
      Vector2<double> sum(0, 0);
      for (int i = 0; i <= kPanels; ++i) {
        const double weight = (i == 0 || i == kPanels) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += weight * Vector2<double>(std::cos(theta(i * h)), std::sin(theta(i * h)));
      }
      return Vector2<double>(sum * h / 3.0);
    };
    const RodState<double> start{0.0, 0.0, theta0, 0.0, 0.0, m0};
    const Vector2<double> exact = centreline(kLength);
    double errors[2];
    for (int pass = 0; pass < 2; ++pass) {
      const RodTip<double> tip = integrate_rod_with_sensitivity(start, r, 512 << pass);
      errors[pass] = (Vector2<double>(tip.state.x, tip.state.y) - exact).norm();
      EXPECT_NEAR(tip.state.theta, theta(kLength), 1e-10) << tip_ratio;
      EXPECT_NEAR(tip.state.m, m0, 1e-18) << tip_ratio;
      const double thinnest = std::min(1.0, tip_ratio) * d;
      const double strain = m0 * thinnest / (2.0 * bending_stiffness(r.young_modulus, thinnest));
      EXPECT_NEAR(tip.max_abs_moment * d / (2.0 * r.bending_stiffness()), strain, 1e-12 * strain)
          << tip_ratio;
    }
    EXPECT_LT(errors[1], 1e-9 * kLength) << tip_ratio;
    if (errors[0] > 1e-13) EXPECT_GT(errors[0] / errors[1], 10.0) << tip_ratio;
    const std::vector<double> arc = {0.3 * kLength, kLength};
    const std::vector<RodState<double>> reference =
        sample_rod_reference(start, r, arc, tight_reference());
    for (std::size_t i = 0; i < arc.size(); ++i) {
      EXPECT_NEAR(reference[i].theta, theta(arc[i]), 1e-11) << tip_ratio;
      EXPECT_LT((Vector2<double>(reference[i].x, reference[i].y) - centreline(arc[i])).norm(),
                1e-11 * kLength)
          << tip_ratio;
    }
  }
}

// The tangents RK4 carries are the derivatives of its own map on a tapered, pre-curved rod: against
// central differences of integrate_rod in each proximal wrench component.
TEST(TaperedRod, SensitivityMatchesCentralDifferences) {
  const Rod<double> r = rod(30.0, -900.0, 0.6);
  const RodState<double> start{0.0, 0.0, 0.2, 0.02, -0.01, 3e-5};
  constexpr int kSteps = 256;
  const RodTip<double> tip = integrate_rod_with_sensitivity(start, r, kSteps);
  const double steps[3] = {1e-6, 1e-6, 1e-9};  // N, N, N m
  for (int j = 0; j < 3; ++j) {
    RodState<double> plus = start, minus = start;
    double* p[3] = {&plus.nx, &plus.ny, &plus.m};
    double* m[3] = {&minus.nx, &minus.ny, &minus.m};
    *p[j] += steps[j];
    *m[j] -= steps[j];
    const RodState<double> a = integrate_rod(plus, r, kSteps), b = integrate_rod(minus, r, kSteps);
    const double numeric[4] = {(a.x - b.x) / (2 * steps[j]), (a.y - b.y) / (2 * steps[j]),
                               (a.theta - b.theta) / (2 * steps[j]), (a.m - b.m) / (2 * steps[j])};
    for (int row = 0; row < 4; ++row) {
      EXPECT_NEAR(tip.sensitivity(row, j), numeric[row],
                  1e-6 * std::max(std::abs(numeric[row]), 1e-3 * tip.sensitivity.col(j).norm()))
          << "row " << row << " column " << j;
    }
  }
}

// Loaded pre-curved rods drawn at random (turns up to a full one, loads up to 3 EI / l^2 with the
// weakest section's EI), half of them tapered (tips 0.5 to 2 times as thick): RK4 converges to
// CVODE at fourth order (512 -> 1024 steps: over ten times closer, to within 1e-9 l) where it is
// above the rounding floor.
TEST(PrecurvedRod, Rk4MatchesCvodeUnderLoad) {
  std::mt19937_64 rng(20261128);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  for (int trial = 0; trial < 40; ++trial) {
    // One draw per statement: the order of a call's arguments is the compiler's.
    const double tip_ratio = trial % 2 ? std::pow(2.0, u(rng)) : 1.0;
    const double u0 = 2.0 * M_PI / kLength * u(rng);
    const double u1 = 4.0 * M_PI / (kLength * kLength) * u(rng);
    const Rod<double> r = rod(u0, u1, tip_ratio);
    // Loads in units of the weakest section's EI / l^2 (N).
    const double unit =
        std::min(r.bending_stiffness(), r.bending_stiffness_at(kLength)) / (kLength * kLength);
    const RodState<double> start{
        0.0, 0.0, u(rng), 3.0 * unit * u(rng), 3.0 * unit * u(rng), 2.0 * unit * kLength * u(rng)};
    const RodState<double> exact = integrate_rod_reference(start, r, tight_reference());
    double errors[2];
    for (int pass = 0; pass < 2; ++pass) {
      const RodState<double> rk4 = integrate_rod(start, r, 512 << pass);
      errors[pass] = std::hypot(rk4.x - exact.x, rk4.y - exact.y);
      EXPECT_NEAR(rk4.theta, exact.theta, 1e-9) << trial;
      EXPECT_NEAR(rk4.m, exact.m, 1e-8 * unit * kLength) << trial;
    }
    if (errors[0] > 1e-13) EXPECT_GT(errors[0] / errors[1], 10.0) << trial;
    EXPECT_LT(errors[1], 1e-9 * kLength) << trial;
    worst = std::max(worst, errors[1]);
  }
  std::printf("[ shaped ] RK4 (1024 steps) vs CVODE, 40 loaded rods: worst tip %.2e m\n", worst);
}

// A cantilever shape-set to a clothoid, uniform or tapered (its tip 0.6 times as thick), clamped
// along x at the origin, under a dead force at its free tip: the shooting answer (m(l) = 0 by
// Newton on m(0), n = the load) against the energy reference's discrete minimum, extrapolated
// from N and 2N segments (its error is O(1 / N^2)), and both call it stable.
TEST(PrecurvedRod, CantileverUnderATipLoadMatchesTheEnergy) {
  double worst = 0;
  for (const double tip_ratio : {1.0, 0.6}) {
    const Rod<double> r = rod(20.0, 800.0, tip_ratio);
    RobotParams<double> robot;
    robot.num_limbs = 1;
    robot.limb(0).rod = r;
    const double unit = r.bending_stiffness_at(kLength) / (kLength * kLength);
    for (const Vector2<double> load :
         {Vector2<double>(0.0, -unit), Vector2<double>(-1.5 * unit, 0.7 * unit),
          Vector2<double>(2.0 * unit, 2.0 * unit)}) {
      constexpr int kSteps = 512;
      double m0 = 0;
      RodTip<double> tip;
      for (int it = 0; it < 30; ++it) {
        tip = integrate_rod_with_sensitivity(RodState<double>{0, 0, 0, load.x(), load.y(), m0}, r,
                                             kSteps);
        m0 -= tip.state.m / tip.sensitivity(3, 2);
        if (std::abs(tip.state.m) < 1e-15 * unit * kLength) break;
      }
      ASSERT_LT(std::abs(tip.state.m), 1e-13 * unit * kLength);
      const Pose2<double> pose{tip.state.x, tip.state.y, tip.state.theta};
      std::array<Wrench<double>, kMaxLimbs> wrenches{};
      wrenches[0] = Wrench<double>{load.x(), load.y(), m0};
      const JointVector q = JointVector::Zero(1);
      EnergyProblem problem = energy_problem(robot, q);
      problem.load.force = load;
      Vector2<double> tips[2];
      double eigenvalue = 0;
      for (int pass = 0; pass < 2; ++pass) {
        const EnergyStability e =
            energy_stability(problem, energy_start(robot, q, pose, wrenches, 200 << pass));
        ASSERT_TRUE(e.converged) << load.transpose();
        tips[pass] = e.state.pose.translation();
        eigenvalue = e.min_eigenvalue;
      }
      const Vector2<double> extrapolated = (4.0 * tips[1] - tips[0]) / 3.0;
      const double error = (extrapolated - pose.translation()).norm();
      EXPECT_LT(error, kPositionPromise) << tip_ratio << " " << load.transpose() << " N=400 alone "
                                         << (tips[1] - pose.translation()).norm();
      worst = std::max(worst, error);
      EXPECT_GT(eigenvalue, 0) << load.transpose();
      EXPECT_TRUE(equilibrium_stability(robot, q, pose, wrenches, kSteps).stable);
    }
  }
  std::printf("[ shaped ] cantilever vs energy (Richardson, N = 200, 400): worst %.2e m\n", worst);
}

/// regular_robot(n) with rods shape-set to random curves (u0 l and u1 l^2 / 2 each up to
/// max_turn rad) and, if `tapered`, half of them tapered (tips 0.6 to 1.6 times as thick), each
/// distal clamp where its stress-free rod ends: stress-free at home (0, 0, 0).
RobotParams<double> precurved_design(int n, std::mt19937_64& rng, double max_turn,
                                     bool tapered = true) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RobotParams<double> robot = testing::regular_robot(n);
  for (int i = 0; i < n; ++i) {
    LimbParams<double>& limb = robot.limb(i);
    const double l = limb.rod.length;
    limb.rod.precurvature = max_turn * u(rng) / l;
    limb.rod.precurvature_slope = 2.0 * max_turn * u(rng) / (l * l);
    if (tapered) {
      const double tip_ratio = 1.1 + 0.5 * u(rng);
      if (u(rng) > 0) limb.rod.diameter_slope = limb.rod.diameter * (tip_ratio - 1.0) / l;
    }
    const RodState<double> free_tip =
        integrate_rod(proximal_rod_state(limb, 0.0, Wrench<double>{}), limb.rod, 4096);
    limb.B = Vector2<double>(free_tip.x, free_tip.y);
    limb.beta = free_tip.theta;
  }
  return robot;
}

/// A pre-curved design with every parameter then drawn inside the paper's intervals.
RobotParams<double> precurved_robot(int n, std::mt19937_64& rng, double max_turn) {
  return testing::perturbed(precurved_design(n, rng, max_turn), rng);
}

struct Case {
  RobotParams<double> robot;
  JointVector q;
  ForwardSolution rk4, reference;
};

/// Robots of 2 to 5 pre-curved limbs (half of them tapered), configurations drawn across their
/// stroke box (from barely to strongly bent, at most 1 % strain), solved cold one by one, as rows
/// in shuffled order come.
std::vector<Case> precurved_cases(int& unjudged) {
  constexpr int kLimbs[] = {3, 2, 3, 4, 3, 5, 2, 3};
  std::mt19937_64 rng(20261128);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), log_scale(std::log(0.01), 0.0);
  ReferenceOptions reference;
  reference.jacobian_rod_steps = 1024;
  std::vector<Case> cases;
  for (int r = 0; r < static_cast<int>(std::size(kLimbs)); ++r) {
    const int n = kLimbs[r];
    const RobotParams<double> robot = precurved_robot(n, rng, 0.6);
    int found = 0;
    for (int tries = 0; found < 6 && tries < 200; ++tries) {
      const double s = std::exp(log_scale(rng));
      JointVector q(n);
      for (int i = 0; i < n; ++i) q(i) = s * unit(rng) * robot.limb(i).q_max;
      Case c{robot, q, forward_kinematics(robot, q), {}};
      if (!c.rk4.summary.converged() || c.rk4.summary.max_strain > 0.01) continue;
      c.reference = forward_kinematics_reference(robot, q, c.rk4, reference);
      if (!c.reference.summary.converged()) {
        ++unjudged;
        continue;
      }
      cases.push_back(c);
      ++found;
    }
  }
  return cases;
}

class PrecurvedRobot : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { cases_ = new std::vector<Case>(precurved_cases(unjudged_)); }
  static void TearDownTestSuite() { delete cases_; }
  static std::vector<Case>* cases_;
  static int unjudged_;
};
std::vector<Case>* PrecurvedRobot::cases_ = nullptr;
int PrecurvedRobot::unjudged_ = 0;

// The home solve of a design stress-free at (0, 0, 0) finds it, stable, its rods unloaded: their
// elastic turn |m| l / EI + |n| l^2 / EI below 1e-4 rad (with n >= 4 limbs the wrenches are
// ill-conditioned, nearly a self-stress, and known only as well as the pose needs them).
TEST(PrecurvedDesign, HomeIsTheStressFreeOrigin) {
  std::mt19937_64 rng(5);
  for (int n = 2; n <= 5; ++n) {
    const RobotParams<double> design = precurved_design(n, rng, 0.6);
    const ForwardSolution home = home_solution(design);
    ASSERT_TRUE(home.summary.converged()) << n << " " << to_string(home.summary.status);
    EXPECT_EQ(home.summary.stability, Stability::kStable) << n;
    EXPECT_LT(home.pose.translation().norm(), kPositionPromise) << n;  // the exact model's home
    EXPECT_LT(std::abs(home.pose.theta), kAnglePromise) << n;
    for (int i = 0; i < n; ++i) {
      const Rod<double>& r = design.limb(i).rod;
      const Wrench<double>& w = home.wrenches[i];
      const double turn =
          (std::abs(w.m) + std::hypot(w.nx, w.ny) * r.length) * r.length / r.bending_stiffness();
      EXPECT_LT(turn, 1e-4) << n << " limb " << i;
    }
  }
}

TEST_F(PrecurvedRobot, ForwardKinematicsIsWithinOneNanometreOfCvode) {
  ASSERT_GE(cases_->size(), 40u) << unjudged_ << " unjudged";
  double worst = 0, worst_angle = 0;
  for (const Case& c : *cases_) {
    const double e = (c.rk4.pose.translation() - c.reference.pose.translation()).norm();
    EXPECT_LE(e, kPositionPromise) << "n " << c.robot.num_limbs << " q " << c.q.transpose();
    EXPECT_LE(std::abs(c.rk4.pose.theta - c.reference.pose.theta), kAnglePromise);
    worst = std::max(worst, e);
    worst_angle = std::max(worst_angle, std::abs(c.rk4.pose.theta - c.reference.pose.theta));
  }
  std::printf("[ shaped ] FK, %zu configurations of 8 robots: worst %.3e m, %.3e rad\n",
              cases_->size(), worst, worst_angle);
}

TEST_F(PrecurvedRobot, InverseKinematicsIsWithinOneNanometreOfCvode) {
  SolverOptions options;
  options.stable_inverse = false;  // accuracy, not stability: the draws need not be stable
  double worst = 0;
  int solved = 0, other_branch = 0;
  for (const Case& c : *cases_) {
    if (c.robot.num_limbs > 3) continue;
    InverseSolution ik = inverse_kinematics(c.robot, c.reference.pose, options);
    if (usable_as_warm_start(ik.summary) && (ik.q - c.q).cwiseAbs().maxCoeff() > 1e-6) {
      ++other_branch;  // two limbs: more than one theta meets x and y
      ik = inverse_kinematics(c.robot, c.reference.pose, as_inverse_warm_start(c.rk4), options);
    }
    ASSERT_TRUE(usable_as_warm_start(ik.summary)) << to_string(ik.summary.status);
    ++solved;
    const double e = (ik.q - c.q).cwiseAbs().maxCoeff();
    EXPECT_LE(e, kPositionPromise) << "n " << c.robot.num_limbs << " q " << c.q.transpose();
    worst = std::max(worst, e);
  }
  EXPECT_GE(solved, 24);
  EXPECT_LE(other_branch, 3);
  std::printf("[ shaped ] IK, %d poses (%d cold on another branch): worst %.3e m\n", solved,
              other_branch, worst);
}

// The stability check against the energy reference on the drawn equilibria, and on both sides of
// a fold: a pre-curved design with a 200 mm stroke, uniform and tapered, its platform moved along a
// line by warm IK left on its branch until the check calls it unstable (25 mm out, rod 0 pushed
// 50 mm in, for the uniform rods).
TEST_F(PrecurvedRobot, StabilityAgreesWithTheEnergy) {
  const auto energy_eigenvalue = [](const RobotParams<double>& robot, const JointVector& q,
                                    const Pose2<double>& pose,
                                    const std::array<Wrench<double>, kMaxLimbs>& wrenches) {
    const EnergyStability e =
        energy_stability(energy_problem(robot, q), energy_start(robot, q, pose, wrenches, 100));
    EXPECT_TRUE(e.converged);
    EXPECT_LT((e.state.pose.translation() - pose.translation()).norm(), 1e-5);
    return e.min_eigenvalue;
  };
  int drawn = 0;
  for (std::size_t k = 0; k < cases_->size(); k += 2) {
    const Case& c = (*cases_)[k];
    const EquilibriumStability s = equilibrium_stability(c.robot, c.rk4.q, c.rk4.pose,
                                                         c.rk4.wrenches, c.rk4.summary.rod_steps);
    EXPECT_EQ(s.stable, energy_eigenvalue(c.robot, c.rk4.q, c.rk4.pose, c.rk4.wrenches) > 0)
        << "n " << c.robot.num_limbs << " q " << c.q.transpose() << " margin " << s.margin;
    ++drawn;
  }
  std::mt19937_64 rng(3);
  const RobotParams<double> design = precurved_design(3, rng, 0.5, /*tapered=*/false);
  // The design as drawn, then its rods tapered (tips 1.3 times as thick: the stress-free shape,
  // hence the home, stays; the stiffness does not).
  for (const double tip_ratio : {1.0, 1.3}) {
    RobotParams<double> robot = design;
    for (int i = 0; i < 3; ++i) {
      robot.limb(i).q_min = -0.1;
      robot.limb(i).q_max = 0.1;
      Rod<double>& r = robot.limb(i).rod;
      r.diameter_slope = r.diameter * (tip_ratio - 1.0) / r.length;
    }
    SolverOptions options;
    options.stable_inverse = false;
    InverseSequence sequence(robot, options, PlatformLoad<double>(), SequenceMode::kPath);
    const double direction = 75 * M_PI / 180;
    int flip = -1, stable = 0, unstable = 0;
    for (int k = 0; k <= 300 && (flip < 0 || k <= flip + 30); ++k) {
      const double t = k * 1e-4;
      const InverseSolution& ik =
          sequence.solve({t * std::cos(direction), t * std::sin(direction), 0.0});
      ASSERT_TRUE(is_equilibrium(ik.summary))
          << tip_ratio << " " << t << " " << to_string(ik.summary.status);
      const bool is_stable = ik.summary.stability == Stability::kStable;
      if (flip < 0 && !is_stable) flip = k;
      // Not at the fold itself: the discrete energy model's own fold lies O(1 / N^2) away.
      if ((flip < 0 && k % 20 == 0) ||
          (flip >= 0 && (k == flip + 10 || k == flip + 20 || k == flip + 30))) {
        EXPECT_EQ(is_stable, energy_eigenvalue(robot, ik.q, ik.pose, ik.wrenches) > 0)
            << tip_ratio << " " << t << " margin " << ik.summary.stability_margin;
        (is_stable ? stable : unstable) += 1;
      }
    }
    ASSERT_GE(flip, 0) << "no fold on the line, tips " << tip_ratio;
    EXPECT_GE(unstable, 2) << tip_ratio;
    std::printf(
        "[ shaped ] stability vs energy: %d drawn equilibria; along a line (tips %.1f times as "
        "thick), the check turns unstable at %.1f mm, %d stable and %d unstable points agree\n",
        drawn, tip_ratio, flip * 0.1, stable, unstable);
  }
}

}  // namespace
}  // namespace pcr
