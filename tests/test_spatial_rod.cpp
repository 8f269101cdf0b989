// The spatial Cosserat rod (pcr/spatial/cosserat_rod.hpp) against independent references: closed
// forms (the circular arc of a pure bending moment, pure torsion, the helices of a pre-curved rod
// and of Kirchhoff's loaded rod, the stretched rod, the linear cantilever under its own weight),
// the planar core (pcr/rod.hpp) for a rod in a plane, Eigen's quaternions, the CVODE integration
// of the rotation matrix (pcr::integrate_spatial_rod_reference), and central differences.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "pcr/reference.hpp"
#include "pcr/rod.hpp"
#include "pcr/spatial/cosserat_rod.hpp"

namespace pcr {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Eigen::Vector4d;
using Index = SpatialRodIndex;

/// A spring-steel rod, 200 mm long, 1 mm thick.
SpatialRod<double> steel_rod() {
  SpatialRod<double> rod;
  rod.length = 0.2;
  rod.diameter = 1e-3;
  rod.young_modulus = 200e9;
  rod.shear_modulus = 200e9 / (2 * (1 + 0.3));
  rod.density = 7850;
  return rod;
}

/// (w, x, y, z) of Eigen's quaternion.
Vector4d wxyz(const Eigen::Quaterniond& q) { return Vector4d(q.w(), q.x(), q.y(), q.z()); }

Matrix3d rotation_about(const Vector3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// The angle of the rotation that takes a to b (rad).
double rotation_error(const Matrix3d& a, const Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

/// A base orientation with no special axis.
const Matrix3d kBaseRotation = rotation_about(Vector3d(0.3, -0.5, 0.8), 2.1);
const Vector3d kBasePosition(0.01, -0.02, 0.03);
const Vector3d kNoGravity = Vector3d::Zero();

SpatialRodState<double> base_state(const Matrix3d& rotation, const Vector3d& force,
                                   const Vector3d& moment) {
  SpatialRodState<double> base;
  base.position = kBasePosition;
  base.orientation = wxyz(Eigen::Quaterniond(rotation));
  base.force = force;
  base.moment = moment;
  return base;
}

// ---- Quaternions
// ----------------------------------------------------------------------------------

TEST(Quaternion, RotationMatchesEigenForAnyScale) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 100; ++i) {
    const Vector4d h(normal(rng), normal(rng), normal(rng), normal(rng));
    const Matrix3d expected =
        Eigen::Quaterniond(h[0], h[1], h[2], h[3]).normalized().toRotationMatrix();
    // rotation_of divides by |h|^2: any non-zero scale gives the same rotation.
    for (double scale : {1.0, 1.0 + 1e-6, 0.3, 7.0}) {
      const Matrix3d R = rotation_of<double>(scale * h);
      // A few roundings apart (GCC and Clang evaluate the products in different orders).
      EXPECT_LT((R - expected).cwiseAbs().maxCoeff(), 4e-15) << i << " scale " << scale;
      EXPECT_LT((R.transpose() * R - Matrix3d::Identity()).cwiseAbs().maxCoeff(), 4e-15);
    }
  }
}

TEST(Quaternion, QuaternionOfRotationRoundTrips) {
  std::mt19937 rng(8);
  std::normal_distribution<double> normal;
  std::vector<Matrix3d> rotations;
  for (int i = 0; i < 100; ++i) {
    rotations.push_back(Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng))
                            .normalized()
                            .toRotationMatrix());
  }
  // Each branch of Shepperd's method: near the identity and near half turns about x, y, z.
  for (const Vector3d& axis :
       {Vector3d(1, 0.1, -0.1), Vector3d(0.1, 1, 0.2), Vector3d(0, 0.1, 1)}) {
    rotations.push_back(rotation_about(axis, M_PI - 0.01));
  }
  rotations.push_back(rotation_about(Vector3d(1, 2, 3), 1e-3));
  for (const Matrix3d& R : rotations) {
    const Vector4d h = quaternion_of<double>(R);
    EXPECT_NEAR(h.norm(), 1.0, 1e-15);
    EXPECT_LT((rotation_of(h) - R).cwiseAbs().maxCoeff(), 1e-15);
    // Eigen's quaternion of R, up to sign.
    const Vector4d eigen = wxyz(Eigen::Quaterniond(R));
    EXPECT_LT(std::min((h - eigen).norm(), (h + eigen).norm()), 1e-15);
  }
}

TEST(Quaternion, ProductsMatchEigen) {
  const Eigen::Quaterniond a(0.3, -1.2, 0.5, 0.7), b(-0.4, 0.9, 1.1, -0.2);
  EXPECT_LT((quaternion_product(wxyz(a), wxyz(b)) - wxyz(a * b)).norm(), 1e-15);
  const Vector3d u(0.8, -0.3, 1.7);
  const Eigen::Quaterniond pure(0, u.x(), u.y(), u.z());
  EXPECT_LT((quaternion_times_vector(wxyz(a), u) - wxyz(a * pure)).norm(), 1e-15);
}

TEST(Quaternion, LogIsTheRotationVector) {
  // Against Eigen's angle-axis, relative to the angle, for any scale and either sign of h: small
  // angles (where a formula through acos would lose digits), ordinary ones, and near a half turn.
  std::mt19937 rng(9);
  std::normal_distribution<double> normal;
  double worst = 0;
  for (int i = 0; i < 100; ++i) {
    const Vector3d axis = Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    const double angle = i < 10   ? std::pow(10.0, -1.0 - i)
                         : i < 20 ? M_PI - std::pow(10.0, -1.0 - (i - 10))
                                  : M_PI * std::uniform_real_distribution<double>(0, 1)(rng);
    const Vector4d h = wxyz(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)));
    for (double scale : {1.0, -1.0, 0.3, -7.0}) {
      const Vector3d v = quaternion_log<double>(scale * h);
      const double error = (v - angle * axis).norm() / std::max(angle, 1e-300);
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-15) << i << " " << scale;
    }
  }
  std::printf("quaternion_log: worst relative error %.1e\n", worst);
  EXPECT_EQ(quaternion_log<double>(identity_quaternion<double>()), Vector3d::Zero());
}

