// The stability check of a spatial robot's equilibrium (pcr/spatial/stability.hpp) against
// independent references: Euler's columns in 3-D (a free column, guided and pinned columns,
// the clamped-clamped column's conjugate point), the closed-form stiffness of a cantilever and of
// a beam-column's pinned end, the platform stiffness by finite differences of re-solved rods,
// the planar core's check (pcr::equilibrium_stability) on the planar robot described as spatial,
// the sign of the forward Jacobian's determinant through a fold, and the reference robot's
// symmetry.

// Eigen asserts on any heap allocation while set_is_malloc_allowed(false), in builds with
// assertions (NeverAllocates; operator new is counted in every build).
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "allocation_counter.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/stability.hpp"
#include "pcr/stability.hpp"
#include "spatial_test_support.hpp"

namespace pcr {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Eigen::Vector4d;
using Point = SpatialShootingPoint<double>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

constexpr double kLength = 0.4;

/// n vertical steel rods of length 0.4 m (2 mm), 50 mm from the axis (one on it), their tips
/// attached to the platform right above their holes; no gravity; the platform pushed down by n P.
SpatialRobotParams<double> column_robot(int n, SpatialAttachment attachment, double p) {
  SpatialRobotParams<double> robot;
  robot.num_rods = n;
  robot.gravity.setZero();
  for (int i = 0; i < n; ++i) {
    SpatialLimbParams<double>& limb = robot.limb(i);
    limb.rod.length = kLength;
    limb.rod.diameter = 2e-3;
    limb.rod.young_modulus = 200e9;
    limb.rod.shear_modulus = 80e9;
    limb.rod.density = 8000;
    const double angle = 2 * M_PI * i / n, radius = n > 1 ? 0.05 : 0.0;
    limb.A = Vector3d(radius * std::cos(angle), radius * std::sin(angle), 0);
    limb.B = limb.A;
    limb.attachment = attachment;
  }
  robot.external_force = Vector3d(0, 0, -n * p);
  return robot;
}

/// The straight equilibrium of column_robot: every rod carries P along its axis.
Point straight_columns(const SpatialRobotParams<double>& robot, double p) {
  Point point;
  point.pose.position = Vector3d(0, 0, kLength);
  for (int i = 0; i < robot.num_rods; ++i) point.wrenches[i].force = Vector3d(0, 0, -p);
  return point;
}

double ei() {
  return column_robot(1, SpatialAttachment::kClamped, 0).limb(0).rod.bending_stiffness();
}

// ---- Closed forms -------------------------------------------------------------------------------

// Unloaded, the cantilever's tip stiffness is the inverse of its closed-form compliance (rod along
// z): x = L^3 / (3 EI) F_x + L^2 / (2 EI) M_y, turn_y = L^2 / (2 EI) F_x + L / EI M_y, and the same
// with y, -x; z = L / EA F_z; twist L / GJ M_z.
TEST(SpatialStability, UnloadedCantileverHasTheClosedFormStiffness) {
  const SpatialRobotParams<double> robot = column_robot(1, SpatialAttachment::kClamped, 0);
  const SpatialRod<double>& rod = robot.limb(0).rod;
  const double l = kLength, b = rod.bending_stiffness();
  Matrix6d compliance = Matrix6d::Zero();
  compliance(0, 0) = compliance(1, 1) = l * l * l / (3 * b);
  compliance(3, 3) = compliance(4, 4) = l / b;
  compliance(0, 4) = compliance(4, 0) = l * l / (2 * b);
  compliance(1, 3) = compliance(3, 1) = -l * l / (2 * b);
  compliance(2, 2) = l / rod.axial_stiffness();
  compliance(5, 5) = l / rod.torsional_stiffness();
  const ShootingScale scale = spatial_shooting_scale(robot);
  Vector6d pose_scale, wrench_scale;
  pose_scale << 1 / l, 1 / l, 1 / l, 1, 1, 1;
  wrench_scale << scale.force, scale.force, scale.force, scale.moment(), scale.moment(),
      scale.moment();
  const Matrix6d expected =
      (pose_scale.asDiagonal() * compliance * wrench_scale.asDiagonal()).inverse();
  const SpatialEquilibriumStability s =
      spatial_equilibrium_stability(robot, straight_columns(robot, 0), 32);
  ASSERT_TRUE(s.stable);
  EXPECT_LT((s.stiffness - expected).norm(), 1e-9 * expected.norm());
  const double smallest = Eigen::SelfAdjointEigenSolver<Matrix6d>(expected).eigenvalues()(0);
  EXPECT_NEAR(s.margin, smallest, 1e-9 * smallest);
  EXPECT_EQ(s.conjugate_limb, -1);
  EXPECT_GT(s.singularity, 0);
}

// A spherical rod's tip rotational stiffness with its position held is that of a beam-column's
// end, the far end clamped, under an axial compression P: s(kL) EI / L with k^2 = P / EI and
// s(x) = x (sin x - x cos x) / (2 - 2 cos x - x sin x) (4 EI / L unloaded); its twist GJ / L.
// It vanishes at tan(kL) = kL, kL = 4.4934: the clamped-pinned column's Euler load
// pi^2 EI / (0.6992 L)^2, where the check reports the rod, pinned at its tip, unstable at L.
TEST(SpatialStability, SphericalTipHasTheBeamColumnsEndStiffness) {
  const double b = ei(), kl_critical = 4.493409457909064;
  double worst = 0;
  for (double kl : {0.0, 1.0, 2.0, 3.0, 4.0, 4.45, 4.49, 4.497, 4.55, 5.0}) {
    const double p = kl * kl * b / (kLength * kLength);
    const SpatialRobotParams<double> robot = column_robot(1, SpatialAttachment::kSpherical, p);
    const Point point = straight_columns(robot, p);
    const ShootingScale scale = spatial_shooting_scale(robot);
    const internal::SpatialRodCheck rod = internal::check_spatial_rod(robot, point, 0, scale, 128);
    const Matrix3d tip = internal::spherical_tip_stiffness(rod, scale);
    const double expected = kl == 0 ? 4.0
                                    : kl * (std::sin(kl) - kl * std::cos(kl)) /
                                          (2 - 2 * std::cos(kl) - kl * std::sin(kl));
    const double twist = robot.limb(0).rod.torsional_stiffness() / b;
    Matrix3d closed_form = Vector3d(expected, expected, twist).asDiagonal();
    const double error = (tip - closed_form).norm();
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-5) << kl;
    const SpatialEquilibriumStability s = spatial_equilibrium_stability(robot, point, 128);
    if (kl < kl_critical) {
      EXPECT_EQ(s.conjugate_limb, -1) << kl;
    } else {
      EXPECT_EQ(s.conjugate_limb, 0) << kl;
      EXPECT_EQ(s.conjugate_arc_length, kLength) << kl;
      EXPECT_FALSE(s.stable);
    }
  }
  std::printf("spherical tip stiffness vs the beam-column's s(kL): worst %.1e (of EI / L)\n",
              worst);
}

