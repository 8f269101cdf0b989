#pragma once
// Trajectories of a spatial robot through inverse kinematics and their ISO 9283 accuracy in 3-D
// (Mauze et al. 2021, Section 6, for the robots of pcr/spatial/): the allocating side of
// pcr/spatial/trajectory.hpp, as pcr/calib/accuracy.hpp is of pcr/trajectory.hpp.
//
// ISO 9283 per commanded pose c = (p_c, R_c) and its n attained poses j = (p_j, R_j), all in W:
//   barycentre  p_bar = mean(p_j); R_bar the Karcher (geodesic L2) mean of the R_j: the rotation
//     about which the deviations w_j = log(R_bar^T R_j) average to zero, found by the fixed-point
//     iteration R_bar <- R_bar exp(mean_j w_j) from R_1. As the planar theta_bar (a mean of angle
//     deviations), it makes the deviations' mean zero, so that their per-axis scatter is a
//     standard deviation about the mean; the chordal mean (the sum of the R_j projected onto
//     SO(3)) differs from it by O(scatter^3) only, but leaves them a non-zero mean.
//   AP_p = |p_bar - p_c|                                                      (Eq. 10, in 3-D)
//   (AP_a, AP_b, AP_c) = log(R_c^T R_bar): the rotation vector of the mean orientation error,
//     in the commanded platform frame P_c: a, b, c are turns about the platform's own x, y and z
//     axes (its tilts and its twist), as the spatial solvers turn the platform
//     (R <- R exp([delta]x)), and do not depend on where W is. ISO 9283 differences three angles
//     of the orientation instead, which depends on their convention and fails at its
//     singularities; a rotation vector has neither.                          (Eq. 11, per axis)
//   l_j = |p_j - p_bar|, S_l = sqrt(sum (l_j - l_bar)^2 / (n - 1)), RP_l = l_bar + 3 S_l;
//   S_a = sqrt(sum a_j^2 / (n - 1)) with (a_j, b_j, c_j) = w_j (in R_bar's frame), RP_a = +-3 S_a;
//   likewise b and c.
// Table 4 of the paper is the max, mean and min over the path of AP_p and |AP_theta|: here of
// AP_p and each of |AP_a|, |AP_b|, |AP_c|, with RP_l and RP_a, RP_b, RP_c.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pcr/calib/accuracy.hpp"
#include "pcr/calib/spatial_virtual_robot.hpp"
#include "pcr/spatial/kinematics.hpp"
#include "pcr/spatial/trajectory.hpp"

namespace pcr {

/// The poses of a path as a vector (pcr/spatial/trajectory.hpp); InputError for a path out of
/// its ranges.
std::vector<SpatialPose<double>> spatial_square_path(
    const SpatialSquarePath& spec = SpatialSquarePath());
std::vector<SpatialPose<double>> spatial_circle_path(
    const SpatialCirclePath& spec = SpatialCirclePath());
std::vector<SpatialPose<double>> spatial_helix_path(
    const SpatialHelixPath& spec = SpatialHelixPath());

/// IK along a spatial path: SpatialInverseSequence in SequenceMode::kPath (the first pose cold,
/// from home; each next one warm-started from the previous solution, retried cold on failure).
struct SpatialPathCommandOptions {
  /// The largest bending strain a commanded pose may reach (SolverSummary::max_strain).
  double strain_limit = kDefaultStrainLimit;
  /// The solves' options; with check_stability and stable_inverse (the defaults) a pose whose
  /// only equilibrium found would not hold is refused.
  SolverOptions solver;
  /// An equilibrium of the model that the first pose's IK starts from (continued along the pose
  /// path from it); none: the model's home solution, cold. For a model whose cold FK fails (an
  /// identified robot: the spatial cold start does not solve every robot), its FK continued from
  /// the nominal robot's at the same joints.
  std::optional<SpatialForwardSolution> start;