// ---- Section constants
// ----------------------------------------------------------------------------

TEST(SpatialRod, StiffnessesOfACircularSection) {
  const SpatialRod<double> rod = steel_rod();
  const double d = rod.diameter, E = rod.young_modulus, G = rod.shear_modulus;
  const double I = M_PI * std::pow(d, 4) / 64, A = M_PI * d * d / 4;
  EXPECT_NEAR(rod.bending_stiffness(), E * I, 1e-15 * E * I);
  EXPECT_NEAR(rod.torsional_stiffness(), G * 2 * I, 1e-15 * G * I);
  EXPECT_NEAR(rod.shear_stiffness(), G * A, 1e-15 * G * A);
  EXPECT_NEAR(rod.axial_stiffness(), E * A, 1e-15 * E * A);
  EXPECT_NEAR(rod.mass_per_length(), rod.density * A, 1e-15 * rod.density * A);
  // The planar rod's EI is the same formula.
  EXPECT_EQ(rod.bending_stiffness(), (Rod<double>{rod.length, d, E}.bending_stiffness()));
}

// ---- 1. Pure bending moment: a circular arc -----------------------------------------------------

/// The tip of a straight rod under the end moment EI kappa about the body axis
/// a = (cos phi, sin phi, 0), no force: u = kappa a is constant, so R(s) = R0 Rot(a, kappa s) and
/// p(s) = p0 + R0 (sin(kappa s) e3 + (1 - cos(kappa s)) a x e3) / kappa.
struct Arc {
  Vector3d position;
  Matrix3d rotation;
};
Arc bent_arc(const Matrix3d& R0, const Vector3d& p0, const Vector3d& axis, double kappa, double s) {
  const Vector3d e3 = Vector3d::UnitZ();
  return Arc{
      p0 + R0 * (std::sin(kappa * s) * e3 + (1 - std::cos(kappa * s)) * axis.cross(e3)) / kappa,
      R0 * rotation_about(axis, kappa * s)};
}

TEST(SpatialRod, PureBendingMomentGivesCircularArc) {
  for (bool shear : {false, true}) {
    SpatialRod<double> rod = steel_rod();
    rod.shear_and_extension = shear;  // no force: no shear, no extension
    const double L = rod.length, ei = rod.bending_stiffness();
    for (double turn : {0.5, 2.0, 5.0}) {  // kappa L (rad)
      const double kappa = turn / L, phi = 0.7;
      const Vector3d axis(std::cos(phi), std::sin(phi), 0);
      const SpatialRodState<double> base =
          base_state(kBaseRotation, Vector3d::Zero(), ei * kappa * (kBaseRotation * axis));
      const Arc exact = bent_arc(kBaseRotation, kBasePosition, axis, kappa, L);
      double errors[3];
      for (int k = 0; k < 3; ++k) {
        errors[k] =
            (integrate_spatial_rod(base, rod, kNoGravity, 32 << k).position - exact.position)
                .norm();
      }
      const SpatialRodState<double> tip = integrate_spatial_rod(base, rod, kNoGravity, 256);
      EXPECT_LT((tip.position - exact.position).norm(), 1e-9 * L) << "turn " << turn;
      EXPECT_LT(rotation_error(tip.rotation(), exact.rotation), 1e-9) << "turn " << turn;
      EXPECT_LT((tip.moment - base.moment).norm(), 1e-15 * base.moment.norm());
      EXPECT_EQ(tip.force, base.force);
      // Fourth order: 16 times closer per doubling of the steps.
      for (int k = 0; k < 2; ++k) {
        EXPECT_GT(errors[k] / errors[k + 1], 14.0) << "turn " << turn << " steps " << (32 << k);
        EXPECT_LT(errors[k] / errors[k + 1], 18.0) << "turn " << turn << " steps " << (32 << k);
      }
      std::printf("arc kappa L = %.1f%s: tip error / L at 32, 64, 128 steps %.2e %.2e %.2e\n", turn,
                  shear ? " (shear)" : "", errors[0] / L, errors[1] / L, errors[2] / L);
    }
  }
}

// ---- 2. Pure torsion
// ------------------------------------------------------------------------------

TEST(SpatialRod, PureTwistingMomentTwistsWithoutBending) {
  SpatialRod<double> rod = steel_rod();
  const double L = rod.length, gj = rod.torsional_stiffness();
  for (double twist : {0.3, 3.0}) {  // m L / GJ (rad)
    const Vector3d axis = kBaseRotation.col(2);
    const SpatialRodState<double> base =
        base_state(kBaseRotation, Vector3d::Zero(), gj * twist / L * axis);
    for (int steps : {8, 128}) {
      const SpatialRodState<double> tip = integrate_spatial_rod(base, rod, kNoGravity, steps);
      // The centreline stays straight to the rounding: h only turns about the body's d3.
      EXPECT_LT((tip.position - (kBasePosition + L * axis)).norm(), 1e-14 * L) << steps;
      const Matrix3d relative = kBaseRotation.transpose() * tip.rotation();
      const double angle = std::atan2(relative(1, 0), relative(0, 0));
      // RK4 on the quaternion's half-angle rotation: (twist / 2 steps)^5 / 120 per step.
      const double bound = 1.5 * steps * std::pow(twist / (2 * steps), 5) / 60 + 1e-15;
      EXPECT_NEAR(angle, twist, bound) << steps;
      EXPECT_LT(
          rotation_error(tip.rotation(), kBaseRotation * rotation_about(Vector3d::UnitZ(), twist)),
          bound + 1e-15);
      EXPECT_LT((tip.moment - base.moment).norm(), 1e-15 * base.moment.norm());
    }
  }
}

