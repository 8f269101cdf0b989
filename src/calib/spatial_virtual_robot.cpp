#include "pcr/calib/spatial_virtual_robot.hpp"

#include <cmath>

#include "pcr/csv_io.hpp"  // format_double
#include "virtual_robot_rules.hpp"

namespace pcr {

double spatial_default_noise_position(const SpatialRobotParams<double>& robot) {
  double length = 0.0;
  for (int i = 0; i < robot.num_rods; ++i) length += robot.limb(i).rod.length;
  return robot.num_rods > 0 ? 9.13e-9 * (length / robot.num_rods) / kPaperRodLength : 0.0;
}

SpatialVirtualRobot::SpatialVirtualRobot(const SpatialRobotDescription& nominal,
                                         const SpatialVirtualRobotOptions& options)
    : nominal_(nominal), truth_(nominal), options_(options) {
  const int n = nominal.params.num_rods;
  if (n < 1 || n > kMaxSpatialRods) {
    throw InputError("SpatialVirtualRobot: robot '" + nominal.name + "' has " + std::to_string(n) +
                     " rods (expected 1 to " + std::to_string(kMaxSpatialRods) + ")");
  }
  require_valid(options, "SpatialVirtualRobotOptions");
  noise_position_ = std::isnan(options.noise_position)
                        ? spatial_default_noise_position(nominal.params)
                        : options.noise_position;

  // Two independent streams from one seed: the truth, and the measurement noise.
  std::seed_seq truth_seq{options.seed, std::uint64_t{0x7472757468}};  // "truth"
  std::seed_seq noise_seq{options.seed, std::uint64_t{0x6e6f697365}};  // "noise"
  std::mt19937_64 rng(truth_seq);
  noise_rng_.seed(noise_seq);

  SpatialUncertainty u;
  if (nominal.uncertainty) u = *nominal.uncertainty;
  const double f = options.truth_at_fraction;
  const int count = num_spatial_parameters(n);
  std::vector<double> d(static_cast<std::size_t>(count), 0.0);
  // One material and one wire: E, G and d drawn once, from the first rod's intervals.
  const int shared[] = {static_cast<int>(SpatialParameterKind::kYoungModulus),
                        static_cast<int>(SpatialParameterKind::kShearModulus),
                        static_cast<int>(SpatialParameterKind::kDiameter)};
  for (const int k : shared) {
    const double value = internal::draw_within(
        rng, 0.0, spatial_half_width(u, SpatialParameterId{SpatialParameterKind(k), 0}), f);
    for (int i = 0; i < n; ++i) d[static_cast<std::size_t>(kSpatialRodParameters * i + k)] = value;
  }
  for (int k = 0; k < count; ++k) {
    const SpatialParameterId id = spatial_parameter_id(k, n);
    if (id.rod >= 0 && static_cast<int>(id.kind) < static_cast<int>(SpatialParameterKind::kLength))
      continue;  // shared above
    d[static_cast<std::size_t>(k)] = internal::draw_within(rng, 0.0, spatial_half_width(u, id), f);
  }

  // Unmodelled effects, each from its own stream: switching one on changes neither the others
  // nor the truth above.
  const SpatialUnmodelledEffects& fx = options.effects;
  if (fx.misalignment_half_width > 0) {
    std::seed_seq seq{options.seed, std::uint64_t{0x6d6973616c}};  // "misal"
    std::mt19937_64 r(seq);
    for (int i = 0; i < n; ++i) {
      for (int axis = 0; axis < 3; ++axis) {
        double& turn = d[static_cast<std::size_t>(
            kSpatialRodParameters * i + static_cast<int>(SpatialParameterKind::kBaseRx) + axis)];
        turn = internal::draw_within(r, turn, fx.misalignment_half_width);
      }
    }
  }
  if (fx.diameter_half_width > 0) {
    std::seed_seq seq{options.seed, std::uint64_t{0x6469616d}};  // "diam"
    std::mt19937_64 r(seq);
    for (int i = 0; i < n; ++i) {
      double& diameter = d[static_cast<std::size_t>(
          kSpatialRodParameters * i + static_cast<int>(SpatialParameterKind::kDiameter))];
      diameter = internal::draw_within(r, diameter, fx.diameter_half_width);
    }
  }
  truth_.params = spatial_with_deviations(nominal.params, d.data());
  truth_.params.platform_mass += fx.payload;
  if (fx.rod_density >= 0) {
    for (int i = 0; i < n; ++i) truth_.params.limb(i).rod.density = fx.rod_density;
  }
  for (int i = 0; i < n; ++i) {
    const SpatialRod<double>& rod = truth_.params.limb(i).rod;
    if (!(rod.diameter > 0 && rod.young_modulus > 0 && rod.shear_modulus > 0 && rod.length > 0)) {
      throw InputError(
          "SpatialVirtualRobot: robot '" + nominal.name + "': the intervals of rod " +
          std::to_string(i) + " reach a diameter, a modulus or a length <= 0 (drawn: d " +
          format_double(rod.diameter) + " m, E " + format_double(rod.young_modulus) + " Pa, G " +
          format_double(rod.shear_modulus) + " Pa, l " + format_double(rod.length) + " m)");
    }
  }
  // A robot moves from configuration to configuration: each measurement continues from the last.
  sequence_ =
      SpatialForwardSequence(truth_.params, options_.solver, SpatialNoLoad(), SequenceMode::kPath);
}

SpatialVirtualMeasurement SpatialVirtualRobot::measure(const SpatialJointVector& q) {
  SpatialVirtualMeasurement m;
  const SpatialForwardSolution& fk = sequence_.solve(q);
  m.summary = fk.summary;
  bool home_again = false;
  if (!internal::measured_equilibrium(m.summary, &home_again)) {
    if (home_again) return_home();
    return m;
  }
  m.ok = true;
  m.platform = fk.pose;
  m.exact = truth_.params.extrinsics.measurement_from_platform(fk.pose);
  std::normal_distribution<double> gauss(0.0, 1.0);
  m.measured = m.exact;
  for (int k = 0; k < 3; ++k) m.measured.position(k) += noise_position_ * gauss(noise_rng_);
  Vector3<double> turn;
  for (int k = 0; k < 3; ++k) turn(k) = options_.noise_angle * gauss(noise_rng_);
  m.measured.orientation = quaternion_product<double>(m.exact.orientation, quaternion_exp(turn));
  return m;
}

std::vector<SpatialVirtualMeasurement> SpatialVirtualRobot::measure_dataset(
    const std::vector<SpatialJointVector>& rows) {
  return_home();
  std::vector<SpatialVirtualMeasurement> out;
  out.reserve(rows.size());
  for (const SpatialJointVector& q : rows) out.push_back(measure(q));
  return out;
}

}  // namespace pcr
