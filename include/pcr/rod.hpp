#pragma once
// Planar Kirchhoff rod (Mauze et al. 2021, Eq. 1), integrated by fixed-step RK4.
//
//   x' = cos(theta), y' = sin(theta), theta' = m / EI, n' = 0, m' = n_x sin(theta) - n_y cos(theta)
//
// Sign convention: n(s) and m(s) are the force and moment exerted by the material beyond s
// (larger arc length) on the material before it. So n(0), m(0) is what the rod exerts on its
// proximal clamp, and -n(l), -m(l) is what the rod exerts on whatever holds its tip.
//
// To avoid a sin/cos pair per RK4 stage, the integrator carries c = cos(theta) and
// s = sin(theta) as states (c' = -s m/EI, s' = c m/EI): the right-hand side is then a polynomial.
// theta is integrated alongside, so it stays continuous over full turns.

#include <Eigen/Core>
#include <cmath>

namespace pcr {

/// EI of a circular section: E * pi * d^4 / 64 (N m^2), E in Pa and d in m.
template <class T>
T bending_stiffness(const T& young_modulus, const T& diameter) {
  const T d2 = diameter * diameter;
  return young_modulus * T(M_PI / 64.0) * d2 * d2;
}

/// State of the rod at one arc length, in the frame the integration runs in.
template <class T>
struct RodState {
  T x{0}, y{0}, theta{0};  ///< centreline position (m) and tangent angle (rad)
  T nx{0}, ny{0}, m{0};    ///< internal force (N) and moment (N m), see the sign convention
};

/// The distal state of a rod plus its sensitivity to the proximal wrench.
template <class T>
struct RodTip {
  RodState<T> state;
  /// d(x, y, theta, m)(l) / d(n_x, n_y, m)(0); n(l) = n(0) needs no sensitivity.
  Eigen::Matrix<T, 4, 3> sensitivity;
  /// max |m(s)| over the RK4 nodes (N m), for the bending strain |m| d / (2 EI).
  T max_abs_moment{0};
};

namespace internal {

struct NoVisitor {
  template <class S, class State>
  void operator()(const S&, const State&) const {}
};

/// RK4 on (x, y, c, s, theta, m), c = cos(theta) and s = sin(theta), one step at a time. Only
/// (c, s, m) are coupled; x, y and theta are quadratures of the stage values, written with the
/// same arithmetic as one RK4 update of the whole vector. With Sens, the tangents w.r.t. the
/// proximal (n_x, n_y, m) are RK4 applied to the variational equations, which is exactly the
/// derivative of the discrete map: Newton sees the true Jacobian. Scalar locals rather than Eigen
/// blocks: the recurrence is latency-bound, and this keeps the three tangent columns (and, in
/// integrate_rods_lockstep, the rods) independent chains the CPU can overlap.
template <class T, bool Sens>
struct RodStepper {
  T nx, ny, x, y, c, s, th, m;
  T inv_ei, h, half_h, sixth_h, max_abs_moment;
  // Tangents, column j: d / d wrench_j, as one padded 4-vector per state (column 3 stays zero)
  // so that in double the three columns step together in SIMD registers.
  using Cols = Eigen::Array<T, 4, 1>;
  Cols tx, ty, tc, ts, tth, tm;

  void init(const RodState<T>& start, const T& ei, const T& length, int steps) {
    using std::abs;
    using std::cos;
    using std::sin;
    nx = start.nx;
    ny = start.ny;
    x = start.x;
    y = start.y;
    c = cos(start.theta);
    s = sin(start.theta);
    th = start.theta;
    m = start.m;
    if constexpr (Sens) {
      tx.setZero();
      ty.setZero();
      tc.setZero();
      ts.setZero();
      tth.setZero();
      tm.setZero();
      tm[2] = T(1);  // only dm/dm0 starts non-zero
    }
    inv_ei = T(1) / ei;
    h = length / T(steps);
    half_h = h / T(2);
    sixth_h = h / T(6);
    max_abs_moment = abs(m);
  }

