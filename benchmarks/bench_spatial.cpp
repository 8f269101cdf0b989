// Speed of the spatial Cosserat rod (pcr/spatial/cosserat_rod.hpp): the rods of one shooting
// residual of a continuum Stewart-Gough robot (six rods), with and without the sensitivity a
// Newton step needs, at the default step count and at half of it; a plain baseline residual
// written the textbook way; and FK and IK of the reference robot (pcr/spatial/kinematics.hpp):
// warm along a path of 1 mm / 1 degree steps around its reference pose, from home, and cold.
//   build/benchmarks/bench_spatial [--benchmark_repetitions=5 --benchmark_report_aggregates_only]
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <vector>

#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/spatial/kinematics.hpp"

namespace {

using namespace pcr;

/// Six rods of a continuum Stewart-Gough robot in a bent configuration: 0.4 m of 1 mm NiTi-like
/// rod each, in pairs around a 0.1 m base circle, each with its own proximal wrench (up to about
/// 2 EI / L^2 and 2 EI / L), under gravity.
struct SixRods {
  SpatialRod<double> rod;
  std::array<SpatialRodState<double>, 6> bases;
  Vector3<double> gravity{0, 0, -9.81};

  SixRods() {
    rod.length = 0.4;
    rod.diameter = 1e-3;
    rod.young_modulus = 60e9;
    rod.shear_modulus = 60e9 / (2 * 1.33);
    rod.density = 6450;
    const double ei = rod.bending_stiffness(), L = rod.length;
    for (int i = 0; i < 6; ++i) {
      const double angle = 2 * M_PI * (i / 2) / 3 + (i % 2 ? 0.2 : -0.2);
      SpatialRodState<double>& base = bases[i];
      base.position = 0.1 * Vector3<double>(std::cos(angle), std::sin(angle), 0);
      base.orientation = identity_quaternion<double>();
      base.force = ei / (L * L) * Vector3<double>(std::cos(3.0 * i), std::sin(2.0 * i), -1.5);
      base.moment = ei / L * Vector3<double>(std::sin(1.0 + i), std::cos(2.0 + i), 0.3);
    }
  }
};

void BM_SixRods(benchmark::State& state) {
  const SixRods robot;
  const int steps = static_cast<int>(state.range(0));
  for (auto _ : state) {
    for (const SpatialRodState<double>& base : robot.bases) {
      benchmark::DoNotOptimize(integrate_spatial_rod(base, robot.rod, robot.gravity, steps));
    }
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_SixRods)->Arg(kDefaultSpatialRodSteps)->Arg(kDefaultSpatialRodSteps / 2);

void BM_SixRodsInLanes(benchmark::State& state) {
  const SixRods robot;
  const int steps = static_cast<int>(state.range(0));
  const std::array<SpatialRod<double>, 6> rods{robot.rod, robot.rod, robot.rod,
                                               robot.rod, robot.rod, robot.rod};
  std::array<SpatialRodState<double>, 6> tips;
  for (auto _ : state) {
    integrate_spatial_rods(robot.bases.data(), rods.data(), 6, robot.gravity, steps, tips.data());
    benchmark::DoNotOptimize(tips.data());
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_SixRodsInLanes)->Arg(kDefaultSpatialRodSteps)->Arg(kDefaultSpatialRodSteps / 2);

void BM_SixRodsWithSensitivity(benchmark::State& state) {
  const SixRods robot;
  const int steps = static_cast<int>(state.range(0));
  for (auto _ : state) {
    for (const SpatialRodState<double>& base : robot.bases) {
      benchmark::DoNotOptimize(
          integrate_spatial_rod_with_sensitivity(base, robot.rod, robot.gravity, steps));
    }
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_SixRodsWithSensitivity)
    ->Arg(kDefaultSpatialRodSteps)
    ->Arg(kDefaultSpatialRodSteps / 2);

/// The plain baseline the issue measures against: one residual's six rods integrated by a
/// straightforward RK4 loop, as a textbook writes the Kirchhoff rod (state p, R, n, m in Eigen's
/// fixed-size types, R as a matrix, u = K^-1 R^T m, p' = R e3, R' = R [u]x, n' = -f,
/// m' = -p' x n), at the step count the library chose at the reference pose: the unit of the
/// "per solve" ratios (the library's solve costs N of these).
struct PlainRod {
  Eigen::Vector3d p;
  Eigen::Matrix3d R;
  Eigen::Vector3d n, m;
};

PlainRod plain_slope(const PlainRod& y, const Eigen::Vector3d& inverse_stiffness,
                     const Eigen::Vector3d& f) {
  const Eigen::Vector3d u = inverse_stiffness.cwiseProduct(y.R.transpose() * y.m);
  Eigen::Matrix3d u_hat;
  u_hat << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  PlainRod dy;
  dy.p = y.R.col(2);
  dy.R = y.R * u_hat;
  dy.n = -f;
  dy.m = -dy.p.cross(y.n);
  return dy;
}

PlainRod plain_axpy(const PlainRod& y, double a, const PlainRod& k) {
  return PlainRod{y.p + a * k.p, y.R + a * k.R, y.n + a * k.n, y.m + a * k.m};
}

PlainRod plain_rk4(PlainRod y, double length, int steps, const Eigen::Vector3d& inverse_stiffness,
                   const Eigen::Vector3d& f) {
  const double h = length / steps;
  for (int i = 0; i < steps; ++i) {
    const PlainRod k1 = plain_slope(y, inverse_stiffness, f);
    const PlainRod k2 = plain_slope(plain_axpy(y, h / 2, k1), inverse_stiffness, f);
    const PlainRod k3 = plain_slope(plain_axpy(y, h / 2, k2), inverse_stiffness, f);
    const PlainRod k4 = plain_slope(plain_axpy(y, h, k3), inverse_stiffness, f);
    y.p += h / 6 * (k1.p + 2 * k2.p + 2 * k3.p + k4.p);
    y.R += h / 6 * (k1.R + 2 * k2.R + 2 * k3.R + k4.R);
    y.n += h / 6 * (k1.n + 2 * k2.n + 2 * k3.n + k4.n);
    y.m += h / 6 * (k1.m + 2 * k2.m + 2 * k3.m + k4.m);
  }
  return y;
}

/// The reference continuum Stewart-Gough robot (the published layout) on a closed path around
/// its reference pose (0.4 m up, tilted 10 degrees about y) in steps of 1 mm and 1 degree: the
/// platform's centre on a 5 mm circle (0.98 mm per step) while it turns about its own z by
/// 9 sin(2 pi k / 32) degrees (up to 0.9 degrees per step), 32 poses, with the IK and FK
/// solutions along it.
struct ReferencePath {
  static constexpr int kPoints = 32;
  SpatialRobotParams<double> robot = continuum_stewart_gough();
  std::vector<SpatialPose<double>> poses;
  std::vector<SpatialInverseSolution> ik;
  std::vector<SpatialJointVector> q;
  SpatialForwardSolution home, first;
  SpatialPose<double> reference;

  static SpatialPose<double> pose_at(double phase) {
    const double deg = M_PI / 180;
    const Eigen::Quaterniond tilt(Eigen::AngleAxisd(10 * deg, Eigen::Vector3d::UnitY()));
    const Eigen::Quaterniond turn(
        Eigen::AngleAxisd(9 * deg * std::sin(phase), Eigen::Vector3d::UnitZ()));
    const Eigen::Quaterniond h = tilt * turn;
    SpatialPose<double> pose;
    pose.position = Vector3<double>(0.005 * std::cos(phase), 0.005 * std::sin(phase), 0.4);
    pose.orientation = Vector4<double>(h.w(), h.x(), h.y(), h.z());
    return pose;
  }

  ReferencePath() {
    home = spatial_forward_kinematics(robot, SpatialJointVector::Zero(6));
    reference.position = Vector3<double>(0, 0, 0.4);
    reference.orientation =
        Vector4<double>(std::cos(5 * M_PI / 180), 0, std::sin(5 * M_PI / 180), 0);
    const SpatialForwardSolution level =
        spatial_forward_kinematics(robot, SpatialJointVector::Constant(6, 0.005285));
    for (int k = 0; k < kPoints; ++k) poses.push_back(pose_at(2 * M_PI * k / kPoints));
    ik.push_back(spatial_inverse_kinematics(robot, poses[0], level));
    for (int k = 1; k < kPoints; ++k)
      ik.push_back(spatial_inverse_kinematics(robot, poses[k], ik.back()));
    for (const SpatialInverseSolution& s : ik) q.push_back(s.q);
    first = spatial_forward_kinematics(robot, q[0]);
  }
};

const ReferencePath& reference_path() {
  static const ReferencePath path;
  return path;
}

SolverOptions options_of(const benchmark::State& state) {
  SolverOptions options;
  options.check_stability = state.range(0) != 0;
  return options;
}

/// One residual of the reference robot at its reference pose the plain way (PlainRod), six rods
/// at the library's step count there.
void BM_PlainResidualBaseline(benchmark::State& state) {
  const ReferencePath& path = reference_path();
  const SpatialInverseSolution& at = path.ik[0];
  const int steps = at.summary.rod_steps;
  for (auto _ : state) {
    for (int i = 0; i < 6; ++i) {
      const SpatialLimbParams<double>& limb = path.robot.limb(i);
      const SpatialRod<double> rod = limb.rod_at(at.q(i));
      const double ei = rod.bending_stiffness(), gj = rod.torsional_stiffness();
      PlainRod y{limb.A, rotation_of(limb.base_orientation), at.wrenches[i].force,
                 at.wrenches[i].moment};
      benchmark::DoNotOptimize(plain_rk4(y, rod.length, steps,
                                         Eigen::Vector3d(1 / ei, 1 / ei, 1 / gj),
                                         rod.mass_per_length() * path.robot.gravity));
    }
  }
  state.counters["rod_steps"] = steps;
}
BENCHMARK(BM_PlainResidualBaseline)->Unit(benchmark::kMicrosecond);

/// Times solve() (which returns its summary) once per iteration, and reports the mean residual
/// evaluations and RK4 steps per solve and the failures.
template <class Solve>
void time_solves(benchmark::State& state, Solve&& solve) {
  long evaluations = 0, solves = 0, failures = 0, steps = 0;
  for (auto _ : state) {
    const SolverSummary summary = solve();
    evaluations += summary.residual_evaluations;
    steps += summary.rod_steps;
    failures += summary.converged() ? 0 : 1;
    ++solves;
  }
  state.counters["evaluations"] = static_cast<double>(evaluations) / solves;
  state.counters["rod_steps"] = static_cast<double>(steps) / solves;
  state.counters["failures"] = static_cast<double>(failures);
}

/// Warm IK along the path, each solve from the previous IK solution, as a controller runs.
/// Arg: the stability check on (1, the default) or off (0).
void BM_SpatialInverseWarm(benchmark::State& state) {
  const ReferencePath& path = reference_path();
  const SolverOptions options = options_of(state);
  SpatialInverseSolution previous = path.ik.back();
  int k = 0;
  time_solves(state, [&] {
    previous = spatial_inverse_kinematics(path.robot, path.poses[k], previous, options);
    benchmark::DoNotOptimize(previous.q.data());
    k = (k + 1) % ReferencePath::kPoints;
    return previous.summary;
  });
}
BENCHMARK(BM_SpatialInverseWarm)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

/// Warm FK along the path's joints, each solve from the previous FK solution.
void BM_SpatialForwardWarm(benchmark::State& state) {
  const ReferencePath& path = reference_path();
  const SolverOptions options = options_of(state);
  SpatialForwardSolution previous = path.first;
  int k = 1;
  time_solves(state, [&] {
    previous = spatial_forward_kinematics(path.robot, path.q[k], previous, options);
    benchmark::DoNotOptimize(previous.pose.position.data());
    k = (k + 1) % ReferencePath::kPoints;
    return previous.summary;
  });
}
BENCHMARK(BM_SpatialForwardWarm)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

/// FK at the joints of the reference pose from the home solution (q = 0).
void BM_SpatialForwardFromHome(benchmark::State& state) {
  const ReferencePath& path = reference_path();
  const SolverOptions options = options_of(state);
  const SpatialInverseSolution at =
      spatial_inverse_kinematics(path.robot, path.reference, path.ik[0]);
  time_solves(state, [&] {
    const SpatialForwardSolution fk =
        spatial_forward_kinematics(path.robot, at.q, path.home, options);
    benchmark::DoNotOptimize(fk.pose.position.data());
    return fk.summary;
  });
}
BENCHMARK(BM_SpatialForwardFromHome)->Arg(1)->Unit(benchmark::kMicrosecond);

/// FK at the same joints from nothing (straight rods).
void BM_SpatialForwardCold(benchmark::State& state) {
  const ReferencePath& path = reference_path();
  const SolverOptions options = options_of(state);
  const SpatialInverseSolution at =
      spatial_inverse_kinematics(path.robot, path.reference, path.ik[0]);
  time_solves(state, [&] {
    const SpatialForwardSolution fk = spatial_forward_kinematics(path.robot, at.q, options);
    benchmark::DoNotOptimize(fk.pose.position.data());
    return fk.summary;
  });
}
BENCHMARK(BM_SpatialForwardCold)->Arg(1)->Unit(benchmark::kMicrosecond);

/// IK that converges on an equilibrium that would not hold and looks for a stable one at the pose
/// (SolverOptions::stable_inverse, a rare fallback): from the first unstable equilibrium the
/// buckled seeds give at the reference pose (one rod looped), 1 mm away.
void BM_SpatialInverseStableSearch(benchmark::State& state) {
  const ReferencePath& path = reference_path();
  SolverOptions keep;
  keep.stable_inverse = false;
  const SpatialInverseSolution normal =
      spatial_inverse_kinematics(path.robot, path.reference, path.ik[0], keep);
  SpatialInverseSolution looped;
  for (int k = 0; k < kSpatialBuckledSeedsPerRod * 6; ++k) {
    looped = spatial_inverse_kinematics(path.robot, path.reference,
                                        spatial_buckled_seed(path.robot, normal, k), keep);
    if (looped.summary.converged() && looped.summary.stability == Stability::kUnstable) break;
  }
  SpatialPose<double> moved = path.reference;
  moved.position.x() += 1e-3;
  time_solves(state, [&] {
    const SpatialInverseSolution ik = spatial_inverse_kinematics(path.robot, moved, looped);
    benchmark::DoNotOptimize(ik.q.data());
    return ik.summary;
  });
}
BENCHMARK(BM_SpatialInverseStableSearch)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
