// RK4 forward kinematics against the CVODE reference on the default robot: the discretisation
// error of the default step count stays below 1 nm / 1 urad for bending strains up to 1%, and
// falls about 16x per doubling of the step count (fourth order).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "pcr/kinematics.hpp"
#include "pcr/reference.hpp"
#include "pcr/robot.hpp"

namespace {

constexpr double kStrainLimit = 0.01;  // about the limit of fused silica
constexpr int kStepCounts[] = {16, 32, 64, 128};

struct Sample {
  pcr::JointVector q;
  pcr::ForwardSolution rk4;        // default SolverOptions
  pcr::ForwardSolution reference;  // CVODE
};

bool acceptable(const pcr::ForwardSolution& fk) {
  return fk.summary.converged() && fk.summary.max_strain <= kStrainLimit;
}

/// Walks q = t * direction from `from` (at t_from) to t_to in `segments` warm-started solves
/// without continuation (a failed solve stays cheap). Returns the last acceptable solution and
/// its t; `complete` tells whether t_to was reached.
struct Walk {
  pcr::ForwardSolution last;
  double t = 0.0;
  bool complete = false;
};

Walk walk(const pcr::RobotParams<double>& robot, const pcr::JointVector& direction,
          const pcr::ForwardSolution& from, double t_from, double t_to, int segments) {
  pcr::SolverOptions options;
  options.continuation = false;
  Walk w{from, t_from, false};
  for (int k = 1; k <= segments; ++k) {
    const double t = t_from + (t_to - t_from) * k / segments;
    const pcr::JointVector q = t * direction;
    pcr::ForwardSolution fk = pcr::forward_kinematics(robot, q, w.last, options);
    if (!acceptable(fk)) return w;
    w.last = fk;
    w.t = t;
  }
  w.complete = true;
  return w;
}

/// Walks the pose p = t * direction from `from` (at t_from) to t_to by warm-started IK without
/// continuation; the same contract as walk().
struct PoseWalk {
  pcr::InverseSolution last;
  double t = 0.0;
  bool complete = false;
};

PoseWalk walk_pose(const pcr::RobotParams<double>& robot, const pcr::Pose2<double>& direction,
                   const pcr::InverseSolution& from, double t_from, double t_to, int segments) {
  pcr::SolverOptions options;
  options.continuation = false;
  PoseWalk w{from, t_from, false};
  for (int k = 1; k <= segments; ++k) {
    const double t = t_from + (t_to - t_from) * k / segments;
    const pcr::Pose2<double> pose{t * direction.x, t * direction.y, t * direction.theta};
    pcr::InverseSolution ik = pcr::inverse_kinematics(robot, pose, w.last, options);
    // Converged also means q inside the stroke box (kOutOfRange otherwise).
    if (!ik.summary.converged() || ik.summary.max_strain > kStrainLimit) return w;
    w.last = ik;
    w.t = t;
  }
  w.complete = true;
  return w;
}

/// 40 reachable configurations of the stroke box: 28 uniform draws of q reached from home with a
/// strain within the limit all along the way, and 12 at a strain just below the limit. The
/// strongly bent ones come from IK along pose rays: with the default robot, strains near 1%
/// arise when the platform turns by about -0.2 rad, which uniform draws of q rarely reach.
std::vector<Sample> make_samples(const pcr::RobotParams<double>& robot) {
  std::mt19937 rng(20240521);
  const int n = robot.num_limbs;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const pcr::ForwardSolution home = pcr::home_solution(robot);
  std::vector<Sample> samples;
  for (int tries = 0; samples.size() < 28 && tries < 1000; ++tries) {
    pcr::JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = unit(rng) * robot.limb(i).q_max;
    const Walk w = walk(robot, q, home, 0.0, 1.0, 8);
    if (w.complete) samples.push_back({q, w.last, {}});
  }
  const pcr::InverseSolution ik_home = pcr::as_inverse_warm_start(home);
  int strong = 0;
  for (int tries = 0; strong < 12 && tries < 200; ++tries) {
    const pcr::Pose2<double> direction{0.006 * unit(rng), 0.006 * unit(rng),
                                       -0.25 + 0.1 * unit(rng)};
    PoseWalk w = walk_pose(robot, direction, ik_home, 0.0, 2.0, 32);
    if (w.complete) continue;
    // Bisection on t between the last acceptable pose and the first that is not.
    double hi = w.t + 2.0 / 32;
    for (int it = 0; it < 12; ++it) {
      const double mid = 0.5 * (w.t + hi);
      const PoseWalk step = walk_pose(robot, direction, w.last, w.t, mid, 1);
      if (step.complete) {
        w = step;
      } else {
        hi = mid;
      }
    }
    if (w.last.summary.max_strain <= 0.95 * kStrainLimit) continue;  // stopped by the stroke
    // The forward solution at those joint values, from the IK solution (same unknowns).
    pcr::ForwardSolution warm;
    warm.q = w.last.q;
    warm.pose = w.last.pose;
    warm.wrenches = w.last.wrenches;
    const pcr::ForwardSolution fk = pcr::forward_kinematics(robot, w.last.q, warm);
    if (acceptable(fk)) {
      samples.push_back({w.last.q, fk, {}});
      ++strong;
    }
  }
  for (Sample& s : samples) s.reference = pcr::forward_kinematics_reference(robot, s.q, s.rk4);
  return samples;
}

struct PoseError {
  double position = 0.0;  // m
  double angle = 0.0;     // rad
};

PoseError pose_error(const pcr::Pose2<double>& a, const pcr::Pose2<double>& b) {
  return {std::hypot(a.x - b.x, a.y - b.y), std::abs(a.theta - b.theta)};
}

class ReferenceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    robot_ = new pcr::RobotParams<double>(pcr::femto_3pf());
    samples_ = new std::vector<Sample>(make_samples(*robot_));
  }
  static void TearDownTestSuite() {
    delete samples_;
    delete robot_;
  }
  static pcr::RobotParams<double>* robot_;
  static std::vector<Sample>* samples_;
};

