#pragma once
// Spatial Cosserat rod, integrated by fixed-step RK4: the rod model of the continuum
// Stewart-Gough robot (Black, Till and Rucker, IEEE T-RO 34(1), 2018), the spatial counterpart
// of the planar Kirchhoff rod of pcr/rod.hpp.
//
// State at arc length s, all in the world frame, 13 numbers:
//   p  centreline position (m)
//   h  orientation, a quaternion (w, x, y, z); R = rotation_of(h) maps the body frame to the
//      world, and d3 = R e3 is the tangent of the stress-free rod
//   n  internal force (N) and m internal moment (N m), exerted by the material beyond s (larger
//      arc length) on the material before it, as in pcr/rod.hpp: n(0), m(0) is what the rod
//      exerts on its proximal clamp, and -n(L), -m(L) what it exerts on whatever holds its tip.
//
// Equilibrium and kinematics:
//   p' = R v,   h' = h (x) (0, u) / 2,   n' = -f,   m' = -p' x n
// with the linear constitutive law of a circular section of diameter d
//   m = R K_bt (u - u*),  K_bt = diag(EI, EI, GJ),  I = pi d^4 / 64, J = 2 I
//   n = R K_se (v - v*),  K_se = diag(GA, GA, EA),  A = pi d^2 / 4,  v* = e3
// so that u = K_bt^-1 R^T m + u* and v = K_se^-1 R^T n + e3. u* is the intrinsic curvature (body
// frame, constant along the rod; zero for a straight rod). f = rho A g is the rod's weight per
// unit of stress-free length under gravity g. There is no distributed moment.
//
// Kirchhoff (the default, like the planar core): the rod is inextensible and unshearable, v = e3
// exactly and n has no constitutive law. With SpatialRod::shear_and_extension the rod shears and
// stretches by the law above (Timoshenko's shear coefficient taken as 1, as Black, Till and
// Rucker do). For the robots' slender rods (d / L < 1/25) the difference is of order
// (d / L)^2 of the bending: below a micrometre, but not below the accuracy the solvers target.
//
// Why a quaternion and not R itself: 13 states instead of 18, and 13 x 6 tangents instead of
// 18 x 6. h' = h (x) (0, u) / 2 keeps |h| constant exactly; RK4 keeps it to its own order only
// (|h| drifts by O(step^4) over the rod). The stepper never renormalises h, which would make the
// step a different map from the one the tangents differentiate; rotation_of divides by |h|^2
// instead, so R is a rotation whatever |h|.
//
// The tangents of the tip state w.r.t. the proximal wrench (n, m)(0) are RK4 applied to the
// variational equations, stage by stage: exactly the derivative of the discrete map, as
// pcr/rod.hpp does for the planar rod. Their right-hand side uses the body-frame increment of
// the rotation, dR = R [w]x with w = 2 vec(conj(h) (x) dh) / |h|^2:
//   du  = K_bt^-1 (R^T dm + (R^T m) x w)
//   dv  = K_se^-1 (R^T dn + (R^T n) x w)            (0 for a Kirchhoff rod)
//   dp' = R (w x v + dv),   dh' = (dh (x) (0, u) + h (x) (0, du)) / 2,
//   dn' = 0,   dm' = n x dp' + dn x p'

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <cmath>

#include "pcr/rod.hpp"
#include "pcr/spatial/quaternion.hpp"

namespace pcr {

/// RK4 steps per rod by default: they keep the tip within 1e-9 L (position / L, orientation in
/// rad, moment / max(EI / L, |m(0)|, |n(0)| L, |f| L^2)) of the exact model on the random rods
/// of tests/test_spatial_rod.cpp (up to 3 EI / L^2 of force, 3 EI / L of moment, intrinsic
/// curvature and gravity; the frame turning through up to 4.7 rad). Measured worst against
/// CVODE: 1.0e-7 at 64 steps, 6.4e-9 at 128, 4.0e-10 at 256, 3.1e-11 at 512 (fourth order: 16
/// times less per doubling). RK4's error grows as (total turn / steps)^4.
constexpr int kDefaultSpatialRodSteps = 256;

/// One spatial rod: a circular section of constant diameter, a linear elastic material, and a
/// constant intrinsic curvature. SI units.
template <class T>
struct SpatialRod {
  T length{0};         ///< stress-free length L (m)
  T diameter{0};       ///< d (m)
  T young_modulus{0};  ///< E (Pa)
  T shear_modulus{0};  ///< G (Pa): E / (2 (1 + nu)) for an isotropic material
  T density{0};        ///< rho (kg/m^3): the weight per unit length rho A g under gravity g
  /// u* (1/m) in the body frame: (u1*, u2*) the curvature of the stress-free rod about the body
  /// axes d1, d2, u3* its twist. Zero for a straight rod; constant u* makes a helix (or an arc).
  Vector3<T> intrinsic_curvature = Vector3<T>::Zero();
  /// false: Kirchhoff (inextensible, unshearable); true: Cosserat, with shear and extension.
  bool shear_and_extension = false;

