// Spatial FK and IK through folds by pseudo-arclength continuation (pcr/spatial/arclength.hpp),
// against independent references: every traced point's residual re-evaluated, the fold where the
// joints' path turns back against the sign change of the forward Jacobian's determinant (an LU of
// the whole matrix) and the stability check's margin, the end point against FK on the CVODE
// residual and against the other branch at the same joints; IK traced along a path without a fold
// against the regular IK.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "pcr/spatial/arclength.hpp"
#include "pcr/spatial/sequence.hpp"
#include "spatial_test_support.hpp"

namespace pcr {
namespace {

/// The reference robot pushed down by 100 N and sideways by 5 N (no symmetry left, so that its
/// loss of stability is a fold, not a bifurcation), its joints raised together: near 59 mm the
/// compressed rods give way and the platform would snap sideways.
SpatialRobotParams<double> loaded_robot() {
  SpatialRobotParams<double> robot = continuum_stewart_gough();
  robot.external_force = Eigen::Vector3d(5.0, 0.0, -100.0);
  return robot;
}

SpatialJointVector raised(double q) { return SpatialJointVector::Constant(6, q); }

/// The stable equilibrium at 30 mm, by warm FK from home in 10 mm steps.
SpatialForwardSolution start_at_30mm(const SpatialRobotParams<double>& robot) {
  SpatialForwardSolution s = spatial_forward_kinematics(robot, raised(0.0));
  for (int k = 1; k <= 3 && s.summary.converged(); ++k) {
    s = spatial_forward_kinematics(robot, raised(0.01 * k), s);
  }
  return s;
}

struct TracedPoint {
  double t, margin, determinant, residual;
  bool stable;
};

// From 30 mm towards 60 mm the stable branch ends at a fold near 59 mm: the trace passes it,
// the joints' path turns back there, and the curve returns on an unstable branch below the start.
TEST(SpatialFolds, ForwardKinematicsIsTracedThroughAFold) {
  const SpatialRobotParams<double> robot = loaded_robot();
  const SpatialForwardSolution start = start_at_30mm(robot);
  ASSERT_TRUE(start.summary.converged());
  ASSERT_EQ(start.summary.stability, Stability::kStable);
  const SpatialJointVector end = raised(0.06);
  const ShootingScale scale = spatial_shooting_scale(robot);
  SolverOptions options;
  std::vector<TracedPoint> points;
  const SpatialForwardSolution traced = spatial_forward_kinematics_through_folds(
      robot, end, start, options, [&](const SpatialForwardSolution& p) {
        ASSERT_NE(p.summary.stability, Stability::kUnchecked);
        // Its joints on the path, its residual and forward Jacobian evaluated anew.
        EXPECT_LT((p.q - (start.q + p.summary.path_fraction * (end - start.q))).norm(), 1e-15);
        SpatialResidualVector<double> r;
        SpatialJacobian J;
        spatial_residual(robot, spatial_shooting_point(robot, p), scale, p.summary.rod_steps, r,
                         &J);
        points.push_back({p.summary.path_fraction, p.summary.stability_margin,
                          J.fullPivLu().determinant(), r.lpNorm<Eigen::Infinity>(),
                          p.summary.stability == Stability::kStable});
      });
  ASSERT_GE(points.size(), 10u);
  double worst = 0;
  for (const TracedPoint& p : points) worst = std::max(worst, p.residual);
  EXPECT_LT(worst, 1e-9);

  // One fold: the path fraction rises to it and falls after it.
  EXPECT_EQ(traced.summary.folds_passed, 1);
  const auto top = std::max_element(points.begin(), points.end(),
                                    [](const auto& a, const auto& b) { return a.t < b.t; });
  const std::size_t peak = static_cast<std::size_t>(top - points.begin());
  ASSERT_GT(peak, 0u);
  ASSERT_LT(peak + 1, points.size());
  for (std::size_t i = 1; i < points.size(); ++i) {
    EXPECT_EQ(points[i].t > points[i - 1].t, i <= peak) << i;
  }
  // Stable up to the fold, unstable after it: one flip, at the step where the determinant changes
  // sign and the margin crosses zero; the first fold reported within that step.
  // (Further on, the unstable branch passes another singular point, where the determinant changes
  // sign again and the margin, already negative, comes near zero.)
  std::size_t flip = 0, first_sign_change = 0;
  int flips = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].stable != points[i - 1].stable) {
      flip = i;
      ++flips;
    }
    if (first_sign_change == 0 && points[i].determinant * points[i - 1].determinant < 0) {
      first_sign_change = i;
    }
  }
  ASSERT_EQ(flips, 1);
  EXPECT_EQ(first_sign_change, flip);
  EXPECT_TRUE(points[flip - 1].stable);
  EXPECT_LT(points[flip - 1].determinant * points[flip].determinant, 0);
  EXPECT_GT(points[flip - 1].margin, 0);
  EXPECT_LT(points[flip].margin, 0);
  const double lo = std::min(points[flip - 1].t, points[flip].t);
  const double hi = std::max(points[flip - 1].t, points[flip].t);
  EXPECT_GE(traced.summary.first_fold, lo);
  EXPECT_LE(traced.summary.first_fold, hi);
  EXPECT_TRUE(flip == peak || flip == peak + 1) << flip << " " << peak;
  const double fold_q = start.q(0) + traced.summary.first_fold * (end(0) - start.q(0));

  // The curve left the path below its start: kSingular at the last point, unstable, an
  // equilibrium of the CVODE residual within RK4's error, and not the stable one that FK continued
  // from the start finds at the same joints.
  EXPECT_EQ(traced.summary.status, SolveStatus::kSingular);
  EXPECT_LT(traced.summary.path_fraction, 0.0);
  EXPECT_FALSE(points.back().stable);
  const testing::ReferenceFk reference =
      testing::reference_forward_kinematics(robot, spatial_shooting_point(robot, traced));
  EXPECT_LT(reference.residual, 1e-9);
  const double to_reference = (reference.x.pose.position - traced.pose.position).norm();
  EXPECT_LT(to_reference, 1e-6);
  const SpatialForwardSolution other = spatial_forward_kinematics(robot, traced.q, start);
  ASSERT_TRUE(other.summary.converged());
  EXPECT_EQ(other.summary.stability, Stability::kStable);
  const double apart = (other.pose.position - traced.pose.position).norm();
  EXPECT_GT(apart, 1e-3);
  std::printf(
      "%zu points, %d fold at %.3f mm (%d residual evaluations), residual <= %.1e; end %.2f mm "
      "below the start on the unstable branch: %.1e m from FK on the CVODE residual, %.1f mm from "
      "the stable one\n",
      points.size(), traced.summary.folds_passed, fold_q * 1e3, traced.summary.residual_evaluations,
      worst, -traced.summary.path_fraction * (end(0) - start.q(0)) * 1e3, to_reference,
      apart * 1e3);

  // Without through_folds the warm solve stops at the fold, its last point short of the furthest
  // point traced.
  const SpatialForwardSolution warm = spatial_forward_kinematics(robot, end, start, options);
  EXPECT_FALSE(usable_as_warm_start(warm.summary)) << to_string(warm.summary.status);
  EXPECT_LT(warm.summary.path_fraction, 1.0);
  EXPECT_LE(warm.q(0), start.q(0) + top->t * (end(0) - start.q(0)));
  EXPECT_GT(warm.q(0), 0.058);
}

