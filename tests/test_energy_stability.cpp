// The energy-based stability reference (pcr::energy_stability) against closed forms: Euler's
// clamped-clamped column, a cantilever under a dead tip load; its discrete equilibrium against the
// shooting solver's on the default robot; and a robot driven past a fold.
#include <gtest/gtest.h>

#include <cmath>

#include "pcr/kinematics.hpp"
#include "pcr/reference.hpp"

namespace pcr {
namespace {

constexpr double kLength = 0.030;
const double kEi = bending_stiffness(69e9, 125e-6);

/// One rod along x from the origin, its tip at the platform's origin (B = 0, beta = 0).
EnergyProblem one_rod(std::array<bool, 3> free, Vector2<double> force) {
  EnergyProblem problem;
  problem.rods.push_back({Vector2<double>(0, 0), 0.0, Vector2<double>(0, 0), 0.0, kLength, kEi});
  problem.platform_free = free;
  problem.load.force = force;
  return problem;
}

EnergyState straight(int segments) {
  EnergyState state;
  state.pose = {kLength, 0.0, 0.0};
  state.angles.assign(1, std::vector<double>(static_cast<std::size_t>(segments), 0.0));
  return state;
}

// A column clamped at both ends, one end sliding along the axis under a compressive dead force F:
// the straight shape is stable below Euler's 4 pi^2 EI / l^2 and unstable above. The discrete
// model's critical load is within O(1 / N^2) of it.
TEST(EnergyStability, ClampedClampedColumnBucklesAtEulersLoad) {
  const double critical = 4 * M_PI * M_PI * kEi / (kLength * kLength);
  const int segments = 200;
  double previous = std::numeric_limits<double>::infinity();
  for (double ratio : {0.0, 0.5, 0.99, 0.998, 1.002, 1.01, 1.5}) {
    const EnergyProblem column = one_rod({true, false, false}, {-ratio * critical, 0.0});
    const EnergyStability s = energy_stability(column, straight(segments));
    ASSERT_TRUE(s.converged) << ratio;
    EXPECT_NEAR(s.state.pose.x, kLength, 1e-15) << ratio;  // still straight
    if (ratio < 1) {
      EXPECT_GT(s.min_eigenvalue, 0) << ratio;
    } else {
      EXPECT_LT(s.min_eigenvalue, 0) << ratio;
    }
    EXPECT_LT(s.min_eigenvalue, previous) << ratio;  // compression softens it
    previous = s.min_eigenvalue;
  }
  // Unloaded, the smallest eigenvalue is that of int EI dtheta'^2 on angles vanishing at both
  // ends with zero mean (the tip's lateral closure): the second mode, (2 pi)^2 in these units,
  // and compression lowers it linearly, to zero at the critical load.
  const EnergyStability free =
      energy_stability(one_rod({true, false, false}, {0.0, 0.0}), straight(segments));
  EXPECT_NEAR(free.min_eigenvalue, 4 * M_PI * M_PI, 1e-3 * 4 * M_PI * M_PI);
  const EnergyStability half =
      energy_stability(one_rod({true, false, false}, {-0.5 * critical, 0.0}), straight(segments));
  EXPECT_NEAR(half.min_eigenvalue, 2 * M_PI * M_PI, 1e-3 * 4 * M_PI * M_PI);
}

// A cantilever (the platform free in x, y and theta, carried by its tip alone) loaded from
// straight by a dead force in steps: every equilibrium on the way is stable, however far it bends,
// and its tip deflection under a small load is the linear F l^3 / (3 EI).
TEST(EnergyStability, CantileverUnderADeadTipLoadIsStable) {
  const int segments = 100;
  for (double direction : {-M_PI / 2, -3 * M_PI / 4, 0.9 * M_PI}) {
    EnergyState state = straight(segments);
    const double unit = kEi / (kLength * kLength);
    for (double load = 0.25; load <= 8.0; load += 0.25) {
      const Vector2<double> force =
          load * unit * Vector2<double>(std::cos(direction), std::sin(direction));
      const EnergyStability s = energy_stability(one_rod({true, true, true}, force), state);
      ASSERT_TRUE(s.converged) << direction << " " << load;
      EXPECT_GT(s.min_eigenvalue, 0) << direction << " " << load;
      if (direction == -M_PI / 2 && load == 0.25) {
        const double linear = 0.25 * kLength / 3;  // F l^3 / (3 EI) with F = 0.25 EI / l^2
        EXPECT_NEAR(-s.state.pose.y, linear, 0.05 * linear);
      }
      state = s.state;
    }
    EXPECT_GT(std::hypot(state.pose.x - kLength, state.pose.y), 0.3 * kLength) << direction;
  }
}

// The default robot: the discrete equilibrium next to the shooting solution is that solution, to
// the discretisation's O(1 / N^2) (an independent check of both models' equations), and home and a
// moved configuration are stable.
TEST(EnergyStability, DefaultRobotAgreesWithShootingAndIsStable) {
  const RobotParams<double> robot = femto_3pf();
  JointVector q(3);
  q << 0.004, -0.002, 0.001;
  const ForwardSolution fk = forward_kinematics(robot, q);
  ASSERT_TRUE(fk.summary.converged());
  double previous_error = std::numeric_limits<double>::infinity();
  for (int segments : {50, 100, 200}) {
    const EnergyStability s = energy_stability(
        energy_problem(robot, q), energy_start(robot, q, fk.pose, fk.wrenches, segments));
    ASSERT_TRUE(s.converged) << segments;
    EXPECT_GT(s.min_eigenvalue, 0) << segments;
    const double error = std::hypot(s.state.pose.x - fk.pose.x, s.state.pose.y - fk.pose.y);
    EXPECT_LT(error, 1e-6) << segments;
    EXPECT_LT(error, previous_error / 3) << segments;  // second order
    previous_error = error;
  }
  const ForwardSolution home = home_solution(robot);
  const JointVector zero = JointVector::Zero(3);
  const EnergyStability at_home = energy_stability(
      energy_problem(robot, zero), energy_start(robot, zero, home.pose, home.wrenches, 100));
  ASSERT_TRUE(at_home.converged);
  EXPECT_GT(at_home.min_eigenvalue, 0);
}

// The default robot with a 60 mm stroke, its platform moved along a line at theta = 0 (75 degrees
// from the x axis) by warm-started IK: the IK solutions continue smoothly past about 22.8 mm, but
// there the equilibrium with the joints held loses its stability (a fold of the forward problem):
// the smallest eigenvalue falls through zero.
TEST(EnergyStability, PastAFoldTheLongerStrokeRobotIsUnstable) {
  RobotParams<double> robot = femto_3pf();
  for (int i = 0; i < 3; ++i) {
    robot.limb(i).q_min = -0.030;
    robot.limb(i).q_max = 0.030;
  }
  SolverOptions options;
  options.stable_inverse = false;  // stay on the branch that loses its stability
  InverseSequence sequence(robot, options, PlatformLoad<double>(), SequenceMode::kPath);
  const double direction = 75 * M_PI / 180;
  double previous = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 250; ++k) {
    const double t = k * 1e-4;
    const InverseSolution& ik =
        sequence.solve({t * std::cos(direction), t * std::sin(direction), 0.0});
    ASSERT_TRUE(ik.summary.converged()) << t;
    if (k != 200 && k != 220 && k != 235 && k != 250) continue;
    const EnergyStability s = energy_stability(
        energy_problem(robot, ik.q), energy_start(robot, ik.q, ik.pose, ik.wrenches, 100));
    ASSERT_TRUE(s.converged) << t;
    EXPECT_LT(std::hypot(s.state.pose.x - ik.pose.x, s.state.pose.y - ik.pose.y), 1e-5) << t;
    if (t < 0.0225) {
      EXPECT_GT(s.min_eigenvalue, 0) << t;
    } else {
      EXPECT_LT(s.min_eigenvalue, 0) << t;
    }
    EXPECT_LT(s.min_eigenvalue, previous) << t;
    previous = s.min_eigenvalue;
  }
}

TEST(EnergyStability, RejectsMalformedProblems) {
  EnergyProblem problem = one_rod({true, true, true}, {0, 0});
  EXPECT_THROW(energy_stability(problem, EnergyState{}), std::invalid_argument);
  problem.rods[0].ei = 0;
  EXPECT_THROW(energy_stability(problem, straight(10)), std::invalid_argument);
}

}  // namespace
}  // namespace pcr
