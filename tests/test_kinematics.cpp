// Forward and inverse kinematics: round trips, exact Jacobians, equilibrium, symmetry,
// statuses, and the real-time guarantees (no allocation).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "allocation_counter.hpp"
#include "pcr/kinematics.hpp"
#include "random_robots.hpp"

namespace pcr {
namespace {

JointVector joints(std::initializer_list<double> values) {
  JointVector q(static_cast<int>(values.size()));
  int i = 0;
  for (double v : values) q(i++) = v;
  return q;
}

std::vector<JointVector> random_configurations(int count, double half_range, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-half_range, half_range);
  std::vector<JointVector> out;
  for (int k = 0; k < count; ++k) out.push_back(joints({u(rng), u(rng), u(rng)}));
  return out;
}

TEST(Kinematics, HomeIsTheStressFreeStraightConfiguration) {
  const ForwardSolution home = home_solution(femto_3pf());
  ASSERT_TRUE(home.summary.converged());
  EXPECT_NEAR(home.pose.x, 0.0, 1e-15);
  EXPECT_NEAR(home.pose.y, 0.0, 1e-15);
  EXPECT_NEAR(home.pose.theta, 0.0, 1e-15);
  EXPECT_NEAR(home.summary.max_strain, 0.0, 1e-15);
}

TEST(Kinematics, ForwardInverseRoundTrip) {
  // With a fixed step count FK and IK solve one discrete model: the round trip is exact to
  // rounding. With the default (each solve picks its own count for its error target) FK and IK
  // may settle on different counts; both lie within their targets of the exact model.
  const RobotParams<double> robot = femto_3pf();
  SolverOptions fixed;
  fixed.rod_steps = 64;
  const SolverOptions automatic;
  for (const SolverOptions& options : {fixed, automatic}) {
    const double tolerance = options.rod_steps > 0 ? 1e-12 : 2 * options.position_accuracy;
    const double angle_tolerance = options.rod_steps > 0 ? 1e-12 : 2 * options.angle_accuracy;
    int converged = 0;
    for (const JointVector& q : random_configurations(30, 0.004, 7)) {
      const ForwardSolution fk = forward_kinematics(robot, q, options);
      if (!fk.summary.converged()) continue;
      ++converged;
      const InverseSolution ik = inverse_kinematics(robot, fk.pose, options);
      ASSERT_TRUE(ik.summary.converged()) << to_string(ik.summary.status);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(ik.q(i), q(i), tolerance);
      // And back: FK of the IK joints lands on the commanded pose.
      const ForwardSolution again = forward_kinematics(robot, ik.q, fk, options);
      ASSERT_TRUE(again.summary.converged());
      EXPECT_LE(std::hypot(again.pose.x - fk.pose.x, again.pose.y - fk.pose.y), tolerance);
      EXPECT_NEAR(again.pose.theta, fk.pose.theta, angle_tolerance);
    }
    EXPECT_GE(converged, 20);
  }
}

TEST(Kinematics, WarmStartConvergesInFewIterations) {
  const RobotParams<double> robot = femto_3pf();
  const ForwardSolution fk = forward_kinematics(robot, joints({0.002, -0.001, 0.003}));
  ASSERT_TRUE(fk.summary.converged());
  const ForwardSolution near = forward_kinematics(robot, joints({0.00201, -0.001, 0.003}), fk);
  ASSERT_TRUE(near.summary.converged());
  EXPECT_LE(near.summary.iterations, 3);
  EXPECT_EQ(near.summary.continuation_steps, 0);
}

// d residual / d unknowns of FK and IK against central differences of the residual.
void check_jacobian(internal::ShootingProblem& problem, const ShootingVector& z) {
  ShootingVector r;
  JacobianMatrix J;
  problem.evaluate(z, r, &J);
  for (int j = 0; j < z.size(); ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(z(j)));
    ShootingVector zp = z, zm = z, rp, rm;
    zp(j) += h;
    zm(j) -= h;
    problem.evaluate(zp, rp, nullptr);
    problem.evaluate(zm, rm, nullptr);
    const ShootingVector fd = (rp - rm) / (2 * h);
    for (int i = 0; i < r.size(); ++i) {
      EXPECT_NEAR(J(i, j), fd(i), 1e-6 * std::max(1.0, std::abs(fd(i)))) << i << "," << j;
    }
  }
}

