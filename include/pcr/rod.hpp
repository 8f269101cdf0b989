#pragma once
// Planar Kirchhoff rod (Mauze et al. 2021, Eq. 1), integrated by fixed-step RK4.
//
//   x' = cos(theta), y' = sin(theta), theta' = m / EI(s) + u*(s), n' = 0,
//   m' = n_x sin(theta) - n_y cos(theta)
//
// u*(s) is the rod's intrinsic curvature (zero for the paper's straight rods): the linear
// constitutive law m = EI (theta' - u*) of a rod shape-set to a curve (Rod below). EI(s) varies
// along a tapered rod (constant for the paper's rods).
//
// Sign convention: n(s) and m(s) are the force and moment exerted by the material beyond s
// (larger arc length) on the material before it. So n(0), m(0) is what the rod exerts on its
// proximal clamp, and -n(l), -m(l) is what the rod exerts on whatever holds its tip.
//
// To avoid a sin/cos pair per RK4 stage, the integrator carries c = cos(theta) and
// s = sin(theta) as states (c' = -s k, s' = c k, k = theta'): the right-hand side is then a
// polynomial in the states.
// theta is integrated alongside, so it stays continuous over full turns.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <type_traits>

/// Compiles the RK4 step of the rods twice, for AVX2 and for the baseline, and picks one when the
/// program loads (GCC's function multiversioning, x86-64 with glibc): four lanes then step in one
/// instruction on the machines that can (the Jacobian's tangents twice as fast). AVX2 without FMA,
/// so that both clones round alike and results do not depend on the machine. Clang 14 emits the
/// clones of a template in every translation unit and fails to link them: there, and elsewhere,
/// the step is built for the target's flags.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(PCR_NO_SIMD_CLONES)
#define PCR_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PCR_SIMD_CLONES
#endif

namespace pcr {

/// EI of a circular section: E * pi * d^4 / 64 (N m^2), E in Pa and d in m.
template <class T>
T bending_stiffness(const T& young_modulus, const T& diameter) {
  const T d2 = diameter * diameter;
  return young_modulus * T(M_PI / 64.0) * d2 * d2;
}

/// Area of a circular section, pi d^2 / 4 (m^2), d in m.
template <class T>
T section_area(const T& diameter) {
  return T(M_PI / 4.0) * diameter * diameter;
}

/// One rod as the model sees it: its constitutive law, its geometry and the parameters a
/// calibration may identify. A circular section of diameter d(s) = d + d' s: uniform (d' = 0,
/// the paper's rods) or tapered (a ground or etched rod), so EI(s) = E pi d(s)^4 / 64 and
/// EA(s) = E pi d(s)^2 / 4. An intrinsic curvature u*(s) = u0 + u1 s: zero for a straight rod, u0
/// for a rod shape-set to a circular arc (superelastic NiTi), u0 + u1 s for a clothoid. The
/// stress-free rod is the curve whose tangent turns by u*; the bending moment is
/// m = EI(s) (theta' - u*).
template <class T>
struct Rod {
  T length{0};              ///< stress-free length l (m)
  T diameter{0};            ///< circular section diameter d = d(0) at the proximal end (m)
  T young_modulus{0};       ///< E (Pa)
  T precurvature{0};        ///< u0 = u*(0) (1/m), positive turning counterclockwise
  T precurvature_slope{0};  ///< u1 = du*/ds (1/m^2)
  T diameter_slope{0};      ///< d' = dd/ds (m/m): negative for a rod thinner at its tip

  /// EI at the proximal end (N m^2): the whole rod's for a uniform rod.
  T bending_stiffness() const { return pcr::bending_stiffness(young_modulus, diameter); }
  /// The section's diameter d(s) = d + d' s (m) and EI(s) (N m^2) at arc length s.
  T diameter_at(const T& s) const { return diameter + diameter_slope * s; }
  T bending_stiffness_at(const T& s) const {
    return pcr::bending_stiffness(young_modulus, diameter_at(s));
  }
  /// EA at the proximal end (N): the kinematics takes the rods as inextensible, the stability
  /// check (pcr/stability.hpp) needs their axial compliance.
  T axial_stiffness() const { return young_modulus * section_area(diameter); }
  /// u*(s) (1/m).
  T intrinsic_curvature(const T& s) const { return precurvature + precurvature_slope * s; }
  /// The angle the stress-free rod's tangent turns through from 0 to s: u0 s + u1 s^2 / 2 (rad).
  T intrinsic_turn(const T& s) const {
    return s * (precurvature + T(0.5) * precurvature_slope * s);
  }
  bool straight() const { return precurvature == T(0) && precurvature_slope == T(0); }
  bool uniform() const { return diameter_slope == T(0); }