// ---- 3. Helices
// -----------------------------------------------------------------------------------

/// A free rod with constant intrinsic curvature u* takes its stress-free shape: R(s) = R0
/// exp(s [u*]x), and with w = |u*|, p(s) = p0 + R0 (s I + (1 - cos ws) / w^2 [u*]x +
/// (ws - sin ws) / w^3 [u*]x^2) e3: a helix of curvature |(u1*, u2*)| and torsion u3*.
TEST(SpatialRod, FreePrecurvedRodIsItsHelix) {
  for (bool shear : {false, true}) {
    SpatialRod<double> rod = steel_rod();
    rod.shear_and_extension = shear;
    const double L = rod.length;
    rod.intrinsic_curvature = Vector3d(12.0, -7.0, 9.0);  // 1/m: 3.4 rad over the rod
    const Vector3d& u = rod.intrinsic_curvature;
    const double w = u.norm();
    Matrix3d u_hat;
    u_hat << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
    const Vector3d chord = (L * Matrix3d::Identity() + (1 - std::cos(w * L)) / (w * w) * u_hat +
                            (w * L - std::sin(w * L)) / (w * w * w) * u_hat * u_hat) *
                           Vector3d::UnitZ();
    const Vector3d exact_position = kBasePosition + kBaseRotation * chord;
    const Matrix3d exact_rotation = kBaseRotation * rotation_about(u, w * L);
    const SpatialRodState<double> base =
        base_state(kBaseRotation, Vector3d::Zero(), Vector3d::Zero());
    double errors[2];
    for (int k = 0; k < 2; ++k) {
      const SpatialRodState<double> tip = integrate_spatial_rod(base, rod, kNoGravity, 32 << k);
      errors[k] = (tip.position - exact_position).norm();
    }
    const SpatialRodState<double> tip = integrate_spatial_rod(base, rod, kNoGravity, 256);
    EXPECT_LT((tip.position - exact_position).norm(), 1e-9 * L);
    EXPECT_LT(rotation_error(tip.rotation(), exact_rotation), 1e-9);
    EXPECT_EQ(tip.moment, Vector3d::Zero());
    EXPECT_NEAR(errors[0] / errors[1], 16.0, 2.0);
    // The helix: the tip lies on the cylinder of radius kappa / w^2 about the axis R0 u* through
    // the centre p0 + R0 (u* x e3) / w^2 (the centre of the osculating circle's projection).
    const double kappa = std::hypot(u.x(), u.y());
    const Vector3d axis = kBaseRotation * u / w;
    const Vector3d centre = kBasePosition + kBaseRotation * u.cross(Vector3d::UnitZ()) / (w * w);
    const Vector3d off = tip.position - centre;
    EXPECT_NEAR((off - off.dot(axis) * axis).norm(), kappa / (w * w), 1e-9 * L);
  }
}

/// Kirchhoff's helix: a naturally straight, inextensible rod along the helix
/// p(s) = (r cos phi, r sin phi, c phi), phi = s / b, b = sqrt(r^2 + c^2), of curvature
/// kappa = r / b^2 and torsion tau = c / b^2, twisted at the rate gamma (u3), is in equilibrium
/// under a constant force n = F e_z with the moment m = EI kappa B + GJ gamma T (T, N, B its
/// Frenet frame). Then m' = kappa (GJ gamma - EI tau) N, and m' = -T x n = F (r / b) N, so
/// F = sqrt(kappa^2 + tau^2) (GJ gamma - EI tau). The material frame starts at (N, B, T) and
/// turns about T relative to the Frenet frame at gamma - tau: d1 = cos psi N + sin psi B,
/// d2 = -sin psi N + cos psi B, psi = (gamma - tau) s. All of it moved by (R0, p0).
TEST(SpatialRod, KirchhoffHelixUnderAxialForceAndMoment) {
  const SpatialRod<double> rod = steel_rod();
  const double L = rod.length, ei = rod.bending_stiffness(), gj = rod.torsional_stiffness();
  struct Helix {
    double kappa, tau, gamma;  // 1/m
  };
  // Tension, compression, a left-handed helix; 3 to 4 turns of the tangent.
  for (const Helix& helix : {Helix{15, 10, 20}, Helix{15, 10, 4}, Helix{20, -6, 3}}) {
    const double kappa = helix.kappa, tau = helix.tau, gamma = helix.gamma;
    const double k2 = kappa * kappa + tau * tau, r = kappa / k2, c = tau / k2,
                 b = 1 / std::sqrt(k2);
    const double force = std::sqrt(k2) * (gj * gamma - ei * tau);
    const auto frame = [&](double s) {  // columns d1, d2, d3
      const double phi = s / b, psi = (gamma - tau) * s;
      const Vector3d T(-r * std::sin(phi) / b, r * std::cos(phi) / b, c / b);
      const Vector3d N(-std::cos(phi), -std::sin(phi), 0);
      const Vector3d B = T.cross(N);
      Matrix3d R;
      R << std::cos(psi) * N + std::sin(psi) * B, -std::sin(psi) * N + std::cos(psi) * B, T;
      return R;
    };
    const auto point = [&](double s) {
      return Vector3d(r * std::cos(s / b), r * std::sin(s / b), c * s / b);
    };
    const auto moment = [&](double s) {
      const Matrix3d R = frame(s);
      const Vector3d T = R.col(2);
      const Vector3d N(-std::cos(s / b), -std::sin(s / b), 0);
      return Vector3d(ei * kappa * T.cross(N) + gj * gamma * T);
    };
    SpatialRodState<double> base;
    base.position = kBasePosition + kBaseRotation * point(0);
    base.orientation = wxyz(Eigen::Quaterniond(kBaseRotation * frame(0)));
    base.force = kBaseRotation * Vector3d(0, 0, force);
    base.moment = kBaseRotation * moment(0);
    const Vector3d exact_position = kBasePosition + kBaseRotation * point(L);
    const Matrix3d exact_rotation = kBaseRotation * frame(L);
    const Vector3d exact_moment = kBaseRotation * moment(L);
    double errors[2];
    for (int k = 0; k < 2; ++k) {
      errors[k] =
          (integrate_spatial_rod(base, rod, kNoGravity, 32 << k).position - exact_position).norm();
    }
    const SpatialRodState<double> tip = integrate_spatial_rod(base, rod, kNoGravity, 512);
    const double moment_scale = std::max(ei / L, base.moment.norm());
    EXPECT_LT((tip.position - exact_position).norm(), 1e-9 * L) << "gamma " << gamma;
    EXPECT_LT(rotation_error(tip.rotation(), exact_rotation), 1e-9) << "gamma " << gamma;
    EXPECT_LT((tip.moment - exact_moment).norm(), 1e-9 * moment_scale) << "gamma " << gamma;
    EXPECT_NEAR(errors[0] / errors[1], 16.0, 2.0) << "gamma " << gamma;
    std::printf(
        "Kirchhoff helix F = %+.3f EI/L^2: tip error / L at 32, 64, 512 steps %.2e %.2e %.2e\n",
        force * L * L / ei, errors[0] / L, errors[1] / L,
        (tip.position - exact_position).norm() / L);
  }
}