// ---- Buckling columns ---------------------------------------------------------------------------

struct ColumnCase {
  const char* name;
  int rods;
  SpatialAttachment attachment;
  double effective_length;  ///< K in pi^2 EI / (K L)^2
  double tolerance;         ///< on the load where the margin crosses zero, relative
};

// Straight columns pushed along their axes: stable below Euler's load pi^2 EI / (K L)^2 for their
// boundary conditions and unstable above it, the margin falling to zero at it (the platform's
// stiffness): one clamped rod, its top free (K = 2); three clamped rods, the platform guiding
// their tops sideways without turning them (K = 1); three spherical rods, their tops free to turn
// and the platform to sway (K = 2, their own clamped-pinned load, K = 0.7, lies 8 times higher).
// The axial compliance adds to the tips' axial entries only, which the lateral modes of a single
// straight column do not involve: it moves its load by nothing (an extensible rod's would move by
// O(P / EA) = 4e-6 relative). Three clamped rods sway 4e-4 below their guided load: their end
// moments tilt the platform against the rods' axial compliance, so that it does not quite keep
// their tops from turning (the shift falls as 1 / r^2 with the rods' distance r from the axis).
TEST(SpatialStability, ColumnsBuckleAtEulersLoads) {
  const ColumnCase cases[] = {
      {"one clamped rod", 1, SpatialAttachment::kClamped, 2.0, 1e-6},
      {"three clamped rods", 3, SpatialAttachment::kClamped, 1.0, 5e-4},
      {"three spherical rods", 3, SpatialAttachment::kSpherical, 2.0, 1e-6}};
  for (const ColumnCase& c : cases) {
    const double critical =
        M_PI * M_PI * ei() / (c.effective_length * kLength * c.effective_length * kLength);
    double previous = HUGE_VAL;
    for (double ratio : {0.0, 0.5, 0.9, 0.999, 1.001, 1.1, 2.0}) {
      const double p = ratio * critical;
      const SpatialRobotParams<double> robot = column_robot(c.rods, c.attachment, p);
      const SpatialEquilibriumStability s =
          spatial_equilibrium_stability(robot, straight_columns(robot, p), 64);
      EXPECT_EQ(s.stable, ratio < 1) << c.name << " " << ratio << " margin " << s.margin;
      EXPECT_EQ(s.conjugate_limb, -1) << c.name << " " << ratio;
      if (ratio < 1) {
        EXPECT_LT(s.margin, previous) << c.name << " " << ratio;  // compression softens it
        previous = s.margin;
      }
    }
    // Where the margin crosses zero, by the secant through 0.999 and 1.001.
    double margins[2];
    for (int k = 0; k < 2; ++k) {
      const double p = (k == 0 ? 0.999 : 1.001) * critical;
      const SpatialRobotParams<double> robot = column_robot(c.rods, c.attachment, p);
      margins[k] = spatial_equilibrium_stability(robot, straight_columns(robot, p), 64).margin;
    }
    const double zero = 0.999 + 0.002 * margins[0] / (margins[0] - margins[1]);
    EXPECT_NEAR(zero, 1.0, c.tolerance) << c.name;
    std::printf("%s: the margin crosses zero at %.7f times pi^2 EI / (%.1f L)^2\n", c.name, zero,
                c.effective_length);
  }
}

