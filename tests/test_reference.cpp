// RK4 kinematics against the CVODE reference. The default step count keeps FK within 1 nm /
// 1 urad and IK within 1 nm of the exact model on robots drawn at random inside the paper's
// uncertainty intervals (n = 2 ... 5 limbs, one under a platform load), over configurations drawn
// across the reachable stroke box; and the RK4 error falls about 16x per doubling of the step
// count (fourth order).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/reference.hpp"
#include "pcr/robot.hpp"
#include "random_robots.hpp"

namespace {

constexpr double kStrainLimit = 0.01;      // about the limit of fused silica
constexpr double kPositionPromise = 1e-9;  // m: SolverOptions' default accuracy, with margin
constexpr double kAnglePromise = 1e-6;     // rad

struct Case {
  int robot_index = 0;
  pcr::RobotParams<double> robot;
  pcr::PlatformLoad<double> load;
  pcr::JointVector q;
  pcr::ForwardSolution rk4;        // default SolverOptions, cold
  pcr::ForwardSolution reference;  // CVODE at the same q
};

struct PoseError {
  double position = 0.0;  // m
  double angle = 0.0;     // rad
};

PoseError pose_error(const pcr::Pose2<double>& a, const pcr::Pose2<double>& b) {
  return {std::hypot(a.x - b.x, a.y - b.y), std::abs(a.theta - b.theta)};
}

/// The robots: 24 drawn inside the intervals around regular n-limb designs (16 with three limbs,
/// three with two, three with four, two with five); robot 1 carries a platform load.
/// CVODE at rtol 1e-12, with a closer Newton matrix than the default for ill-conditioned
/// (pre-stressed) robots.
pcr::ReferenceOptions reference_options() {
  pcr::ReferenceOptions options;
  options.jacobian_rod_steps = 1024;
  return options;
}

int unjudged_ = 0;  // configurations redrawn because the reference did not converge

std::vector<Case> make_cases() {
  constexpr int kLimbs[] = {3, 3, 2, 3, 4, 3, 5, 3, 3, 2, 3, 4, 3, 3, 5, 3, 3, 2, 3, 4, 3, 3, 3, 3};
  constexpr int kConfigurationsPerRobot = 6;
  std::mt19937_64 rng(20261123);
  std::vector<Case> cases;
  for (int r = 0; r < static_cast<int>(std::size(kLimbs)); ++r) {
    const int n = kLimbs[r];
    const pcr::RobotParams<double> robot =
        pcr::testing::perturbed(pcr::testing::regular_robot(n), rng);
    pcr::PlatformLoad<double> load;
    if (r == 1) {
      load.force = pcr::Vector2<double>(3e-3, -2e-3);
      load.moment = 4e-5;
    }
    // q = s u q_max, u uniform in the box and s log-uniform in [0.01, 1]: from barely to strongly
    // bent rods, the mildly bent ones (strain 0.05% - 0.3%) as often as the others.
    std::uniform_real_distribution<double> unit(-1.0, 1.0), log_scale(std::log(0.01), 0.0);
    int found = 0;
    for (int tries = 0; found < kConfigurationsPerRobot && tries < 200; ++tries) {
      const double s = std::exp(log_scale(rng));
      pcr::JointVector q(n);
      for (int i = 0; i < n; ++i) q(i) = s * unit(rng) * robot.limb(i).q_max;
      Case c{r, robot, load, q, pcr::forward_kinematics(robot, q, pcr::SolverOptions(), load), {}};
      if (!c.rk4.summary.converged() || c.rk4.summary.max_strain > kStrainLimit) continue;
      c.reference = pcr::forward_kinematics_reference(robot, q, c.rk4, reference_options(), load);
      // A reference that cannot reach its own tolerance (CVODE's floor on a strongly
      // pre-stressed, ill-conditioned robot) cannot judge the RK4 answer: draw another.
      if (!c.reference.summary.converged()) {
        ++unjudged_;
        continue;
      }
      cases.push_back(c);
      ++found;
    }
  }
  return cases;
}

class ReferenceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { cases_ = new std::vector<Case>(make_cases()); }
  static void TearDownTestSuite() { delete cases_; }
  static std::vector<Case>* cases_;
};

std::vector<Case>* ReferenceTest::cases_ = nullptr;

