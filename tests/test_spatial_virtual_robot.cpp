// The virtual spatial robot (pcr/calib/spatial_virtual_robot.hpp) and the 6-D dataset file:
// truths inside the intervals (and at their corners), one material and one wire, the unmodelled
// effects on their own streams and by name, the measurement against a CVODE FK of the truth seen
// through Eigen's Isometry3d, the noise's declared spread, and the dataset's round trip and bad
// rows.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <vector>

#include "pcr/calib/dataset.hpp"
#include "pcr/calib/named_effects.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"
#include "scratch_directory.hpp"
#include "spatial_test_support.hpp"

namespace {

using pcr::SpatialParameterId;
using pcr::SpatialParameterKind;

std::vector<double> deviations_of(const pcr::SpatialVirtualRobot& robot) {
  std::vector<double> d(
      static_cast<std::size_t>(pcr::num_spatial_parameters(robot.nominal().params.num_rods)));
  pcr::spatial_deviations(robot.nominal().params, robot.truth().params, d.data());
  return d;
}

Eigen::Isometry3d isometry(const pcr::SpatialPose<double>& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = pcr::testing::eigen_quaternion(pose.orientation).normalized().toRotationMatrix();
  t.translation() = pose.position;
  return t;
}

TEST(SpatialVirtualRobot, TruthsLieInsideTheIntervals) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  const pcr::SpatialUncertainty& u = *nominal.uncertainty;
  const int n = nominal.params.num_rods;
  for (const double fraction : {0.0, 0.9}) {
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      pcr::SpatialVirtualRobotOptions options;
      options.seed = seed;
      options.truth_at_fraction = fraction;
      const pcr::SpatialVirtualRobot robot(nominal, options);
      const std::vector<double> d = deviations_of(robot);
      double largest = 0;  // of |d| / h
      for (int k = 0; k < pcr::num_spatial_parameters(n); ++k) {
        const SpatialParameterId id = pcr::spatial_parameter_id(k, n);
        const double h = pcr::spatial_half_width(u, id);
        const double ratio = std::abs(d[static_cast<std::size_t>(k)]) / h;
        largest = std::max(largest, ratio);
        // A modulus's deviation is the difference of two values near 1e11: 1e-5 Pa of rounding.
        const double rounding = id.kind == SpatialParameterKind::kYoungModulus ||
                                        id.kind == SpatialParameterKind::kShearModulus
                                    ? 1e-15
                                    : 1e-12;
        if (fraction > 0) {
          EXPECT_NEAR(ratio, fraction, rounding) << pcr::spatial_parameter_name(id);
        } else {
          EXPECT_LE(ratio, 1.0 + rounding) << pcr::spatial_parameter_name(id);
        }
      }
      if (fraction == 0) EXPECT_GT(largest, 0.5);  // drawn, not left at the nominal values
      // One material and one wire.
      for (int i = 1; i < n; ++i) {
        EXPECT_EQ(robot.truth().params.limb(i).rod.young_modulus,
                  robot.truth().params.limb(0).rod.young_modulus);
        EXPECT_EQ(robot.truth().params.limb(i).rod.shear_modulus,
                  robot.truth().params.limb(0).rod.shear_modulus);
        EXPECT_EQ(robot.truth().params.limb(i).rod.diameter,
                  robot.truth().params.limb(0).rod.diameter);
      }
    }
  }
  // A description without intervals: the truth is the nominal robot.
  pcr::SpatialRobotDescription known = nominal;
  known.uncertainty.reset();
  const pcr::SpatialVirtualRobot exact(known);
  for (const double d : deviations_of(exact)) EXPECT_EQ(d, 0.0);
}