// A straight column clamped at both ends (the platform of one clamped rod held) has its first
// conjugate point at 2 pi sqrt(EI / P), inside the rod exactly above Euler's 4 pi^2 EI / L^2
// (K = 1/2): a double one, since the rod buckles in any plane through its axis.
TEST(SpatialStability, ClampedClampedColumnHasItsConjugatePointAtEulersLength) {
  const double critical = 4 * M_PI * M_PI * ei() / (kLength * kLength);
  double worst = 0;
  for (double ratio : {0.5, 0.99, 0.998, 1.002, 1.01, 1.5, 3.0}) {
    const double p = ratio * critical;
    const SpatialRobotParams<double> robot = column_robot(1, SpatialAttachment::kClamped, p);
    const SpatialEquilibriumStability s =
        spatial_equilibrium_stability(robot, straight_columns(robot, p), 64);
    EXPECT_FALSE(s.stable);  // the free column buckled long before
    if (ratio < 1) {
      EXPECT_EQ(s.conjugate_limb, -1) << ratio;
    } else {
      ASSERT_EQ(s.conjugate_limb, 0) << ratio;
      const double expected = 2 * M_PI * std::sqrt(ei() / p);
      worst = std::max(worst, std::abs(s.conjugate_arc_length - expected));
      EXPECT_NEAR(s.conjugate_arc_length, expected, 1e-3 * kLength) << ratio;
    }
  }
  std::printf("clamped-clamped conjugate point: within %.1e m of 2 pi sqrt(EI / P)\n", worst);
}

// ---- The stiffness against finite differences ---------------------------------------------------

/// The platform's stiffness by central differences: move the pose, re-solve each rod's proximal
/// wrench so that it meets its attachment again (Newton on its 6 closure rows), difference the
/// platform's residual, its moment rows taken into P.
Matrix6d stiffness_by_differences(const SpatialRobotParams<double>& robot, const Point& solved,
                                  int steps) {
  const ShootingScale scale = spatial_shooting_scale(robot);
  const int n = robot.num_rods;
  const internal::SpatialForwardProblem problem(robot, steps);
  const auto equilibrium_at = [&](const Point& moved) {
    Point p = moved;
    SpatialResidualVector<double> r;
    SpatialJacobian J;
    for (int it = 0; it < 12; ++it) {
      spatial_residual(robot, p, scale, steps, r, &J);
      for (int i = 0; i < n; ++i) {
        const Vector6d dw =
            Matrix6d(J.block<6, 6>(6 * i, 6 * i)).fullPivLu().solve(-r.segment<6>(6 * i));
        p.wrenches[i].force += dw.head<3>() * scale.force;
        p.wrenches[i].moment += dw.tail<3>() * scale.moment();
      }
    }
    spatial_residual(robot, p, scale, steps, r);
    Vector6d out = r.tail<6>();
    out.tail<3>() = moved.pose.rotation().transpose() * out.tail<3>();
    return out;
  };
  const double h = 1e-6;
  Matrix6d k;
  for (int j = 0; j < 6; ++j) {
    const SpatialVector unit = SpatialVector::Unit(6 * n + 6, 6 * n + j);
    k.col(j) = (equilibrium_at(problem.retract(solved, h * unit)) -
                equilibrium_at(problem.retract(solved, -h * unit))) /
               (2 * h);
  }
  return k;
}