// ---- Shear and extension
// --------------------------------------------------------------------------

TEST(SpatialRod, AxialForceStretchesOnlyAnExtensibleRod) {
  SpatialRod<double> rod = steel_rod();
  const double L = rod.length, force = 50.0;  // N: 0.03% strain
  const Vector3d axis = kBaseRotation.col(2);
  const SpatialRodState<double> base = base_state(kBaseRotation, force * axis, Vector3d::Zero());
  const SpatialRodState<double> kirchhoff = integrate_spatial_rod(base, rod, kNoGravity, 16);
  EXPECT_LT((kirchhoff.position - (kBasePosition + L * axis)).norm(), 1e-15 * L);
  rod.shear_and_extension = true;
  const SpatialRodState<double> cosserat = integrate_spatial_rod(base, rod, kNoGravity, 16);
  const Vector3d stretched = kBasePosition + L * (1 + force / rod.axial_stiffness()) * axis;
  EXPECT_LT((cosserat.position - stretched).norm(), 1e-15 * L);
  // Rounding only (a force of 200 EI / L^2 amplifies it).
  EXPECT_LT(rotation_error(cosserat.rotation(), kBaseRotation), 1e-13);
  EXPECT_LT(rotation_error(kirchhoff.rotation(), kBaseRotation), 1e-13);
}

/// A transverse force on a free end shears the section by F / GA on top of the bending: on a
/// short thick rod the tip deflection is F L^3 / (3 EI) + F L / GA to first order (Timoshenko's
/// cantilever with shear coefficient 1).
TEST(SpatialRod, ShearAddsTimoshenkoDeflection) {
  SpatialRod<double> rod = steel_rod();
  rod.length = 0.005;  // 5 diameters: shear is 2% of the deflection
  rod.shear_and_extension = true;
  const double L = rod.length, ei = rod.bending_stiffness(), force = 1e-4 * ei / (L * L);
  const SpatialRodState<double> base =
      base_state(Matrix3d::Identity(), Vector3d(force, 0, 0), Vector3d(0, force * L, 0));
  const SpatialRodState<double> tip = integrate_spatial_rod(base, rod, kNoGravity, 64);
  const double bending = force * L * L * L / (3 * ei), shear = force * L / rod.shear_stiffness();
  // n(0) = F e1 and m(0) = F L e2 leave m(L) = 0 to first order: the tip is pushed by
  // n(L) = F e1 and deflects along +e1.
  EXPECT_NEAR(tip.position.x() - kBasePosition.x(), bending + shear, 1e-4 * (bending + shear));
  EXPECT_GT(shear, 0.015 * bending);
}

// ---- 4. The planar case
// --------------------------------------------------------------------------

/// The planar rod (x, y, theta) in the world's y-z plane, bending about the world x axis: planar
/// x -> world y, planar y -> world z, so that d3 = (0, cos theta, sin theta) and the orientation
/// is a rotation about x by phi = theta - pi/2, the quaternion (cos phi/2, sin phi/2, 0, 0). Its
/// zeros stay exact: the out-of-plane components are exactly zero, not small.
SpatialRodState<double> spatial_of_planar(const RodState<double>& planar) {
  const double phi = planar.theta - M_PI / 2;
  SpatialRodState<double> state;
  state.position = Vector3d(0, planar.x, planar.y);
  state.orientation = Vector4d(std::cos(phi / 2), std::sin(phi / 2), 0, 0);
  state.force = Vector3d(0, planar.nx, planar.ny);
  state.moment = Vector3d(planar.m, 0, 0);
  return state;
}