TEST_F(ReferenceTest, EveryRobotIsSampledAcrossItsWorkspace) {
  int robots_seen[32] = {};
  double max_strain = 0.0;
  int mild = 0;
  for (const Case& c : *cases_) {
    ++robots_seen[c.robot_index];
    max_strain = std::max(max_strain, c.rk4.summary.max_strain);
    if (c.rk4.summary.max_strain > 5e-4 && c.rk4.summary.max_strain < 3e-3) ++mild;
  }
  for (int r = 0; r < 24; ++r) EXPECT_GE(robots_seen[r], 3) << "robot " << r;
  EXPECT_GT(max_strain, 0.005);
  EXPECT_GE(mild, 20);
  EXPECT_LE(unjudged_, 6);
  std::printf(
      "[ reference ] %zu configurations of 24 robots, %d mildly bent (0.05%%-0.3%%), "
      "max strain %.3f%%; %d redrawn (CVODE reference not converged)\n",
      cases_->size(), mild, 100 * max_strain, unjudged_);
}

TEST_F(ReferenceTest, CvodeSolutionsConvergeAndAreTolerancesIndependent) {
  pcr::ReferenceOptions tighter = reference_options();
  tighter.relative_tolerance = 1e-13;
  PoseError worst;
  // On the robots of up to three limbs: the pre-stressed redundant ones can be ill-conditioned
  // enough for CVODE's floor at rtol 1e-13 to stay above the reference's tolerance.
  for (std::size_t k = 0; k < cases_->size(); k += 3) {
    const Case& c = (*cases_)[k];
    if (c.robot.num_limbs > 3) continue;
    ASSERT_TRUE(c.reference.summary.converged())
        << "robot " << c.robot_index << " q " << c.q.transpose() << " status "
        << pcr::to_string(c.reference.summary.status);
    // The CVODE residual, evaluated here at the returned point.
    pcr::ShootingPoint<double> point;
    for (int i = 0; i < c.robot.num_limbs; ++i) {
      point.q[i] = c.q(i);
      point.wrenches[i] = c.reference.wrenches[i];
    }
    point.pose = c.reference.pose;
    pcr::ResidualVector<double> r;
    pcr::shooting_residual_reference(c.robot, point, c.load, pcr::shooting_scale(c.robot), r);
    EXPECT_LE(r.lpNorm<Eigen::Infinity>(), 1e-10);
    // The reference's own error: ten times tighter CVODE tolerances barely move the pose.
    const pcr::ForwardSolution tight =
        pcr::forward_kinematics_reference(c.robot, c.q, c.reference, tighter, c.load);
    ASSERT_TRUE(tight.summary.converged());
    const PoseError e = pose_error(tight.pose, c.reference.pose);
    worst.position = std::max(worst.position, e.position);
    worst.angle = std::max(worst.angle, e.angle);
  }
  EXPECT_LE(worst.position, 1e-12);
  EXPECT_LE(worst.angle, 1e-10);
  std::printf("[ reference ] rtol 1e-12 -> 1e-13 moves the CVODE pose by %.2e m, %.2e rad\n",
              worst.position, worst.angle);
}

TEST_F(ReferenceTest, DefaultForwardKinematicsIsWithinOneNanometreAndOneMicroradian) {
  PoseError worst;
  const Case* worst_case = nullptr;
  int max_steps = 0;
  for (const Case& c : *cases_) {
    ASSERT_TRUE(c.reference.summary.converged())
        << "robot " << c.robot_index << " q " << c.q.transpose() << " "
        << pcr::to_string(c.reference.summary.status) << " strain " << c.rk4.summary.max_strain
        << " residual " << c.reference.summary.final_residual_norm << " from "
        << c.reference.summary.initial_residual_norm;
    const PoseError e = pose_error(c.rk4.pose, c.reference.pose);
    EXPECT_LE(e.position, kPositionPromise)
        << "robot " << c.robot_index << " q " << c.q.transpose() << " strain "
        << c.rk4.summary.max_strain << " steps " << c.rk4.summary.rod_steps;
    EXPECT_LE(e.angle, kAnglePromise) << "robot " << c.robot_index << " q " << c.q.transpose();
    if (e.position > worst.position) worst_case = &c;
    worst.position = std::max(worst.position, e.position);
    worst.angle = std::max(worst.angle, e.angle);
    max_steps = std::max(max_steps, c.rk4.summary.rod_steps);
  }
  ASSERT_NE(worst_case, nullptr);
  std::printf(
      "[ reference ] default FK: worst %.3e m, %.3e rad (up to %d RK4 steps); worst "
      "position on robot %d (n = %d), strain %.3f%%, %d steps, estimate %.2e m\n",
      worst.position, worst.angle, max_steps, worst_case->robot_index, worst_case->robot.num_limbs,
      100 * worst_case->rk4.summary.max_strain, worst_case->rk4.summary.rod_steps,
      worst_case->rk4.summary.position_error_estimate);
}