  void step() {
    using std::abs;
    // Stage values (the rhs of x, y, theta are c, s, k) and slopes of (c, s, m).
    T sc[4], ss[4], sk[4], dc[4], ds[4], dm[4];
    Cols gc[4], gs[4], gk[4], gdc[4], gds[4], gdm[4];
    for (int st = 0; st < 4; ++st) {
      const T a = st == 3 ? h : half_h;
      const int p = st == 0 ? 0 : st - 1;
      const T cc = st == 0 ? c : c + a * dc[p];
      const T sv = st == 0 ? s : s + a * ds[p];
      const T mm = st == 0 ? m : m + a * dm[p];
      const T k = mm * inv_ei;
      sc[st] = cc;
      ss[st] = sv;
      sk[st] = k;
      dc[st] = -sv * k;
      ds[st] = cc * k;
      dm[st] = nx * sv - ny * cc;
      if constexpr (Sens) {
        if (st == 0) {
          gc[0] = tc;
          gs[0] = ts;
          gk[0] = tm * inv_ei;
        } else {
          gc[st] = tc + a * gdc[p];
          gs[st] = ts + a * gds[p];
          gk[st] = (tm + a * gdm[p]) * inv_ei;
        }
        gdc[st] = -gs[st] * k - sv * gk[st];
        gds[st] = gc[st] * k + cc * gk[st];
        gdm[st] = nx * gs[st] - ny * gc[st];
        gdm[st][0] += sv;  // d/dn_x of n_x s
        gdm[st][1] -= cc;  // d/dn_y of -n_y c
      }
    }
    // One RK4 update, of a state (T) or of its tangent columns (Cols).
    const auto rk4 = [this](auto& v, const auto& k) {
      v += sixth_h * (k[0] + T(2) * (k[1] + k[2]) + k[3]);
    };
    rk4(x, sc);
    rk4(y, ss);
    rk4(c, dc);
    rk4(s, ds);
    rk4(th, sk);
    rk4(m, dm);
    if constexpr (Sens) {
      rk4(tx, gc);
      rk4(ty, gs);
      rk4(tc, gdc);
      rk4(ts, gds);
      rk4(tth, gk);
      rk4(tm, gdm);
    }
    const T abs_m = abs(m);
    if (abs_m > max_abs_moment) max_abs_moment = abs_m;
  }

  RodState<T> state() const { return RodState<T>{x, y, th, nx, ny, m}; }
};

/// Integrates up to MaxRods rods over their lengths in `steps` steps each, in lockstep (bit for
/// bit the same as one at a time: each rod is a serial chain, interleaving them overlaps them).
template <int MaxRods, bool Sens, class T>
void integrate_rods_lockstep(RodStepper<T, Sens>* rods, int n, int steps) {
  for (int i = 0; i < steps; ++i) {
    for (int r = 0; r < n && r < MaxRods; ++r) rods[r].step();
  }
}

template <class T, bool Sens, class Visitor>
RodStepper<T, Sens> integrate_rod_pass(const RodState<T>& start, const T& ei, const T& length,
                                       int steps, Visitor&& visit) {
  RodStepper<T, Sens> rod;
  rod.init(start, ei, length, steps);
  visit(T(0), rod.state());
  for (int i = 0; i < steps; ++i) {
    rod.step();
    visit(T(i + 1) * rod.h, rod.state());
  }
  return rod;
}

}  // namespace internal

/// Integrates the rod from its proximal state over [0, length]; EI in N m^2.
template <class T>
RodState<T> integrate_rod(const RodState<T>& start, const T& ei, const T& length, int steps,
                          T* max_abs_moment = nullptr) {
  const auto pass =
      internal::integrate_rod_pass<T, false>(start, ei, length, steps, internal::NoVisitor{});
  if (max_abs_moment) *max_abs_moment = pass.max_abs_moment;
  return pass.state();
}

/// Integrates the rod and its sensitivity to the proximal wrench (n_x, n_y, m)(0).
template <class T>
RodTip<T> integrate_rod_with_sensitivity(const RodState<T>& start, const T& ei, const T& length,
                                         int steps) {
  RodTip<T> tip;
  const auto pass =
      internal::integrate_rod_pass<T, true>(start, ei, length, steps, internal::NoVisitor{});
  tip.state = pass.state();
  tip.max_abs_moment = pass.max_abs_moment;
  for (int j = 0; j < 3; ++j) {
    tip.sensitivity(0, j) = pass.tx[j];
    tip.sensitivity(1, j) = pass.ty[j];
    tip.sensitivity(2, j) = pass.tth[j];
    tip.sensitivity(3, j) = pass.tm[j];
  }
  return tip;
}

/// Integrates the rod and calls visit(s, RodState) at each of the steps + 1 nodes (the shape).
template <class T, class Visitor>
RodState<T> sample_rod(const RodState<T>& start, const T& ei, const T& length, int steps,
                       Visitor&& visit) {
  return internal::integrate_rod_pass<T, false>(start, ei, length, steps, visit).state();
}

}  // namespace pcr