TEST(SpatialRod, PlanarRodMatchesThePlanarCore) {
  const SpatialRod<double> steel = steel_rod();
  const double L = steel.length, ei = steel.bending_stiffness();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1, 1);
  double worst = 0, worst_default = 0;
  for (int i = 0; i < 20; ++i) {
    const RodState<double> start{0.01 * unit(rng),
                                 0.01 * unit(rng),
                                 M_PI * unit(rng),
                                 3 * ei / (L * L) * unit(rng),
                                 3 * ei / (L * L) * unit(rng),
                                 3 * ei / L * unit(rng)};
    SpatialRod<double> rod = steel;
    const double precurvature = i % 2 ? 2.0 / L * unit(rng) : 0.0;
    rod.intrinsic_curvature = Vector3d(precurvature, 0, 0);
    rod.shear_and_extension = i % 4 >= 2;  // Kirchhoff only, below, except for the exact zeros
    const Rod<double> planar_rod{L, steel.diameter, steel.young_modulus, precurvature};
    const int steps = 1024;
    const RodState<double> planar = integrate_rod(start, planar_rod, steps);
    const SpatialRodState<double> tip =
        integrate_spatial_rod(spatial_of_planar(start), rod, kNoGravity, steps);
    const RodState<double> planar_default =
        integrate_rod(start, planar_rod, kDefaultSpatialRodSteps);
    const SpatialRodState<double> tip_default =
        integrate_spatial_rod(spatial_of_planar(start), rod, kNoGravity);
    // Exactly in the plane, whatever the law.
    EXPECT_EQ(tip.position.x(), 0.0) << i;
    EXPECT_EQ(tip.orientation[2], 0.0) << i;
    EXPECT_EQ(tip.orientation[3], 0.0) << i;
    EXPECT_EQ(tip.force.x(), 0.0) << i;
    EXPECT_EQ(tip.moment.y(), 0.0) << i;
    EXPECT_EQ(tip.moment.z(), 0.0) << i;
    const Matrix3d R = tip.rotation();
    EXPECT_EQ(R(0, 0), 1.0);
    EXPECT_EQ(R(0, 2), 0.0);
    if (rod.shear_and_extension) continue;
    // The two RK4 discretisations differ (the planar core steps (cos, sin) of theta, the spatial
    // rod the half-angle quaternion), both within ~1e-13 L of the exact rod at 1024 steps.
    const double error =
        std::max({std::abs(tip.position.y() - planar.x), std::abs(tip.position.z() - planar.y),
                  L * std::abs(R(1, 2) - std::cos(planar.theta)),
                  L * std::abs(R(2, 2) - std::sin(planar.theta)),
                  L * std::abs(tip.moment.x() - planar.m) / (ei / L + std::abs(start.m))});
    EXPECT_LT(error, 1e-12 * L) << i;
    worst = std::max(worst, error / L);
    const double error_default = std::max(std::abs(tip_default.position.y() - planar_default.x),
                                          std::abs(tip_default.position.z() - planar_default.y));
    EXPECT_LT(error_default, 1e-9 * L) << i;
    worst_default = std::max(worst_default, error_default / L);
  }
  std::printf(
      "planar rod: worst tip difference from the planar core %.2e L at 1024 steps, %.2e L at "
      "%d\n",
      worst, worst_default, kDefaultSpatialRodSteps);
}

// ---- CVODE reference and random rods
// -------------------------------------------------------------

/// A rod, a proximal state and gravity drawn in the documented ranges: L in [0.05, 0.5] m,
/// d in [0.5, 2] mm, E in [50, 210] GPa, Poisson's ratio in [0.25, 0.35], rho in [2000, 8000]
/// kg/m^3; |n(0)| up to 3 EI / L^2 and |m(0)| up to 3 EI / L in uniform directions; a uniform
/// base orientation and a base position in a 0.2 m cube. Flags (bits of `variant`): 1 gravity
/// (9.81 m/s^2 in a uniform direction), 2 an intrinsic curvature (each component up to 2 / L),
/// 4 shear and extension.
struct RodCase {
  SpatialRodState<double> base;
  SpatialRod<double> rod;
  Vector3d gravity = Vector3d::Zero();
  double moment_scale = 0;  ///< max(EI / L, |m(0)|, |n(0)| L, |f| L^2) (N m)
};

Vector3d uniform_direction(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
}

