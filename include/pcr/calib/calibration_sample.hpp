#pragma once
// One measured configuration of a calibration dataset: its joints and the measured pattern pose.

#include <string>

#include "pcr/se2.hpp"
#include "pcr/shooting.hpp"

namespace pcr {

/// One measured configuration: joints (m) and measured pattern pose ^Se T_M (m, m, rad).
struct CalibrationSample {
  JointVector q;
  Pose2<double> measured;
  std::string origin;  ///< where the row came from ("data.csv:17"); empty: "configuration j"
  int line = 0;        ///< 1-based line in its file (0: not from a file)
};

}  // namespace pcr