// Random robots with every kind of rod (mixed_robot: clamped and spherical tips, holes and
// translated clamps, gravity, a payload off centre, an external force), solved by FK at random
// joints: the check's stiffness (the inextensible model's) matches the re-solved rods' finite
// differences, and those are symmetric, as the Hessian of an energy is: nothing in either
// construction makes them so. No external moment: a dead moment is not conservative in 3-D.
TEST(SpatialStability, StiffnessMatchesDifferencesOfResolvedRods) {
  std::mt19937_64 rng(20261128);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kSteps = 64;
  SolverOptions options;
  options.rod_steps = kSteps;
  options.chord_output_share = 0;
  int compared = 0, spherical = 0;
  double worst = 0, worst_asymmetry = 0;
  for (int trial = 0; trial < 16; ++trial) {
    const int n = 3 + trial % 4;
    SpatialRobotParams<double> robot = testing::mixed_robot(rng, n);
    robot.external_moment.setZero();
    SpatialJointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = 0.01 * u(rng);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q, options);
    if (!fk.summary.converged()) continue;  // the cold-start limit of test_spatial_kinematics
    const Point point = spatial_shooting_point(robot, fk);
    const SpatialEquilibriumStability s =
        internal::spatial_equilibrium_stability(robot, point, kSteps, false);
    // A straight inextensible rod has no finite stiffness to difference (the re-solve of its
    // wrench is singular), as in the planar test.
    if (!(s.singularity > 1e-12)) continue;
    const Matrix6d k = stiffness_by_differences(robot, point, kSteps);
    const double size = k.norm();
    const double asymmetry = (k - k.transpose()).norm() / size;
    const double error = (s.stiffness - k).norm() / size;
    worst = std::max(worst, error);
    worst_asymmetry = std::max(worst_asymmetry, asymmetry);
    EXPECT_LT(asymmetry, 1e-4) << trial;
    EXPECT_LT(error, 2e-4) << trial;
    ++compared;
    for (int i = 0; i < n; ++i)
      spherical += robot.limb(i).attachment == SpatialAttachment::kSpherical;
    std::printf(
        "robot %d (%d rods): stable %d, margin %.3e, singularity %.2e, conjugate %d at %.4f, "
        "error %.1e\n",
        trial, n, s.stable, s.margin, s.singularity, s.conjugate_limb, s.conjugate_arc_length,
        error);
  }
  EXPECT_GE(compared, 6);
  EXPECT_GE(spherical, 4);
  std::printf("stiffness vs differences: worst %.1e, asymmetry %.1e of |K|\n", worst,
              worst_asymmetry);
}

// ---- The planar robot in space ------------------------------------------------------------------

/// The planar solution as a spatial shooting point (the spatial rod frames of spatial_of_planar:
/// d1 = e3, so the planar moment is about z).
Point spatial_point_of_planar(const JointVector& q, const Pose2<double>& pose,
                              const std::array<Wrench<double>, kMaxLimbs>& wrenches) {
  Point point;
  point.pose.position = Vector3d(pose.x, pose.y, 0);
  point.pose.orientation = Vector4d(std::cos(pose.theta / 2), 0, 0, std::sin(pose.theta / 2));
  for (int i = 0; i < q.size(); ++i) {
    point.q[i] = q(i);
    point.wrenches[i].force = Vector3d(wrenches[i].nx, wrenches[i].ny, 0);
    point.wrenches[i].moment = Vector3d(0, 0, wrenches[i].m);
  }
  return point;
}

/// The spatial FK solution next to a point (Newton from it at its joints).
SpatialForwardSolution polished(const SpatialRobotParams<double>& robot, const Point& point) {
  SpatialForwardSolution warm;
  warm.pose = point.pose;
  warm.q.resize(robot.num_rods);
  for (int i = 0; i < robot.num_rods; ++i) {
    warm.q(i) = point.q[i];
    warm.wrenches[i] = point.wrenches[i];
  }
  SolverOptions options;
  options.chord_output_share = 0;
  return spatial_forward_kinematics(robot, warm.q, warm, options);
}

/// The in-plane rows and columns (x, y, turn about z) of a spatial stiffness.
Matrix3d in_plane(const Matrix6d& k) {
  const int index[3] = {0, 1, 5};
  Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = k(index[r], index[c]);
  }
  return out;
}