TEST(Kinematics, JacobianMatchesCentralDifferences) {
  const RobotParams<double> robot = femto_3pf();
  const SolverOptions options;
  const PlatformLoad<double> load{Vector2<double>(2e-4, -1e-4), 3e-6};
  const ForwardSolution fk =
      forward_kinematics(robot, joints({0.003, -0.002, 0.001}), options, load);
  ASSERT_TRUE(fk.summary.converged());
  ShootingPoint<double> point;
  point.pose = fk.pose;
  for (int i = 0; i < 3; ++i) {
    point.q[i] = fk.q(i);
    point.wrenches[i] = fk.wrenches[i];
  }
  // Off the solution too, where the residual is not zero.
  point.pose.theta += 0.01;
  point.wrenches[1].m += 1e-6;
  internal::ShootingProblem forward(internal::ShootingProblem::Kind::kForward, robot, load,
                                    options);
  forward.set_input(fk.q);
  check_jacobian(forward, forward.pack(point));
  internal::ShootingProblem inverse(internal::ShootingProblem::Kind::kInverse, robot, load,
                                    options);
  ShootingVector pose(3);
  pose << fk.pose.x, fk.pose.y, fk.pose.theta;
  inverse.set_input(pose);
  check_jacobian(inverse, inverse.pack(point));
}

// The chord matrix's inverse, formed at its first secant correction from the factorisation,
// against a QR solve of the same systems: random matrices of every size up to the largest shooting
// problem's, their rows scaled apart so that partial pivoting reorders them.
TEST(Kinematics, ChordMatrixInverseMatchesAnIndependentSolve) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int size = 1; size <= kMaxResiduals; ++size) {
    JacobianMatrix J(size, size);
    for (int i = 0; i < size; ++i) {
      for (int j = 0; j < size; ++j) J(i, j) = normal(rng) * std::pow(10.0, (i % 3) - 1);
    }
    internal::ChordMatrix chord;
    chord.compute(J);
    ShootingVector s(size), b(size);
    for (int i = 0; i < size; ++i) {
      s(i) = normal(rng);
      b(i) = normal(rng);
    }
    // A secant the Jacobian already satisfies forms the inverse and leaves it as it is.
    const ShootingVector y = J * s;
    chord.secant_update(s, y);
    const ShootingVector expected = J.colPivHouseholderQr().solve(b);
    const ShootingVector x = chord.solve(b);
    EXPECT_LE((x - expected).norm(), 1e-10 * expected.norm()) << "size " << size;
    EXPECT_LE((J * x - b).norm(), 1e-12 * J.norm() * x.norm()) << "size " << size;
  }
}
// The clamps' reactions balance the external load: sum n_i(0) = f and
// sum (A_i(q) x n_i(0) + m_i(0)) = p_P x f + m_z about W's origin (the whole robot is in
// equilibrium).
TEST(Kinematics, ClampReactionsBalanceTheLoad) {
  const RobotParams<double> robot = femto_3pf();
  const PlatformLoad<double> load{Vector2<double>(5e-4, 3e-4), -4e-6};
  const ForwardSolution fk =
      forward_kinematics(robot, joints({0.001, 0.002, -0.001}), SolverOptions(), load);
  ASSERT_TRUE(fk.summary.converged());
  Vector2<double> force(0, 0);
  double moment = 0;
  for (int i = 0; i < 3; ++i) {
    const Wrench<double>& w = fk.wrenches[i];
    const Vector2<double> a = robot.limb(i).proximal_position(fk.q(i));
    force += Vector2<double>(w.nx, w.ny);
    moment += a.x() * w.ny - a.y() * w.nx + w.m;
  }
  const double expected_moment =
      fk.pose.x * load.force.y() - fk.pose.y * load.force.x() + load.moment;
  EXPECT_NEAR(force.x(), load.force.x(), 1e-14);
  EXPECT_NEAR(force.y(), load.force.y(), 1e-14);
  EXPECT_NEAR(moment, expected_moment, 1e-15);
}

