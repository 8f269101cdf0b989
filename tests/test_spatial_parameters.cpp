// The flat view of a spatial robot's parameters (pcr/spatial/parameters.hpp): indices and names,
// the half-widths each kind reads, deviations that come back from the description they make, turns
// composed on the right in the frame they turn (checked with Eigen's AngleAxis), and the
// measurement of Eq. 5 in 3-D against Eigen's Isometry3d.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <set>
#include <string>

#include "pcr/calib/jet_traits.hpp"  // before the core templates meet a Jet
#include "pcr/spatial/parameters.hpp"
#include "pcr/spatial/robot_io.hpp"

namespace {

using pcr::SpatialParameterId;
using pcr::SpatialParameterKind;

Eigen::Quaterniond eigen_quaternion(const pcr::Vector4<double>& h) {
  return Eigen::Quaterniond(h(0), h(1), h(2), h(3));
}

Eigen::Isometry3d isometry(const pcr::SpatialPose<double>& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = eigen_quaternion(pose.orientation).normalized().toRotationMatrix();
  t.translation() = pose.position;
  return t;
}

pcr::Vector4<double> random_unit_quaternion(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  const pcr::Vector4<double> h(g(rng), g(rng), g(rng), g(rng));
  return h / h.norm();
}

TEST(SpatialParameters, IndicesNamesAndHalfWidths) {
  const int n = 6;
  EXPECT_EQ(pcr::num_spatial_parameters(n), 16 * 6 + 12);
  std::set<std::string> names;
  for (int k = 0; k < pcr::num_spatial_parameters(n); ++k) {
    const SpatialParameterId id = pcr::spatial_parameter_id(k, n);
    EXPECT_EQ(pcr::spatial_parameter_index(id, n), k);
    names.insert(pcr::spatial_parameter_name(id));
  }
  EXPECT_EQ(names.size(), static_cast<std::size_t>(pcr::num_spatial_parameters(n)));
  EXPECT_EQ(pcr::spatial_parameter_name(pcr::spatial_parameter_id(16 + 3, n)), "l[1]");
  EXPECT_EQ(pcr::spatial_parameter_name(pcr::spatial_parameter_id(16 * 5 + 9, n)), "base_rz[5]");
  EXPECT_EQ(pcr::spatial_parameter_name(pcr::spatial_parameter_id(16 * 6 + 2, n)), "tracker_z");
  EXPECT_EQ(pcr::spatial_parameter_name(pcr::spatial_parameter_id(16 * 6 + 11, n)), "marker_rz");

  // Every field of the intervals a distinct value; each kind must read its own.
  pcr::SpatialUncertainty u;
  u.rods.resize(2);
  for (int i = 0; i < 2; ++i) {
    pcr::SpatialRodUncertainty& r = u.rods[static_cast<std::size_t>(i)];
    const double b = 100.0 * (i + 1);
    r.young_modulus = b + 1;
    r.shear_modulus = b + 2;
    r.diameter = b + 3;
    r.length = b + 4;
    r.A = Eigen::Vector3d(b + 5, b + 6, b + 7);
    r.base_rotation = Eigen::Vector3d(b + 8, b + 9, b + 10);
    r.B = Eigen::Vector3d(b + 11, b + 12, b + 13);
    r.tip_rotation = Eigen::Vector3d(b + 14, b + 15, b + 16);
  }
  for (int k = 0; k < 6; ++k) {
    u.tracker(k) = 1001 + k;
    u.marker(k) = 1007 + k;
  }
  for (int k = 0; k < pcr::num_spatial_parameters(2); ++k) {
    const SpatialParameterId id = pcr::spatial_parameter_id(k, 2);
    const double expected = id.rod >= 0 ? 100.0 * (id.rod + 1) + (k % 16) + 1 : 1001 + (k - 32);
    EXPECT_EQ(pcr::spatial_half_width(u, id), expected) << pcr::spatial_parameter_name(id);
  }
  // Without per-rod entries, the default.
  pcr::SpatialUncertainty global;
  global.global.B = Eigen::Vector3d(1, 2, 3);
  EXPECT_EQ(pcr::spatial_half_width(global, SpatialParameterId{SpatialParameterKind::kBy, 4}), 2);
}

TEST(SpatialParameters, DeviationsComeBackFromTheDescriptionTheyMake) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> turn(-0.5, 0.5), small(-1e-3, 1e-3);
  double worst = 0;
  for (int trial = 0; trial < 20; ++trial) {
    pcr::SpatialRobotParams<double> nominal = pcr::continuum_stewart_gough();
    for (int i = 0; i < nominal.num_rods; ++i) {
      nominal.limb(i).base_orientation = random_unit_quaternion(rng);
      nominal.limb(i).tip_orientation = random_unit_quaternion(rng);
    }
    nominal.extrinsics.tracker =
        pcr::SpatialPose<double>{pcr::Vector3<double>(0.1, -0.2, 1.0), random_unit_quaternion(rng)};
    nominal.extrinsics.marker =
        pcr::SpatialPose<double>{pcr::Vector3<double>(0, 0, 0.01), random_unit_quaternion(rng)};
    const int count = pcr::num_spatial_parameters(nominal.num_rods);
    std::vector<double> d(static_cast<std::size_t>(count)), back(d.size());
    for (int k = 0; k < count; ++k) {
      const SpatialParameterKind kind = pcr::spatial_parameter_id(k, nominal.num_rods).kind;
      const bool rotation = std::string(pcr::spatial_parameter_kind_info(kind).unit) == "rad";
      const bool modulus = std::string(pcr::spatial_parameter_kind_info(kind).unit) == "Pa";
      // A modulus deviates by up to 1 GPa (0.5 %): its sum with 200 GPa rounds to 3e-5 Pa.
      d[static_cast<std::size_t>(k)] = rotation ? turn(rng) : small(rng) * (modulus ? 1e12 : 1.0);
    }
    const pcr::SpatialRobotParams<double> moved = pcr::spatial_with_deviations(nominal, d.data());
    pcr::spatial_deviations(nominal, moved, back.data());
    for (int k = 0; k < count; ++k) {
      const double value = d[static_cast<std::size_t>(k)];
      // Relative to a modulus, whose deviation is the difference of two values near 2e11.
      const double e = std::abs(back[static_cast<std::size_t>(k)] - value) /
                       (std::abs(value) > 1.0 ? 2e11 : 1.0);
      worst = std::max(worst, e);
      EXPECT_LT(e, 1e-12) << pcr::spatial_parameter_name(
          pcr::spatial_parameter_id(k, nominal.num_rods));
    }

    // The turns, in the frame they turn: R = R_nominal AngleAxis(|r|, r / |r|).
    for (int i = 0; i < nominal.num_rods; ++i) {
      const double* r = d.data() + 16 * i;
      const Eigen::Vector3d base(r[7], r[8], r[9]), tip(r[13], r[14], r[15]);
      const Eigen::Matrix3d expected_base =
          eigen_quaternion(nominal.limb(i).base_orientation).toRotationMatrix() *
          Eigen::AngleAxisd(base.norm(), base.normalized()).toRotationMatrix();
      const Eigen::Matrix3d expected_tip =
          eigen_quaternion(nominal.limb(i).tip_orientation).toRotationMatrix() *
          Eigen::AngleAxisd(tip.norm(), tip.normalized()).toRotationMatrix();
      EXPECT_LT((pcr::rotation_of(moved.limb(i).base_orientation) - expected_base).norm(), 1e-14);
      EXPECT_LT((pcr::rotation_of(moved.limb(i).tip_orientation) - expected_tip).norm(), 1e-14);
      EXPECT_EQ(moved.limb(i).A, nominal.limb(i).A + Eigen::Vector3d(r[4], r[5], r[6]));
      EXPECT_EQ(moved.limb(i).rod.length, nominal.limb(i).rod.length + r[3]);
      EXPECT_EQ(moved.limb(i).rod.shear_modulus, nominal.limb(i).rod.shear_modulus + r[1]);
    }
    const double* e = d.data() + 16 * nominal.num_rods;
    const Eigen::Vector3d tracker_turn(e[3], e[4], e[5]);
    const Eigen::Matrix3d expected_tracker =
        eigen_quaternion(nominal.extrinsics.tracker.orientation).toRotationMatrix() *
        Eigen::AngleAxisd(tracker_turn.norm(), tracker_turn.normalized()).toRotationMatrix();
    EXPECT_LT((moved.extrinsics.tracker.rotation() - expected_tracker).norm(), 1e-14);
    EXPECT_EQ(moved.extrinsics.marker.position,
              nominal.extrinsics.marker.position + Eigen::Vector3d(e[6], e[7], e[8]));
  }
  std::printf("worst deviation round trip: %.3g\n", worst);
}