RodCase random_rod(std::mt19937& rng, int variant) {
  std::uniform_real_distribution<double> unit(0, 1);
  const auto draw = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  RodCase c;
  c.rod.length = draw(0.05, 0.5);
  c.rod.diameter = draw(0.5e-3, 2e-3);
  c.rod.young_modulus = draw(50e9, 210e9);
  c.rod.shear_modulus = c.rod.young_modulus / (2 * (1 + draw(0.25, 0.35)));
  c.rod.density = draw(2000, 8000);
  const double L = c.rod.length, ei = c.rod.bending_stiffness();
  if (variant & 2) {
    c.rod.intrinsic_curvature = Vector3d(draw(-2, 2), draw(-2, 2), draw(-2, 2)) / L;
  }
  c.rod.shear_and_extension = (variant & 4) != 0;
  if (variant & 1) c.gravity = 9.81 * uniform_direction(rng);
  std::normal_distribution<double> normal;
  c.base.position = Vector3d(draw(-0.1, 0.1), draw(-0.1, 0.1), draw(-0.1, 0.1));
  c.base.orientation = Vector4d(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
  c.base.force = draw(0, 3) * ei / (L * L) * uniform_direction(rng);
  c.base.moment = draw(0, 3) * ei / L * uniform_direction(rng);
  c.moment_scale = std::max({ei / L, c.base.moment.norm(), c.base.force.norm() * L,
                             c.rod.mass_per_length() * c.gravity.norm() * L * L});
  return c;
}

std::vector<RodCase> random_rods(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<RodCase> cases;
  for (int i = 0; i < count; ++i) cases.push_back(random_rod(rng, i % 8));
  return cases;
}

/// Distances between two tip states, each in its scale: position / L, orientation (rad),
/// moment / moment_scale; the force is exact in both.
struct TipError {
  double position = 0, orientation = 0, moment = 0;
  double max() const { return std::max({position, orientation, moment}); }
};
TipError tip_error(const SpatialRodState<double>& a, const SpatialRodState<double>& b,
                   const RodCase& c) {
  return TipError{(a.position - b.position).norm() / c.rod.length,
                  rotation_error(a.rotation(), b.rotation()),
                  (a.moment - b.moment).norm() / c.moment_scale};
}

TEST(SpatialRodReference, AgreesWithItselfAtTighterTolerances) {
  // CVODE's own error, so that the comparisons below measure RK4's: Adams at the default
  // tolerances against BDF at tolerances 10 times tighter.
  ReferenceOptions tight;
  tight.method = ReferenceOptions::Method::kBdf;
  tight.relative_tolerance = 1e-13;
  tight.absolute_tolerance = 1e-15;
  double worst = 0;
  for (const RodCase& c : random_rods(16, 3)) {
    const auto a = integrate_spatial_rod_reference(c.base, c.rod, c.gravity);
    const auto b = integrate_spatial_rod_reference(c.base, c.rod, c.gravity, tight);
    const TipError e = tip_error(a, b, c);
    EXPECT_LT(e.max(), 1e-10);
    worst = std::max(worst, e.max());
    EXPECT_EQ(a.force, b.force);
  }
  std::printf("CVODE default vs tight tolerances: worst %.2e\n", worst);
}

TEST(SpatialRodReference, MatchesTheClosedFormArc) {
  const SpatialRod<double> rod = steel_rod();
  const double L = rod.length, kappa = 5.0 / L;
  const Vector3d axis(0.6, 0.8, 0);
  const SpatialRodState<double> base = base_state(
      kBaseRotation, Vector3d::Zero(), rod.bending_stiffness() * kappa * (kBaseRotation * axis));
  const Arc exact = bent_arc(kBaseRotation, kBasePosition, axis, kappa, L);
  const SpatialRodState<double> tip = integrate_spatial_rod_reference(base, rod, Vector3d::Zero());
  EXPECT_LT((tip.position - exact.position).norm(), 1e-10 * L);
  EXPECT_LT(rotation_error(tip.rotation(), exact.rotation), 1e-10);
}

TEST(SpatialRodReference, RejectsBadInput) {
  const SpatialRod<double> rod = steel_rod();
  const SpatialRodState<double> base;
  const Vector3d g = Vector3d::Zero();
  SpatialRod<double> bad = rod;
  bad.shear_modulus = 0;
  EXPECT_THROW(integrate_spatial_rod_reference(base, bad, g), std::invalid_argument);
  bad = rod;
  bad.length = -1;
  EXPECT_THROW(integrate_spatial_rod_reference(base, bad, g), std::invalid_argument);
  bad = rod;
  bad.intrinsic_curvature.y() = std::nan("");
  EXPECT_THROW(integrate_spatial_rod_reference(base, bad, g), std::invalid_argument);
  SpatialRodState<double> zero = base;
  zero.orientation.setZero();
  EXPECT_THROW(integrate_spatial_rod_reference(zero, rod, g), std::invalid_argument);
  EXPECT_THROW(integrate_spatial_rod_reference(base, rod, Vector3d(0, 0, HUGE_VAL)),
               std::invalid_argument);
  ReferenceOptions tiny;
  tiny.max_steps = 3;
  SpatialRodState<double> bent = base;
  bent.moment.x() = 5 * rod.bending_stiffness() / rod.length;
  EXPECT_THROW(integrate_spatial_rod_reference(bent, rod, g, tiny), std::runtime_error);
}

/// Random rods against CVODE: the error curve over the step count, the default's worst, fourth
/// order, and the drift of |h|.
TEST(SpatialRod, RandomRodsMatchCvode) {
  const std::vector<RodCase> cases = random_rods(64, 1);
  const int step_counts[] = {16, 32, 64, 128, 256, 512};
  constexpr int kCounts = 6;
  std::vector<SpatialRodState<double>> reference;
  for (const RodCase& c : cases) {
    reference.push_back(integrate_spatial_rod_reference(c.base, c.rod, c.gravity));
  }
  double worst[kCounts] = {}, worst_drift[kCounts] = {};
  double worst_default = 0, worst_default_drift = 0;
  int worst_case = -1;
  // The frame's total turn int |u| ds (rad), which sets RK4's error: C L (turn / steps)^4.
  const auto total_turn = [](const RodCase& c) {
    double turn = 0;
    Matrix3d last = c.base.rotation();
    sample_spatial_rod(c.base, c.rod, c.gravity, 512,
                       [&](double, const SpatialRodState<double>& state) {
                         turn += rotation_error(last, state.rotation());
                         last = state.rotation();
                       });
    return turn;
  };
  double largest_turn = 0;
  double ratio_range[2] = {HUGE_VAL, 0};
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const RodCase& c = cases[i];
    double errors[kCounts];
    for (int k = 0; k < kCounts; ++k) {
      const SpatialRodState<double> tip =
          integrate_spatial_rod(c.base, c.rod, c.gravity, step_counts[k]);
      errors[k] = tip_error(tip, reference[i], c).max();
      worst[k] = std::max(worst[k], errors[k]);
      worst_drift[k] = std::max(worst_drift[k], std::abs(1 - tip.orientation.norm()));
    }
    // Fourth order where the error is well above CVODE's (1e-12): 16 times less per doubling.
    EXPECT_GT(errors[1] / errors[2], 14.0) << "rod " << i;
    EXPECT_LT(errors[1] / errors[2], 18.0) << "rod " << i;
    ratio_range[0] = std::min(ratio_range[0], errors[1] / errors[2]);
    ratio_range[1] = std::max(ratio_range[1], errors[1] / errors[2]);
    const SpatialRodState<double> tip = integrate_spatial_rod(c.base, c.rod, c.gravity);
    const TipError e = tip_error(tip, reference[i], c);
    EXPECT_LT(e.position, 1e-9) << "rod " << i;
    EXPECT_LT(e.orientation, 1e-9) << "rod " << i;
    EXPECT_LT(e.moment, 1e-9) << "rod " << i;
    const Vector3d tip_force = c.base.force - c.rod.length * c.rod.mass_per_length() * c.gravity;
    // n' = -f is constant: RK4 integrates it exactly, up to the rounding of 256 additions.
    EXPECT_LT((tip.force - tip_force).norm(), 1e-13 * c.moment_scale / c.rod.length);
    const double drift = std::abs(1 - tip.orientation.norm());
    EXPECT_LT(drift, 1e-10) << "rod " << i;
    if (e.max() > worst_default) {
      worst_default = e.max();
      worst_case = static_cast<int>(i);
    }
    worst_default_drift = std::max(worst_default_drift, drift);
    largest_turn = std::max(largest_turn, total_turn(c));
  }
  std::printf("random rods against CVODE (worst of %zu; position / L, rad, moment / scale):\n",
              cases.size());
  for (int k = 0; k < kCounts; ++k) {
    std::printf("  %4d steps: tip %.2e, |1 - |h|| %.2e\n", step_counts[k], worst[k],
                worst_drift[k]);
  }
  std::printf("  default %d steps: worst %.2e (rod %d, turning through %.2f rad), |1 - |h|| %.2e\n",
              kDefaultSpatialRodSteps, worst_default, worst_case, total_turn(cases[worst_case]),
              worst_default_drift);
  std::printf("  largest total turn int |u| ds: %.2f rad\n", largest_turn);
  std::printf("  error ratio 32 -> 64 steps: %.1f to %.1f\n", ratio_range[0], ratio_range[1]);
  const RodCase& w = cases[worst_case];
  const double ei = w.rod.bending_stiffness(), L = w.rod.length;
  std::printf(
      "  worst rod: L %.3f m, d %.2f mm, |n(0)| %.2f EI/L^2, |m(0)| %.2f EI/L, |u*| L %.2f, "
      "q L^3/EI %.2f, %s\n",
      L, 1e3 * w.rod.diameter, w.base.force.norm() * L * L / ei, w.base.moment.norm() * L / ei,
      w.rod.intrinsic_curvature.norm() * L,
      w.rod.mass_per_length() * w.gravity.norm() * L * L * L / ei,
      w.rod.shear_and_extension ? "shear and extension" : "Kirchhoff");
}

