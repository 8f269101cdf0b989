#pragma once
// The spatial robot file: a `pcr-robot` JSON file with "kind": "spatial", describing a
// SpatialRobotParams (pcr/spatial/robot.hpp). Compiled in pcr::io, with the planar loader's
// parser and messages (pcr/robot_io.hpp); the format is documented in docs/formats.md, "Spatial
// robots". Orientations in the file are unit quaternions (w, x, y, z), body -> parent, as in the
// model; a quaternion whose norm is not 1 within kUnitQuaternionTolerance is refused, not
// normalised (a typo in one component would otherwise turn the frame silently).

#include <optional>
#include <string>

#include "pcr/input_error.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/spatial/parameters.hpp"
#include "pcr/spatial/robot.hpp"

namespace pcr {

/// How far from 1 the norm of a quaternion (or a unit direction) in a file may be.
inline constexpr double kUnitQuaternionTolerance = 1e-9;

/// A spatial robot as its file describes it: its name, its parameters (the measuring system's
/// extrinsics included) and the intervals its uncertain parameters lie in.
struct SpatialRobotDescription {
  std::string name;
  SpatialRobotParams<double> params;
  /// Half-widths, rods resolved (one entry per rod); absent: every parameter known.
  std::optional<SpatialUncertainty> uncertainty;
};

/// The reference robot's intervals, a lab's tolerances for a robot of this size (the paper's for
/// its angles and its camera, Section 4): holes and attachment points within 0.1 mm along each
/// axis, their frames within 5 mrad about each axis, the free length at q = 0 within 0.5 mm (the
/// actuators' zero), the wire's diameter within 10 um, E and G within 5 %, the tracker's frame
/// within 1 mm and 50 mrad, the marker's within 1 mm and 50 mrad.
inline SpatialUncertainty continuum_stewart_gough_uncertainty(int num_rods = 6) {
  SpatialUncertainty u;
  u.global.young_modulus = 10e9;
  u.global.shear_modulus = 4e9;
  u.global.diameter = 10e-6;
  u.global.length = 0.5e-3;
  u.global.A = Eigen::Vector3d::Constant(0.1e-3);
  u.global.base_rotation = Eigen::Vector3d::Constant(5e-3);
  u.global.B = Eigen::Vector3d::Constant(0.1e-3);
  u.global.tip_rotation = Eigen::Vector3d::Constant(5e-3);
  u.rods.assign(static_cast<std::size_t>(num_rods), u.global);
  u.tracker << 1e-3, 1e-3, 1e-3, 50e-3, 50e-3, 50e-3;
  u.marker << 1e-3, 1e-3, 1e-3, 50e-3, 50e-3, 50e-3;
  return u;
}

/// The reference continuum Stewart-Gough robot (continuum_stewart_gough()) with its intervals, as
/// robots/continuum-stewart-gough.json describes it.
inline SpatialRobotDescription continuum_stewart_gough_description() {
  return SpatialRobotDescription{"continuum-stewart-gough", continuum_stewart_gough(),
                                 continuum_stewart_gough_uncertainty()};
}

/// The file's name of an actuation ("length_through_hole", "translated_clamp") and of an
/// attachment ("clamped", "spherical").
const char* to_string(SpatialActuation actuation);
const char* to_string(SpatialAttachment attachment);

/// Parses and validates a spatial description; `source` names the file in error messages (an
/// InputError naming the file, the field path and the value; a planar file names its kind).
SpatialRobotDescription parse_spatial_robot(const std::string& json_text,
                                            const std::string& source);
/// Reads a spatial description from a file (throws InputError naming the file on any problem).
SpatialRobotDescription load_spatial_robot(const std::string& path);
/// Serialises every field with full double precision (lossless round trip).
std::string spatial_robot_to_json(const SpatialRobotDescription& robot);
/// Writes to a temporary file in the same directory, then renames it over `path`; refuses (an
/// InputError) a description that would not load back.
void save_spatial_robot(const SpatialRobotDescription& robot, const std::string& path);

}  // namespace pcr