  template <class U>
  Rod<U> cast() const {
    return Rod<U>{U(length),       U(diameter),           U(young_modulus),
                  U(precurvature), U(precurvature_slope), U(diameter_slope)};
  }
};

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
  /// max |m(s)| (d / d(s))^3 over the RK4 nodes (N m): the largest moment, scaled to the proximal
  /// section (|m| itself for a uniform rod), for the bending strain |m| d / (2 EI).
  T max_abs_moment{0};
};

namespace internal {

struct NoVisitor {
  template <class S, class State>
  void operator()(const S&, const State&) const {}
};

/// N doubles, one per rod of a bundle (RodBundle), with the arithmetic RodStepper uses done lane
/// by lane in plain loops over a fixed N, unrolled, which the optimiser turns into SIMD
/// instructions (SSE2 by default, AVX with -march=native; GCC at -O2 as at -O3). Not Eigen::Array:
/// in a function as long as RodStepper::step, GCC leaves layers of Eigen's expression templates as
/// calls, which cost more than the lanes save. Forced inline, for the same reason. (GCC's vector
/// extension was tried too: no faster on the Jacobian, 10% slower on the residual and warm FK.)
template <int N>
struct LaneArray {
  double v[N];

  LaneArray() = default;
  /// Every lane x.
  EIGEN_ALWAYS_INLINE explicit LaneArray(double x) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) v[i] = x;
  }
  EIGEN_ALWAYS_INLINE double& operator[](int i) { return v[i]; }
  EIGEN_ALWAYS_INLINE const double& operator[](int i) const { return v[i]; }

  EIGEN_ALWAYS_INLINE LaneArray& operator+=(const LaneArray& b) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) v[i] += b.v[i];
    return *this;
  }
  EIGEN_ALWAYS_INLINE LaneArray& operator-=(const LaneArray& b) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) v[i] -= b.v[i];
    return *this;
  }
  EIGEN_ALWAYS_INLINE LaneArray& operator*=(const LaneArray& b) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) v[i] *= b.v[i];
    return *this;
  }
  EIGEN_ALWAYS_INLINE friend LaneArray operator+(LaneArray a, const LaneArray& b) { return a += b; }
  EIGEN_ALWAYS_INLINE friend LaneArray operator-(LaneArray a, const LaneArray& b) { return a -= b; }
  EIGEN_ALWAYS_INLINE friend LaneArray operator*(LaneArray a, const LaneArray& b) { return a *= b; }
  EIGEN_ALWAYS_INLINE friend LaneArray operator/(LaneArray a, const LaneArray& b) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) a.v[i] /= b.v[i];
    return a;
  }
  EIGEN_ALWAYS_INLINE friend LaneArray operator-(LaneArray a) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) a.v[i] = -a.v[i];
    return a;
  }
  EIGEN_ALWAYS_INLINE friend LaneArray abs(LaneArray a) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) a.v[i] = std::abs(a.v[i]);
    return a;
  }
  /// Lane by lane, `if (v > max) max = v`.
  EIGEN_ALWAYS_INLINE friend void keep_larger(LaneArray& max, const LaneArray& v) {
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) max.v[i] = v.v[i] > max.v[i] ? v.v[i] : max.v[i];
  }
};

template <class L>
struct is_lane_array : std::false_type {};
template <int N>
struct is_lane_array<LaneArray<N>> : std::true_type {};

/// The constitutive laws RodStepper steps by, from the cheapest: each handles the ones before.
enum class RodLaw { kStraightUniform, kCurvedUniform, kTapered };

/// `if (v > max) max = v` (NaN never replaces max); LaneArray has its own, lane by lane.
template <class T>
void keep_larger(T& max, const T& v) {
  if (v > max) max = v;
}

