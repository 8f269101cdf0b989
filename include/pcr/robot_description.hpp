#pragma once
// A robot as a lab describes it: its parameters, its name, and the uncertainty intervals of the
// parameters it may calibrate. The model's types; pcr/robot_io.hpp reads and writes them.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "pcr/robot.hpp"

namespace pcr {

/// Half-widths of a rod's identifiable parameters (Rod's fields of the same names). A
/// precurvature slope is described, not identified.
struct RodUncertainty {
  double length{0};         ///< m
  double diameter{0};       ///< m
  double young_modulus{0};  ///< Pa
  double precurvature{0};   ///< 1/m
};

/// Half-widths of the uncertainty intervals of one limb's parameters (SI units, radians), in
/// LimbParams' shape (pcr::limb_parameter reads both).
struct LimbUncertainty {
  Eigen::Vector2d A{0, 0};  ///< m, on A_x and A_y
  double alpha{0};          ///< rad
  double gamma{0};          ///< rad
  Eigen::Vector2d B{0, 0};  ///< m, on B_x and B_y
  double beta{0};           ///< rad
  RodUncertainty rod{};
};

/// Uncertainty half-widths: a global default for every limb, per-limb values (the default with the
/// file's overrides applied), and the extrinsics.
struct RobotUncertainty {
  LimbUncertainty global;
  std::vector<LimbUncertainty> limbs;  ///< one per limb, overrides applied
  Eigen::Vector3d camera{0, 0, 0};     ///< on (x m, y m, theta rad) of ^W T_Se
  Eigen::Vector3d pattern{0, 0, 0};    ///< on (x m, y m, theta rad) of ^M T_P
};

struct RobotDescription {
  std::string name;
  double young_modulus{
      0};  ///< the global E (Pa); params.limb(i).rod.young_modulus holds the resolved value
  RobotParams<double> params;
  std::optional<RobotUncertainty> uncertainty;
};

/// The paper's robot (femto_3pf()) with the paper's uncertainty intervals (Section 4).
inline RobotDescription default_robot() {
  RobotDescription robot;
  robot.name = "femto-3pf";
  robot.params = femto_3pf();
  robot.young_modulus = robot.params.limb(0).rod.young_modulus;
  RobotUncertainty u;
  // Mauze et al. 2021, Section 4: the intervals of the calibrated parameters.
  u.global.rod.length = 126e-6;
  u.global.A = Eigen::Vector2d(160e-6, 160e-6);
  u.global.B = Eigen::Vector2d(160e-6, 160e-6);
  u.global.alpha = 5e-3;
  u.global.beta = 5e-3;
  u.global.gamma = 5e-3;
  u.global.rod.diameter = 20e-6;
  u.global.rod.young_modulus = 0.0;
  u.limbs.assign(static_cast<std::size_t>(robot.params.num_limbs), u.global);
  u.camera = Eigen::Vector3d(1e-3, 1e-3, 50e-3);
  u.pattern = Eigen::Vector3d(1e-3, 1e-3, 50e-3);
  robot.uncertainty = u;
  return robot;
}

}  // namespace pcr