// The default planar robot described as spatial, at random joints: the in-plane part of the
// spatial check's stiffness is the planar check's (its rows and columns x, y and the turn about z;
// the out-of-plane ones decouple by the mirror z -> -z), and the flag is the planar one.
TEST(SpatialStability, PlanarRobotInSpaceGivesThePlanarCheck) {
  const RobotParams<double> planar = femto_3pf();
  const SpatialRobotParams<double> robot = testing::spatial_of_planar(planar);
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  for (int trial = 0; trial < 8; ++trial) {
    JointVector q(3);
    for (int i = 0; i < 3; ++i) q(i) = 0.004 * u(rng);
    const ForwardSolution fk = forward_kinematics(planar, q);
    ASSERT_TRUE(fk.summary.converged());
    const EquilibriumStability expected =
        equilibrium_stability(planar, fk.q, fk.pose, fk.wrenches, 4 * fk.summary.rod_steps);
    const SpatialForwardSolution spatial =
        polished(robot, spatial_point_of_planar(fk.q, fk.pose, fk.wrenches));
    ASSERT_TRUE(spatial.summary.converged());
    const SpatialEquilibriumStability s =
        spatial_equilibrium_stability(robot, spatial, spatial.summary.rod_steps);
    EXPECT_EQ(s.stable, expected.stable) << trial;
    const double error =
        (in_plane(s.stiffness) - expected.stiffness).norm() / expected.stiffness.norm();
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-3) << trial;
    std::printf("q %+.4f %+.4f %+.4f: margin %.4e (planar %.4e), in-plane stiffness within %.1e\n",
                q(0), q(1), q(2), s.margin, expected.margin, error);
  }
  std::printf("planar robot in space: in-plane stiffness within %.1e of the planar check's\n",
              worst);
}

// The default robot with a 60 mm stroke, its platform moved along a line at theta = 0 (75 degrees
// from the x axis) by the planar core's warm-started IK left on its branch, which loses its planar
// stability near 22.78 mm (tests/test_stability.cpp): each solution described as spatial and
// re-solved by spatial FK at its joints. In space the robot loses its stability earlier, near
// 14.5 mm, out of its plane (a bifurcation that the mirror z -> -z makes symmetric): its platform
// is held out of plane by the rods' bending and torsion alone (no rod's axial stiffness), which the
// compressed rod 0 overcomes first. There the margin crosses zero where the spatial forward
// Jacobian's determinant (an LU of the whole matrix) changes sign, and the singularity measure is
// least; the in-plane part of the check (its stiffness' in-plane block, the rods' conjugate points)
// gives the planar flag all along.
TEST(SpatialStability, MarginCrossesZeroWhereTheForwardJacobianTurnsSingular) {
  RobotParams<double> planar = femto_3pf();
  for (int i = 0; i < 3; ++i) {
    planar.limb(i).q_min = -0.030;
    planar.limb(i).q_max = 0.030;
  }
  const SpatialRobotParams<double> robot = testing::spatial_of_planar(planar);
  const ShootingScale scale = spatial_shooting_scale(robot);
  SolverOptions options;
  options.stable_inverse = false;
  InverseSequence sequence(planar, options, PlatformLoad<double>(), SequenceMode::kPath);
  const double direction = 75 * M_PI / 180;
  std::vector<double> ts, margins, singularities, determinants;
  int stable = 0, out_of_plane = 0, both = 0;
  for (int k = 0; k <= 250; ++k) {
    const double t = k * 1e-4;
    const InverseSolution& ik =
        sequence.solve({t * std::cos(direction), t * std::sin(direction), 0.0});
    ASSERT_TRUE(ik.summary.converged()) << t;
    if (k % 5 != 0 && (k < 140 || k > 150)) continue;
    const SpatialForwardSolution fk =
        polished(robot, spatial_point_of_planar(ik.q, ik.pose, ik.wrenches));
    ASSERT_TRUE(fk.summary.converged()) << t;
    const int steps = fk.summary.rod_steps;
    const SpatialEquilibriumStability s = spatial_equilibrium_stability(robot, fk, steps);
    SpatialResidualVector<double> r;
    SpatialJacobian J;
    spatial_residual(robot, spatial_shooting_point(robot, fk), scale, steps, r, &J);
    const double det = J.fullPivLu().determinant();
    const bool planar_stable = ik.summary.stability == Stability::kStable;
    const double in_plane_least =
        Eigen::SelfAdjointEigenSolver<Matrix3d>(in_plane(s.stiffness)).eigenvalues()(0);
    EXPECT_EQ(in_plane_least > 0 && s.conjugate_limb < 0, planar_stable) << t;
    EXPECT_TRUE(!s.stable || planar_stable) << t;
    (s.stable ? stable : planar_stable ? out_of_plane : both) += 1;
    ts.push_back(t);
    margins.push_back(s.margin);
    singularities.push_back(s.singularity);
    determinants.push_back(det);
    if (s.conjugate_limb < 0) {
      EXPECT_EQ(s.margin > 0, det * determinants.front() > 0) << t << " margin " << s.margin;
    }
    // The solver's own check (at half the steps) in its summary, away from the crossing.
    if (std::abs(s.margin) > 1.0) {
      EXPECT_EQ(fk.summary.stability, s.stable ? Stability::kStable : Stability::kUnstable) << t;
      EXPECT_EQ(fk.summary.stability_margin > 0, s.margin > 0) << t;
    }
    if (k % 10 == 0 || (k >= 142 && k <= 148)) {
      std::printf("%.1f mm: margin %+.4e, singularity %.3e, det %+.3e, planar %s, conjugate %d\n",
                  t * 1e3, s.margin, s.singularity, det, planar_stable ? "stable" : "unstable",
                  s.conjugate_limb);
    }
  }
  EXPECT_GE(stable, 10);
  EXPECT_GE(out_of_plane, 10);
  EXPECT_GE(both, 3);
  // The one sign change of the margin and of the determinant: the same interval, and their
  // zeros by linear interpolation within a tenth of it.
  std::size_t cross = 0, det_cross = 0;
  for (std::size_t i = 1; i < ts.size(); ++i) {
    if (margins[i - 1] > 0 && margins[i] <= 0) cross = i;
    if (det_cross == 0 && determinants[i - 1] * determinants[i] <= 0) det_cross = i;
  }
  ASSERT_GT(cross, 0u);
  EXPECT_EQ(det_cross, cross);
  const auto zero = [&](const std::vector<double>& v) {
    return ts[cross - 1] + (ts[cross] - ts[cross - 1]) * v[cross - 1] / (v[cross - 1] - v[cross]);
  };
  const double margin_zero = zero(margins), det_zero = zero(determinants);
  EXPECT_NEAR(margin_zero, det_zero, 0.1 * (ts[cross] - ts[cross - 1]));
  // The singularity measure: least, among the points around the crossing, at the one whose margin
  // is nearest zero.
  const std::size_t nearest =
      std::abs(margins[cross - 1]) < std::abs(margins[cross]) ? cross - 1 : cross;
  for (std::size_t i = nearest - 3; i <= nearest + 3; ++i) {
    if (i != nearest) {
      EXPECT_LT(singularities[nearest], 0.75 * singularities[i]) << ts[i];
    }
  }
  std::printf(
      "out-of-plane bifurcation: the margin crosses zero at %.5f mm, the forward Jacobian's "
      "determinant "
      "at %.5f mm; singularity %.2e there, %.2e at home\n",
      margin_zero * 1e3, det_zero * 1e3, singularities[nearest], singularities.front());
}