// Rotating the symmetric robot by 120 degrees maps limb i onto limb i + 1.
TEST(Kinematics, SymmetricRobotCommutesWithRotation) {
  const RobotParams<double> robot = femto_3pf();
  const JointVector q = joints({0.003, -0.001, 0.0015});
  const JointVector shifted = joints({q(2), q(0), q(1)});
  const ForwardSolution a = forward_kinematics(robot, q);
  const ForwardSolution b = forward_kinematics(robot, shifted);
  ASSERT_TRUE(a.summary.converged() && b.summary.converged());
  const double c = std::cos(2 * M_PI / 3), s = std::sin(2 * M_PI / 3);
  EXPECT_NEAR(b.pose.x, c * a.pose.x - s * a.pose.y, 1e-13);
  EXPECT_NEAR(b.pose.y, s * a.pose.x + c * a.pose.y, 1e-13);
  EXPECT_NEAR(b.pose.theta, a.pose.theta, 1e-12);
}

// Without external load the pose does not depend on E (the paper's Table 2), and forces scale with
// E.
TEST(Kinematics, YoungModulusHasNoEffectWithoutLoad) {
  RobotParams<double> robot = femto_3pf();
  const JointVector q = joints({0.002, 0.004, -0.001});
  const ForwardSolution a = forward_kinematics(robot, q);
  for (int i = 0; i < 3; ++i) robot.limb(i).rod.young_modulus *= 2.5;
  const ForwardSolution b = forward_kinematics(robot, q);
  ASSERT_TRUE(a.summary.converged() && b.summary.converged());
  EXPECT_NEAR(a.pose.x, b.pose.x, 1e-15);
  EXPECT_NEAR(a.pose.y, b.pose.y, 1e-15);
  EXPECT_NEAR(a.pose.theta, b.pose.theta, 1e-13);
  EXPECT_NEAR(b.wrenches[0].nx, 2.5 * a.wrenches[0].nx, 1e-12 * std::abs(b.wrenches[0].nx) + 1e-18);
}

TEST(Kinematics, PullingEveryRodTooFarIsSingularNotAFailure) {
  const ForwardSolution fk = forward_kinematics(femto_3pf(), joints({-0.006, -0.006, -0.006}));
  EXPECT_EQ(fk.summary.status, SolveStatus::kSingular);
  EXPECT_GT(fk.summary.continuation_steps, 0);
}

TEST(Kinematics, LargeMovesNeedContinuationAndConverge) {
  const RobotParams<double> robot = femto_3pf();
  const ForwardSolution fk = forward_kinematics(robot, joints({0.008, -0.004, 0.006}));
  ASSERT_TRUE(fk.summary.converged()) << to_string(fk.summary.status);
  const InverseSolution ik = inverse_kinematics(robot, fk.pose);
  ASSERT_TRUE(ik.summary.converged()) << to_string(ik.summary.status);
  EXPECT_NEAR(ik.q(0), 0.008, 2 * SolverOptions().position_accuracy);
}

TEST(Kinematics, InverseReportsJointsOutsideTheStroke) {
  RobotParams<double> robot = femto_3pf();
  const ForwardSolution fk = forward_kinematics(robot, joints({0.002, 0.0, 0.0}));
  for (int i = 0; i < 3; ++i) robot.limb(i).q_max = 0.001;
  const InverseSolution ik = inverse_kinematics(robot, fk.pose);
  EXPECT_EQ(ik.summary.status, SolveStatus::kOutOfRange);
  EXPECT_NEAR(ik.q(0), 0.002, 1e-12);
}

