// Slices through the spatial robot's workspace (pcr/spatial/workspace_map.hpp) on the reference
// continuum Stewart-Gough robot: each reachable point's joints checked by a cold FK from straight
// rods (which knows nothing of the IK), the same map on 1 and 2 threads, points beyond the rods'
// reach unreachable, bad options refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "pcr/input_error.hpp"
#include "pcr/spatial/workspace_map.hpp"

namespace pcr {
namespace {

bool same_value(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

/// A fixed step count: the map's IK and the checking FK solve the same discrete model, so they
/// agree to Newton's convergence, not to RK4's error.
SolverOptions fixed_steps() {
  SolverOptions o;
  o.rod_steps = 96;
  return o;
}

/// The worst disagreement (m, rad) between each reachable point's pose and a cold FK at its joints.
void expect_points_are_their_joints_equilibria(const SpatialRobotParams<double>& robot,
                                               const SpatialWorkspaceMap& map, const char* what) {
  double position = 0, angle = 0;
  int checked = 0;
  for (const SpatialWorkspaceMapPoint& p : map.points) {
    if (!p.reachable) continue;
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, p.q, fixed_steps());
    ASSERT_TRUE(fk.summary.converged()) << what << " (" << p.u << ", " << p.v << ")";
    const SpatialPoseCoordinates at = spatial_pose_coordinates(fk.pose);
    for (int c = 0; c < 3; ++c) position = std::max(position, std::abs(at[c] - p.pose[c]));
    for (int c = 3; c < 6; ++c) angle = std::max(angle, std::abs(at[c] - p.pose[c]));
    ++checked;
  }
  std::printf("%s: %d reachable points; FK of their joints within %.2e m, %.2e rad\n", what,
              checked, position, angle);
  EXPECT_GT(checked, 0);
  EXPECT_LT(position, 1e-9) << what;
  EXPECT_LT(angle, 1e-9) << what;
}

TEST(SpatialWorkspaceMap, ReachablePointsAreEquilibriaOfTheirJoints) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialWorkspaceMapOptions options;
  options.solver = fixed_steps();
  options.grid = 5;
  // A plane of positions 0.4 m up, tilted 0.1 rad about y.
  options.pose = SpatialPoseCoordinates{0, 0, 0.4, 0, 0.1, 0};
  options.range = std::array<double, 4>{-0.03, 0.03, -0.03, 0.03};
  const SpatialWorkspaceMap positions = spatial_workspace_map(robot, options);
  ASSERT_EQ(positions.points.size(), 25u);
  for (const SpatialWorkspaceMapPoint& p : positions.points) {
    EXPECT_EQ(p.pose[2], 0.4);  // the held coordinates are the pose's
    EXPECT_EQ(p.pose[4], 0.1);
    EXPECT_EQ(p.pose[0], p.u);
    EXPECT_EQ(p.pose[1], p.v);
  }
  expect_points_are_their_joints_equilibria(robot, positions, "x-y plane at z = 0.4 m");
  EXPECT_NEAR(positions.reachable_area, positions.reachable_count * 0.015 * 0.015, 1e-18);

  // Rotation vectors about x and y at that position.
  options.plane = SpatialMapPlane::kRxRy;
  options.range = std::array<double, 4>{-0.2, 0.2, -0.2, 0.2};
  const SpatialWorkspaceMap turns = spatial_workspace_map(robot, options);
  for (const SpatialWorkspaceMapPoint& p : turns.points) {
    EXPECT_EQ(p.pose[3], p.u);
    EXPECT_EQ(p.pose[4], p.v);
    EXPECT_EQ(p.pose[5], 0.0);
  }
  expect_points_are_their_joints_equilibria(robot, turns, "rx-ry slice at (0, 0, 0.4) m");
}

TEST(SpatialWorkspaceMap, IsTheSameWhateverTheNumberOfThreads) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialWorkspaceMapOptions options;
  options.plane = SpatialMapPlane::kXZ;
  options.grid = 6;
  options.range = std::array<double, 4>{-0.05, 0.05, 0.36, 0.44};
  options.stroke = std::array<double, 2>{-0.02, 0.02};
  options.threads = 1;
  const SpatialWorkspaceMap one = spatial_workspace_map(robot, options);
  options.threads = 2;
  const SpatialWorkspaceMap two = spatial_workspace_map(robot, options);
  ASSERT_EQ(one.points.size(), two.points.size());
  std::ostringstream a, b;
  write_spatial_workspace_map_csv(one, a);
  write_spatial_workspace_map_csv(two, b);
  EXPECT_EQ(a.str(), b.str());
  for (std::size_t k = 0; k < one.points.size(); ++k) {
    const SpatialWorkspaceMapPoint &p = one.points[k], &r = two.points[k];
    EXPECT_TRUE(p.visited == r.visited && p.reachable == r.reachable && p.stable == r.stable &&
                p.status == r.status && same_value(p.max_strain, r.max_strain) &&
                same_value(p.stability_margin, r.stability_margin))
        << "point " << k;
    for (int i = 0; i < 6; ++i) EXPECT_TRUE(same_value(p.q(i), r.q(i))) << "point " << k;
  }
  EXPECT_EQ(one.reachable_count, two.reachable_count);
  EXPECT_GT(one.reachable_count, 0);
  EXPECT_LT(one.reachable_count, 36);  // the stroke cuts the slice
}