  /// EI (N m^2), the same formula as the planar rod's.
  T bending_stiffness() const { return pcr::bending_stiffness(young_modulus, diameter); }
  /// GJ (N m^2), J = 2 I for a circular section.
  T torsional_stiffness() const { return T(2) * pcr::bending_stiffness(shear_modulus, diameter); }
  /// GA (N), shear coefficient 1.
  T shear_stiffness() const { return shear_modulus * section_area(diameter); }
  /// EA (N).
  T axial_stiffness() const { return young_modulus * section_area(diameter); }
  /// rho A (kg/m).
  T mass_per_length() const { return density * section_area(diameter); }

  template <class U>
  SpatialRod<U> cast() const {
    SpatialRod<U> rod;
    rod.length = U(length);
    rod.diameter = U(diameter);
    rod.young_modulus = U(young_modulus);
    rod.shear_modulus = U(shear_modulus);
    rod.density = U(density);
    rod.intrinsic_curvature = intrinsic_curvature.template cast<U>();
    rod.shear_and_extension = shear_and_extension;
    return rod;
  }
};

/// Where each part of the state sits in SpatialRodVector (and in the rows of the sensitivity).
struct SpatialRodIndex {
  static constexpr int kPosition = 0;     ///< p: 3 rows
  static constexpr int kOrientation = 3;  ///< h: 4 rows, (w, x, y, z)
  static constexpr int kForce = 7;        ///< n: 3 rows
  static constexpr int kMoment = 10;      ///< m: 3 rows
  static constexpr int kSize = 13;
};

template <class T>
using SpatialRodVector = Eigen::Matrix<T, SpatialRodIndex::kSize, 1>;
/// d state / d (n, m)(0): 13 rows as SpatialRodVector, columns (n_x, n_y, n_z, m_x, m_y, m_z).
template <class T>
using SpatialRodSensitivity = Eigen::Matrix<T, SpatialRodIndex::kSize, 6>;

/// The rod's state at one arc length, in the world frame.
template <class T>
struct SpatialRodState {
  Vector3<T> position = Vector3<T>::Zero();           ///< p (m)
  Vector4<T> orientation = identity_quaternion<T>();  ///< h (w, x, y, z), body -> world
  Vector3<T> force = Vector3<T>::Zero();              ///< n (N), see the sign convention
  Vector3<T> moment = Vector3<T>::Zero();             ///< m (N m)

  /// R (body -> world) of h / |h|.
  Matrix3<T> rotation() const { return rotation_of(orientation); }

  SpatialRodVector<T> vector() const {
    SpatialRodVector<T> y;
    y << position, orientation, force, moment;
    return y;
  }
  static SpatialRodState from_vector(const SpatialRodVector<T>& y) {
    SpatialRodState state;
    state.position = y.template segment<3>(SpatialRodIndex::kPosition);
    state.orientation = y.template segment<4>(SpatialRodIndex::kOrientation);
    state.force = y.template segment<3>(SpatialRodIndex::kForce);
    state.moment = y.template segment<3>(SpatialRodIndex::kMoment);
    return state;
  }
};

/// The distal state of a rod plus its sensitivity to the proximal wrench.
template <class T>
struct SpatialRodTip {
  SpatialRodState<T> state;
  /// d(p, h, n, m)(L) / d(n, m)(0). The n rows are (I 0): n(L) = n(0) - f L.
  SpatialRodSensitivity<T> sensitivity;
};

namespace internal {

/// The per-rod constants of the right-hand side.
template <class T>
struct SpatialRodLaw {
  Vector3<T> bending_compliance;   ///< (1/EI, 1/EI, 1/GJ) (1 / (N m^2))
  Vector3<T> shear_compliance;     ///< (1/GA, 1/GA, 1/EA) (1/N); unused by a Kirchhoff rod
  Vector3<T> intrinsic_curvature;  ///< u* (1/m), body frame
  Vector3<T> distributed_force;    ///< f = rho A g (N/m), world frame
  bool shear_and_extension = false;