// A path sequence follows the curve through the fold when told to (and, the trace not coming back
// to the input, retries cold as without): it spends the trace's evaluations on top.
TEST(SpatialFolds, PathSequenceTracesThroughFoldsWhenTold) {
  const SpatialRobotParams<double> robot = loaded_robot();
  const SpatialForwardSolution start = start_at_30mm(robot);
  ASSERT_TRUE(start.summary.converged());
  const SpatialJointVector end = raised(0.06);
  SolverOptions through;
  through.through_folds = true;
  const SpatialForwardSolution trace =
      spatial_forward_kinematics_through_folds(robot, end, start, through);
  ASSERT_EQ(trace.summary.folds_passed, 1);
  int evaluations[2];
  SpatialPose<double> poses[2];
  for (const bool folds : {false, true}) {
    SolverOptions options;
    options.through_folds = folds;
    SpatialForwardSequence sequence(robot, options, SpatialNoLoad(), SequenceMode::kPath);
    for (int k = 0; k <= 3; ++k) ASSERT_TRUE(sequence.solve(raised(0.01 * k)).summary.converged());
    const SpatialForwardSolution& s = sequence.solve(end);
    evaluations[folds] = s.summary.residual_evaluations;
    poses[folds] = s.pose;
  }
  EXPECT_EQ(evaluations[1], evaluations[0] + trace.summary.residual_evaluations);
  EXPECT_EQ((poses[1].position - poses[0].position).norm(), 0.0);
}