// Inextensible rods of free length at most L + q_max, clamped vertically at the base and to an
// untilted platform whose attachments lie in its plane z = 0: the platform's height is a rod tip's,
// at most L + q_max above the base. Points higher are out of reach whatever the solver does.
TEST(SpatialWorkspaceMap, PointsBeyondTheRodsReachAreUnreachable) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialWorkspaceMapOptions options;
  options.plane = SpatialMapPlane::kXZ;
  options.grid = 5;
  options.stroke = std::array<double, 2>{-0.01, 0.01};
  options.pose = SpatialPoseCoordinates{0, 0, 0.4, 0, 0, 0};
  options.range = std::array<double, 4>{-0.02, 0.02, 0.38, 0.46};  // z in 20 mm steps
  const SpatialWorkspaceMap map = spatial_workspace_map(robot, options);
  const double reach = robot.limb(0).rod.length + 0.01;
  int beyond = 0;
  for (const SpatialWorkspaceMapPoint& p : map.points) {
    if (p.pose[2] <= reach) continue;
    ++beyond;
    EXPECT_FALSE(p.reachable) << "z = " << p.pose[2] << ": q " << p.q.transpose();
    // An equilibrium there, if IK found one, has a rod at least as long as the height: a joint
    // past the stroke.
    if (std::isfinite(p.q(0))) {
      EXPECT_GE(robot.limb(0).rod.length + p.q.maxCoeff(), p.pose[2]);
      EXPECT_EQ(p.status, SolveStatus::kOutOfRange);
    }
  }
  EXPECT_EQ(beyond, 15);  // z = 0.42, 0.44 and 0.46 m
  // On the axis at 0.4 m, within the stroke (equal joints of 5.3 mm hold it there): reachable.
  const SpatialWorkspaceMapPoint& centre = map.points[static_cast<std::size_t>(1 * 5 + 2)];
  EXPECT_EQ(centre.pose[2], 0.4);
  EXPECT_TRUE(centre.reachable && centre.stable);
  EXPECT_EQ(centre.status, SolveStatus::kConverged);
}

TEST(SpatialWorkspaceMap, WritesOneRowPerPointAndRefusesBadOptions) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialWorkspaceMapOptions options;
  options.grid = 3;
  options.range = std::array<double, 4>{-0.001, 0.001, -0.001, 0.001};
  const SpatialWorkspaceMap map = spatial_workspace_map(robot, options);
  std::ostringstream out;
  write_spatial_workspace_map_csv(map, out);
  const std::string text = out.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10);  // a header and 9 rows
  EXPECT_EQ(text.rfind("u,v,x,y,z,rx,ry,rz,reachable,stable,status,q1,q2,q3,q4,q5,q6,max_strain,"
                       "stability_margin,singularity\n",
                       0),
            0u);
  EXPECT_EQ(map.reachable_count, 9);
  // By default the slice goes through the home pose (FK at q = 0).
  const SpatialForwardSolution home =
      spatial_forward_kinematics(robot, SpatialJointVector::Zero(6));
  EXPECT_EQ(map.pose[2], home.pose.position.z());

  const auto refused = [&](const SpatialWorkspaceMapOptions& o, const SpatialRobotParams<double>& r,
                           const std::string& fragment) {
    try {
      spatial_workspace_map(r, o);
      ADD_FAILURE() << "accepted; expected '" << fragment << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  SpatialWorkspaceMapOptions o = options;
  o.grid = 1;
  refused(o, robot, "grid: expected a number from 2 to 500, got 1");
  o = options;
  o.range = std::array<double, 4>{0.001, -0.001, -0.001, 0.001};
  refused(o, robot, "range: expected x_min < x_max and y_min < y_max for the plane xy");
  o.plane = SpatialMapPlane::kRxRz;
  o.range = std::array<double, 4>{-0.1, 0.1, -7, 0.1};
  refused(o, robot, "range.rz_min: expected a number from -6.28");
  o = options;
  o.pose = SpatialPoseCoordinates{0, 0, NAN, 0, 0, 0};
  refused(o, robot, "pose.z: expected a number from -1 to 1 (m), got nan");
  o = options;
  o.stroke = std::array<double, 2>{0.01, -0.01};
  refused(o, robot, "stroke: expected q_min <= q_max (m), got 0.01,-0.01");
  SpatialRobotParams<double> five = robot;
  five.num_rods = 5;
  refused(options, five, "maps robots of 6 rods, whose IK imposes the whole pose; the robot has 5");
}

}  // namespace
}  // namespace pcr
