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
// Rucker do). The two differ by the strains n / EA and n / GA: 2e-5 for 1 N on a 1 mm NiTi rod
// (EA = 47 kN), 8 um over 0.4 m of it, far above what the solvers resolve; which law a robot
// uses is a modelling choice to make, not a detail.
//
// Why a quaternion and not R itself: 13 states instead of 18, and 13 x 6 tangents instead of
// 18 x 6. h' = h (x) (0, u) / 2 keeps |h| constant exactly; RK4 keeps it to its own order only
// (|h| drifts by O(step^4) over the rod: 4e-11 at the default step count on the tests' rods).
// The stepper never renormalises h, which would make the step a different map from the one the
// tangents differentiate; R is computed as Q(h) / |h|^2 (rotation_of's formula, Q quadratic in
// h), a rotation whatever |h|.
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
#include <cmath>

#include "pcr/rod.hpp"
#include "pcr/spatial/quaternion.hpp"

namespace pcr {

/// RK4 steps per rod by default. On the random rods of tests/test_spatial_rod.cpp (up to 3 EI / L^2
/// of force and 3 EI / L of moment, with intrinsic curvature and gravity; frames turning through
/// up to 4.7 rad) the tip's worst error against CVODE, the largest of position / L, orientation
/// (rad) and moment / max(EI / L, |m(0)|, |n(0)| L, |f| L^2), is 1.0e-7 at 64 steps, 6.4e-9 at 128,
/// 4.0e-10 at 256 and 3.1e-11 at 512: 256 is the first count within 1e-9. RK4's error grows as
/// (total turn / steps)^4.
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

/// The per-rod constants of the right-hand side. The curvature enters h' = h (x) (0, u) / 2 only
/// halved: the stepper carries u / 2 (exactly half, a power of 2) and saves a product per stage.
template <class T>
struct SpatialRodLaw {
  T half_bending_compliance[3];   ///< (1/EI, 1/EI, 1/GJ) / 2 (1 / (N m^2))
  T half_intrinsic_curvature[3];  ///< u* / 2 (1/m), body frame
  T shear_compliance[3];          ///< (1/GA, 1/GA, 1/EA) (1/N); unused by a Kirchhoff rod
  T distributed_force[3];         ///< f = rho A g (N/m), world frame
  bool shear_and_extension = false;

  SpatialRodLaw() = default;
  SpatialRodLaw(const SpatialRod<T>& rod, const Vector3<T>& gravity) {
    const T stiffness[3] = {rod.bending_stiffness(), rod.bending_stiffness(),
                            rod.torsional_stiffness()};
    const T shear[3] = {rod.shear_stiffness(), rod.shear_stiffness(), rod.axial_stiffness()};
    for (int i = 0; i < 3; ++i) {
      half_bending_compliance[i] = T(0.5) / stiffness[i];
      half_intrinsic_curvature[i] = T(0.5) * rod.intrinsic_curvature[i];
      shear_compliance[i] = T(1) / shear[i];
      distributed_force[i] = rod.mass_per_length() * gravity[i];
    }
    shear_and_extension = rod.shear_and_extension;
  }
};

/// The tangents stored transposed: row j holds d state / d wrench_j, so that each state
/// component's six derivatives are contiguous and the variational right-hand side runs over all
/// six columns at once, vectorised along them, rather than as six chains of 3-vector operations.
template <class T>
using SpatialRodTangents = Eigen::Matrix<T, 6, SpatialRodIndex::kSize>;

/// The right-hand side at one RK4 stage and what its linearisation needs, in plain scalars (the
/// recurrence is latency-bound: GCC left layers of Eigen's expressions here as calls).
template <class T>
struct SpatialRodSlope {
  T dy[SpatialRodIndex::kSize];  ///< (p', h', n', m')
  T R[3][3];                     ///< rotation of h / |h|
  T h[4], n[3], p_prime[3];
  T half_u[3];       ///< u / 2 (1/m), body frame
  T v[3];            ///< body-frame strain (e3 for a Kirchhoff rod)
  T body_moment[3];  ///< R^T m (N m)
  T body_force[3];   ///< R^T n (N), with shear and extension only
  T inv_norm2;       ///< 1 / |h|^2