// The out-of-plane loss of stability above, checked against finite differences: the same robot
// with rods that shear and stretch (so that the straight rod 0 has a finite axial stiffness to
// difference, and the check takes no compliance of its own), at 16 mm along the line. Its
// stiffness' out-of-plane block and least eigenvalue, negative, are those of the re-solved rods.
TEST(SpatialStability, OutOfPlaneLossMatchesDifferencesOfResolvedRods) {
  RobotParams<double> planar = femto_3pf();
  for (int i = 0; i < 3; ++i) {
    planar.limb(i).q_min = -0.030;
    planar.limb(i).q_max = 0.030;
  }
  SpatialRobotParams<double> robot = testing::spatial_of_planar(planar);
  for (int i = 0; i < 3; ++i) robot.limb(i).rod.shear_and_extension = true;
  SolverOptions options;
  options.stable_inverse = false;
  InverseSequence sequence(planar, options, PlatformLoad<double>(), SequenceMode::kPath);
  const double direction = 75 * M_PI / 180;
  InverseSolution ik;
  for (int k = 0; k <= 160; ++k) {
    const double t = k * 1e-4;
    ik = sequence.solve({t * std::cos(direction), t * std::sin(direction), 0.0});
    ASSERT_TRUE(ik.summary.converged()) << t;
  }
  const SpatialForwardSolution fk =
      polished(robot, spatial_point_of_planar(ik.q, ik.pose, ik.wrenches));
  ASSERT_TRUE(fk.summary.converged());
  constexpr int kSteps = 128;
  const Point point = spatial_shooting_point(robot, fk);
  const SpatialEquilibriumStability s =
      internal::spatial_equilibrium_stability(robot, point, kSteps, false);
  const Matrix6d k = stiffness_by_differences(robot, point, kSteps);
  const Matrix6d symmetric = 0.5 * (k + k.transpose());
  const int index[3] = {2, 3, 4};
  Matrix3d out_check, out_differences;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      out_check(a, b) = s.stiffness(index[a], index[b]);
      out_differences(a, b) = symmetric(index[a], index[b]);
    }
  }
  const double error = (out_check - out_differences).norm() / out_differences.norm();
  const double least = Eigen::SelfAdjointEigenSolver<Matrix6d>(symmetric).eigenvalues()(0);
  EXPECT_LT(error, 1e-4);
  EXPECT_LT(least, 0);
  EXPECT_FALSE(s.stable);
  EXPECT_EQ(s.conjugate_limb, -1);
  EXPECT_NEAR(s.margin, least, 1e-4 * std::abs(least));
  EXPECT_LT((in_plane(s.stiffness) - in_plane(symmetric)).norm(),
            1e-4 * in_plane(symmetric).norm());
  std::printf(
      "16 mm, rods with shear and extension: margin %.5e, differences' least eigenvalue %.5e; "
      "out-of-plane block within %.1e\n",
      s.margin, least, error);
}

