// The embedded controller (pcr/controller.hpp): a 1 kHz loop following the circle by warm-started
// IK never allocates, never throws, and its joints put the platform on the commanded poses (checked
// by forward kinematics, an independent solve).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <vector>

#include "allocation_counter.hpp"
#include "pcr/controller.hpp"

namespace pcr {
namespace {

constexpr double kTick = 1e-3;  // 1 kHz

static_assert(noexcept(std::declval<PathFollower<CirclePath>&>().step(0.0)),
              "a control tick must not throw");
static_assert(noexcept(path_ik_step(std::declval<const RobotParams<double>&>(),
                                    std::declval<const Pose2<double>&>(),
                                    std::declval<const InverseSolution&>(),
                                    std::declval<const PathStepOptions&>())),
              "an IK step must not throw");

TEST(Controller, FollowsTheCircleWithoutAllocatingAndReachesEveryPose) {
  const RobotParams<double> robot = femto_3pf();
  const CirclePath circle;    // the paper's: diameter 3 mm, theta = 0
  const double period = 1.0;  // s per turn: 1000 ticks
  const int ticks = static_cast<int>(std::lround(period / kTick));
  std::vector<ControllerTick> log(static_cast<std::size_t>(ticks) + 1);  // allocated beforehand

  g_allocations = 0;
  g_counting = true;
  PathFollower<CirclePath> follower(robot, circle, period);
  for (int k = 0; k <= ticks; ++k) log[static_cast<std::size_t>(k)] = follower.step(k * kTick);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  ASSERT_TRUE(follower.ready());

  // The loop closes: the last tick is the first pose again.
  EXPECT_NEAR(log.back().desired.x, log.front().desired.x, 1e-15);
  EXPECT_NEAR(log.back().desired.y, log.front().desired.y, 1e-15);

  ForwardSolution fk = home_solution(robot);
  double worst = 0;
  for (const ControllerTick& tick : log) {
    ASSERT_TRUE(tick.ok()) << "t = " << tick.time << ": " << to_string(tick.status);
    // The desired pose is on the circle (closed form).
    EXPECT_NEAR(std::hypot(tick.desired.x, tick.desired.y), 1.5e-3, 1e-15);
    EXPECT_EQ(tick.desired.theta, 0.0);
    fk = forward_kinematics(robot, tick.q, fk);
    ASSERT_TRUE(fk.summary.converged()) << tick.time;
    worst = std::max(worst, std::hypot(fk.pose.x - tick.desired.x, fk.pose.y - tick.desired.y));
    EXPECT_NEAR(fk.pose.theta, 0.0, 1e-6);  // IK and FK each within the default 1 urad
    for (int i = 0; i < robot.num_limbs; ++i) {
      EXPECT_GE(tick.q(i), robot.limb(i).q_min);
      EXPECT_LE(tick.q(i), robot.limb(i).q_max);
    }
  }
  EXPECT_LT(worst, 1e-9);
}

/// Home for the first half of every period, then a pose far outside the workspace.
struct JumpPath {
  Pose2<double> at(double fraction) const noexcept {
    const double f = fraction - std::floor(fraction);
    return f < 0.5 ? Pose2<double>{0.2e-3, 0, 0} : Pose2<double>{40e-3, 0, 0};
  }
};

TEST(Controller, UnreachablePosesHoldTheLastJointsAndRecover) {
  const RobotParams<double> robot = femto_3pf();
  g_allocations = 0;
  g_counting = true;
  PathFollower<JumpPath> follower(robot, JumpPath(), 1.0);
  const ControllerTick good = follower.step(0.1);
  const ControllerTick bad = follower.step(0.6);
  const ControllerTick again = follower.step(1.1);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  ASSERT_TRUE(good.ok());
  EXPECT_FALSE(bad.ok());
  for (int i = 0; i < robot.num_limbs; ++i) EXPECT_EQ(bad.q(i), good.q(i));
  EXPECT_TRUE(again.ok());

  // A path whose start is out of reach: not ready, every tick reports it, nothing thrown.
  SquarePath huge;
  huge.side = 80e-3;
  PathFollower<SquarePath> lost(robot, huge, 1.0);
  EXPECT_FALSE(lost.ready());
  const ControllerTick tick = lost.step(0.0);
  EXPECT_FALSE(tick.ok());
  EXPECT_EQ(tick.q.size(), robot.num_limbs);
}

TEST(Controller, StrainLimitIsEnforcedPerTick) {
  const RobotParams<double> robot = femto_3pf();
  PathStepOptions options;
  options.strain_limit = 1e-7;  // the 3 mm circle bends the rods far more than this
  PathFollower<CirclePath> follower(robot, CirclePath(), 1.0, options);
  EXPECT_FALSE(follower.ready());
  EXPECT_EQ(follower.step(0.0).status, PathPoseStatus::kStrainExceeded);
}

}  // namespace
}  // namespace pcr