  /// y' at y. R = Q / |h|^2 with Q = |h|^2 R a polynomial in h, so that the division runs
  /// alongside Q^T m instead of before it, off the stage-to-stage chain h -> u -> h'.
  EIGEN_ALWAYS_INLINE void evaluate(const SpatialRodLaw<T>& law, const T* y) {
    using Index = SpatialRodIndex;
    for (int i = 0; i < 4; ++i) h[i] = y[Index::kOrientation + i];
    const T &w = h[0], &x = h[1], &yq = h[2], &z = h[3];
    const T ww = w * w, xx = x * x, yy = yq * yq, zz = z * z;
    inv_norm2 = T(1) / ((ww + xx) + (yy + zz));
    const T xy = x * yq, xz = x * z, yz = yq * z, wx = w * x, wy = w * yq, wz = w * z;
    const T Q[3][3] = {{(ww + xx) - (yy + zz), T(2) * (xy - wz), T(2) * (xz + wy)},
                       {T(2) * (xy + wz), (ww - xx) + (yy - zz), T(2) * (yz - wx)},
                       {T(2) * (xz - wy), T(2) * (yz + wx), (ww - xx) - (yy - zz)}};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R[r][c] = Q[r][c] * inv_norm2;
    }
    const T* m = y + Index::kMoment;
    for (int i = 0; i < 3; ++i) n[i] = y[Index::kForce + i];
    for (int c = 0; c < 3; ++c) {
      body_moment[c] = (Q[0][c] * m[0] + Q[1][c] * m[1] + Q[2][c] * m[2]) * inv_norm2;
      half_u[c] = law.half_bending_compliance[c] * body_moment[c] + law.half_intrinsic_curvature[c];
    }
    if (law.shear_and_extension) {
      for (int c = 0; c < 3; ++c) {
        body_force[c] = (Q[0][c] * n[0] + Q[1][c] * n[1] + Q[2][c] * n[2]) * inv_norm2;
        v[c] = law.shear_compliance[c] * body_force[c];
      }
      v[2] += T(1);
      for (int r = 0; r < 3; ++r) p_prime[r] = R[r][0] * v[0] + R[r][1] * v[1] + R[r][2] * v[2];
    } else {
      v[0] = v[1] = T(0);
      v[2] = T(1);
      for (int r = 0; r < 3; ++r) p_prime[r] = R[r][2];
    }
    for (int r = 0; r < 3; ++r) dy[Index::kPosition + r] = p_prime[r];
    // h' = h (x) (0, u / 2).
    const T* u = half_u;
    dy[Index::kOrientation] = -x * u[0] - yq * u[1] - z * u[2];
    dy[Index::kOrientation + 1] = w * u[0] + yq * u[2] - z * u[1];
    dy[Index::kOrientation + 2] = w * u[1] + z * u[0] - x * u[2];
    dy[Index::kOrientation + 3] = w * u[2] + x * u[1] - yq * u[0];
    for (int i = 0; i < 3; ++i) dy[Index::kForce + i] = -law.distributed_force[i];
    // m' = -p' x n = n x p'.
    dy[Index::kMoment] = n[1] * p_prime[2] - n[2] * p_prime[1];
    dy[Index::kMoment + 1] = n[2] * p_prime[0] - n[0] * p_prime[2];
    dy[Index::kMoment + 2] = n[0] * p_prime[1] - n[1] * p_prime[0];
  }