  /// As SolverOptions::is_valid, for the strain limit and the solver's options.
  bool is_valid(std::string* error = nullptr) const {
    return kStrainLimitRange.check(strain_limit, error) && solver.is_valid(error);
  }
};

struct SpatialPathCommand {
  std::vector<SpatialJointVector> q;  ///< commanded joints of each pose (m)
  std::vector<SpatialPose<double>>
      poses;                       ///< the poses solved for (free angles solved, 3 or 5 rods)
  std::vector<double> max_strain;  ///< largest bending strain at each pose
  std::vector<int> iterations;     ///< Newton iterations on each pose, cold retries included
  std::vector<int> residual_evaluations;  ///< residual evaluations on each pose, likewise
};

/// Throws InputError "pose k (x m, y m, z m, rx rad, ry rad, rz rad): <reason>" (k 0-based, the
/// orientation as a rotation vector) at the first pose that is not finite, has no converged IK
/// solution (or only an unstable one, when the options ask for stable ones), or exceeds the
/// strain limit; and on an empty path, invalid options or a robot whose IK is not square (other
/// than 3, 5 or 6 rods).
SpatialPathCommand spatial_command_path(
    const SpatialRobotParams<double>& model, const std::vector<SpatialPose<double>>& path,
    const SpatialPathCommandOptions& options = SpatialPathCommandOptions());

/// ISO 9283 statistics of one commanded pose (see the header's comment).
struct SpatialIso9283Pose {
  SpatialPose<double> commanded;
  SpatialPose<double> barycentre;                    ///< (p_bar, R_bar)
  int cycles = 0;                                    ///< n attained poses
  Vector3<double> ap_xyz = Vector3<double>::Zero();  ///< p_bar - p_c (m)
  double ap_p = 0;                                   ///< |p_bar - p_c| (m)
  Vector3<double> ap_abc = Vector3<double>::Zero();  ///< (AP_a, AP_b, AP_c), signed (rad)
  double l_bar = 0, s_l = 0;                         ///< m
  double rp_l = 0;                                   ///< l_bar + 3 S_l (m)
  Vector3<double> s_abc = Vector3<double>::Zero();   ///< (S_a, S_b, S_c) (rad)
  Vector3<double> rp_abc = Vector3<double>::Zero();  ///< 3 (S_a, S_b, S_c): +-rp (rad)
};

struct SpatialIso9283Result {
  std::vector<SpatialIso9283Pose> poses;
  Iso9283Stats ap_p;                       ///< m
  std::array<Iso9283Stats, 3> ap_abc_abs;  ///< rad, of |AP_a|, |AP_b|, |AP_c|
  Iso9283Stats rp_l;                       ///< m
  std::array<Iso9283Stats, 3> rp_abc;      ///< rad, of RP_a, RP_b, RP_c
};

/// attained[k] holds the attained poses of commanded[k] (all in W). Throws InputError when the
/// sizes differ, there is no pose, a pose has fewer than 2 attained poses, a position or
/// quaternion is not finite (or a quaternion is zero), or a pose's attained orientations spread
/// so far (a deviation of pi / 2 or more from their mean) that their mean is not unique.
SpatialIso9283Result iso9283_spatial(const std::vector<SpatialPose<double>>& commanded,
                                     const std::vector<std::vector<SpatialPose<double>>>& attained);

struct SpatialAccuracyOptions {
  int repeat = 30;  ///< ISO 9283 cycles per pose (>= 2; the standard asks for >= 30)
  SpatialPathCommandOptions command;
  AttainedFrame frame = AttainedFrame::kModelExtrinsics;

  /// As AccuracyOptions::kRepeat.
  static constexpr OptionRange kRepeat = AccuracyOptions::kRepeat;
  bool is_valid(std::string* error = nullptr) const {
    return kRepeat.check(repeat, error) && command.is_valid(error);
  }
};

struct SpatialAccuracyEvaluation {
  std::vector<SpatialPose<double>> commanded;  ///< the poses solved for
  SpatialPathCommand command;
  std::vector<std::vector<SpatialPose<double>>> attained;  ///< [pose][cycle], ^W T_P
  SpatialIso9283Result iso;
};

/// Commands the path with `model` (nominal or identified), then runs `repeat` cycles on the
/// virtual robot, as evaluate_on_virtual_robot does for a planar one: each cycle visits every
/// pose in path order; the robot moves on its true parameters, the measuring system adds its
/// noise, and each measured marker pose is taken to ^W T_P through the model's extrinsics (or the
/// truth's, options.frame). Throws InputError for a path the model cannot command, and
/// std::runtime_error naming the cycle and pose where the true robot has no stable equilibrium.
SpatialAccuracyEvaluation evaluate_on_spatial_virtual_robot(
    const SpatialRobotParams<double>& model, SpatialVirtualRobot& robot,
    const std::vector<SpatialPose<double>>& path,
    const SpatialAccuracyOptions& options = SpatialAccuracyOptions());

/// Table 4 in 3-D as Markdown, one row per path and statistic (max, mean, min; AP_p and RP_l in
/// um, the angles in mrad); the per-pose statistics as CSV and everything as JSON (SI units).
/// CSV columns: pose, the commanded pose x_c, y_c, z_c, rx_c, ry_c, rz_c (m, rotation vector in
/// rad), the barycentre x_bar ... rz_bar, cycles, ap_x, ap_y, ap_z, ap_p, ap_a, ap_b, ap_c, l_bar,
/// s_l, rp_l, s_a, s_b, s_c, rp_a, rp_b, rp_c.
std::string iso9283_spatial_table_markdown(
    const std::vector<std::pair<std::string, const SpatialIso9283Result*>>& rows);
std::string iso9283_spatial_poses_csv(const SpatialIso9283Result& result);
std::string iso9283_spatial_json(
    const std::vector<std::pair<std::string, const SpatialIso9283Result*>>& rows);

}  // namespace pcr