TEST(SpatialParameters, JetsCarryTheDerivativesOfATurn) {
  // d R_base / d base_ry through a Jet against central differences.
  using Jet = ceres::Jet<double, 1>;
  const pcr::SpatialRobotParams<double> nominal = pcr::continuum_stewart_gough();
  const int count = pcr::num_spatial_parameters(nominal.num_rods);
  std::vector<Jet> d(static_cast<std::size_t>(count), Jet(0.0));
  std::vector<double> plus(d.size(), 0.0), minus(d.size(), 0.0);
  const int k = 16 * 2 + 8;  // base_ry[2]
  d[k] = Jet(0.01, 0);
  const double h = 1e-6;
  plus[k] = 0.01 + h;
  minus[k] = 0.01 - h;
  const pcr::Matrix3<Jet> R =
      pcr::rotation_of(pcr::spatial_with_deviations(nominal, d.data()).limb(2).base_orientation);
  const Eigen::Matrix3d difference =
      (pcr::rotation_of(
           pcr::spatial_with_deviations(nominal, plus.data()).limb(2).base_orientation) -
       pcr::rotation_of(
           pcr::spatial_with_deviations(nominal, minus.data()).limb(2).base_orientation)) /
      (2 * h);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(R(r, c).v[0], difference(r, c), 1e-9);
  }
}

TEST(SpatialParameters, MeasurementIsEquationFiveInThreeDimensions) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> x(-0.5, 0.5);
  for (int trial = 0; trial < 10; ++trial) {
    pcr::SpatialExtrinsics<double> e;
    e.tracker = {pcr::Vector3<double>(x(rng), x(rng), x(rng)), random_unit_quaternion(rng)};
    e.marker = {pcr::Vector3<double>(x(rng), x(rng), x(rng)), random_unit_quaternion(rng)};
    const pcr::SpatialPose<double> platform{pcr::Vector3<double>(x(rng), x(rng), x(rng)),
                                            random_unit_quaternion(rng)};
    const Eigen::Isometry3d expected =
        isometry(e.tracker).inverse() * isometry(platform) * isometry(e.marker).inverse();
    // Three rotations composed: a few ulps of each entry.
    const pcr::SpatialPose<double> measured = e.measurement_from_platform(platform);
    EXPECT_LT((measured.position - expected.translation()).norm(), 1e-14);
    EXPECT_LT((measured.rotation() - expected.linear()).norm(), 1e-14);
    const pcr::SpatialPose<double> back = e.platform_from_measurement(measured);
    EXPECT_LT((back.position - platform.position).norm(), 1e-14);
    EXPECT_LT((back.rotation() - platform.rotation()).norm(), 1e-14);
  }
}

}  // namespace