  /// The variational right-hand side of the (transposed) tangents t at this stage; see the
  /// header for the equations. Written as plain loops over the six columns, which the compiler
  /// unrolls and vectorises.
  EIGEN_ALWAYS_INLINE void linearise(const SpatialRodLaw<T>& law, const SpatialRodTangents<T>& t,
                                     SpatialRodTangents<T>& dt) const {
    constexpr int kColumns = 6;
    using Index = SpatialRodIndex;
    const T* dh[4];
    const T *dn[3], *dm[3];
    for (int i = 0; i < 4; ++i) dh[i] = t.col(Index::kOrientation + i).data();
    for (int i = 0; i < 3; ++i) {
      dn[i] = t.col(Index::kForce + i).data();
      dm[i] = t.col(Index::kMoment + i).data();
    }
    const T &w = h[0], &x = h[1], &y = h[2], &z = h[3];
    const T k = T(2) * inv_norm2;
    const T* mb = body_moment;
    const T* cb = law.half_bending_compliance;
    // omega (body frame, dR = R [omega]x), du / 2 and dp', column by column.
    T omega[3][kColumns], half_du[3][kColumns], dp[3][kColumns];
    for (int j = 0; j < kColumns; ++j) {
      // omega = 2 vec(conj(h) (x) dh) / |h|^2.
      omega[0][j] = k * (w * dh[1][j] - x * dh[0][j] + z * dh[2][j] - y * dh[3][j]);
      omega[1][j] = k * (w * dh[2][j] - y * dh[0][j] + x * dh[3][j] - z * dh[1][j]);
      omega[2][j] = k * (w * dh[3][j] - z * dh[0][j] + y * dh[1][j] - x * dh[2][j]);
    }
    for (int j = 0; j < kColumns; ++j) {
      // du = K_bt^-1 (R^T dm + (R^T m) x omega).
      T a[3];
      for (int c = 0; c < 3; ++c)
        a[c] = R[0][c] * dm[0][j] + R[1][c] * dm[1][j] + R[2][c] * dm[2][j];
      half_du[0][j] = cb[0] * (a[0] + (mb[1] * omega[2][j] - mb[2] * omega[1][j]));
      half_du[1][j] = cb[1] * (a[1] + (mb[2] * omega[0][j] - mb[0] * omega[2][j]));
      half_du[2][j] = cb[2] * (a[2] + (mb[0] * omega[1][j] - mb[1] * omega[0][j]));
    }
    if (law.shear_and_extension) {
      const T* nb = body_force;
      const T* cs = law.shear_compliance;
      for (int j = 0; j < kColumns; ++j) {
        // dp' = R (omega x v + dv), dv = K_se^-1 (R^T dn + (R^T n) x omega).
        T b[3];
        for (int c = 0; c < 3; ++c)
          b[c] = R[0][c] * dn[0][j] + R[1][c] * dn[1][j] + R[2][c] * dn[2][j];
        b[0] = cs[0] * (b[0] + (nb[1] * omega[2][j] - nb[2] * omega[1][j])) +
               (omega[1][j] * v[2] - omega[2][j] * v[1]);
        b[1] = cs[1] * (b[1] + (nb[2] * omega[0][j] - nb[0] * omega[2][j])) +
               (omega[2][j] * v[0] - omega[0][j] * v[2]);
        b[2] = cs[2] * (b[2] + (nb[0] * omega[1][j] - nb[1] * omega[0][j])) +
               (omega[0][j] * v[1] - omega[1][j] * v[0]);
        for (int r = 0; r < 3; ++r) dp[r][j] = R[r][0] * b[0] + R[r][1] * b[1] + R[r][2] * b[2];
      }
    } else {
      for (int j = 0; j < kColumns; ++j) {
        // dp' = R (omega x e3) = omega_y d1 - omega_x d2.
        for (int r = 0; r < 3; ++r) dp[r][j] = R[r][0] * omega[1][j] - R[r][1] * omega[0][j];
      }
    }
    T* out[Index::kSize];
    for (int i = 0; i < Index::kSize; ++i) out[i] = dt.col(i).data();
    const T* u = half_u;
    for (int j = 0; j < kColumns; ++j) {
      for (int r = 0; r < 3; ++r) out[Index::kPosition + r][j] = dp[r][j];
      // dh' = dh (x) (0, u / 2) + h (x) (0, du / 2).
      const T h0 = dh[0][j], h1 = dh[1][j], h2 = dh[2][j], h3 = dh[3][j];
      const T d0 = half_du[0][j], d1 = half_du[1][j], d2 = half_du[2][j];
      out[Index::kOrientation][j] =
          (-h1 * u[0] - h2 * u[1] - h3 * u[2]) - (x * d0 + y * d1 + z * d2);
      out[Index::kOrientation + 1][j] =
          (h0 * u[0] + h2 * u[2] - h3 * u[1]) + (w * d0 + y * d2 - z * d1);
      out[Index::kOrientation + 2][j] =
          (h0 * u[1] + h3 * u[0] - h1 * u[2]) + (w * d1 + z * d0 - x * d2);
      out[Index::kOrientation + 3][j] =
          (h0 * u[2] + h1 * u[1] - h2 * u[0]) + (w * d2 + x * d1 - y * d0);
      for (int r = 0; r < 3; ++r) out[Index::kForce + r][j] = T(0);
      // dm' = n x dp' + dn x p'.
      out[Index::kMoment][j] =
          (n[1] * dp[2][j] - n[2] * dp[1][j]) + (dn[1][j] * p_prime[2] - dn[2][j] * p_prime[1]);
      out[Index::kMoment + 1][j] =
          (n[2] * dp[0][j] - n[0] * dp[2][j]) + (dn[2][j] * p_prime[0] - dn[0][j] * p_prime[2]);
      out[Index::kMoment + 2][j] =
          (n[0] * dp[1][j] - n[1] * dp[0][j]) + (dn[0][j] * p_prime[1] - dn[1][j] * p_prime[0]);
    }
  }
};

