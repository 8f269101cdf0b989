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

#include <cmath>

#include <Eigen/Core>

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

// Column 0: (x, y, c, s, theta, m); columns 1..3: their derivatives w.r.t. n_x0, n_y0, m0.
template <class T, int Cols>
using RodBlock = Eigen::Matrix<T, 6, Cols>;

template <class T, int Cols>
inline void rod_rhs(const RodBlock<T, Cols>& Y, const T& nx, const T& ny, const T& inv_ei,
                    RodBlock<T, Cols>& D) {
  const T c = Y(2, 0), s = Y(3, 0), k = Y(5, 0) * inv_ei;
  D(0, 0) = c;
  D(1, 0) = s;
  D(2, 0) = -s * k;
  D(3, 0) = c * k;
  D(4, 0) = k;
  D(5, 0) = nx * s - ny * c;
  for (int j = 1; j < Cols; ++j) {
    const T dc = Y(2, j), ds = Y(3, j), dk = Y(5, j) * inv_ei;
    D(0, j) = dc;
    D(1, j) = ds;
    D(2, j) = -ds * k - s * dk;
    D(3, j) = dc * k + c * dk;
    D(4, j) = dk;
    D(5, j) = nx * ds - ny * dc;
  }
  if constexpr (Cols > 1) {
    D(5, 1) += s;  // d/dn_x of n_x s
    D(5, 2) -= c;  // d/dn_y of -n_y c
  }
}

struct NoVisitor {
  template <class S, class State>
  void operator()(const S&, const State&) const {}
};

/// RK4 over [0, length] in `steps` steps. The tangent columns are RK4 applied to the variational
/// equations, which is exactly the derivative of the discrete map: Newton sees the true Jacobian.
template <class T, int Cols, class Visitor>
RodBlock<T, Cols> integrate_rod_block(const RodState<T>& start, const T& ei, const T& length,
                                      int steps, T& max_abs_moment, Visitor&& visit) {
  using std::abs;
  using std::cos;
  using std::sin;
  RodBlock<T, Cols> Y = RodBlock<T, Cols>::Zero();
  Y(0, 0) = start.x;
  Y(1, 0) = start.y;
  Y(2, 0) = cos(start.theta);
  Y(3, 0) = sin(start.theta);
  Y(4, 0) = start.theta;
  Y(5, 0) = start.m;
  if constexpr (Cols > 1) Y(5, 3) = T(1);

  const T inv_ei = T(1) / ei;
  const T h = length / T(steps);
  const T half_h = h / T(2);
  const T sixth_h = h / T(6);
  RodBlock<T, Cols> k1, k2, k3, k4, tmp;
  max_abs_moment = abs(Y(5, 0));
  const auto report = [&](int step) {
    RodState<T> state{Y(0, 0), Y(1, 0), Y(4, 0), start.nx, start.ny, Y(5, 0)};
    visit(T(step) * h, state);
  };
  report(0);
  for (int i = 0; i < steps; ++i) {
    rod_rhs<T, Cols>(Y, start.nx, start.ny, inv_ei, k1);
    tmp = Y + half_h * k1;
    rod_rhs<T, Cols>(tmp, start.nx, start.ny, inv_ei, k2);
    tmp = Y + half_h * k2;
    rod_rhs<T, Cols>(tmp, start.nx, start.ny, inv_ei, k3);
    tmp = Y + h * k3;
    rod_rhs<T, Cols>(tmp, start.nx, start.ny, inv_ei, k4);
    Y += sixth_h * (k1 + T(2) * (k2 + k3) + k4);
    const T abs_m = abs(Y(5, 0));
    if (abs_m > max_abs_moment) max_abs_moment = abs_m;
    report(i + 1);
  }
  return Y;
}

}  // namespace internal

/// Integrates the rod from its proximal state over [0, length]; EI in N m^2.
template <class T>
RodState<T> integrate_rod(const RodState<T>& start, const T& ei, const T& length, int steps,
                          T* max_abs_moment = nullptr) {
  T max_m;
  const auto Y = internal::integrate_rod_block<T, 1>(start, ei, length, steps, max_m,
                                                     internal::NoVisitor{});
  if (max_abs_moment) *max_abs_moment = max_m;
  return RodState<T>{Y(0, 0), Y(1, 0), Y(4, 0), start.nx, start.ny, Y(5, 0)};
}

/// Integrates the rod and its sensitivity to the proximal wrench (n_x, n_y, m)(0).
template <class T>
RodTip<T> integrate_rod_with_sensitivity(const RodState<T>& start, const T& ei, const T& length,
                                         int steps) {
  RodTip<T> tip;
  const auto Y = internal::integrate_rod_block<T, 4>(start, ei, length, steps, tip.max_abs_moment,
                                                     internal::NoVisitor{});
  tip.state = RodState<T>{Y(0, 0), Y(1, 0), Y(4, 0), start.nx, start.ny, Y(5, 0)};
  for (int j = 0; j < 3; ++j) {
    tip.sensitivity(0, j) = Y(0, j + 1);
    tip.sensitivity(1, j) = Y(1, j + 1);
    tip.sensitivity(2, j) = Y(4, j + 1);
    tip.sensitivity(3, j) = Y(5, j + 1);
  }
  return tip;
}

/// Integrates the rod and calls visit(s, RodState) at each of the steps + 1 nodes (the shape).
template <class T, class Visitor>
RodState<T> sample_rod(const RodState<T>& start, const T& ei, const T& length, int steps,
                       Visitor&& visit) {
  T max_m;
  const auto Y = internal::integrate_rod_block<T, 1>(start, ei, length, steps, max_m, visit);
  return RodState<T>{Y(0, 0), Y(1, 0), Y(4, 0), start.nx, start.ny, Y(5, 0)};
}

}  // namespace pcr