// The stroke is decided by the solver: every way of solving FK at joints outside it says
// kOutOfRange and still gives the equilibrium, the one a robot with a wider stroke reaches there.
TEST(Kinematics, ForwardReportsJointsOutsideTheStroke) {
  const RobotParams<double> wide = femto_3pf();
  RobotParams<double> robot = wide;
  for (int i = 0; i < 3; ++i) robot.limb(i).q_max = 0.001;
  const JointVector inside = joints({0.0005, -0.002, 0.001});
  const JointVector outside = joints({0.002, -0.002, 0.001});
  ASSERT_TRUE(within_stroke(robot, inside));
  ASSERT_FALSE(within_stroke(robot, outside));
  const ForwardSolution reference = forward_kinematics(wide, outside);
  ASSERT_TRUE(reference.summary.converged()) << to_string(reference.summary.status);

  const ForwardSolution cold = forward_kinematics(robot, outside);
  const ForwardSolution from_inside = forward_kinematics(robot, inside);
  ASSERT_TRUE(from_inside.summary.converged()) << to_string(from_inside.summary.status);
  const ForwardSolution warm = forward_kinematics(robot, outside, from_inside);
  const ForwardSolution folds = forward_kinematics_through_folds(robot, outside, from_inside);
  ForwardSequence path(robot, SolverOptions(), PlatformLoad<double>(), SequenceMode::kPath);
  path.solve(inside);
  const ForwardSolution in_path = path.solve(outside);
  ForwardSequence rows(robot);
  const ForwardSolution in_rows = rows.solve(outside);
  for (const ForwardSolution* s : {&cold, &warm, &folds, &in_path, &in_rows}) {
    EXPECT_EQ(s->summary.status, SolveStatus::kOutOfRange) << to_string(s->summary.status);
    EXPECT_TRUE(is_equilibrium(s->summary));
    EXPECT_NEAR(s->pose.x, reference.pose.x, 1e-9);
    EXPECT_NEAR(s->pose.y, reference.pose.y, 1e-9);
    EXPECT_NEAR(s->pose.theta, reference.pose.theta, 1e-6);
  }
  // It warm-starts the next solve, back inside the stroke.
  EXPECT_TRUE(path.solve(inside).summary.converged());
}

RobotParams<double> two_limb_robot() {
  RobotParams<double> robot = femto_3pf();
  robot.num_limbs = 2;
  return robot;
}

TEST(Kinematics, TwoLimbInverseImposesPositionAndSolvesTheta) {
  const RobotParams<double> robot = two_limb_robot();
  const ForwardSolution fk = forward_kinematics(robot, joints({0.002, -0.001}));
  ASSERT_TRUE(fk.summary.converged()) << to_string(fk.summary.status);
  Pose2<double> target = fk.pose;
  target.theta = 0.7;  // ignored: theta is free for two limbs
  const InverseSolution ik = inverse_kinematics(robot, target);
  ASSERT_TRUE(ik.summary.converged()) << to_string(ik.summary.status);
  EXPECT_NEAR(ik.q(0), 0.002, 1e-12);
  EXPECT_NEAR(ik.q(1), -0.001, 1e-12);
  EXPECT_NEAR(ik.pose.theta, fk.pose.theta, 1e-10);
}