/// One RK4 step of the 13 states y (in place) of one rod (T a scalar) or of a bundle of rods, one
/// per SIMD lane (T = LaneArray<N>: the same operations in the same order, so a lane is bit for bit
/// the rod stepped alone). at_stage(st, slope) sees each stage's slope, st = 0 ... 3 (the
/// tangents' hook).
template <class T, class AtStage>
EIGEN_ALWAYS_INLINE void spatial_rk4_step(const SpatialRodLaw<T>& law, T* y, const T& h,
                                          const T& half_h, const T& sixth_h, AtStage&& at_stage) {
  constexpr int kSize = SpatialRodIndex::kSize;
  SpatialRodSlope<T> slope;
  T k[4][kSize], stage[kSize];
  for (int st = 0; st < 4; ++st) {
    const T& a = st == 3 ? h : half_h;
    if (st == 0) {
      slope.evaluate(law, y);
    } else {
      for (int i = 0; i < kSize; ++i) stage[i] = y[i] + a * k[st - 1][i];
      slope.evaluate(law, stage);
    }
    for (int i = 0; i < kSize; ++i) k[st][i] = slope.dy[i];
    at_stage(st, slope);
  }
  for (int i = 0; i < kSize; ++i) {
    y[i] += sixth_h * (k[0][i] + T(2) * (k[1][i] + k[2][i]) + k[3][i]);
  }
}

/// RK4 on the 13 states, one step at a time; with Sens, also on the tangents w.r.t. the
/// proximal (n, m), stage by stage with the states (the derivative of the discrete map).
template <class T, bool Sens>
struct SpatialRodStepper {
  static constexpr int kSize = SpatialRodIndex::kSize;
  SpatialRodVector<T> y;
  SpatialRodTangents<T> tangents;  ///< with Sens, transposed (SpatialRodTangents)
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
      tangents.setZero();
      for (int j = 0; j < 3; ++j) {
        tangents(j, SpatialRodIndex::kForce + j) = T(1);
        tangents(3 + j, SpatialRodIndex::kMoment + j) = T(1);
      }
    }
  }

  void step() {
    if constexpr (Sens) {
      SpatialRodTangents<T> kt[4], tangent_stage;
      spatial_rk4_step(law, y.data(), h, half_h, sixth_h,
                       [&](int st, const SpatialRodSlope<T>& slope) {
                         if (st == 0) {
                           slope.linearise(law, tangents, kt[0]);
                         } else {
                           tangent_stage = tangents + (st == 3 ? h : half_h) * kt[st - 1];
                           slope.linearise(law, tangent_stage, kt[st]);
                         }
                       });
      tangents += sixth_h * (kt[0] + T(2) * (kt[1] + kt[2]) + kt[3]);
    } else {
      spatial_rk4_step(law, y.data(), h, half_h, sixth_h, [](int, const SpatialRodSlope<T>&) {});
    }
  }

  SpatialRodState<T> state() const { return SpatialRodState<T>::from_vector(y); }
  /// d state / d (n, m)(0), 13 x 6.
  SpatialRodSensitivity<T> sensitivity() const { return tangents.transpose(); }
};

