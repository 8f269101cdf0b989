#pragma once
// What the planar and spatial accuracy evaluations share (src/calib/accuracy.cpp,
// src/calib/spatial_accuracy.cpp), not part of the API.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace pcr::calib_internal {

/// ISO 9283's cycles on a virtual robot: `repeat` cycles, each visiting poses 0 to count - 1 in
/// path order, so that every pose is approached from the same direction in every cycle.
/// measure(k, Pose* attained) moves to pose k's commanded joints and gives the attained pose, or
/// returns the solver status's name when the true robot holds no stable equilibrium there (empty
/// on success); name(k) names the pose in the error. Returns [pose][cycle].
template <class Pose, class Measure, class Name>
std::vector<std::vector<Pose>> attained_in_cycles(int repeat, std::size_t count, Measure&& measure,
                                                  Name&& name) {
  std::vector<std::vector<Pose>> attained(count);
  for (auto& a : attained) a.reserve(static_cast<std::size_t>(repeat));
  for (int cycle = 0; cycle < repeat; ++cycle) {
    for (std::size_t k = 0; k < count; ++k) {
      Pose pose;
      const std::string failure = measure(k, &pose);
      if (!failure.empty()) {
        throw std::runtime_error("virtual robot: cycle " + std::to_string(cycle) + ", pose " +
                                 std::to_string(k) + " " + name(k) +
                                 ": the true robot has no stable equilibrium at the commanded "
                                 "joints (solver status " +
                                 failure + ")");
      }
      attained[k].push_back(pose);
    }
  }
  return attained;
}

}  // namespace pcr::calib_internal