// ---- Symmetry, steps, real time -----------------------------------------------------------------

// The reference robot is symmetric under turns of 120 degrees about z, which take rod i to rod
// i + 2: its FK at joints q and at the joints turned (q_{i - 2} on rod i), solved each on its own,
// give the same flag, margin and stiffness eigenvalues.
TEST(SpatialStability, ReferenceRobotTurnedByAThirdOfATurnGivesTheSameCheck) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  std::mt19937_64 rng(53);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  for (int trial = 0; trial < 4; ++trial) {
    SpatialJointVector q(6), turned(6);
    for (int i = 0; i < 6; ++i) q(i) = 0.005 + 0.01 * u(rng);
    for (int i = 0; i < 6; ++i) turned((i + 2) % 6) = q(i);
    const SpatialForwardSolution a = spatial_forward_kinematics(robot, q);
    const SpatialForwardSolution b = spatial_forward_kinematics(robot, turned);
    ASSERT_TRUE(a.summary.converged() && b.summary.converged());
    const SpatialEquilibriumStability sa = spatial_equilibrium_stability(robot, a, 128);
    const SpatialEquilibriumStability sb = spatial_equilibrium_stability(robot, b, 128);
    EXPECT_EQ(sa.stable, sb.stable);
    const Eigen::Matrix<double, 6, 1> ea =
        Eigen::SelfAdjointEigenSolver<Matrix6d>(sa.stiffness).eigenvalues();
    const Eigen::Matrix<double, 6, 1> eb =
        Eigen::SelfAdjointEigenSolver<Matrix6d>(sb.stiffness).eigenvalues();
    const double error = (ea - eb).cwiseAbs().maxCoeff() / ea.cwiseAbs().maxCoeff();
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-6) << trial;
    EXPECT_NEAR(sa.margin, sb.margin, 1e-6 * std::abs(sa.margin)) << trial;
    std::printf("q %s: stable %d, margin %.6e / %.6e, singularity %.3e\n",
                trial == 0 ? "first" : "next", sa.stable, sa.margin, sb.margin, sa.singularity);
  }
  std::printf("turned by 120 degrees: stiffness eigenvalues within %.1e\n", worst);
}

// Half a solution's RK4 steps (stability_rod_steps, as the planar solvers check) against eight
// times as many, on the reference robot and random robots: the same flag, the margin within 1e-3.
TEST(SpatialStability, CheckAtHalfTheStepsAgreesWithAFineIntegration) {
  std::mt19937_64 rng(59);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  int checked = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const int n = trial < 4 ? 6 : 3 + trial % 4;
    const SpatialRobotParams<double> robot =
        trial < 4 ? continuum_stewart_gough() : testing::mixed_robot(rng, n);
    SpatialJointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = 0.01 * u(rng);
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, q);
    if (!fk.summary.converged()) continue;
    ++checked;
    const int steps = fk.summary.rod_steps;
    const SpatialEquilibriumStability half =
        spatial_equilibrium_stability(robot, fk, stability_rod_steps(steps));
    const SpatialEquilibriumStability fine = spatial_equilibrium_stability(robot, fk, 4 * steps);
    EXPECT_EQ(half.stable, fine.stable) << trial;
    const double error = std::abs(half.margin - fine.margin) / std::abs(fine.margin);
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-3) << trial;
  }
  EXPECT_GE(checked, 6);
  std::printf("half the steps vs four times: margin within %.1e relative\n", worst);
}