// ---- 5. Gravity: a cantilever under its own weight ----------------------------------------------

/// A horizontal cantilever (clamped along world x) with a free tip: n(0) = f L carries the weight
/// and m(0) is shot so that m(L) = 0, by Newton with the RK4 sensitivity as matrix (quasi-Newton
/// for CVODE, whose fixed point is its own).
template <class Integrate>
SpatialRodState<double> cantilever(const SpatialRod<double>& rod, const Vector3d& gravity,
                                   Integrate&& integrate, SpatialRodState<double>* base_out) {
  SpatialRodState<double> base;
  base.orientation = wxyz(Eigen::Quaterniond(rotation_about(Vector3d::UnitY(), M_PI / 2)));
  base.force = rod.mass_per_length() * rod.length * gravity;
  SpatialRodState<double> tip;
  for (int iteration = 0; iteration < 12; ++iteration) {
    tip = integrate(base);
    const Matrix3d J = integrate_spatial_rod_with_sensitivity(base, rod, gravity, 256)
                           .sensitivity.block<3, 3>(Index::kMoment, 3);
    base.moment -= J.lu().solve(tip.moment);
  }
  *base_out = base;
  return integrate(base);
}

TEST(SpatialRod, CantileverUnderItsOwnWeightMatchesCvode) {
  const Vector3d gravity(0, 0, -9.81);
  for (bool shear : {false, true}) {
    SpatialRod<double> rod = steel_rod();
    rod.length = 0.5;
    rod.diameter = 0.5e-3;
    rod.shear_and_extension = shear;
    const double L = rod.length, ei = rod.bending_stiffness();
    const double load = rod.mass_per_length() * 9.81 * L * L * L / ei;  // q L^3 / EI
    SpatialRodState<double> rk4_base, cvode_base;
    const SpatialRodState<double> rk4 = cantilever(
        rod, gravity,
        [&](const SpatialRodState<double>& b) { return integrate_spatial_rod(b, rod, gravity); },
        &rk4_base);
    const SpatialRodState<double> cvode = cantilever(
        rod, gravity,
        [&](const SpatialRodState<double>& b) {
          return integrate_spatial_rod_reference(b, rod, gravity);
        },
        &cvode_base);
    EXPECT_GT(load, 3.0);  // a large deflection
    EXPECT_LT(rk4.moment.norm(), 1e-14 * ei / L);
    EXPECT_LT(cvode.moment.norm(), 1e-11 * ei / L);
    EXPECT_LT(rk4.force.norm(), 1e-13 * rod.mass_per_length() * 9.81 * L);
    EXPECT_LT((rk4.position - cvode.position).norm(), 1e-9 * L);
    EXPECT_LT(rotation_error(rk4.rotation(), cvode.rotation()), 1e-9);
    EXPECT_LT((rk4_base.moment - cvode_base.moment).norm(), 1e-9 * ei / L);
    // It sags in the x-z plane.
    EXPECT_LT(rk4.position.z(), -0.25 * L);
    EXPECT_EQ(rk4.position.y(), 0.0);
    std::printf("cantilever q L^3 / EI = %.2f%s: sag %.4f L, RK4 - CVODE %.2e L\n", load,
                shear ? " (shear)" : "", -rk4.position.z() / L,
                (rk4.position - cvode.position).norm() / L);
  }
}

TEST(SpatialRod, LightCantileverSagsAsALinearBeam) {
  SpatialRod<double> rod = steel_rod();
  const double L = rod.length, ei = rod.bending_stiffness();
  // Gravity scaled so that q L^3 / EI = 1e-3: the nonlinear terms are 1e-6 of the sag.
  const double q = 1e-3 * ei / (L * L * L);
  const Vector3d gravity(0, 0, -q / rod.mass_per_length());
  SpatialRodState<double> base;
  const SpatialRodState<double> tip = cantilever(
      rod, gravity,
      [&](const SpatialRodState<double>& b) { return integrate_spatial_rod(b, rod, gravity); },
      &base);
  const double sag = q * L * L * L * L / (8 * ei);
  EXPECT_NEAR(-tip.position.z(), sag, 1e-5 * sag);
  EXPECT_NEAR(base.moment.y(), q * L * L / 2, 1e-5 * q * L * L / 2);
}