pcr::RobotParams<double>* ReferenceTest::robot_ = nullptr;
std::vector<Sample>* ReferenceTest::samples_ = nullptr;

TEST_F(ReferenceTest, SampleCoversStrainsUpToTheLimit) {
  ASSERT_EQ(samples_->size(), 40u);
  double max_strain = 0.0;
  int near_limit = 0;
  for (const Sample& s : *samples_) {
    max_strain = std::max(max_strain, s.rk4.summary.max_strain);
    if (s.rk4.summary.max_strain > 0.95 * kStrainLimit) ++near_limit;
  }
  EXPECT_GT(max_strain, 0.95 * kStrainLimit);
  EXPECT_LE(max_strain, kStrainLimit);
  EXPECT_GE(near_limit, 10);
  std::printf("[ reference ] %zu configurations, max bending strain %.4f%% (curvature %.1f 1/m)\n",
              samples_->size(), 100 * max_strain,
              2 * max_strain / robot_->limb(0).diameter);
}

TEST_F(ReferenceTest, CvodeSolutionsConvergeAndAreTolerancesIndependent) {
  pcr::ReferenceOptions tighter;
  tighter.relative_tolerance = 1e-13;
  double worst_position = 0.0, worst_angle = 0.0;
  for (const Sample& s : *samples_) {
    ASSERT_TRUE(s.reference.summary.converged())
        << "q " << s.q.transpose() << " status " << pcr::to_string(s.reference.summary.status)
        << " residual " << s.reference.summary.final_residual_norm;
    // The CVODE residual, evaluated here at the returned point.
    pcr::ShootingPoint<double> point;
    for (int i = 0; i < robot_->num_limbs; ++i) {
      point.q[i] = s.q(i);
      point.wrenches[i] = s.reference.wrenches[i];
    }
    point.pose = s.reference.pose;
    pcr::ResidualVector<double> r;
    pcr::shooting_residual_reference(*robot_, point, {}, pcr::shooting_scale(*robot_), r);
    EXPECT_LE(r.lpNorm<Eigen::Infinity>(), 1e-10);
    // The reference's own error: ten times tighter CVODE tolerances barely move the pose.
    const pcr::ForwardSolution tight =
        pcr::forward_kinematics_reference(*robot_, s.q, s.reference, tighter);
    ASSERT_TRUE(tight.summary.converged());
    const PoseError e = pose_error(tight.pose, s.reference.pose);
    worst_position = std::max(worst_position, e.position);
    worst_angle = std::max(worst_angle, e.angle);
  }
  EXPECT_LE(worst_position, 1e-12);
  EXPECT_LE(worst_angle, 1e-10);
  std::printf("[ reference ] rtol 1e-12 -> 1e-13 moves the CVODE pose by %.2e m, %.2e rad\n",
              worst_position, worst_angle);
}

