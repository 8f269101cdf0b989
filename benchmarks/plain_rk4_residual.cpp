// Built with -O2 on its own (benchmarks/CMakeLists.txt), as a plain program would be.
#include "plain_rk4_residual.hpp"

#include <cmath>

namespace pcr::bench {
namespace {

struct State {
  double x, y, theta, m;
};

State derivative(const State& s, double nx, double ny, double ei) {
  const double c = std::cos(s.theta), sn = std::sin(s.theta);
  return {c, sn, s.m / ei, nx * sn - ny * c};
}

State step(const State& s, const State& k, double h) {
  return {s.x + h * k.x, s.y + h * k.y, s.theta + h * k.theta, s.m + h * k.m};
}

}  // namespace

void plain_rk4_residual(const PlainRod (&rods)[3], const double (&unknowns)[12],
                        double (&residual)[12]) {
  constexpr int kSteps = 64;
  const double px = unknowns[9], py = unknowns[10], ptheta = unknowns[11];
  const double c = std::cos(ptheta), s = std::sin(ptheta);
  double fx = 0, fy = 0, moment = 0;
  for (int i = 0; i < 3; ++i) {
    const PlainRod& rod = rods[i];
    const double nx = unknowns[3 * i], ny = unknowns[3 * i + 1];
    State state{rod.ax, rod.ay, rod.alpha, unknowns[3 * i + 2]};
    const double h = rod.length / kSteps;
    for (int k = 0; k < kSteps; ++k) {
      const State k1 = derivative(state, nx, ny, rod.ei);
      const State k2 = derivative(step(state, k1, h / 2), nx, ny, rod.ei);
      const State k3 = derivative(step(state, k2, h / 2), nx, ny, rod.ei);
      const State k4 = derivative(step(state, k3, h), nx, ny, rod.ei);
      state.x += h / 6 * (k1.x + 2 * k2.x + 2 * k3.x + k4.x);
      state.y += h / 6 * (k1.y + 2 * k2.y + 2 * k3.y + k4.y);
      state.theta += h / 6 * (k1.theta + 2 * k2.theta + 2 * k3.theta + k4.theta);
      state.m += h / 6 * (k1.m + 2 * k2.m + 2 * k3.m + k4.m);
    }
    residual[3 * i] = state.x - (px + c * rod.bx - s * rod.by);
    residual[3 * i + 1] = state.y - (py + s * rod.bx + c * rod.by);
    residual[3 * i + 2] = state.theta - (ptheta + rod.beta);
    fx += nx;
    fy += ny;
    moment += state.m + (state.x - px) * ny - (state.y - py) * nx;
  }
  residual[9] = fx;
  residual[10] = fy;
  residual[11] = moment;
}

}  // namespace pcr::bench