TEST(SpatialVirtualRobot, EffectsKeepTheirOwnStreams) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  const int n = nominal.params.num_rods;
  const pcr::SpatialVirtualRobot plain(nominal);
  pcr::SpatialVirtualRobotOptions options;
  options.effects.payload = 0.05;
  options.effects.misalignment_half_width = 0.02;
  options.effects.rod_density = 7800;
  const pcr::SpatialVirtualRobot affected(nominal, options);
  const std::vector<double> a = deviations_of(plain), b = deviations_of(affected);
  int turned = 0;
  for (int k = 0; k < pcr::num_spatial_parameters(n); ++k) {
    const SpatialParameterKind kind = pcr::spatial_parameter_id(k, n).kind;
    const bool base_turn = kind == SpatialParameterKind::kBaseRx ||
                           kind == SpatialParameterKind::kBaseRy ||
                           kind == SpatialParameterKind::kBaseRz;
    if (base_turn) {
      // The truth's turn and the misalignment add (to first order: both compose on the right).
      EXPECT_LE(std::abs(b[k] - a[k]), 0.02 + 1e-4);
      turned += b[k] != a[k];
    } else {
      EXPECT_NEAR(b[k], a[k], 1e-15 * 2e11) << k;
    }
  }
  EXPECT_EQ(turned, 3 * n);
  EXPECT_EQ(affected.truth().params.platform_mass, nominal.params.platform_mass + 0.05);
  for (int i = 0; i < n; ++i) EXPECT_EQ(affected.truth().params.limb(i).rod.density, 7800);

  pcr::SpatialVirtualRobotOptions bad;
  bad.noise_angle = -1e-6;
  try {
    pcr::SpatialVirtualRobot robot(nominal, bad);
    ADD_FAILURE() << "a negative noise accepted";
  } catch (const pcr::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("noise_angle"), std::string::npos) << e.what();
  }
  pcr::SpatialRobotDescription wide = nominal;
  wide.uncertainty->rods[0].diameter = 5e-3;  // wider than the 2 mm wire
  pcr::SpatialVirtualRobotOptions corner;
  corner.truth_at_fraction = 1.0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    corner.seed = seed;
    try {
      pcr::SpatialVirtualRobot robot(wide, corner);
      EXPECT_GT(robot.truth().params.limb(0).rod.diameter, 0);
    } catch (const pcr::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("rod 0"), std::string::npos) << e.what();
    }
  }
}

// pcr demo --effects NAMES on either robot: one mapping (pcr/calib/named_effects.hpp). A name
// means the same on both; "diameters" gives the spatial rods unequal diameters, each drawn on its
// own about the one wire's, and nothing else moves.
TEST(SpatialVirtualRobot, NamedEffectsMeanWhatThePlanarNamesMean) {
  const pcr::UnmodelledEffects planar = pcr::planar_effects_named({"all"}, "--effects");
  EXPECT_TRUE(planar.misalignments && planar.unequal_diameters && planar.external_load);
  const pcr::SpatialUnmodelledEffects all = pcr::spatial_effects_named({"all"}, "--effects");
  EXPECT_EQ(all.misalignment_half_width, 5e-3);  // the paper's 5 mrad, as the planar one's
  EXPECT_EQ(all.misalignment_half_width, planar.misalignment_half_width);
  EXPECT_EQ(all.diameter_half_width, 10e-6);
  EXPECT_EQ(all.payload, 0.1);
  EXPECT_LT(all.rod_density, 0);  // not a named effect: the rods as described
  const pcr::SpatialUnmodelledEffects load = pcr::spatial_effects_named({"load"}, "--effects");
  EXPECT_EQ(load.payload, 0.1);
  EXPECT_EQ(load.misalignment_half_width, 0);
  EXPECT_EQ(load.diameter_half_width, 0);
  EXPECT_EQ(pcr::describe(pcr::SpatialUnmodelledEffects()), "none");
  EXPECT_EQ(pcr::describe(load), "a 0.1 kg payload at P's origin");
  try {
    pcr::spatial_effects_named({"load", "gravity"}, "--effects");
    ADD_FAILURE() << "an unknown effect accepted";
  } catch (const pcr::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--effects: unknown unmodelled effect 'gravity'"),
              std::string::npos)
        << e.what();
  }

  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  const int n = nominal.params.num_rods;
  const pcr::SpatialVirtualRobot plain(nominal);
  pcr::SpatialVirtualRobotOptions options;
  options.effects = pcr::spatial_effects_named({"diameters"}, "--effects");
  const pcr::SpatialVirtualRobot unequal(nominal, options);
  const std::vector<double> a = deviations_of(plain), b = deviations_of(unequal);
  double spread = 0;  // of the rods' diameters
  for (int k = 0; k < pcr::num_spatial_parameters(n); ++k) {
    const SpatialParameterId id = pcr::spatial_parameter_id(k, n);
    if (id.kind == SpatialParameterKind::kDiameter) {
      EXPECT_LE(std::abs(b[k] - a[k]), 10e-6) << k;
      EXPECT_NE(b[k], a[k]) << k;
      spread = std::max(
          spread,
          std::abs(b[k] - b[static_cast<std::size_t>(k - id.rod * pcr::kSpatialRodParameters)]));
    } else {
      EXPECT_EQ(b[k], a[k]) << k;
    }
  }
  EXPECT_GT(spread, 1e-6);  // no longer one wire
}

