#pragma once
// The spatial robot file: a `pcr-robot` JSON file with "kind": "spatial", describing a
// SpatialRobotParams (pcr/spatial/robot.hpp). Compiled in pcr::io, with the planar loader's
// parser and messages (pcr/robot_io.hpp); the format is documented in docs/formats.md, "Spatial
// robots". Orientations in the file are unit quaternions (w, x, y, z), body -> parent, as in the
// model; a quaternion whose norm is not 1 within kUnitQuaternionTolerance is refused, not
// normalised (a typo in one component would otherwise turn the frame silently).

#include <string>

#include "pcr/input_error.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/spatial/robot.hpp"

namespace pcr {

/// How far from 1 the norm of a quaternion (or a unit direction) in a file may be.
inline constexpr double kUnitQuaternionTolerance = 1e-9;

/// A spatial robot as its file describes it: its name and its parameters.
struct SpatialRobotDescription {
  std::string name;
  SpatialRobotParams<double> params;
};

/// The reference continuum Stewart-Gough robot (continuum_stewart_gough()), as
/// robots/continuum-stewart-gough.json describes it.
inline SpatialRobotDescription continuum_stewart_gough_description() {
  return SpatialRobotDescription{"continuum-stewart-gough", continuum_stewart_gough()};
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