TEST_F(ReferenceTest, DefaultOptionsAreWithinOneNanometreAndOneMicroradian) {
  // s.rk4 was solved with the default SolverOptions (whatever their step-count policy).
  PoseError worst_default;
  int max_default_steps = 0;
  for (const Sample& s : *samples_) {
    ASSERT_TRUE(s.reference.summary.converged());
    const PoseError e = pose_error(s.rk4.pose, s.reference.pose);
    EXPECT_LE(e.position, 1e-9) << "q " << s.q.transpose() << " strain " << s.rk4.summary.max_strain;
    EXPECT_LE(e.angle, 1e-6) << "q " << s.q.transpose() << " strain " << s.rk4.summary.max_strain;
    worst_default.position = std::max(worst_default.position, e.position);
    worst_default.angle = std::max(worst_default.angle, e.angle);
    max_default_steps = std::max(max_default_steps, s.rk4.summary.rod_steps);
  }
  std::printf("[ reference ] default options (up to %d RK4 steps): max pose error %.3e m, "
              "%.3e rad\n", max_default_steps, worst_default.position, worst_default.angle);
}

TEST_F(ReferenceTest, ErrorPerFixedStepCount) {
  // Measured for the record (the choice of the default step policy); asserts convergence only,
  // and that the error decreases with the step count.
  PoseError worst[4];
  for (const Sample& s : *samples_) {
    for (int k = 0; k < 4; ++k) {
      pcr::SolverOptions options;
      options.rod_steps = kStepCounts[k];
      const pcr::ForwardSolution fk = pcr::forward_kinematics(*robot_, s.q, s.rk4, options);
      ASSERT_TRUE(fk.summary.converged()) << kStepCounts[k] << " steps, q " << s.q.transpose();
      const PoseError e = pose_error(fk.pose, s.reference.pose);
      worst[k].position = std::max(worst[k].position, e.position);
      worst[k].angle = std::max(worst[k].angle, e.angle);
    }
  }
  for (int k = 0; k < 4; ++k) {
    std::printf("[ reference ] %3d RK4 steps: max pose error %.3e m, %.3e rad\n", kStepCounts[k],
                worst[k].position, worst[k].angle);
    if (k > 0) {
      EXPECT_LT(worst[k].position, worst[k - 1].position / 8);
      EXPECT_LT(worst[k].angle, worst[k - 1].angle / 8);
    }
  }
}

TEST_F(ReferenceTest, ErrorFallsSixteenfoldPerDoubling) {
  // The most strongly bent configuration: its error is far above CVODE's floor at 16 and 32 steps.
  const Sample& s = *std::max_element(
      samples_->begin(), samples_->end(), [](const Sample& a, const Sample& b) {
        return a.rk4.summary.max_strain < b.rk4.summary.max_strain;
      });
  PoseError e[2];
  for (int k = 0; k < 2; ++k) {
    pcr::SolverOptions options;
    options.rod_steps = kStepCounts[k];
    const pcr::ForwardSolution fk = pcr::forward_kinematics(*robot_, s.q, s.rk4, options);
    ASSERT_TRUE(fk.summary.converged());
    e[k] = pose_error(fk.pose, s.reference.pose);
  }
  ASSERT_GT(e[1].position, 1e-12);  // well above the reference's own error
  const double position_ratio = e[0].position / e[1].position;
  const double angle_ratio = e[0].angle / e[1].angle;
  std::printf("[ reference ] strain %.4f%%: 16 -> 32 steps, error ratio %.2f (position), "
              "%.2f (angle)\n", 100 * s.rk4.summary.max_strain, position_ratio, angle_ratio);
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
  EXPECT_LE(e.position, 1e-9);
  EXPECT_LE(e.angle, 1e-6);
}

TEST(ReferenceFk, RejectsWrongSizes) {
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  const pcr::ForwardSolution home = pcr::home_solution(robot);
  EXPECT_THROW(pcr::forward_kinematics_reference(robot, pcr::JointVector::Zero(2), home),
               std::invalid_argument);
}

}  // namespace