/// RK4 on (x, y, c, s, theta, m), c = cos(theta) and s = sin(theta), one step at a time, of one
/// rod (L a scalar T, Jets included) or of a bundle of rods, one per SIMD lane (L = LaneArray<N>,
/// see RodBundle). Only (c, s, m) are coupled; x, y and theta are quadratures of the stage values,
/// written with the same arithmetic as one RK4 update of the whole vector. With Sens, the tangents
/// w.r.t. the proximal (n_x, n_y, m) are RK4 applied to the variational equations, which is
/// exactly the derivative of the discrete map: Newton sees the true Jacobian. Plain locals rather
/// than Eigen blocks: the recurrence is latency-bound, and this keeps the three tangent columns
/// and the lanes independent chains the CPU can overlap. A lane does the scalar stepper's
/// operations in the same order, so a bundle's lane is bit for bit the rod stepped alone (unless
/// the compiler contracts multiply-adds into FMAs differently in the two, as -march=native lets
/// it).
template <class L, bool Sens>
struct RodStepper {
  static constexpr bool kSens = Sens;
  L nx, ny, x, y, c, s, th, m;
  L inv_ei, h, half_h, sixth_h, max_abs_moment;  ///< inv_ei: 1 / EI at the current node
  /// u* at the current node, and its increase over half a step and a whole step (u* is linear in
  /// s, so the stages' values are exact; all zero for a straight rod, which then steps as before).
  L u_node, du_half, du_step;
  /// A tapered rod: 1 / EI(s) = inv_ei_base / w^4 with w = d(s) / d = 1 + taper s, evaluated at
  /// each stage (taper = d' / d, 1/m); s_node is the current node's arc length.
  L inv_ei_base, taper, s_node;
  /// Which law this stepper's rods need (for a bundle: the most general of its lanes). A straight
  /// uniform rod steps without the three adds of u*: they sit on the latency-bound chain
  /// m -> theta' -> (c, s) and cost a fifth of a step; only a tapered rod pays for EI(s) at the
  /// stages. Jets always step by the general law: their derivatives in u* and d' may be non-zero
  /// at zero.
  RodLaw law = RodLaw::kTapered;
  L tx[3], ty[3], tc[3], ts[3], tth[3], tm[3];  ///< tangents, [j]: d / d wrench_j (with Sens)

  /// One rod (L a scalar): its proximal state, the rod and the RK4 step count.
  void init(const RodState<L>& start, const Rod<L>& rod, int steps) {
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
    inv_ei = L(1) / rod.bending_stiffness();
    h = rod.length / L(steps);
    half_h = h / L(2);
    sixth_h = h / L(6);
    max_abs_moment = abs(m);
    u_node = rod.precurvature;
    du_half = rod.precurvature_slope * half_h;
    du_step = rod.precurvature_slope * h;
    inv_ei_base = inv_ei;
    taper = rod.diameter_slope / rod.diameter;
    s_node = L(0);
    if constexpr (std::is_arithmetic_v<L>) {
      law = !rod.uniform()   ? RodLaw::kTapered
            : rod.straight() ? RodLaw::kStraightUniform
                             : RodLaw::kCurvedUniform;
    }
  }

  EIGEN_ALWAYS_INLINE void step() {
    if constexpr (std::is_arithmetic_v<L> || is_lane_array<L>::value) {
      if (law == RodLaw::kStraightUniform) {
        step_with<RodLaw::kStraightUniform>();
      } else if (law == RodLaw::kCurvedUniform) {
        step_with<RodLaw::kCurvedUniform>();
      } else {
        step_with<RodLaw::kTapered>();
      }
    } else {
      step_with<RodLaw::kTapered>();
    }
  }

  RodState<L> state() const { return RodState<L>{x, y, th, nx, ny, m}; }

