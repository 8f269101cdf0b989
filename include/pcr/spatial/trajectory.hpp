#pragma once
// Cartesian paths of a spatial robot's platform at a constant orientation: the spatial
// counterparts of pcr/trajectory.hpp's SquarePath and CirclePath (Mauze et al. 2021,
// Section 6.1), in any plane, and a helix. Pose generators (pose(k), at(fraction), fill_path):
// header-only, no heap, no exceptions. The allocating side (vectors, IK along a whole path,
// ISO 9283 in 3-D) lives in pcr/calib/spatial_accuracy.hpp; IK along a path is
// SpatialInverseSequence in SequenceMode::kPath (pcr/spatial/sequence.hpp).
//
// A plane is given by a frame (a quaternion (w, x, y, z), any non-zero scale, body -> W) whose
// e1, e2 span the plane and whose e3 is its normal: a path drawn counter-clockwise about e3.
// The platform's orientation is its own quaternion, the same at every pose; both default to the
// identity (a path in W's x-y plane, the platform untilted).

#include <cmath>
#include <string>

#include "pcr/option_range.hpp"
#include "pcr/spatial/shooting.hpp"
#include "pcr/trajectory.hpp"

namespace pcr {

namespace internal {

/// The point (u, v, w) of a plane's frame in W, the frame's origin at `centre`.
inline Vector3<double> point_in_plane(const Vector3<double>& centre, const Vector4<double>& plane,
                                      double u, double v, double w = 0.0) {
  return centre + rotation_of(plane) * Vector3<double>(u, v, w);
}

}  // namespace internal

/// A square in a plane through `centre`, traversed counter-clockwise about the plane's normal
/// from the perimeter fraction `start` (0: the corner (-side/2, -side/2) in the plane's frame),
/// at the constant platform orientation `orientation`. With num_poses a multiple of 4 and start
/// a multiple of 1/4 the corners are poses; closed: pose(num_poses) == pose(0), not repeated.
struct SpatialSquarePath {
  Vector3<double> centre = Vector3<double>::Zero();                   ///< m, in W
  Vector4<double> plane_orientation = identity_quaternion<double>();  ///< e3 the plane's normal
  double side = kPaperSquareSide;                                     ///< m
  double start = 0.0;  ///< fraction of the perimeter where pose 0 lies
  Vector4<double> orientation = identity_quaternion<double>();  ///< the platform's, P -> W
  int num_poses = 40;

  // The documented ranges (is_valid): the planar sizes and counts (SquarePath); a centre within a
  // metre of W's origin (the spatial IK's inputs, pcr ik); quaternions of any finite, non-zero
  // norm (rotation_of divides by it), bounded so that a typo of a zero shows.
  static constexpr OptionRange kSide = SquarePath::kSide;
  static constexpr OptionRange kCentre{"centre", -1, 1, "m"};  ///< each of x, y and z
  static constexpr OptionRange kPlaneNorm{"|plane_orientation|", 1e-6, 1e6};
  static constexpr OptionRange kOrientationNorm{"|orientation|", 1e-6, 1e6};
  static constexpr OptionRange kStart{"start", 0, 1};
  static constexpr OptionRange kNumPoses = SquarePath::kNumPoses;

  /// As SolverOptions::is_valid, naming the field with `prefix` ("square." when nested).
  bool is_valid(std::string* error = nullptr, const char* prefix = "") const {
    return kSide.check(side, error, prefix) &&
           valid_frame(centre, plane_orientation, kPlaneNorm, error, prefix) &&
           kStart.check(start, error, prefix) &&
           kOrientationNorm.check(orientation.norm(), error, prefix) &&
           kNumPoses.check(num_poses, error, prefix);
  }
  /// The centre's and the plane's (or axis') frame's checks, shared by the spatial paths.
  static bool valid_frame(const Vector3<double>& centre, const Vector4<double>& frame,
                          const OptionRange& frame_norm, std::string* error, const char* prefix) {
    return kCentre.check(centre.x(), error, prefix) && kCentre.check(centre.y(), error, prefix) &&
           kCentre.check(centre.z(), error, prefix) &&
           frame_norm.check(frame.norm(), error, prefix);
  }

  /// The pose at `fraction` of the perimeter from pose 0 (wrapped into [0, 1)).
  SpatialPose<double> at(double fraction) const noexcept {
    SquarePath square;  // the planar square about the plane's origin gives the in-plane point
    square.side = side;
    const Pose2<double> p = square.at(start + fraction);
    return SpatialPose<double>{internal::point_in_plane(centre, plane_orientation, p.x, p.y),
                               orientation};
  }
  SpatialPose<double> pose(int k) const noexcept {
    return at(num_poses > 0 ? static_cast<double>(k) / num_poses : 0.0);
  }
  int size() const noexcept { return num_poses; }
};

/// A circle in a plane through `centre`, traversed counter-clockwise about the plane's normal
/// from the polar angle `start` (about the plane's e3, from its e1), at the constant platform
/// orientation; closed like SpatialSquarePath.
struct SpatialCirclePath {
  Vector3<double> centre = Vector3<double>::Zero();                   ///< m, in W
  Vector4<double> plane_orientation = identity_quaternion<double>();  ///< e3 the plane's normal
  double diameter = kPaperCircleDiameter;                             ///< m
  double start = 0.0;                                           ///< rad, polar angle of pose 0
  Vector4<double> orientation = identity_quaternion<double>();  ///< the platform's, P -> W
  int num_poses = 36;