// Four straight rods at q = 0 carry a self-stress mode (four axial forces, three equilibrium
// equations) that inextensible straight rods cannot feel: the home Jacobian is singular, a
// bifurcation where the branches of rods bowed to either side meet. A warm solve from there says
// so; a cold one takes the branch of the bowed variant. IK is not square for four limbs.
TEST(Kinematics, FourLimbRobotBranchesOffItsStraightHome) {
  const RobotParams<double> robot = testing::regular_robot(4);
  const ForwardSolution home = home_solution(robot);
  ASSERT_TRUE(home.summary.converged());
  EXPECT_EQ(home.summary.max_strain, 0.0);
  const JointVector q = joints({0.0001, 0.0, 0.0, 0.0});
  EXPECT_EQ(forward_kinematics(robot, q, home).summary.status, SolveStatus::kBifurcation);
  const ForwardSolution cold = forward_kinematics(robot, q);
  ASSERT_TRUE(cold.summary.converged()) << to_string(cold.summary.status);
  // Pushing one rod 0.1 mm in bows the rods (a straight, rigid platform motion cannot absorb it).
  EXPECT_GT(cold.summary.max_strain, 1e-4);
  // The same branch is followed by warm solves from there.
  const ForwardSolution next = forward_kinematics(robot, joints({0.00011, 0.0, 0.0, 0.0}), cold);
  ASSERT_TRUE(next.summary.converged()) << to_string(next.summary.status);
  EXPECT_LT(std::abs(next.pose.x - cold.pose.x), 1e-5);
  // Back through q = 0 the bowed branch meets the straight home, a bifurcation: said so (not
  // `singular`, which would mean no solution ahead), the last point solved next to it.
  const ForwardSolution through = forward_kinematics(robot, joints({-0.0001, 0.0, 0.0, 0.0}), cold);
  EXPECT_EQ(through.summary.status, SolveStatus::kBifurcation);
  EXPECT_NEAR(through.summary.path_fraction, 0.5, 0.01);
  EXPECT_NEAR(through.q(0), 0.0, 2e-6);
  InverseSolution warm;
  warm.q = JointVector::Zero(4);
  EXPECT_EQ(inverse_kinematics(robot, Pose2<double>{}, warm).summary.status,
            SolveStatus::kUnsupported);
}

// One limb 80 um longer and its alpha 3 mrad off (4 to 6 limbs): the robot is pre-stressed at home,
// and the straight guess sits on the bifurcation. The home solve reaches the bowed home from a
// bowed variant; so it does for robots with every parameter drawn inside the paper's intervals.
TEST(Kinematics, PreStressedRedundantRobotsFindTheirBowedHome) {
  std::vector<RobotParams<double>> robots;
  for (int n = 4; n <= 6; ++n) {
    RobotParams<double> longer = testing::regular_robot(n);
    longer.limb(1).rod.length += 80e-6;
    longer.limb(1).alpha += 3e-3;
    robots.push_back(longer);
  }
  std::mt19937_64 rng(12);
  for (int n = 4; n <= 6; ++n) {
    for (int k = 0; k < 3; ++k)
      robots.push_back(testing::perturbed(testing::regular_robot(n), rng));
  }
  for (std::size_t r = 0; r < robots.size(); ++r) {
    const RobotParams<double>& robot = robots[r];
    const int n = robot.num_limbs;
    const ForwardSolution home = home_solution(robot);
    ASSERT_TRUE(home.summary.converged())
        << "robot " << r << ": " << to_string(home.summary.status);
    EXPECT_GT(home.summary.max_strain, 1e-4) << "robot " << r;
    // An equilibrium of the exact model too: solved again from there at 4x the steps, the pose
    // moves by far less than 1 nm. Where straight rods at home still carry a self-stress, home is
    // a bifurcation (the warm solve says so) and the cold solve at 4x the steps stands in.
    SolverOptions fine;
    fine.rod_steps = 4 * home.summary.rod_steps;
    ForwardSolution refined = forward_kinematics(robot, JointVector::Zero(n), home, fine);
    if (refined.summary.status == SolveStatus::kBifurcation) refined = home_solution(robot, fine);
    ASSERT_TRUE(refined.summary.converged())
        << "robot " << r << ": " << to_string(refined.summary.status);
    EXPECT_LT(std::hypot(refined.pose.x - home.pose.x, refined.pose.y - home.pose.y), 1e-9)
        << "robot " << r;
    // And the robot moves from there: warm, or, where straight rods at home still carry a
    // self-stress (a bifurcation), cold from the bowed variant at those joints.
    JointVector q = JointVector::Zero(n);
    q(0) = 1e-5;
    // A warm solve from a home where four or more rods stay straight (a self-stress) meets a
    // bifurcation and says so: not `singular`, which would deny the solutions on the bowed
    // branches.
    const SolveStatus warm = forward_kinematics(robot, q, home).summary.status;
    EXPECT_TRUE(warm == SolveStatus::kConverged || warm == SolveStatus::kBifurcation)
        << "robot " << r << ": " << to_string(warm);
    ForwardSequence sequence(robot, SolverOptions(), PlatformLoad<double>(), SequenceMode::kPath);
    sequence.set_warm_start(home);
    const ForwardSolution& moved = sequence.solve(q);
    EXPECT_TRUE(moved.summary.converged())
        << "robot " << r << ": " << to_string(moved.summary.status);
  }
}