/// Up to N rods' states stepped together, one per SIMD lane (LaneArray, pcr/rod.hpp): the rods of
/// a residual evaluation, whose chains of dependent operations the CPU then overlaps.
template <int N>
struct SpatialRodBundle {
  using L = LaneArray<N>;
  L y[SpatialRodIndex::kSize];
  SpatialRodLaw<L> law;
  L h, half_h, sixth_h;

  /// Lane `lane` from a one-rod stepper (lane 0 first: it sets the bundle's law kind).
  void set_lane(int lane, const SpatialRodStepper<double, false>& rod) {
    for (int i = 0; i < SpatialRodIndex::kSize; ++i) y[i][lane] = rod.y[i];
    for (int i = 0; i < 3; ++i) {
      law.half_bending_compliance[i][lane] = rod.law.half_bending_compliance[i];
      law.half_intrinsic_curvature[i][lane] = rod.law.half_intrinsic_curvature[i];
      law.shear_compliance[i][lane] =
          rod.law.shear_and_extension ? rod.law.shear_compliance[i] : 0.0;
      law.distributed_force[i][lane] = rod.law.distributed_force[i];
    }
    // A Kirchhoff rod in a bundle stepped with shear and extension has zero compliances, which
    // give v = e3 and p' = R e3 exactly.
    law.shear_and_extension = (lane > 0 && law.shear_and_extension) || rod.law.shear_and_extension;
    h[lane] = rod.h;
    half_h[lane] = rod.half_h;
    sixth_h[lane] = rod.sixth_h;
  }

  void step() {
    spatial_rk4_step(law, y, h, half_h, sixth_h, [](int, const SpatialRodSlope<L>&) {});
  }

  SpatialRodState<double> state(int lane) const {
    SpatialRodVector<double> v;
    for (int i = 0; i < SpatialRodIndex::kSize; ++i) v[i] = y[i][lane];
    return SpatialRodState<double>::from_vector(v);
  }
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
  return SpatialRodTip<T>{pass.state(), pass.sensitivity()};
}

/// Integrates n rods (n <= 8) from their proximal states over their lengths in `steps` RK4 steps
/// each, under gravity, their states stepped together in SIMD lanes (a bundle of 2, 4 or 8): the
/// tips, bit for bit those of integrate_spatial_rod (unless the compiler contracts multiply-adds
/// into FMAs differently in the two, as -march=native lets it).
inline void integrate_spatial_rods(const SpatialRodState<double>* bases,
                                   const SpatialRod<double>* rods, int n,
                                   const Vector3<double>& gravity, int steps,
                                   SpatialRodState<double>* tips) {
  if (n <= 0) return;
  internal::with_lane_count(n, [&](auto lanes) {
    constexpr int kLanes = decltype(lanes)::value;
    internal::SpatialRodBundle<kLanes> bundle;
    for (int r = 0; r < kLanes; ++r) {
      const int rod = r < n ? r : 0;  // idle lanes repeat rod 0
      bundle.set_lane(
          r, internal::SpatialRodStepper<double, false>(bases[rod], rods[rod], gravity, steps));
    }
    for (int i = 0; i < steps; ++i) bundle.step();
    for (int r = 0; r < n; ++r) tips[r] = bundle.state(r);
  });
}

/// Integrates the rod and calls visit(s, SpatialRodState) at each of the steps + 1 nodes
/// (s = 0 and the base first): the shape, for plotting.
template <class T, class Visitor>
SpatialRodState<T> sample_spatial_rod(const SpatialRodState<T>& base, const SpatialRod<T>& rod,
                                      const Vector3<T>& gravity, int steps, Visitor&& visit) {
  return internal::integrate_spatial_rod_pass<T, false>(base, rod, gravity, steps, visit).state();
}

}  // namespace pcr