  SpatialRodLaw(const SpatialRod<T>& rod, const Vector3<T>& gravity) {
    const T inv_ei = T(1) / rod.bending_stiffness(), inv_ga = T(1) / rod.shear_stiffness();
    bending_compliance << inv_ei, inv_ei, T(1) / rod.torsional_stiffness();
    shear_compliance << inv_ga, inv_ga, T(1) / rod.axial_stiffness();
    intrinsic_curvature = rod.intrinsic_curvature;
    distributed_force = rod.mass_per_length() * gravity;
    shear_and_extension = rod.shear_and_extension;
  }
};

/// The right-hand side at one RK4 stage and what its linearisation needs.
template <class T>
struct SpatialRodSlope {
  SpatialRodVector<T> dy;  ///< (p', h', n', m')
  Matrix3<T> R;
  Vector4<T> h;
  Vector3<T> n;
  Vector3<T> p_prime;
  Vector3<T> u, v;         ///< body-frame curvature (1/m) and strain
  Vector3<T> body_moment;  ///< R^T m (N m)
  Vector3<T> body_force;   ///< R^T n (N), with shear and extension only
  T two_over_norm2;        ///< 2 / |h|^2

  void evaluate(const SpatialRodLaw<T>& law, const SpatialRodVector<T>& y) {
    h = y.template segment<4>(SpatialRodIndex::kOrientation);
    n = y.template segment<3>(SpatialRodIndex::kForce);
    const Vector3<T> m = y.template segment<3>(SpatialRodIndex::kMoment);
    R = rotation_of(h);
    two_over_norm2 = T(2) / h.squaredNorm();
    body_moment.noalias() = R.transpose() * m;
    u = law.bending_compliance.cwiseProduct(body_moment) + law.intrinsic_curvature;
    if (law.shear_and_extension) {
      body_force.noalias() = R.transpose() * n;
      v = law.shear_compliance.cwiseProduct(body_force);
      v[2] += T(1);
      p_prime.noalias() = R * v;
    } else {
      v = Vector3<T>(T(0), T(0), T(1));
      p_prime = R.col(2);
    }
    dy.template segment<3>(SpatialRodIndex::kPosition) = p_prime;
    dy.template segment<4>(SpatialRodIndex::kOrientation) = T(0.5) * quaternion_times_vector(h, u);
    dy.template segment<3>(SpatialRodIndex::kForce) = -law.distributed_force;
    dy.template segment<3>(SpatialRodIndex::kMoment) = n.cross(p_prime);
  }

  /// The variational right-hand side of the tangent columns t at this stage (see the header).
  void linearise(const SpatialRodLaw<T>& law, const SpatialRodSensitivity<T>& t,
                 SpatialRodSensitivity<T>& dt) const {
    const T &w = h[0], &x = h[1], &y = h[2], &z = h[3];
    for (int j = 0; j < 6; ++j) {
      const Vector4<T> dh = t.col(j).template segment<4>(SpatialRodIndex::kOrientation);
      const Vector3<T> dn = t.col(j).template segment<3>(SpatialRodIndex::kForce);
      const Vector3<T> dm = t.col(j).template segment<3>(SpatialRodIndex::kMoment);
      // omega = 2 vec(conj(h) (x) dh) / |h|^2, dR = R [omega]x.
      const Vector3<T> omega =
          two_over_norm2 * Vector3<T>(w * dh[1] - x * dh[0] + z * dh[2] - y * dh[3],
                                      w * dh[2] - y * dh[0] + x * dh[3] - z * dh[1],
                                      w * dh[3] - z * dh[0] + y * dh[1] - x * dh[2]);
      const Vector3<T> du =
          law.bending_compliance.cwiseProduct(R.transpose() * dm + body_moment.cross(omega));
      Vector3<T> dp_prime;
      if (law.shear_and_extension) {
        const Vector3<T> dv =
            law.shear_compliance.cwiseProduct(R.transpose() * dn + body_force.cross(omega));
        dp_prime.noalias() = R * (omega.cross(v) + dv);
      } else {
        dp_prime = R.col(0) * omega[1] - R.col(1) * omega[0];  // R (omega x e3)
      }
      auto col = dt.col(j);
      col.template segment<3>(SpatialRodIndex::kPosition) = dp_prime;
      col.template segment<4>(SpatialRodIndex::kOrientation) =
          T(0.5) * (quaternion_times_vector(dh, u) + quaternion_times_vector(h, du));
      col.template segment<3>(SpatialRodIndex::kForce).setZero();
      col.template segment<3>(SpatialRodIndex::kMoment) = n.cross(dp_prime) + dn.cross(p_prime);
    }
  }
};

/// RK4 on the 13 states, one step at a time; with Sens, also on the 13 x 6 tangents w.r.t. the
/// proximal (n, m), stage by stage with the states (the derivative of the discrete map).
template <class T, bool Sens>
struct SpatialRodStepper {
  SpatialRodVector<T> y;
  SpatialRodSensitivity<T> tangent;  ///< with Sens
  SpatialRodLaw<T> law;
  T h, half_h, sixth_h;  ///< the step (m), its half and its sixth