// IK returns a stable equilibrium where one exists. At the reference pose a buckled seed leads IK
// (stable_inverse off) to another equilibrium, one rod looped and about 0.4 m longer, unstable
// with the joints held. IK warm-started from it 1 mm away stays on that branch with the search
// off; with it on (the default) it returns a stable equilibrium, which a CVODE FK at its joints
// puts at the requested pose.
TEST(SpatialStability, InverseLeavesAnUnstableEquilibriumForAStableOne) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialPose<double> pose;
  pose.position = Vector3d(0, 0, 0.4);
  pose.orientation = quaternion_exp<double>(Vector3d(0, 10 * M_PI / 180, 0));
  SolverOptions keep;
  keep.stable_inverse = false;
  const SpatialInverseSolution normal = spatial_inverse_kinematics(robot, pose, keep);
  ASSERT_TRUE(normal.summary.converged());
  ASSERT_EQ(normal.summary.stability, Stability::kStable);
  SpatialInverseSolution looped;
  for (int k = 0; k < kSpatialBuckledSeedsPerRod * robot.num_rods; ++k) {
    looped = spatial_inverse_kinematics(robot, pose, spatial_buckled_seed(robot, normal, k), keep);
    if (looped.summary.converged() && looped.summary.stability == Stability::kUnstable) break;
  }
  ASSERT_EQ(looped.summary.stability, Stability::kUnstable);
  EXPECT_LT(looped.summary.stability_margin, 0);
  EXPECT_GT((looped.q - normal.q).lpNorm<Eigen::Infinity>(), 0.1);

  SpatialPose<double> moved = pose;
  moved.position.x() += 1e-3;
  const SpatialInverseSolution stays = spatial_inverse_kinematics(robot, moved, looped, keep);
  ASSERT_TRUE(stays.summary.converged());
  EXPECT_EQ(stays.summary.stability, Stability::kUnstable);
  EXPECT_GT((stays.q - normal.q).lpNorm<Eigen::Infinity>(), 0.1);

  const SpatialInverseSolution stable = spatial_inverse_kinematics(robot, moved, looped);
  ASSERT_TRUE(stable.summary.converged()) << static_cast<int>(stable.summary.status);
  EXPECT_EQ(stable.summary.stability, Stability::kStable);
  EXPECT_GT(stable.summary.stability_margin, 0);
  EXPECT_LT((stable.q - normal.q).lpNorm<Eigen::Infinity>(), 0.01);
  EXPECT_GT(stable.summary.residual_evaluations, stays.summary.residual_evaluations);
  const testing::ReferenceFk reference =
      testing::reference_forward_kinematics(robot, spatial_shooting_point(robot, stable));
  const testing::PoseError error = testing::pose_error(reference.x.pose, moved);
  EXPECT_LT(error.position, 1e-9);
  EXPECT_LT(error.angle, 1e-8);
  std::printf(
      "looped rod: margin %.3e, joints %.3f m from the stable ones; IK 1 mm away finds a stable "
      "equilibrium (margin %.3e) in %d evaluations; CVODE FK at its joints within %.1e m, "
      "%.1e rad of the pose\n",
      looped.summary.stability_margin, (looped.q - normal.q).lpNorm<Eigen::Infinity>(),
      stable.summary.stability_margin, stable.summary.residual_evaluations, error.position,
      error.angle);
}

TEST(SpatialStability, NeverAllocates) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const SpatialForwardSolution fk =
      spatial_forward_kinematics(robot, SpatialJointVector::Constant(6, 0.005));
  ASSERT_TRUE(fk.summary.converged());
  g_allocations = 0;
  g_counting = true;
  Eigen::internal::set_is_malloc_allowed(false);
  const SpatialEquilibriumStability s = spatial_equilibrium_stability(robot, fk, 64);
  Eigen::internal::set_is_malloc_allowed(true);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(std::isfinite(s.margin));
}

TEST(SpatialStability, RejectsBadInput) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialForwardSolution wrong;
  wrong.q = SpatialJointVector::Zero(5);
  EXPECT_FALSE(spatial_equilibrium_stability(robot, wrong, 64).stable);
  EXPECT_TRUE(std::isnan(spatial_equilibrium_stability(robot, wrong, 64).margin));
  Point point;
  point.wrenches[0].force.x() = std::nan("");
  EXPECT_FALSE(spatial_equilibrium_stability(robot, point, 64).stable);
  EXPECT_FALSE(spatial_equilibrium_stability(robot, Point(), 0).stable);
}

}  // namespace
}  // namespace pcr