TEST_F(ReferenceTest, DefaultInverseKinematicsIsWithinOneNanometre) {
  // The exact joints of the CVODE pose are the q it was solved at. IK is square for n <= 3
  // (n = 2: x and y imposed, theta solved). Cold IK may land on another branch (with two limbs
  // more than one theta meets x and y): those poses are solved again from the FK solution, as a
  // user with a nearby solution would, and counted.
  // Accuracy, not stability: IK stays on the branch it converges on (the configurations are drawn
  // across the stroke box, stable or not).
  pcr::SolverOptions options;
  options.stable_inverse = false;
  double worst = 0.0;
  const Case* worst_case = nullptr;
  int solved = 0, other_branch = 0;
  for (const Case& c : *cases_) {
    if (c.robot.num_limbs > 3) continue;
    pcr::InverseSolution ik = pcr::inverse_kinematics(c.robot, c.reference.pose, options, c.load);
    if (pcr::usable_as_warm_start(ik.summary) && (ik.q - c.q).cwiseAbs().maxCoeff() > 1e-6) {
      ++other_branch;
      ik = pcr::inverse_kinematics(c.robot, c.reference.pose, pcr::as_inverse_warm_start(c.rk4),
                                   options, c.load);
    }
    ASSERT_TRUE(pcr::usable_as_warm_start(ik.summary))
        << "robot " << c.robot_index << " q " << c.q.transpose() << " "
        << pcr::to_string(ik.summary.status);
    ++solved;
    const double e = (ik.q - c.q).cwiseAbs().maxCoeff();
    EXPECT_LE(e, kPositionPromise) << "robot " << c.robot_index << " q " << c.q.transpose()
                                   << " steps " << ik.summary.rod_steps;
    if (e > worst) worst_case = &c;
    worst = std::max(worst, e);
  }
  EXPECT_GE(solved, 100);
  EXPECT_LE(other_branch, 5);
  ASSERT_NE(worst_case, nullptr);
  std::printf(
      "[ reference ] default IK (%d poses, %d of them cold on another branch): worst "
      "joint error %.3e m, on robot %d (n = %d)\n",
      solved, other_branch, worst, worst_case->robot_index, worst_case->robot.num_limbs);
}

TEST_F(ReferenceTest, ErrorFallsSixteenfoldPerDoubling) {
  // The most strongly bent configuration: its error is far above CVODE's floor at 16 and 32 steps.
  const Case& c =
      *std::max_element(cases_->begin(), cases_->end(), [](const Case& a, const Case& b) {
        return a.rk4.summary.max_strain < b.rk4.summary.max_strain;
      });
  PoseError e[2];
  for (int k = 0; k < 2; ++k) {
    pcr::SolverOptions options;
    options.rod_steps = 16 << k;
    const pcr::ForwardSolution fk = pcr::forward_kinematics(c.robot, c.q, c.rk4, options, c.load);
    ASSERT_TRUE(fk.summary.converged());
    e[k] = pose_error(fk.pose, c.reference.pose);
  }
  ASSERT_GT(e[1].position, 1e-11);  // well above the reference's own error
  const double position_ratio = e[0].position / e[1].position;
  const double angle_ratio = e[0].angle / e[1].angle;
  std::printf(
      "[ reference ] strain %.4f%%: 16 -> 32 steps, error ratio %.2f (position), "
      "%.2f (angle)\n",
      100 * c.rk4.summary.max_strain, position_ratio, angle_ratio);
  EXPECT_GT(position_ratio, 10.0);
  EXPECT_LT(position_ratio, 22.0);
  EXPECT_GT(angle_ratio, 10.0);
  EXPECT_LT(angle_ratio, 22.0);
}

