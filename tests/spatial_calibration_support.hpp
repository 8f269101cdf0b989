#pragma once
// Helpers shared by the spatial calibration's tests (test_spatial_calibration.cpp,
// test_pcr_calibrate_spatial.cpp): seeded joints and the rows a virtual spatial robot measures.

#include <random>
#include <vector>

#include "pcr/calib/dataset.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"

namespace pcr::testing {

/// Joints drawn uniformly in [lo, hi] per rod, in the order a robot visits them (long jumps).
inline std::vector<SpatialJointVector> random_joints(std::mt19937_64& rng, int rows, double lo,
                                                     double hi, int rods = 6) {
  std::uniform_real_distribution<double> joint(lo, hi);
  std::vector<SpatialJointVector> out;
  for (int r = 0; r < rows; ++r) {
    SpatialJointVector q(rods);
    for (int i = 0; i < rods; ++i) q(i) = joint(rng);
    out.push_back(q);
  }
  return out;
}

/// The rows a virtual robot measured (those it could); `exact`: without the noise.
inline SpatialDataset measured(SpatialVirtualRobot& robot, const std::vector<SpatialJointVector>& q,
                               bool exact = false) {
  SpatialDataset data;
  data.num_joints = q.empty() ? 0 : static_cast<int>(q.front().size());
  const std::vector<SpatialVirtualMeasurement> m = robot.measure_dataset(q);
  for (std::size_t r = 0; r < q.size(); ++r) {
    if (m[r].ok) data.add(q[r], exact ? m[r].exact : m[r].measured);
  }
  return data;
}

}  // namespace pcr::testing