// IK traced along a pose path without a fold comes to the pose as the regular IK does: the same
// equilibrium, no fold, every point an equilibrium at its pose on the path.
TEST(SpatialFolds, InverseKinematicsTracedWithoutAFoldMatchesTheRegularSolve) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const SpatialForwardSolution home = spatial_forward_kinematics(robot, raised(0.0));
  ASSERT_TRUE(home.summary.converged());
  const SpatialInverseSolution start = spatial_inverse_kinematics(robot, home.pose, home);
  ASSERT_TRUE(start.summary.converged());
  SpatialPose<double> pose = start.pose;
  pose.position += Eigen::Vector3d(0.01, -0.005, 0.02);
  const Eigen::Vector4d turn = quaternion_exp<double>(Eigen::Vector3d(0.05, 0.02, -0.03));
  pose.orientation = quaternion_product<double>(start.pose.orientation, turn);
  const ShootingScale scale = spatial_shooting_scale(robot);
  int points = 0;
  double worst = 0;
  const SpatialInverseSolution traced = spatial_inverse_kinematics_through_folds(
      robot, pose, start, SolverOptions(), [&](const SpatialInverseSolution& p) {
        ++points;
        const double t = p.summary.path_fraction;
        EXPECT_LT(
            (p.pose.position - (start.pose.position + t * (pose.position - start.pose.position)))
                .norm(),
            1e-12);
        SpatialResidualVector<double> r;
        spatial_residual(robot, spatial_shooting_point(robot, p), scale, p.summary.rod_steps, r,
                         nullptr);
        worst = std::max(worst, r.lpNorm<Eigen::Infinity>());
      });
  ASSERT_TRUE(traced.summary.converged()) << to_string(traced.summary.status);
  EXPECT_EQ(traced.summary.folds_passed, 0);
  EXPECT_GE(points, 2);
  EXPECT_LT(worst, 1e-9);
  const SpatialInverseSolution regular = spatial_inverse_kinematics(robot, pose, start);
  ASSERT_TRUE(regular.summary.converged());
  EXPECT_LT((traced.q - regular.q).lpNorm<Eigen::Infinity>(), 1e-9);
  EXPECT_LT(testing::angle_between(traced.pose.orientation, pose.orientation), 1e-12);
  std::printf("IK traced in %d points (residual <= %.1e): joints within %.1e m of the regular IK\n",
              points, worst, (traced.q - regular.q).lpNorm<Eigen::Infinity>());
}

TEST(SpatialFolds, RejectsBadInput) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const SpatialForwardSolution home = spatial_forward_kinematics(robot, raised(0.0));
  ASSERT_TRUE(home.summary.converged());
  SpatialJointVector q = raised(0.01);
  q(2) = std::nan("");
  EXPECT_EQ(spatial_forward_kinematics_through_folds(robot, q, home).summary.status,
            SolveStatus::kInvalidInput);
  EXPECT_EQ(spatial_forward_kinematics_through_folds(robot, raised(0.01).head(5).eval(), home)
                .summary.status,
            SolveStatus::kInvalidInput);
  SpatialRobotParams<double> four = robot;
  four.num_rods = 4;
  SpatialInverseSolution warm;
  warm.q = raised(0.0).head(4);
  EXPECT_EQ(spatial_inverse_kinematics_through_folds(four, home.pose, warm).summary.status,
            SolveStatus::kUnsupported);
  SolverOptions bad;
  bad.max_arclength_steps = 0;
  EXPECT_EQ(spatial_forward_kinematics_through_folds(robot, raised(0.01), home, bad).summary.status,
            SolveStatus::kInvalidInput);
}

}  // namespace
}  // namespace pcr