TEST(ReferenceFk, AgreesWithFineRk4UnderPlatformLoad) {
  // With an external load on the platform the reference and a fine RK4 converge to the same
  // equilibrium: both are consistent discretisations of one ODE boundary-value problem.
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  pcr::PlatformLoad<double> load;
  load.force = pcr::Vector2<double>(0.02, -0.01);
  load.moment = 2e-4;
  pcr::JointVector q(3);
  q << 0.004, -0.002, 0.001;
  pcr::SolverOptions fine;
  fine.rod_steps = 1024;
  const pcr::ForwardSolution rk4 = pcr::forward_kinematics(robot, q, fine, load);
  ASSERT_TRUE(rk4.summary.converged());
  const pcr::ForwardSolution ref = pcr::forward_kinematics_reference(robot, q, rk4, {}, load);
  ASSERT_TRUE(ref.summary.converged());
  const PoseError e = pose_error(rk4.pose, ref.pose);
  EXPECT_LE(e.position, 1e-12);
  EXPECT_LE(e.angle, 1e-10);
  // The load moved the platform: the test is not trivially passed by the unloaded pose.
  const pcr::ForwardSolution unloaded = pcr::forward_kinematics(robot, q, fine);
  EXPECT_GT(pose_error(unloaded.pose, ref.pose).position, 1e-6);
}

TEST(ReferenceFk, ColdSolveFindsStronglyBentSolutionsNearAFold) {
  // Cold FK to these joints ends, after a continuation from home at the coarse step count of the
  // straight rods, at a 1.35% bending strain whose step count (192) is too far from the coarse
  // one for a single Newton solve: the solver ramps the count up rung by rung. The answer is the
  // one CVODE gives, to the default accuracy.
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  pcr::JointVector q(3);
  q << -0.0034541402081974151, -0.010240264538673199, 0.0070414799077143488;
  const pcr::ForwardSolution rk4 = pcr::forward_kinematics(robot, q);
  ASSERT_TRUE(rk4.summary.converged()) << pcr::to_string(rk4.summary.status);
  EXPECT_GT(rk4.summary.max_strain, kStrainLimit);
  EXPECT_GT(rk4.summary.continuation_steps, 0);
  const pcr::ForwardSolution ref = pcr::forward_kinematics_reference(robot, q, rk4);
  ASSERT_TRUE(ref.summary.converged());
  const PoseError e = pose_error(rk4.pose, ref.pose);
  EXPECT_LE(e.position, kPositionPromise);
  EXPECT_LE(e.angle, kAnglePromise);
}

TEST(ReferenceFk, AStepBudgetShortOfTheTargetsIsReportedInaccurate) {
  // Too few RK4 steps allowed (max_rod_steps) for the targets: the solve converges on its model
  // and says the answer is kInaccurate; CVODE confirms it is off by more than the targets, by
  // about what the estimate says.
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  pcr::JointVector q(3);
  q << 0.004, -0.002, 0.001;
  for (const int budget : {4, 8}) {
    pcr::SolverOptions options;
    options.min_rod_steps = options.max_rod_steps = budget;
    const pcr::ForwardSolution rk4 = pcr::forward_kinematics(robot, q, options);
    ASSERT_EQ(rk4.summary.status, pcr::SolveStatus::kInaccurate) << budget << " steps";
    const pcr::ForwardSolution ref = pcr::forward_kinematics_reference(robot, q, rk4);
    ASSERT_TRUE(ref.summary.converged());
    const PoseError e = pose_error(rk4.pose, ref.pose);
    EXPECT_GT(std::max(e.position / options.position_accuracy, e.angle / options.angle_accuracy),
              1.0)
        << budget << " steps";
    EXPECT_LT(e.position, 2 * rk4.summary.position_error_estimate) << budget << " steps";
    EXPECT_GT(e.position, 0.5 * rk4.summary.position_error_estimate) << budget << " steps";
    std::printf(
        "[ reference ] %d RK4 steps: %s, %.2e m, %.2e rad from CVODE; estimated %.2e m, "
        "%.2e rad\n",
        budget, pcr::to_string(rk4.summary.status), e.position, e.angle,
        rk4.summary.position_error_estimate, rk4.summary.angle_error_estimate);
  }
  EXPECT_TRUE(pcr::forward_kinematics(robot, q).summary.converged());
}

TEST(ReferenceFk, RejectsWrongSizes) {
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  const pcr::ForwardSolution home = pcr::home_solution(robot);
  EXPECT_THROW(pcr::forward_kinematics_reference(robot, pcr::JointVector::Zero(2), home),
               std::invalid_argument);
}

}  // namespace
