// The gauge orbit of the flat parameters: generators, motions along it, the limb-0 gauge fix.

#include "pcr/calib/gauge.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibration_internal.hpp"
#include "pcr/calib/calibrator.hpp"

namespace pcr {
namespace calib_internal {

std::vector<bool> present_generators(const std::vector<GaugeGenerator>& generators,
                                     const std::vector<bool>& is_free) {
  std::vector<bool> present(generators.size(), false);
  for (std::size_t g = 0; g < generators.size(); ++g) {
    bool ok = true, any = false;
    for (std::size_t k = 0; k < is_free.size(); ++k) {
      if (generators[g].direction[k] != 0.0) {
        ok = ok && is_free[k];
        any = true;
      }
    }
    present[g] = ok && any;
  }
  return present;
}

}  // namespace calib_internal

std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot) {
  const int n = robot.num_limbs;
  const int count = num_parameters(n);
  auto idx = [n](ParameterKind kind, int limb) {
    return parameter_index(ParameterId{kind, limb}, n);
  };
  auto blank = [count]() { return std::vector<double>(static_cast<std::size_t>(count), 0.0); };
  std::vector<GaugeGenerator> out;
  const Pose2<double>& camera = robot.extrinsics.camera;
  const Pose2<double>& pattern = robot.extrinsics.pattern;
  for (int axis = 0; axis < 2; ++axis) {
    GaugeGenerator g{std::string("proximal clamps + camera: translation ") + (axis ? "y" : "x"),
                     std::string(axis ? "A_y[*] + camera_y" : "A_x[*] + camera_x"), blank()};
    for (int i = 0; i < n; ++i)
      g.direction[idx(axis ? ParameterKind::kAy : ParameterKind::kAx, i)] = 1;
    g.direction[idx(axis ? ParameterKind::kCameraY : ParameterKind::kCameraX, -1)] = 1;
    out.push_back(g);
  }
  {
    GaugeGenerator g{"proximal clamps + camera: rotation",
                     "(A_x, A_y)[*] rotated about W + alpha[*] + camera", blank()};
    for (int i = 0; i < n; ++i) {
      g.direction[idx(ParameterKind::kAx, i)] = -robot.limb(i).A.y();
      g.direction[idx(ParameterKind::kAy, i)] = robot.limb(i).A.x();
      g.direction[idx(ParameterKind::kAlpha, i)] = 1;
    }
    g.direction[idx(ParameterKind::kCameraX, -1)] = -camera.y;
    g.direction[idx(ParameterKind::kCameraY, -1)] = camera.x;
    g.direction[idx(ParameterKind::kCameraTheta, -1)] = 1;
    out.push_back(g);
  }
  for (int axis = 0; axis < 2; ++axis) {
    GaugeGenerator g{
        std::string("distal clamps + pattern: translation ") + (axis ? "y" : "x"),
        std::string(axis ? "B_y[*] - R(pattern_theta) e_y" : "B_x[*] - R(pattern_theta) e_x"),
        blank()};
    for (int i = 0; i < n; ++i)
      g.direction[idx(axis ? ParameterKind::kBy : ParameterKind::kBx, i)] = 1;
    const Vector2<double> e = axis ? Vector2<double>(0, 1) : Vector2<double>(1, 0);
    const Vector2<double> d = -pattern.rotate(e);
    g.direction[idx(ParameterKind::kPatternX, -1)] = d.x();
    g.direction[idx(ParameterKind::kPatternY, -1)] = d.y();
    out.push_back(g);
  }
  {
    GaugeGenerator g{"distal clamps + pattern: rotation",
                     "(B_x, B_y)[*] rotated about P + beta[*] - pattern_theta", blank()};
    for (int i = 0; i < n; ++i) {
      g.direction[idx(ParameterKind::kBx, i)] = -robot.limb(i).B.y();
      g.direction[idx(ParameterKind::kBy, i)] = robot.limb(i).B.x();
      g.direction[idx(ParameterKind::kBeta, i)] = 1;
    }
    g.direction[idx(ParameterKind::kPatternTheta, -1)] = -1;
    out.push_back(g);
  }
  {
    GaugeGenerator g{"bending stiffness: common scale", "d[*] scaled together", blank()};
    for (int i = 0; i < n; ++i)
      g.direction[idx(ParameterKind::kDiameter, i)] = robot.limb(i).rod.diameter;
    out.push_back(g);
  }
  return out;
}

RobotParams<double> move_along_gauge(const RobotParams<double>& params, const Pose2<double>& G,
                                     const Pose2<double>& H, double stiffness_scale) {
  RobotParams<double> out = params;
  for (int i = 0; i < params.num_limbs; ++i) {
    LimbParams<double>& limb = out.limb(i);
    limb.A = G.transform(params.limb(i).A);
    limb.alpha = params.limb(i).alpha + G.theta;
    limb.B = H.transform(params.limb(i).B);
    limb.beta = params.limb(i).beta + H.theta;
    limb.rod.diameter = params.limb(i).rod.diameter * stiffness_scale;
  }
  out.extrinsics.camera = G * params.extrinsics.camera;
  out.extrinsics.pattern = params.extrinsics.pattern * H.inverse();
  return out;
}

PlatformLoad<double> move_load_along_gauge(const PlatformLoad<double>& load, const Pose2<double>& G,
                                           const Pose2<double>& H, double stiffness_scale) {
  const double stiffness = std::pow(stiffness_scale, 4);  // EI ~ d^4
  PlatformLoad<double> out;
  out.force = stiffness * G.rotate(load.force);
  // The new platform origin lies at H^-1(0) in the old platform frame: the moment about it
  // loses that arm's cross product with the force (platform angle taken as 0).
  const Vector2<double> arm = H.inverse().translation();
  out.moment = stiffness * (load.moment - (arm.x() * load.force.y() - arm.y() * load.force.x()));
  return out;
}