// A pre-stressed robot has several homes: a 4-limb robot with two rods 300 um and 200 um longer
// reaches seven from the 16 patterns of bow sides said (LimbParams::home_bow), in three groups of
// platform poses up to 0.5 mm apart; within a group the poses lie 4 nm to 2 um apart and the
// bent rods bow to other sides (the signs of their proximal moments). Said in the robot, the home
// solve and FK near home follow the home said; choose_home names each from its pose.
TEST(Kinematics, APreStressedRobotFollowsTheHomeItSays) {
  RobotParams<double> robot = testing::regular_robot(4);
  robot.limb(1).rod.length += 300e-6;
  robot.limb(3).rod.length += 200e-6;
  // The sides of the rods bent at home: the signs of the proximal moments above a tenth of the
  // largest (a nearly straight rod has none).
  const auto sides = [](const ForwardSolution& s) {
    double largest = 0;
    for (int i = 0; i < 4; ++i) largest = std::max(largest, std::abs(s.wrenches[i].m));
    std::array<int, 4> out{};
    for (int i = 0; i < 4; ++i) {
      if (std::abs(s.wrenches[i].m) > 0.1 * largest) out[i] = s.wrenches[i].m > 0 ? 1 : -1;
    }
    return out;
  };
  std::vector<ForwardSolution> homes;  // distinct homes: pose or sides differ
  for (int pattern = -1; pattern < 16; ++pattern) {
    RobotParams<double> said = robot;
    for (int i = 0; i < 4; ++i)
      said.limb(i).home_bow = pattern < 0 ? 0 : ((pattern >> i) & 1 ? 1 : -1);
    const ForwardSolution home = home_solution(said);
    ASSERT_TRUE(home.summary.converged()) << "pattern " << pattern;
    // FK 1 um away follows the home said: the same sides, the pose moved by about a micrometre.
    JointVector q = JointVector::Zero(4);
    q(0) = 1e-6;
    const ForwardSolution moved = forward_kinematics(said, q);
    ASSERT_TRUE(moved.summary.converged()) << "pattern " << pattern;
    EXPECT_EQ(sides(moved), sides(home)) << "pattern " << pattern;
    EXPECT_LT(std::hypot(moved.pose.x - home.pose.x, moved.pose.y - home.pose.y), 3e-6)
        << "pattern " << pattern;
    bool known = false;
    for (const ForwardSolution& h : homes) {
      known = known || (std::hypot(h.pose.x - home.pose.x, h.pose.y - home.pose.y) < 1e-9 &&
                        sides(h) == sides(home));
    }
    if (!known) homes.push_back(home);
  }
  ASSERT_GE(homes.size(), 5u);
  for (std::size_t k = 0; k < homes.size(); ++k) {
    RobotParams<double> chosen;
    ASSERT_TRUE(choose_home(robot, homes[k].pose, chosen));
    const ForwardSolution home = home_solution(chosen);
    ASSERT_TRUE(home.summary.converged());
    EXPECT_LT(std::hypot(home.pose.x - homes[k].pose.x, home.pose.y - homes[k].pose.y), 1e-12)
        << "home " << k;
  }
}