  static constexpr OptionRange kDiameter = CirclePath::kDiameter;
  static constexpr OptionRange kStart{"start", -M_PI, M_PI, "rad"};
  static constexpr OptionRange kNumPoses = SquarePath::kNumPoses;

  /// As SpatialSquarePath::is_valid.
  bool is_valid(std::string* error = nullptr, const char* prefix = "") const {
    return kDiameter.check(diameter, error, prefix) &&
           SpatialSquarePath::valid_frame(centre, plane_orientation, SpatialSquarePath::kPlaneNorm,
                                          error, prefix) &&
           kStart.check(start, error, prefix) &&
           SpatialSquarePath::kOrientationNorm.check(orientation.norm(), error, prefix) &&
           kNumPoses.check(num_poses, error, prefix);
  }

  SpatialPose<double> at(double fraction) const noexcept {
    CirclePath circle;  // the planar circle about the plane's origin
    circle.diameter = diameter;
    circle.start_angle = start;
    const Pose2<double> p = circle.at(fraction);
    return SpatialPose<double>{internal::point_in_plane(centre, plane_orientation, p.x, p.y),
                               orientation};
  }
  SpatialPose<double> pose(int k) const noexcept {
    return at(num_poses > 0 ? static_cast<double>(k) / num_poses : 0.0);
  }
  int size() const noexcept { return num_poses; }
};

/// A helix about the axis e3 of `axis_orientation` through `centre`, the midpoint of its axis:
/// `turns` turns counter-clockwise about e3 from the polar angle `start`, rising `pitch` per
/// turn along e3 (a negative pitch descends), from centre - pitch turns / 2 e3 to
/// centre + pitch turns / 2 e3, at the constant platform orientation. Not closed: pose 0 is the
/// start, pose num_poses - 1 the end.
struct SpatialHelixPath {
  Vector3<double> centre = Vector3<double>::Zero();  ///< m, in W: the midpoint of the axis
  Vector4<double> axis_orientation = identity_quaternion<double>();  ///< e3 the helix's axis
  double diameter = kPaperCircleDiameter;                            ///< m
  double pitch = 1e-3;                                               ///< m per turn
  double turns = 2.0;
  double start = 0.0;                                           ///< rad, polar angle of pose 0
  Vector4<double> orientation = identity_quaternion<double>();  ///< the platform's, P -> W
  int num_poses = 73;                                           ///< 36 a turn, both ends included

  static constexpr OptionRange kDiameter = CirclePath::kDiameter;
  /// Up or down, as far as a side or diameter: pitch 0 retraces a circle.
  static constexpr OptionRange kPitch{"pitch", -SquarePath::kSide.hi, SquarePath::kSide.hi, "m"};
  static constexpr OptionRange kTurns{"turns", 1e-3, 1000};
  static constexpr OptionRange kAxisNorm{"|axis_orientation|", SpatialSquarePath::kPlaneNorm.lo,
                                         SpatialSquarePath::kPlaneNorm.hi};
  static constexpr OptionRange kStart = SpatialCirclePath::kStart;
  static constexpr OptionRange kNumPoses = SquarePath::kNumPoses;

  /// As SpatialSquarePath::is_valid.
  bool is_valid(std::string* error = nullptr, const char* prefix = "") const {
    return kDiameter.check(diameter, error, prefix) && kPitch.check(pitch, error, prefix) &&
           kTurns.check(turns, error, prefix) &&
           SpatialSquarePath::valid_frame(centre, axis_orientation, kAxisNorm, error, prefix) &&
           kStart.check(start, error, prefix) &&
           SpatialSquarePath::kOrientationNorm.check(orientation.norm(), error, prefix) &&
           kNumPoses.check(num_poses, error, prefix);
  }

  /// The pose at `fraction` of the way from start to end (clamped to [0, 1]).
  SpatialPose<double> at(double fraction) const noexcept {
    const double f = fraction < 0.0 ? 0.0 : (fraction > 1.0 ? 1.0 : fraction);
    CirclePath circle;  // the turn about the axis; CirclePath wraps the fraction of a turn
    circle.diameter = diameter;
    circle.start_angle = start;
    const Pose2<double> p = circle.at(turns * f);
    return SpatialPose<double>{
        internal::point_in_plane(centre, axis_orientation, p.x, p.y, pitch * turns * (f - 0.5)),
        orientation};
  }
  SpatialPose<double> pose(int k) const noexcept {
    return at(num_poses > 1 ? static_cast<double>(k) / (num_poses - 1) : 0.0);
  }
  int size() const noexcept { return num_poses; }
};

}  // namespace pcr