// ---- 7. Sensitivity
// -------------------------------------------------------------------------------

TEST(SpatialRod, SensitivityMatchesCentralDifferences) {
  double worst = 0;
  for (const RodCase& c : random_rods(16, 5)) {
    const double L = c.rod.length, ei = c.rod.bending_stiffness();
    const SpatialRodTip<double> tip =
        integrate_spatial_rod_with_sensitivity(c.base, c.rod, c.gravity);
    // The same integration as without the sensitivity, to the bit.
    EXPECT_EQ(tip.state.vector(), integrate_spatial_rod(c.base, c.rod, c.gravity).vector());
    for (int j = 0; j < 6; ++j) {
      const double delta = 1e-5 * (j < 3 ? ei / (L * L) : ei / L);
      SpatialRodState<double> plus = c.base, minus = c.base;
      (j < 3 ? plus.force : plus.moment)[j % 3] += delta;
      (j < 3 ? minus.force : minus.moment)[j % 3] -= delta;
      const SpatialRodVector<double> fd =
          (integrate_spatial_rod(plus, c.rod, c.gravity).vector() -
           integrate_spatial_rod(minus, c.rod, c.gravity).vector()) /
          (2 * delta);
      // Each block of rows (p, h, n, m) relative to its largest entry in the column.
      for (const auto& [first, size] : {std::pair<int, int>{Index::kPosition, 3},
                                        {Index::kOrientation, 4},
                                        {Index::kMoment, 3}}) {
        const double scale = fd.segment(first, size).cwiseAbs().maxCoeff();
        const double error = (tip.sensitivity.col(j).segment(first, size) - fd.segment(first, size))
                                 .cwiseAbs()
                                 .maxCoeff();
        EXPECT_LT(error, 1e-6 * scale) << "column " << j << " rows " << first;
        worst = std::max(worst, error / scale);
      }
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(tip.sensitivity(Index::kForce + k, j), j == k ? 1.0 : 0.0);
      }
    }
  }
  std::printf("sensitivity against central differences: worst %.2e relative\n", worst);
}

// ---- Rods in SIMD lanes -------------------------------------------------------------------------

TEST(SpatialRod, RodsInLanesMatchRodsAlone) {
  // integrate_spatial_rods steps the rods of a residual together, one per lane, with the same
  // operations in the same order as each rod alone: the same tips to the bit. Every bundle size
  // (2, 4, 8 lanes, some idle), rods of all kinds mixed (curved, sheared and extended, Kirchhoff),
  // one gravity for all as in a robot. A compiler free to fuse a * b + c into an FMA
  // (-march=native) may fuse in one path and not in the other.
#ifdef __FMA__
  const double tolerance = 1e-13;
#else
  const double tolerance = 0.0;
#endif
  const std::vector<RodCase> cases = random_rods(8, 17);
  const Vector3d gravity(0, 0, -9.81);
  constexpr int kSteps = 40;
  for (int n = 1; n <= 8; ++n) {
    SpatialRodState<double> bases[8], tips[8];
    SpatialRod<double> rods[8];
    for (int i = 0; i < n; ++i) {
      // Shift which kinds share a bundle with n.
      const RodCase& c = cases[static_cast<std::size_t>((i + n) % 8)];
      bases[i] = c.base;
      rods[i] = c.rod;
    }
    integrate_spatial_rods(bases, rods, n, gravity, kSteps, tips);
    for (int i = 0; i < n; ++i) {
      const SpatialRodVector<double> alone =
          integrate_spatial_rod(bases[i], rods[i], gravity, kSteps).vector();
      const SpatialRodVector<double> lanes = tips[i].vector();
      for (int k = 0; k < SpatialRodIndex::kSize; ++k) {
        EXPECT_NEAR(lanes[k], alone[k], tolerance * std::abs(alone[k]))
            << "state " << k << ", rod " << i << " of " << n;
      }
    }
  }
}

// ---- The quaternion's scale, the sampler --------------------------------------------------------

TEST(SpatialRod, QuaternionScaleDoesNotChangeTheRod) {
  // rotation_of divides by |h|^2 and h' is linear in h: a scaled base quaternion gives the same
  // rod, its tip quaternion scaled alike.
  for (const RodCase& c : random_rods(8, 9)) {
    SpatialRodState<double> scaled = c.base;
    scaled.orientation *= 4.0;  // a power of 2: every product scales exactly
    const SpatialRodState<double> a = integrate_spatial_rod(c.base, c.rod, c.gravity);
    const SpatialRodState<double> b = integrate_spatial_rod(scaled, c.rod, c.gravity);
    EXPECT_LT((a.position - b.position).norm(), 1e-14 * c.rod.length);
    EXPECT_LT((4.0 * a.orientation - b.orientation).norm(), 1e-13);
  }
}

TEST(SpatialRod, SampledShapeVisitsEveryNode) {
  const RodCase c = random_rods(8, 13)[7];
  int count = 0;
  double last_s = -1;
  SpatialRodState<double> last;
  const SpatialRodState<double> tip =
      sample_spatial_rod(c.base, c.rod, c.gravity, 24, [&](double s, const auto& state) {
        if (count == 0) {
          EXPECT_EQ(state.vector(), c.base.vector());
        }
        EXPECT_GT(s, last_s);
        last_s = s;
        last = state;
        ++count;
      });
  EXPECT_EQ(count, 25);
  EXPECT_NEAR(last_s, c.rod.length, 1e-15);
  EXPECT_EQ(last.vector(), tip.vector());
  EXPECT_EQ(tip.vector(), integrate_spatial_rod(c.base, c.rod, c.gravity, 24).vector());
}

}  // namespace
}  // namespace pcr