ForwardSolution move_equilibrium_along_gauge(const ForwardSolution& solution,
                                             const Pose2<double>& G, const Pose2<double>& H,
                                             double stiffness_scale) {
  const double stiffness = std::pow(stiffness_scale, 4);  // EI ~ d^4
  ForwardSolution out = solution;
  out.pose = G * solution.pose * H.inverse();
  for (Wrench<double>& w : out.wrenches) {
    const Vector2<double> n = stiffness * G.rotate(Vector2<double>(w.nx, w.ny));
    w = Wrench<double>{n.x(), n.y(), stiffness * w.m};  // m(0), about the rod's start: not turned
  }
  out.jacobian.clear();
  return out;
}

std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot,
                                             const PlatformLoad<double>& load) {
  std::vector<GaugeGenerator> out = gauge_generators(robot);
  const double fx = load.force.x(), fy = load.force.y(), m = load.moment;
  // d load / d coefficient of each generator, in gauge_generators' order (see
  // move_load_along_gauge): proximal x, y, rotation; distal x, y, rotation; stiffness.
  const double components[7][kLoadParameters] = {
      {0, 0, 0},   {0, 0, 0}, {-fy, fx, 0},           {0, 0, fy},
      {0, 0, -fx}, {0, 0, 0}, {4 * fx, 4 * fy, 4 * m}};
  for (std::size_t j = 0; j < out.size(); ++j) {
    out[j].direction.insert(out[j].direction.end(), components[j], components[j] + kLoadParameters);
  }
  return out;
}

GaugeMotion gauge_fix_motion(const RobotParams<double>& params,
                             const RobotParams<double>& reference, bool proximal_translation,
                             bool proximal_rotation, bool distal_translation, bool distal_rotation,
                             bool stiffness) {
  // The motion that maps limb 0's estimated clamp frame onto its reference one; a rotation alone
  // turns about the origin.
  const auto onto_reference = [](bool translation, bool rotation, const Vector2<double>& estimated,
                                 double estimated_angle, const Vector2<double>& wanted,
                                 double wanted_angle) {
    const double rot = rotation ? wanted_angle - estimated_angle : 0.0;
    if (!translation) return Pose2<double>{0, 0, rot};
    const Vector2<double> t = wanted - Pose2<double>{0, 0, rot}.rotate(estimated);
    return Pose2<double>{t.x(), t.y(), rot};
  };
  const LimbParams<double>& limb = params.limb(0);
  const LimbParams<double>& ref = reference.limb(0);
  return GaugeMotion{
      onto_reference(proximal_translation, proximal_rotation, limb.A, limb.alpha, ref.A, ref.alpha),
      onto_reference(distal_translation, distal_rotation, limb.B, limb.beta, ref.B, ref.beta),
      stiffness ? ref.rod.diameter / limb.rod.diameter : 1.0};
}

GaugeMotion gauge_fix_motion(const RobotParams<double>& params, const PlatformLoad<double>& load,
                             const RobotParams<double>& reference, bool held[2]) {
  const Vector2<double>& B = params.limb(0).B;
  const Vector2<double>& wanted = reference.limb(0).B;
  const double force = load.force.norm();
  if (!(force > 0)) {
    held[0] = held[1] = true;
    return GaugeMotion{Pose2<double>{0, 0, 0},
                       Pose2<double>{wanted.x() - B.x(), wanted.y() - B.y(), 0}, 1.0};
  }
  // The platform origin moves by -t: its moment arm about the old origin, t x f at angle 0, is
  // compensated by move_load_along_gauge; what is left, (R(theta) - I) t x f, is second order in
  // theta when t is perpendicular to f.
  const Vector2<double> u(-load.force.y() / force, load.force.x() / force);
  const int c = std::abs(u.x()) >= std::abs(u.y()) ? 0 : 1;
  held[c] = true;
  held[1 - c] = false;
  const Vector2<double> t = (wanted[c] - B[c]) / u[c] * u;
  return GaugeMotion{Pose2<double>{0, 0, 0}, Pose2<double>{t.x(), t.y(), 0}, 1.0};
}

RobotParams<double> fix_gauge(const RobotParams<double>& params,
                              const RobotParams<double>& reference, bool proximal_translation,
                              bool proximal_rotation, bool distal_translation, bool distal_rotation,
                              bool stiffness) {
  const GaugeMotion m = gauge_fix_motion(params, reference, proximal_translation, proximal_rotation,
                                         distal_translation, distal_rotation, stiffness);
  return move_along_gauge(params, m.G, m.H, m.stiffness_scale);
}

RobotParams<double> in_calibration_gauge(const CalibrationResult& result,
                                         const RobotParams<double>& nominal,
                                         const RobotParams<double>& robot) {
  if (robot.num_limbs != nominal.num_limbs) {
    throw std::invalid_argument("robot: expected " + std::to_string(nominal.num_limbs) +
                                " limbs, got " + std::to_string(robot.num_limbs));
  }
  const auto held = [&result](const char* name) {
    for (const ParameterEstimate& p : result.parameters) {
      if (p.name == name) return p.gauge_reference;
    }
    return false;
  };
  return fix_gauge(robot, nominal, held("A_x[0]") && held("A_y[0]"), held("alpha[0]"),
                   held("B_x[0]") && held("B_y[0]"), held("beta[0]"), held("d[0]"));
}

}  // namespace pcr
