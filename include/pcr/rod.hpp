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

/// `if (v > max) max = v` (NaN never replaces max).
template <class T>
void keep_larger(T& max, const T& v) {
  if (v > max) max = v;
}

/// RK4 on (x, y, c, s, theta, m), c = cos(theta) and s = sin(theta), one step at a time, of one
/// rod; L is the scalar (double or a Jet), or any type with its arithmetic, abs and keep_larger.
/// Only (c, s, m) are coupled; x, y and theta are quadratures of the stage values,
/// written with the same arithmetic as one RK4 update of the whole vector. With Sens, the tangents
/// w.r.t. the proximal (n_x, n_y, m) are RK4 applied to the variational equations, which is
/// exactly the derivative of the discrete map: Newton sees the true Jacobian. Plain locals rather
/// than Eigen blocks: the recurrence is latency-bound, and this keeps the three tangent columns
/// (and, in integrate_rods_lockstep, the rods) independent chains the CPU can overlap.
template <class L, bool Sens>
struct RodStepper {
  L nx, ny, x, y, c, s, th, m;
  L inv_ei, h, half_h, sixth_h, max_abs_moment;
  L tx[3], ty[3], tc[3], ts[3], tth[3], tm[3];  ///< tangents, [j]: d / d wrench_j (with Sens)

  /// One rod (L a scalar): its proximal state, EI (N m^2), length (m) and RK4 step count.
  void init(const RodState<L>& start, const L& ei, const L& length, int steps) {
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
      for (int j = 0; j < 3; ++j) {
        tx[j] = ty[j] = tc[j] = ts[j] = tth[j] = tm[j] = L(0);
      }
      tm[2] = L(1);  // only dm/dm0 starts non-zero
    }
    inv_ei = L(1) / ei;
    h = length / L(steps);
    half_h = h / L(2);
    sixth_h = h / L(6);
    max_abs_moment = abs(m);
  }

  void step() {
    using std::abs;
    // Stage values (the rhs of x, y, theta are c, s, k) and slopes of (c, s, m); g: tangents.
    L sc[4], ss[4], sk[4], dc[4], ds[4], dm[4];
    L gc[3][4], gs[3][4], gk[3][4], gdc[3][4], gds[3][4], gdm[3][4];  // [column][stage]
    for (int st = 0; st < 4; ++st) {
      const L& a = st == 3 ? h : half_h;
      const int p = st == 0 ? 0 : st - 1;
      const L cc = st == 0 ? c : L(c + a * dc[p]);
      const L sv = st == 0 ? s : L(s + a * ds[p]);
      const L mm = st == 0 ? m : L(m + a * dm[p]);
      const L k = mm * inv_ei;
      sc[st] = cc;
      ss[st] = sv;
      sk[st] = k;
      dc[st] = -sv * k;
      ds[st] = cc * k;
      dm[st] = nx * sv - ny * cc;
      if constexpr (Sens) {
        for (int j = 0; j < 3; ++j) {
          if (st == 0) {
            gc[j][0] = tc[j];
            gs[j][0] = ts[j];
            gk[j][0] = tm[j] * inv_ei;
          } else {
            gc[j][st] = tc[j] + a * gdc[j][p];
            gs[j][st] = ts[j] + a * gds[j][p];
            gk[j][st] = (tm[j] + a * gdm[j][p]) * inv_ei;
          }
          gdc[j][st] = -gs[j][st] * k - sv * gk[j][st];
          gds[j][st] = gc[j][st] * k + cc * gk[j][st];
          gdm[j][st] = nx * gs[j][st] - ny * gc[j][st];
        }
        gdm[0][st] += sv;  // d/dn_x of n_x s
        gdm[1][st] -= cc;  // d/dn_y of -n_y c
      }
    }
    rk4(x, sc);
    rk4(y, ss);
    rk4(c, dc);
    rk4(s, ds);
    rk4(th, sk);
    rk4(m, dm);
    if constexpr (Sens) {
      for (int j = 0; j < 3; ++j) {
        rk4(tx[j], gc[j]);
        rk4(ty[j], gs[j]);
        rk4(tc[j], gdc[j]);
        rk4(ts[j], gds[j]);
        rk4(tth[j], gk[j]);
        rk4(tm[j], gdm[j]);
      }
    }
    keep_larger(max_abs_moment, L(abs(m)));
  }

  RodState<L> state() const { return RodState<L>{x, y, th, nx, ny, m}; }

 private:
  /// One RK4 update of a state or a tangent column from its four slopes.
  void rk4(L& v, const L (&k)[4]) const { v += sixth_h * (k[0] + L(2) * (k[1] + k[2]) + k[3]); }
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