 private:
  template <RodLaw Law>
  PCR_SIMD_CLONES void step_with() {
    using std::abs;
    constexpr bool kCurved = Law != RodLaw::kStraightUniform, kTapered = Law == RodLaw::kTapered;
    // Stage values (the rhs of x, y, theta are c, s, k) and slopes of (c, s, m); g: tangents.
    L sc[4], ss[4], sk[4], dc[4], ds[4], dm[4];
    L gc[3][4], gs[3][4], gk[3][4], gdc[3][4], gds[3][4], gdm[3][4];  // [column][stage]
    const L u_half = u_node + du_half, u_end = u_node + du_step;      // u* at the stages
    // 1 / EI at the stages and (d / d(s))^3 at the step's end (its strain scale): off the chain.
    L inv_ei_half = inv_ei, inv_ei_end = inv_ei, cube_end = L(1);
    if constexpr (kTapered) {
      const L r_half = L(1) / (L(1) + taper * (s_node + half_h));
      const L r_end = L(1) / (L(1) + taper * (s_node + h));
      const L r2_half = r_half * r_half, r2_end = r_end * r_end;
      inv_ei_half = inv_ei_base * (r2_half * r2_half);
      inv_ei_end = inv_ei_base * (r2_end * r2_end);
      cube_end = r2_end * r_end;
    }
    // The loops over stages and columns are unrolled, so that the branches fold away and the
    // values stay in registers (with lanes GCC kept them rolled, going through memory).
#pragma GCC unroll 4
    for (int st = 0; st < 4; ++st) {
      const L& a = st == 3 ? h : half_h;
      const int p = st == 0 ? 0 : st - 1;
      const L cc = st == 0 ? c : L(c + a * dc[p]);
      const L sv = st == 0 ? s : L(s + a * ds[p]);
      const L mm = st == 0 ? m : L(m + a * dm[p]);
      const L& u = st == 0 ? u_node : st == 3 ? u_end : u_half;
      const L& ie = !kTapered || st == 0 ? inv_ei : st == 3 ? inv_ei_end : inv_ei_half;
      const L k = kCurved ? L(mm * ie + u) : L(mm * ie);
      sc[st] = cc;
      ss[st] = sv;
      sk[st] = k;
      dc[st] = -sv * k;
      ds[st] = cc * k;
      dm[st] = nx * sv - ny * cc;
      if constexpr (Sens) {
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) {
          if (st == 0) {
            gc[j][0] = tc[j];
            gs[j][0] = ts[j];
            gk[j][0] = tm[j] * ie;
          } else {
            gc[j][st] = tc[j] + a * gdc[j][p];
            gs[j][st] = ts[j] + a * gds[j][p];
            gk[j][st] = (tm[j] + a * gdm[j][p]) * ie;
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
#pragma GCC unroll 3
      for (int j = 0; j < 3; ++j) {
        rk4(tx[j], gc[j]);
        rk4(ty[j], gs[j]);
        rk4(tc[j], gdc[j]);
        rk4(ts[j], gds[j]);
        rk4(tth[j], gk[j]);
        rk4(tm[j], gdm[j]);
      }
    }
    keep_larger(max_abs_moment, kTapered ? L(abs(m) * cube_end) : L(abs(m)));
    if constexpr (kCurved) u_node += du_step;
    if constexpr (kTapered) {
      inv_ei = inv_ei_end;
      s_node += h;
    }
  }

  /// One RK4 update of a state or a tangent column from its four slopes (forced inline: with
  /// lanes, in a large translation unit, GCC made it a call).
  EIGEN_ALWAYS_INLINE void rk4(L& v, const L (&k)[4]) const {
    v += sixth_h * (k[0] + L(2) * (k[1] + k[2]) + k[3]);
  }
};

/// Up to N rods stepped together, one per lane.
template <int N, bool Sens>
using RodBundle = RodStepper<LaneArray<N>, Sens>;

/// Calls f(bundle's field, rod's field) for every field of a bundle and a one-rod stepper (either
/// may be const).
template <class Bundle, class Rod, class F>
void zip_lane_fields(Bundle& bundle, Rod& rod, F&& f) {
  f(bundle.nx, rod.nx);
  f(bundle.ny, rod.ny);
  f(bundle.x, rod.x);
  f(bundle.y, rod.y);
  f(bundle.c, rod.c);
  f(bundle.s, rod.s);
  f(bundle.th, rod.th);
  f(bundle.m, rod.m);
  f(bundle.inv_ei, rod.inv_ei);
  f(bundle.h, rod.h);
  f(bundle.half_h, rod.half_h);
  f(bundle.sixth_h, rod.sixth_h);
  f(bundle.max_abs_moment, rod.max_abs_moment);
  f(bundle.u_node, rod.u_node);
  f(bundle.du_half, rod.du_half);
  f(bundle.du_step, rod.du_step);
  f(bundle.inv_ei_base, rod.inv_ei_base);
  f(bundle.taper, rod.taper);
  f(bundle.s_node, rod.s_node);
  if constexpr (std::decay_t<Rod>::kSens) {
    for (int j = 0; j < 3; ++j) {
      f(bundle.tx[j], rod.tx[j]);
      f(bundle.ty[j], rod.ty[j]);
      f(bundle.tc[j], rod.tc[j]);
      f(bundle.ts[j], rod.ts[j]);
      f(bundle.tth[j], rod.tth[j]);
      f(bundle.tm[j], rod.tm[j]);
    }
  }
}

/// Puts an initialised one-rod stepper into lane `lane` of a bundle.
template <int N, bool Sens>
void set_lane(RodBundle<N, Sens>& bundle, int lane, const RodStepper<double, Sens>& rod) {
  zip_lane_fields(bundle, rod, [lane](auto& lanes, const double& v) { lanes[lane] = v; });
  bundle.law = lane == 0 ? rod.law : std::max(bundle.law, rod.law);  // lane 0 is set first
}

/// The one-rod stepper in lane `lane` of a bundle.
template <int N, bool Sens>
RodStepper<double, Sens> get_lane(const RodBundle<N, Sens>& bundle, int lane) {
  RodStepper<double, Sens> rod;
  zip_lane_fields(bundle, rod, [lane](const auto& lanes, double& v) { v = lanes[lane]; });
  rod.law = bundle.law;
  return rod;
}

struct NoStepVisitor {
  template <class Bundle>
  void operator()(int, const Bundle&) const {}
};

/// Integrates n <= N initialised rods over `steps` steps in one bundle of N lanes, and writes
/// their final states back (bit for bit what one at a time gives, see RodStepper). Lanes beyond n
/// carry a copy of rod 0. after_step(k, bundle) sees the bundle at node k = 1 ... steps.
template <int N, bool Sens, class AfterStep = NoStepVisitor>
void integrate_rods_bundled(RodStepper<double, Sens>* rods, int n, int steps,
                            AfterStep&& after_step = AfterStep()) {
  RodBundle<N, Sens> bundle;
  for (int r = 0; r < N; ++r) set_lane(bundle, r, rods[r < n ? r : 0]);
  for (int i = 0; i < steps; ++i) {
    bundle.step();
    after_step(i + 1, bundle);
  }
  for (int r = 0; r < n; ++r) rods[r] = get_lane(bundle, r);
}

/// Calls f(std::integral_constant<int, N>()) with the lane count N of the smallest bundle (2, 4 or
/// 8 lanes) that holds n rods (n <= 8).
template <class F>
decltype(auto) with_lane_count(int n, F&& f) {
  if (n <= 2) return f(std::integral_constant<int, 2>());
  if (n <= 4) return f(std::integral_constant<int, 4>());
  return f(std::integral_constant<int, 8>());
}

/// Integrates n initialised rods (n <= 8) over `steps` steps in SIMD lanes: in a bundle of 2, 4 or
/// 8 lanes, the smallest that holds them. after_step(k, bundle) as in integrate_rods_bundled (rod
/// r in lane r).
template <bool Sens, class AfterStep = NoStepVisitor>
void integrate_rods_in_lanes(RodStepper<double, Sens>* rods, int n, int steps,
                             AfterStep&& after_step = AfterStep()) {
  if (n <= 0) return;
  with_lane_count(n, [&](auto lanes) {
    integrate_rods_bundled<decltype(lanes)::value>(rods, n, steps, after_step);
  });
}

template <class T, bool Sens, class Visitor>
RodStepper<T, Sens> integrate_rod_pass(const RodState<T>& start, const Rod<T>& rod, int steps,
                                       Visitor&& visit) {
  RodStepper<T, Sens> stepper;
  stepper.init(start, rod, steps);
  visit(T(0), stepper.state());
  for (int i = 0; i < steps; ++i) {
    stepper.step();
    visit(T(i + 1) * stepper.h, stepper.state());
  }
  return stepper;
}

/// A one-rod stepper's state as a RodTip: its sensitivities with Sens, else left unset.
template <class T, bool Sens>
RodTip<T> tip_of(const RodStepper<T, Sens>& rod) {
  RodTip<T> tip;
  tip.state = rod.state();
  tip.max_abs_moment = rod.max_abs_moment;
  if constexpr (Sens) {
    for (int j = 0; j < 3; ++j) {
      tip.sensitivity(0, j) = rod.tx[j];
      tip.sensitivity(1, j) = rod.ty[j];
      tip.sensitivity(2, j) = rod.tth[j];
      tip.sensitivity(3, j) = rod.tm[j];
    }
  }
  return tip;
}

}  // namespace internal

/// Integrates the rod from its proximal state over [0, rod.length].
template <class T>
RodState<T> integrate_rod(const RodState<T>& start, const Rod<T>& rod, int steps,
                          T* max_abs_moment = nullptr) {
  const auto pass =
      internal::integrate_rod_pass<T, false>(start, rod, steps, internal::NoVisitor{});
  if (max_abs_moment) *max_abs_moment = pass.max_abs_moment;
  return pass.state();
}

/// Integrates the rod and its sensitivity to the proximal wrench (n_x, n_y, m)(0).
template <class T>
RodTip<T> integrate_rod_with_sensitivity(const RodState<T>& start, const Rod<T>& rod, int steps) {
  return internal::tip_of(
      internal::integrate_rod_pass<T, true>(start, rod, steps, internal::NoVisitor{}));
}

/// Integrates the rod and calls visit(s, RodState) at each of the steps + 1 nodes (the shape).
template <class T, class Visitor>
RodState<T> sample_rod(const RodState<T>& start, const Rod<T>& rod, int steps, Visitor&& visit) {
  return internal::integrate_rod_pass<T, false>(start, rod, steps, visit).state();
}

}  // namespace pcr
