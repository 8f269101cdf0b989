#pragma once
// The gauge orbit of the flat parameters (how the calibration uses it: pcr/calib/calibrator.hpp).

#include <string>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/robot.hpp"
#include "pcr/se2.hpp"
#include "pcr/shooting.hpp"

namespace pcr {

/// A tangent vector of the gauge orbit (see pcr/calib/calibrator.hpp): moving the parameters along
/// it changes no prediction when the platform carries no load.
struct GaugeGenerator {
  std::string name;               ///< e.g. "proximal clamps + camera: rotation"
  std::string combination;        ///< the parameters it moves, in words
  std::vector<double> direction;  ///< flat (parameters.hpp order), unscaled
};

/// The seven generators at `robot`: proximal translation x, y and rotation, distal translation
/// x, y and rotation, common scale of the bending stiffness.
std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot);

/// Moves `params` along the gauge orbit (predictions with no load are unchanged): the proximal
/// clamps and the camera frame by the rigid motion G (A -> G A, alpha -> alpha + G.theta,
/// camera -> G camera), the distal clamps and the pattern frame by H (B -> H B,
/// beta -> beta + H.theta, pattern -> pattern H^-1), every diameter times stiffness_scale.
RobotParams<double> move_along_gauge(const RobotParams<double>& params, const Pose2<double>& G,
                                     const Pose2<double>& H, double stiffness_scale);

/// The constant platform load (pcr/calib/cost.hpp, kLoadParameters) that keeps the predictions
/// of move_along_gauge(params, G, H, stiffness_scale) under `load`: the force turns with G (the
/// world moves), force and moment scale with the bending stiffness (stiffness_scale^4), and the
/// moment, taken about the platform origin that H moves, gains the force's arm. That arm turns
/// with each configuration's platform angle; it is taken at theta = 0. So with a force on the
/// platform a distal translation is no longer a gauge (the spread of the platform angles over the
/// data sees it, weakly), and the predictions are kept exactly only when H does not translate.
PlatformLoad<double> move_load_along_gauge(const PlatformLoad<double>& load, const Pose2<double>& G,
                                           const Pose2<double>& H, double stiffness_scale);

/// The equilibrium `solution` of a robot moved along the gauge orbit by (G, H, stiffness_scale):
/// the same rods turned by G, the platform pose G P H^-1, the proximal forces turned by G and every
/// wrench scaled with the bending stiffness (stiffness_scale^4). The model's symmetry makes it the
/// equilibrium of move_along_gauge(...) exactly under move_load_along_gauge(...) when H does not
/// translate; otherwise a start one Newton step away. Its chord matrix is dropped.
ForwardSolution move_equilibrium_along_gauge(const ForwardSolution& solution,
                                             const Pose2<double>& G, const Pose2<double>& H,
                                             double stiffness_scale);

/// The seven generators at `robot` under a constant platform load, with the load's components
/// (move_load_along_gauge to first order, the distal translations' at platform angle 0) after
/// the flat ones: directions of num_parameters(n) + kLoadParameters values.
std::vector<GaugeGenerator> gauge_generators(const RobotParams<double>& robot,
                                             const PlatformLoad<double>& load);

/// A motion along the gauge orbit (move_along_gauge's arguments).
struct GaugeMotion {
  Pose2<double> G{0, 0, 0};  ///< of the proximal clamps and the camera frame
  Pose2<double> H{0, 0, 0};  ///< of the distal clamps, about the platform origin
  double stiffness_scale = 1;
};

/// The motion that puts limb 0's clamps and d_0 at `reference`'s values: A_0 (with
/// `proximal_translation`) and alpha_0 (with `proximal_rotation` too), B_0 and beta_0 alike (a
/// distal rotation alone turns about the platform origin and sets beta_0), d_0 (`stiffness`).
GaugeMotion gauge_fix_motion(const RobotParams<double>& params,
                             const RobotParams<double>& reference, bool proximal_translation,
                             bool proximal_rotation, bool distal_translation, bool distal_rotation,
                             bool stiffness);

/// The distal translation that fixes the gauge of `params` under a constant platform `load`
/// (after gauge_fix_motion's rotations). Without a force: B_0 takes `reference`'s value, both
/// coordinates `held`. With one, a distal translation changes the predictions, by the force's arm
/// that turns with the platform, to first order in the platform angle unless it is perpendicular
/// to the force: the motion is along that perpendicular, until the coordinate of B_0 with the
/// larger share in it takes `reference`'s value (held[0]: x, held[1]: y). Move the load with it
/// (move_load_along_gauge).
GaugeMotion gauge_fix_motion(const RobotParams<double>& params, const PlatformLoad<double>& load,
                             const RobotParams<double>& reference, bool held[2]);

/// move_along_gauge by gauge_fix_motion: predictions (with no load) are unchanged.
RobotParams<double> fix_gauge(const RobotParams<double>& params,
                              const RobotParams<double>& reference, bool proximal_translation,
                              bool proximal_rotation, bool distal_translation, bool distal_rotation,
                              bool stiffness);

}  // namespace pcr