TEST(SpatialVirtualRobot, MeasuresTheTruthsEquilibriumFromTheTracker) {
  pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  nominal.params.extrinsics.tracker = {pcr::Vector3<double>(0.3, -0.2, 0.9),
                                       pcr::Vector4<double>(0.0, 0.6, 0.8, 0.0)};  // looks down
  nominal.params.extrinsics.marker = {pcr::Vector3<double>(0.0, 0.0, -0.01),
                                      pcr::Vector4<double>(0.6, 0.0, 0.0, 0.8)};
  pcr::SpatialVirtualRobotOptions options;
  options.seed = 3;
  options.noise_position = 0;
  options.noise_angle = 0;
  pcr::SpatialVirtualRobot robot(nominal, options);
  const pcr::SpatialRobotParams<double>& truth = robot.truth().params;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> joint(-0.01, 0.01);
  double worst_position = 0, worst_angle = 0;
  for (int trial = 0; trial < 4; ++trial) {
    pcr::SpatialJointVector q(6);
    for (int i = 0; i < 6; ++i) q(i) = 0.005 + joint(rng);
    const pcr::SpatialVirtualMeasurement m = robot.measure(q);
    ASSERT_TRUE(m.ok) << pcr::to_string(m.summary.status);
    EXPECT_EQ(m.measured.position, m.exact.position);  // no noise
    // The truth's equilibrium at q by CVODE, from a cold RK4 start.
    const pcr::SpatialForwardSolution cold = pcr::spatial_forward_kinematics(truth, q);
    ASSERT_TRUE(cold.summary.converged());
    pcr::testing::Point start;
    for (int i = 0; i < 6; ++i) start.q[static_cast<std::size_t>(i)] = q(i);
    start.pose = cold.pose;
    start.wrenches = cold.wrenches;
    const pcr::testing::ReferenceFk reference =
        pcr::testing::reference_forward_kinematics(truth, start);
    const Eigen::Isometry3d expected = isometry(truth.extrinsics.tracker).inverse() *
                                       isometry(reference.x.pose) *
                                       isometry(truth.extrinsics.marker).inverse();
    const double position = (m.exact.position - expected.translation()).norm();
    const double angle =
        Eigen::AngleAxisd(m.exact.rotation().transpose() * expected.linear()).angle();
    worst_position = std::max(worst_position, position);
    worst_angle = std::max(worst_angle, angle);
    EXPECT_LT(position, 1e-9);
    EXPECT_LT(angle, 1e-6);
  }
  std::printf("measurement against CVODE: %.3g m, %.3g rad\n", worst_position, worst_angle);
}