// Limb 0 of the pre-stressed 4-limb robot pushed 0.1 mm in: the branch followed from the bowed
// home folds back near 80 um (its Jacobian's smallest singular value falls to 2e-9 of the largest,
// with the push along it). The continuation stalls there in ever shorter steps too short to show
// rcond's trend; the stall is still a singularity (no solution ahead on this branch), not a
// budget that ran out.
TEST(Kinematics, PreStressedRobotPushedIntoAFoldSaysSingular) {
  RobotParams<double> robot = testing::regular_robot(4);
  robot.limb(1).rod.length += 80e-6;
  robot.limb(1).alpha += 3e-3;
  const ForwardSolution home = home_solution(robot);
  ASSERT_TRUE(home.summary.converged());
  const ForwardSolution pushed = forward_kinematics(robot, joints({1e-4, 0.0, 0.0, 0.0}), home);
  EXPECT_EQ(pushed.summary.status, SolveStatus::kSingular);
  EXPECT_GT(pushed.summary.path_fraction, 0.5);
  EXPECT_LT(pushed.summary.path_fraction, 1.0);
  EXPECT_NEAR(pushed.q(0), 1e-4 * pushed.summary.path_fraction, 1e-12);
  // Short of the fold the branch is there: solved warm from home.
  const ForwardSolution before = forward_kinematics(
      robot, joints({0.9e-4 * pushed.summary.path_fraction, 0.0, 0.0, 0.0}), home);
  EXPECT_TRUE(before.summary.converged()) << to_string(before.summary.status);
}

TEST(Kinematics, SequenceSolveRetriesAFailedWarmStartCold) {
  const RobotParams<double> robot = femto_3pf();
  const JointVector q = joints({0.003, -0.002, 0.001});
  const ForwardSolution cold = forward_kinematics(robot, q);
  ASSERT_TRUE(cold.summary.converged());
  // No warm start: the cold solve itself.
  const ForwardSolution first = forward_kinematics_or_cold(robot, q, nullptr);
  EXPECT_EQ(first.pose.x, cold.pose.x);
  EXPECT_EQ(first.summary.residual_evaluations, cold.summary.residual_evaluations);
  // A warm start that cannot work (non-finite wrenches): the cold retry's answer, with the
  // failed attempt's work counted.
  ForwardSolution broken = cold;
  broken.wrenches[1].nx = std::nan("");
  broken.jacobian.clear();
  EXPECT_EQ(forward_kinematics(robot, q, broken).summary.status, SolveStatus::kNonFinite);
  const ForwardSolution retried = forward_kinematics_or_cold(robot, q, &broken);
  ASSERT_TRUE(retried.summary.converged());
  EXPECT_EQ(retried.pose.x, cold.pose.x);
  EXPECT_EQ(retried.pose.theta, cold.pose.theta);
  EXPECT_EQ(retried.summary.residual_evaluations, cold.summary.residual_evaluations + 1);
  // A usable warm start is kept: fewer evaluations than from home.
  const ForwardSolution warm = forward_kinematics_or_cold(robot, q, &cold);
  ASSERT_TRUE(warm.summary.converged());
  EXPECT_LT(warm.summary.residual_evaluations, cold.summary.residual_evaluations);
  // IK: joints out of the stroke are a usable equilibrium (a warm start), not retried cold.
  RobotParams<double> short_stroke = robot;
  for (int i = 0; i < 3; ++i) short_stroke.limb(i).q_max = 0.002;
  const InverseSolution ik_warm = as_inverse_warm_start(cold);
  const InverseSolution out = inverse_kinematics_or_cold(short_stroke, cold.pose, &ik_warm);
  EXPECT_EQ(out.summary.status, SolveStatus::kOutOfRange);
  EXPECT_TRUE(usable_as_warm_start(out.summary));
  EXPECT_EQ(out.summary.residual_evaluations,
            inverse_kinematics(short_stroke, cold.pose, ik_warm).summary.residual_evaluations);
}

