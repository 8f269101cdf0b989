#pragma once
// The `pcr-robot` JSON file format: a robot description with its uncertainty intervals.
// Compiled in pcr::io (nlohmann_json stays private). Format documented in docs/formats.md.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "pcr/robot.hpp"

namespace pcr {

/// Bad input (a file, a field, a value). The message names the file, the field path and the value.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A value from a user's file as an error message shows it: at most 60 characters, "..." where
/// it was cut (a field may hold megabytes).
std::string excerpt(std::string text);

/// Half-widths of the uncertainty intervals of one limb's parameters (SI units, radians).
struct LimbUncertainty {
  Eigen::Vector2d A{0, 0};  ///< m, on A_x and A_y
  double alpha{0};          ///< rad
  double gamma{0};          ///< rad
  Eigen::Vector2d B{0, 0};  ///< m, on B_x and B_y
  double beta{0};           ///< rad
  double length{0};         ///< m
  double diameter{0};       ///< m
  double young_modulus{0};  ///< Pa
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
      0};  ///< the global E (Pa); params.limb(i).young_modulus holds the resolved value
  RobotParams<double> params;
  std::optional<RobotUncertainty> uncertainty;
};

/// Parses and validates a description; `source` names the file in error messages.
RobotDescription parse_robot(const std::string& json_text, const std::string& source);

/// The deepest nesting of arrays and objects a pcr JSON file may have: every format is a few
/// levels deep. Parsers and messages walk nested values recursively, so every JSON loader
/// (robot, mount layout, stages) checks the text first with check_json_nesting.
inline constexpr int kMaxJsonNesting = 32;

/// InputError naming `source`, the line and the column where the text nests deeper than
/// kMaxJsonNesting.
void check_json_nesting(const std::string& json_text, const std::string& source);
/// Reads a description from a file (throws InputError naming the file on any problem).
RobotDescription load_robot(const std::string& path);
/// Serialises with full double precision (lossless round trip).
std::string robot_to_json(const RobotDescription& robot);
/// Writes to a temporary file in the same directory, then renames it over `path`.
void save_robot(const RobotDescription& robot, const std::string& path);

/// The paper's robot (femto_3pf()) with the paper's uncertainty intervals (Section 4).
RobotDescription default_robot();

/// load_robot(path), or default_robot() when path is empty.
RobotDescription load_robot_or_default(const std::string& path);

}  // namespace pcr