  SpatialRodStepper(const SpatialRodState<T>& base, const SpatialRod<T>& rod,
                    const Vector3<T>& gravity, int steps)
      : y(base.vector()), law(rod, gravity) {
    eigen_assert(steps >= 1);
    h = rod.length / T(steps);
    half_h = h / T(2);
    sixth_h = h / T(6);
    if constexpr (Sens) {
      tangent.setZero();
      for (int j = 0; j < 3; ++j) {
        tangent(SpatialRodIndex::kForce + j, j) = T(1);
        tangent(SpatialRodIndex::kMoment + j, 3 + j) = T(1);
      }
    }
  }

  void step() {
    SpatialRodSlope<T> slope;
    SpatialRodVector<T> k[4];
    SpatialRodSensitivity<T> kt[4];
    for (int st = 0; st < 4; ++st) {
      if (st == 0) {
        slope.evaluate(law, y);
      } else {
        const T& a = st == 3 ? h : half_h;
        slope.evaluate(law, y + a * k[st - 1]);
      }
      k[st] = slope.dy;
      if constexpr (Sens) {
        if (st == 0) {
          slope.linearise(law, tangent, kt[0]);
        } else {
          const T& a = st == 3 ? h : half_h;
          slope.linearise(law, tangent + a * kt[st - 1], kt[st]);
        }
      }
    }
    y += sixth_h * (k[0] + T(2) * (k[1] + k[2]) + k[3]);
    if constexpr (Sens) tangent += sixth_h * (kt[0] + T(2) * (kt[1] + kt[2]) + kt[3]);
  }

  SpatialRodState<T> state() const { return SpatialRodState<T>::from_vector(y); }
};

template <class T, bool Sens, class Visitor>
SpatialRodStepper<T, Sens> integrate_spatial_rod_pass(const SpatialRodState<T>& base,
                                                      const SpatialRod<T>& rod,
                                                      const Vector3<T>& gravity, int steps,
                                                      Visitor&& visit) {
  SpatialRodStepper<T, Sens> stepper(base, rod, gravity, steps);
  visit(T(0), base);
  for (int i = 0; i < steps; ++i) {
    stepper.step();
    visit(T(i + 1) * stepper.h, stepper.state());
  }
  return stepper;
}

}  // namespace internal

/// Integrates the rod from its proximal state over [0, rod.length] in `steps` RK4 steps
/// (steps >= 1), under gravity (m/s^2, world frame): the tip state.
template <class T>
SpatialRodState<T> integrate_spatial_rod(const SpatialRodState<T>& base, const SpatialRod<T>& rod,
                                         const Vector3<T>& gravity,
                                         int steps = kDefaultSpatialRodSteps) {
  return internal::integrate_spatial_rod_pass<T, false>(base, rod, gravity, steps,
                                                        internal::NoVisitor{})
      .state();
}

/// Integrates the rod and the sensitivity of its tip state to the proximal wrench (n, m)(0).
template <class T>
SpatialRodTip<T> integrate_spatial_rod_with_sensitivity(const SpatialRodState<T>& base,
                                                        const SpatialRod<T>& rod,
                                                        const Vector3<T>& gravity,
                                                        int steps = kDefaultSpatialRodSteps) {
  const auto pass = internal::integrate_spatial_rod_pass<T, true>(base, rod, gravity, steps,
                                                                  internal::NoVisitor{});
  return SpatialRodTip<T>{pass.state(), pass.tangent};
}

/// Integrates the rod and calls visit(s, SpatialRodState) at each of the steps + 1 nodes
/// (s = 0 and the base first): the shape, for plotting.
template <class T, class Visitor>
SpatialRodState<T> sample_spatial_rod(const SpatialRodState<T>& base, const SpatialRod<T>& rod,
                                      const Vector3<T>& gravity, int steps, Visitor&& visit) {
  return internal::integrate_spatial_rod_pass<T, false>(base, rod, gravity, steps, visit).state();
}

}  // namespace pcr
