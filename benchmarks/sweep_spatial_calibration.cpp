// The spatial calibration on hidden virtual robots (docs/calibration.md, "Spatial robots"): the
// reference continuum Stewart-Gough robot, truths drawn uniformly inside its intervals (seeds
// 1-20) and at +-0.9 half-widths (seeds 21-40), 60 calibration and 20 validation rows with every
// joint drawn uniformly in [0, 10] mm, in the order drawn (long jumps), the default noise. For
// each truth: the time of calibrate_spatial (one core), the residual variance, and the validation
// rms position and angle against the floor sqrt(3) sigma; then the median and worst.
//   build/benchmarks/sweep_spatial_calibration [first last fraction]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "pcr/calib/spatial_calibrator.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"

namespace {

struct Outcome {
  double time_s, position_ratio, angle_ratio;
};

Outcome calibrate_one(const pcr::SpatialRobotDescription& nominal, int seed, double fraction) {
  pcr::SpatialVirtualRobotOptions options;
  options.seed = static_cast<std::uint64_t>(seed);
  options.truth_at_fraction = fraction;
  pcr::SpatialVirtualRobot robot(nominal, options);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> joint(0.0, 0.01);
  const auto measured = [&](int rows) {
    std::vector<pcr::SpatialJointVector> q(static_cast<std::size_t>(rows),
                                           pcr::SpatialJointVector(nominal.params.num_rods));
    for (auto& row : q)
      for (int i = 0; i < row.size(); ++i) row(i) = joint(rng);
    const std::vector<pcr::SpatialVirtualMeasurement> m = robot.measure_dataset(q);
    pcr::SpatialDataset data;
    data.num_joints = nominal.params.num_rods;
    for (std::size_t r = 0; r < q.size(); ++r)
      if (m[r].ok) data.add(q[r], m[r].measured);
    return data;
  };
  const pcr::SpatialDataset calibration = measured(60), validation = measured(20);
  const pcr::SpatialCalibrationResult result = pcr::calibrate_spatial(nominal, calibration);
  const pcr::SpatialPredictionErrors errors =
      pcr::spatial_prediction_errors(result.identified, validation);
  const double floor_position = std::sqrt(3.0) * robot.noise_position();
  const double floor_angle = std::sqrt(3.0) * options.noise_angle;
  const Outcome out{result.time_s, errors.rms_position / floor_position,
                    errors.rms_angle / floor_angle};
  std::printf(
      "seed %2d at %.1f: %5.2f s, variance %6.3f, validation %.3g m %.3g rad = %.2f x, %.2f x "
      "the floor, %d rows without FK\n",
      seed, fraction, result.time_s, result.residual_variance, errors.rms_position,
      errors.rms_angle, out.position_ratio, out.angle_ratio, errors.failures);
  std::fflush(stdout);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  std::vector<Outcome> outcomes;
  if (argc == 4) {
    for (int seed = std::atoi(argv[1]); seed <= std::atoi(argv[2]); ++seed)
      outcomes.push_back(calibrate_one(nominal, seed, std::atof(argv[3])));
  } else {
    for (int seed = 1; seed <= 20; ++seed) outcomes.push_back(calibrate_one(nominal, seed, 0.0));
    for (int seed = 21; seed <= 40; ++seed) outcomes.push_back(calibrate_one(nominal, seed, 0.9));
  }
  std::vector<double> times;
  double worst_position = 0, worst_angle = 0;
  for (const Outcome& o : outcomes) {
    times.push_back(o.time_s);
    worst_position = std::max(worst_position, o.position_ratio);
    worst_angle = std::max(worst_angle, o.angle_ratio);
  }
  std::sort(times.begin(), times.end());
  const std::size_t m = times.size();
  const double median = m % 2 ? times[m / 2] : 0.5 * (times[m / 2 - 1] + times[m / 2]);
  std::printf(
      "%zu truths: time median %.2f s, max %.2f s; worst validation %.2f x (position), "
      "%.2f x (angle) the floor\n",
      m, median, times.back(), worst_position, worst_angle);
  return 0;
}
