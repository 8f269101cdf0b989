// The spatial rod in ceres::Jet (what calibrations will differentiate): forward-mode derivatives
// of the RK4 map against its variational sensitivity (both the derivative of the same discrete
// map, so equal to the rounding) and, for a rod parameter, against central differences.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "pcr/calib/jet_traits.hpp"
#include "pcr/spatial/cosserat_rod.hpp"

namespace pcr {
namespace {

using Eigen::Vector3d;
using Eigen::Vector4d;
constexpr int kWrench = 6;  // derivative slots 0..5: n(0), m(0)
constexpr int kYoung = 6;   // slot 6: E
using Jet = ceres::Jet<double, 7>;

SpatialRod<double> bent_rod() {
  SpatialRod<double> rod;
  rod.length = 0.3;
  rod.diameter = 0.8e-3;
  rod.young_modulus = 75e9;
  rod.shear_modulus = 75e9 / 2.66;
  rod.density = 6450;
  rod.intrinsic_curvature = Vector3d(3.0, -1.5, 2.0);
  return rod;
}

SpatialRodState<double> loaded_base(const SpatialRod<double>& rod) {
  const double L = rod.length, ei = rod.bending_stiffness();
  SpatialRodState<double> base;
  base.position = Vector3d(0.02, -0.01, 0.05);
  base.orientation = Vector4d(0.4, -0.3, 0.8, 0.2).normalized();
  base.force = ei / (L * L) * Vector3d(1.2, -0.7, 0.4);
  base.moment = ei / L * Vector3d(-0.5, 1.1, 0.3);
  return base;
}

TEST(SpatialRodJet, DerivativesMatchTheSensitivityAndCentralDifferences) {
  const Vector3d gravity(0, 0, -9.81);
  const Vector3<Jet> gravity_jet = gravity.cast<Jet>();
  double worst = 0;
  for (bool shear : {false, true}) {
    SpatialRod<double> rod = bent_rod();
    rod.shear_and_extension = shear;
    const SpatialRodState<double> base = loaded_base(rod);
    const int steps = 64;
    const SpatialRodTip<double> tip =
        integrate_spatial_rod_with_sensitivity(base, rod, gravity, steps);

    SpatialRod<Jet> rod_jet = rod.cast<Jet>();
    rod_jet.young_modulus.v[kYoung] = 1.0;
    SpatialRodState<Jet> base_jet;
    base_jet.position = base.position.cast<Jet>();
    base_jet.orientation = base.orientation.cast<Jet>();
    base_jet.force = base.force.cast<Jet>();
    base_jet.moment = base.moment.cast<Jet>();
    for (int j = 0; j < 3; ++j) {
      base_jet.force[j].v[j] = 1.0;
      base_jet.moment[j].v[3 + j] = 1.0;
    }
    const SpatialRodVector<Jet> y =
        integrate_spatial_rod(base_jet, rod_jet, gravity_jet, steps).vector();
    const SpatialRodVector<double> value = tip.state.vector();
    for (int i = 0; i < SpatialRodIndex::kSize; ++i) {
      EXPECT_NEAR(y[i].a, value[i], 1e-15 * (std::abs(value[i]) + 1e-3)) << "row " << i;
      for (int j = 0; j < kWrench; ++j) {
        const double column_scale = tip.sensitivity.col(j).cwiseAbs().maxCoeff();
        EXPECT_NEAR(y[i].v[j], tip.sensitivity(i, j), 1e-12 * column_scale)
            << "row " << i << " column " << j;
        worst = std::max(worst, std::abs(y[i].v[j] - tip.sensitivity(i, j)) / column_scale);
      }
    }
    // d / dE against central differences.
    const double dE = 1e-5 * rod.young_modulus;
    SpatialRod<double> plus = rod, minus = rod;
    plus.young_modulus += dE;
    minus.young_modulus -= dE;
    const SpatialRodVector<double> fd =
        (integrate_spatial_rod(base, plus, gravity, steps).vector() -
         integrate_spatial_rod(base, minus, gravity, steps).vector()) /
        (2 * dE);
    // Each block of rows (p, h, m) relative to its largest entry; n(L) does not depend on E.
    for (const auto& [first, size] : {std::pair<int, int>{SpatialRodIndex::kPosition, 3},
                                      {SpatialRodIndex::kOrientation, 4},
                                      {SpatialRodIndex::kMoment, 3}}) {
      const double scale = fd.segment(first, size).cwiseAbs().maxCoeff();
      EXPECT_GT(scale, 0.0);
      for (int i = first; i < first + size; ++i) {
        EXPECT_NEAR(y[i].v[kYoung], fd[i], 1e-6 * scale) << "row " << i;
      }
    }
    for (int i = 0; i < 3; ++i) EXPECT_EQ(y[SpatialRodIndex::kForce + i].v[kYoung], 0.0);
  }
  std::printf("Jets against the variational sensitivity: worst %.2e of the column\n", worst);
}

}  // namespace
}  // namespace pcr
