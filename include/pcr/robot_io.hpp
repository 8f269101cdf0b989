#pragma once
// The `pcr-robot` JSON file format: a robot description with its uncertainty intervals.
// Compiled in pcr::io (nlohmann_json stays private). Format documented in docs/formats.md. The
// types it reads and writes are the model's (pcr/robot_description.hpp).

#include <Eigen/Core>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/robot_description.hpp"

namespace pcr {

/// A value from a user's file as an error message shows it: at most 60 characters, "..." where
/// it was cut (a field may hold megabytes).
std::string excerpt(std::string text);

/// Parses and validates a description; `source` names the file in error messages. A file of
/// another kind (a spatial robot) is an InputError naming the file and its kind.
RobotDescription parse_robot(const std::string& json_text, const std::string& source);

/// The deepest nesting of arrays and objects a pcr JSON file may have: every format is a few
/// levels deep. Parsers and messages walk nested values recursively, so every JSON loader
/// (robot, mount layout, stages) checks the text first with check_json_nesting.
inline constexpr int kMaxJsonNesting = 32;

/// InputError naming `source`, the line and the column where the text nests deeper than
/// kMaxJsonNesting.
void check_json_nesting(const std::string& json_text, const std::string& source);
/// What a pcr-robot file describes: its "kind" field, "planar" (the default when absent: this
/// header's RobotDescription) or "spatial" (pcr/spatial/robot_io.hpp).
enum class RobotKind { kPlanar, kSpatial };
/// The kind of the robot in `json_text` (InputError naming `source` on a bad file or kind).
RobotKind robot_kind(const std::string& json_text, const std::string& source);
/// The kind of the robot in the file at `path`, for a command that takes either.
RobotKind load_robot_kind(const std::string& path);

/// Reads a description from a file (throws InputError naming the file on any problem).
RobotDescription load_robot(const std::string& path);
/// Serialises with full double precision (lossless round trip).
std::string robot_to_json(const RobotDescription& robot);
/// Writes to a temporary file in the same directory, then renames it over `path`.
void save_robot(const RobotDescription& robot, const std::string& path);

/// load_robot(path), or default_robot() when path is empty.
RobotDescription load_robot_or_default(const std::string& path);

}  // namespace pcr