TEST(SpatialVirtualRobot, NoiseHasItsDeclaredSpread) {
  const pcr::SpatialRobotDescription nominal = pcr::continuum_stewart_gough_description();
  EXPECT_NEAR(pcr::spatial_default_noise_position(nominal.params), 9.13e-9 * 0.4 / 0.03, 1e-20);
  pcr::SpatialVirtualRobotOptions options;
  options.noise_position = 1e-6;
  options.noise_angle = 2e-5;
  pcr::SpatialVirtualRobot robot(nominal, options);
  EXPECT_EQ(robot.noise_position(), 1e-6);
  const pcr::SpatialJointVector q = pcr::testing::equal_joints(6, 0.004);
  const int count = 600;
  Eigen::Vector3d sum_p = Eigen::Vector3d::Zero(), sum_p2 = sum_p, sum_a = sum_p, sum_a2 = sum_p;
  for (int k = 0; k < count; ++k) {
    const pcr::SpatialVirtualMeasurement m = robot.measure(q);
    ASSERT_TRUE(m.ok);
    const Eigen::Vector3d dp = m.measured.position - m.exact.position;
    // The turn from the exact to the measured orientation, in the marker frame (Eigen's).
    const Eigen::AngleAxisd turn(pcr::testing::eigen_quaternion(m.exact.orientation).conjugate() *
                                 pcr::testing::eigen_quaternion(m.measured.orientation));
    const Eigen::Vector3d da = turn.angle() * turn.axis();
    sum_p += dp;
    sum_p2 += dp.cwiseAbs2();
    sum_a += da;
    sum_a2 += da.cwiseAbs2();
  }
  // Each component's mean within 4 standard errors, its spread within 15 % (about 5 of its
  // standard errors, 1 / sqrt(2 count) = 2.9 %).
  for (int c = 0; c < 3; ++c) {
    EXPECT_LT(std::abs(sum_p(c) / count), 4 * 1e-6 / std::sqrt(count));
    EXPECT_NEAR(std::sqrt(sum_p2(c) / count), 1e-6, 0.15e-6);
    EXPECT_LT(std::abs(sum_a(c) / count), 4 * 2e-5 / std::sqrt(count));
    EXPECT_NEAR(std::sqrt(sum_a2(c) / count), 2e-5, 0.15 * 2e-5);
  }
}

TEST(SpatialDataset, RoundTripsAndNamesBadRows) {
  pcr::SpatialDataset data;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> x(-1, 1);
  for (int r = 0; r < 5; ++r) {
    pcr::SpatialJointVector q(5);
    for (int i = 0; i < 5; ++i) q(i) = 0.01 * x(rng);
    const Eigen::Vector3d turn(x(rng), x(rng), x(rng));
    data.add(q, pcr::SpatialPose<double>{Eigen::Vector3d(x(rng), x(rng), x(rng)),
                                         pcr::quaternion_exp(turn)});
  }
  const pcr::test::ScratchDirectory scratch("spatial_dataset");
  const std::string path = (scratch.path() / "data.csv").string();
  pcr::write_spatial_dataset(data, path);
  const pcr::SpatialDataset back = pcr::read_spatial_dataset(path);
  ASSERT_EQ(back.num_joints, 5);
  ASSERT_EQ(back.size(), data.size());
  for (std::size_t r = 0; r < data.size(); ++r) {
    EXPECT_EQ(back.q[r], data.q[r]);
    EXPECT_EQ(back.poses[r].position, data.poses[r].position);
    EXPECT_LT(pcr::testing::angle_between(back.poses[r].orientation, data.poses[r].orientation),
              1e-15);
    EXPECT_EQ(back.line_numbers[r], static_cast<int>(r) + 2);
  }

  const auto error_of = [](const std::string& text) {
    std::istringstream in(text);
    try {
      pcr::parse_spatial_dataset(in, "d.csv");
    } catch (const pcr::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_of("q1,q2,q3,x,y,z,rx,ry,rz\n0,0,0,0,0,0.4,0,0.1,0\n"), "");
  std::string m =
      error_of("q1,q2,q3,x,y,z,rx,ry,rz\n0,0,0,0,0,0.4,0,0.1,0\n0,0,0,0,0,0.4,0,900,0\n");
  EXPECT_NE(m.find("d.csv:3"), std::string::npos) << m;
  EXPECT_NE(m.find("ry"), std::string::npos) << m;
  EXPECT_NE(m.find("900"), std::string::npos) << m;
  m = error_of("q1,q2,q3,x,y,theta\n0,0,0,0,0,0\n");  // a planar file
  EXPECT_NE(m.find("d.csv"), std::string::npos) << m;
  EXPECT_NE(m.find("z"), std::string::npos) << m;
  m = error_of("0,0,0,0,0\n");  // five fields cannot hold one joint and a 6-D pose
  EXPECT_NE(m.find("q1,...,qn,x,y,z,rx,ry,rz"), std::string::npos) << m;
  m = error_of("q1,q2,q3,x,y,z,rx,ry,rz\n0,0,0,0,0,abc,0,0,0\n");
  EXPECT_NE(m.find("d.csv:2"), std::string::npos) << m;
}

}  // namespace