// The order of a sequence's attempts (SequenceSolver, through solve_with_cold_fallback): the warm
// solve; when it stops at a fold (kSingular or kMaxIterations) and SolverOptions::through_folds,
// the pseudo-arclength trace through it; the cold solve when neither is usable; the work of every
// attempt counted.
TEST(Kinematics, SequenceTracesThroughAFoldBeforeTheColdRetry) {
  ForwardSolution start;
  start.summary.status = SolveStatus::kConverged;
  std::vector<std::string> calls;
  const auto attempt = [](SolveStatus status, int evaluations) {
    ForwardSolution s;
    s.summary.status = status;
    s.summary.iterations = 1;
    s.summary.residual_evaluations = evaluations;
    return s;
  };
  const auto run = [&](SolveStatus warm, bool through_folds, SolveStatus traced) {
    calls.clear();
    return internal::solve_with_cold_fallback<ForwardSolution>(
        &start,
        [&](const ForwardSolution&) {
          calls.push_back("warm");
          return attempt(warm, 3);
        },
        through_folds,
        [&](const ForwardSolution&) {
          calls.push_back("fold");
          ForwardSolution s = attempt(traced, 20);
          s.summary.folds_passed = 2;
          return s;
        },
        [&] {
          calls.push_back("cold");
          return attempt(SolveStatus::kConverged, 50);
        });
  };
  using Calls = std::vector<std::string>;
  ForwardSolution s = run(SolveStatus::kSingular, true, SolveStatus::kConverged);
  EXPECT_EQ(calls, (Calls{"warm", "fold"}));
  EXPECT_EQ(s.summary.folds_passed, 2);
  EXPECT_EQ(s.summary.residual_evaluations, 23);
  EXPECT_EQ(s.summary.iterations, 2);
  s = run(SolveStatus::kMaxIterations, true, SolveStatus::kSingular);
  EXPECT_EQ(calls, (Calls{"warm", "fold", "cold"}));
  EXPECT_EQ(s.summary.residual_evaluations, 73);
  EXPECT_EQ(s.summary.iterations, 3);
  s = run(SolveStatus::kSingular, false, SolveStatus::kConverged);
  EXPECT_EQ(calls, (Calls{"warm", "cold"}));
  EXPECT_EQ(s.summary.residual_evaluations, 53);
  s = run(SolveStatus::kNonFinite, true, SolveStatus::kConverged);  // not a fold
  EXPECT_EQ(calls, (Calls{"warm", "cold"}));
  s = run(SolveStatus::kConverged, true, SolveStatus::kConverged);
  EXPECT_EQ(calls, (Calls{"warm"}));
  EXPECT_EQ(s.summary.residual_evaluations, 3);
}

TEST(Kinematics, InvalidInputsAreReported) {
  const RobotParams<double> robot = femto_3pf();
  EXPECT_EQ(forward_kinematics(robot, joints({0.001, 0.002})).summary.status,
            SolveStatus::kInvalidInput);
  EXPECT_EQ(forward_kinematics(robot, joints({NAN, 0.0, 0.0})).summary.status,
            SolveStatus::kInvalidInput);
  EXPECT_EQ(inverse_kinematics(robot, Pose2<double>{NAN, 0, 0}).summary.status,
            SolveStatus::kInvalidInput);
  RobotParams<double> one = robot;
  one.num_limbs = 1;
  EXPECT_EQ(home_solution(one).summary.status, SolveStatus::kInvalidInput);
}

TEST(Kinematics, SolvesNeverAllocate) {
  const RobotParams<double> robot = femto_3pf();
  const SolverOptions options;
  ForwardSolution fk = forward_kinematics(robot, joints({0.001, 0.0, 0.0}));
  InverseSolution ik = as_inverse_warm_start(fk);
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 50; ++k) {
    const double phase = 0.1 * k;
    fk = forward_kinematics(robot, joints({0.001 * std::cos(phase), 0.001 * std::sin(phase), 0.0}),
                            fk);
    ik = inverse_kinematics(robot,
                            Pose2<double>{1e-3 * std::cos(phase), 1e-3 * std::sin(phase), 0.0}, ik);
  }
  const ForwardSolution cold = forward_kinematics(robot, joints({0.006, -0.004, 0.002}));
  const ForwardSolution beyond = forward_kinematics(robot, joints({-0.006, -0.006, -0.006}));
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(fk.summary.converged());
  EXPECT_TRUE(ik.summary.converged());
  EXPECT_TRUE(cold.summary.converged());
  EXPECT_FALSE(beyond.summary.converged());
}

}  // namespace
}  // namespace pcr
