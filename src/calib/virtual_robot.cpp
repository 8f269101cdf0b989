#include "pcr/calib/virtual_robot.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "virtual_robot_rules.hpp"

namespace pcr {
namespace {

std::string format_q(const JointVector& q) {
  std::ostringstream out;
  out.precision(17);
  out << "(";
  for (int i = 0; i < q.size(); ++i) out << (i ? ", " : "") << q(i);
  out << ")";
  return out.str();
}

}  // namespace

VirtualRobot::VirtualRobot(const RobotDescription& nominal, const VirtualRobotOptions& options)
    : nominal_(nominal), truth_(nominal), options_(options), noise_rng_() {
  const int n = nominal.params.num_limbs;
  if (n < 2 || n > kMaxLimbs) {
    throw InputError("VirtualRobot: robot '" + nominal.name + "' has " + std::to_string(n) +
                     " limbs (expected 2 to " + std::to_string(kMaxLimbs) + ")");
  }
  require_valid(options, "VirtualRobotOptions");
  const double f = options.truth_at_fraction;

  // Two independent streams from one seed: the truth, and the measurement noise.
  std::seed_seq truth_seq{options.seed, std::uint64_t{0x7472757468}};  // "truth"
  std::seed_seq noise_seq{options.seed, std::uint64_t{0x6e6f697365}};  // "noise"
  std::mt19937_64 rng(truth_seq);
  noise_rng_.seed(noise_seq);

  RobotUncertainty u;
  if (nominal.uncertainty) u = *nominal.uncertainty;
  if (u.limbs.size() != static_cast<std::size_t>(n))
    u.limbs.assign(static_cast<std::size_t>(n), u.global);

  RobotParams<double>& p = truth_.params;
  // One material and one wire: E and d are drawn once for all limbs (relative to limb 0's
  // nominal offset, so per-limb nominal differences are kept).
  const double e_offset = internal::draw_within(rng, 0.0, u.global.rod.young_modulus, f);
  const double d_offset = internal::draw_within(rng, 0.0, u.global.rod.diameter, f);
  truth_.young_modulus = nominal.young_modulus + e_offset;
  for (int i = 0; i < n; ++i) {
    const LimbUncertainty& h = u.limbs[static_cast<std::size_t>(i)];
    LimbParams<double>& limb = p.limb(i);
    limb.rod.young_modulus += e_offset;
    limb.rod.diameter += d_offset;
    limb.rod.length = internal::draw_within(rng, limb.rod.length, h.rod.length, f);
    limb.A.x() = internal::draw_within(rng, limb.A.x(), h.A.x(), f);
    limb.A.y() = internal::draw_within(rng, limb.A.y(), h.A.y(), f);
    limb.alpha = internal::draw_within(rng, limb.alpha, h.alpha, f);
    limb.B.x() = internal::draw_within(rng, limb.B.x(), h.B.x(), f);
    limb.B.y() = internal::draw_within(rng, limb.B.y(), h.B.y(), f);
    limb.beta = internal::draw_within(rng, limb.beta, h.beta, f);
    limb.gamma = internal::draw_within(rng, limb.gamma, h.gamma, f);
    // Drawn when declared only: the paper's robots keep their truths seed for seed.
    if (h.rod.precurvature > 0)
      limb.rod.precurvature =
          internal::draw_within(rng, limb.rod.precurvature, h.rod.precurvature, f);
  }
  Pose2<double>& camera = p.extrinsics.camera;
  Pose2<double>& pattern = p.extrinsics.pattern;
  camera.x = internal::draw_within(rng, camera.x, u.camera.x(), f);
  camera.y = internal::draw_within(rng, camera.y, u.camera.y(), f);
  camera.theta = internal::draw_within(rng, camera.theta, u.camera.z(), f);
  pattern.x = internal::draw_within(rng, pattern.x, u.pattern.x(), f);
  pattern.y = internal::draw_within(rng, pattern.y, u.pattern.y(), f);
  pattern.theta = internal::draw_within(rng, pattern.theta, u.pattern.z(), f);

  // Unmodelled effects: each from its own stream, so switching one on does not change the others
  // nor the base truth above.
  const UnmodelledEffects& fx = options.effects;
  if (fx.misalignments) {
    std::seed_seq seq{options.seed, std::uint64_t{0x6d6973616c}};
    std::mt19937_64 r(seq);
    for (int i = 0; i < n; ++i) {
      p.limb(i).beta = internal::draw_within(r, p.limb(i).beta, fx.misalignment_half_width);
      p.limb(i).gamma = internal::draw_within(r, p.limb(i).gamma, fx.misalignment_half_width);
    }
  }
  if (fx.unequal_diameters) {
    std::seed_seq seq{options.seed, std::uint64_t{0x6469616d}};
    std::mt19937_64 r(seq);
    for (int i = 0; i < n; ++i) {
      p.limb(i).rod.diameter =
          internal::draw_within(r, p.limb(i).rod.diameter, fx.diameter_half_width);
      if (!(p.limb(i).rod.diameter > 0)) {
        throw InputError("VirtualRobot: effects.diameter_half_width " +
                         std::to_string(fx.diameter_half_width) + " makes a diameter <= 0");
      }
    }
  }
  if (fx.external_load) load_ = fx.load;
  // A robot moves from configuration to configuration: each measurement continues from the last.
  sequence_ = ForwardSequence(truth_.params, options_.solver, load_, SequenceMode::kPath);
}

VirtualMeasurement VirtualRobot::measure(const JointVector& q) {
  VirtualMeasurement m;
  const RobotParams<double>& robot = truth_.params;
  const ForwardSolution& fk = sequence_.solve(q);
  m.summary = fk.summary;
  bool home_again = false;
  if (!internal::measured_equilibrium(m.summary, &home_again)) {
    if (home_again) return_home();
    return m;
  }
  m.ok = true;
  m.platform = fk.pose;
  m.exact = robot.extrinsics.measurement_from_platform(fk.pose);
  std::normal_distribution<double> gauss(0.0, 1.0);
  m.measured = m.exact;
  m.measured.x += options_.noise_position * gauss(noise_rng_);
  m.measured.y += options_.noise_position * gauss(noise_rng_);
  m.measured.theta += options_.noise_angle * gauss(noise_rng_);
  return m;
}

std::vector<VirtualMeasurement> VirtualRobot::measure_dataset(
    const std::vector<JointVector>& rows) {
  return_home();
  std::vector<VirtualMeasurement> out;
  out.reserve(rows.size());
  for (const JointVector& q : rows) out.push_back(measure(q));
  return out;
}

Pose2<double> VirtualRobot::measure_or_throw(const JointVector& q) {
  const VirtualMeasurement m = measure(q);
  if (!m.ok) {
    throw std::runtime_error("virtual robot: no forward-kinematics solution at q = " + format_q(q) +
                             " (solver status " + to_string(m.summary.status) + ", residual " +
                             std::to_string(m.summary.final_residual_norm) + ")");
  }
  return m.measured;
}

}  // namespace pcr
