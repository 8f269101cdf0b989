#pragma once
// The mount layout file: where each rod mount's tag is and how its clamp sits relative to the tag.
//
// Format (JSON, SI units, angles in radians; see docs/vision.md and data/mounts-femto-3pf.json):
//   {
//     "format": "pcr-mounts", "version": 1,
//     "family": "tag36h11",            // default for every mount (optional)
//     "tag_size": 0.010,               // default black-border edge, m (optional)
//     "mounts": [
//       { "name": "A1",                // free text, used in messages
//         "role": "proximal",          // "proximal" (on actuator i, gives A_i, alpha_i)
//                                      // or "distal" (on the platform, gives B_i, beta_i)
//         "limb": 0,                   // limb index, 0-based, as in the pcr-robot file
//         "family": "tag36h11", "id": 0, "tag_size": 0.010,   // family, tag_size optional
//         "clamp_offset": [0.014, 0.00025],               // clamp point in the tag frame, m
//         "clamp_offset_uncertainty": [0.00084, 0.000015], // half-widths, m
//         "rod_angle": 0.0,            // rod tangent (from A towards B) in the tag frame, rad
//         "rod_angle_uncertainty": 0.005 }                // half-width, rad
//     ]
//   }
// The tag frame is defined in pcr/vision/tags.hpp (centre, x to the bitmap's right, y to its top).
// Every limb needs exactly one proximal and one distal mount; ids are unique per family.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pcr/vision/tags.hpp"

namespace pcr::vision {

enum class MountRole { kProximal, kDistal };

struct Mount {
  std::string name;
  MountRole role{MountRole::kProximal};
  int limb{0};
  std::string family{kDefaultTagFamily};
  int id{0};
  double tag_size{0.01};
  Eigen::Vector2d clamp_offset{0, 0};
  Eigen::Vector2d clamp_offset_uncertainty{0, 0};
  double rod_angle{0};
  double rod_angle_uncertainty{0};
};

struct MountLayout {
  std::vector<Mount> mounts;
  int num_limbs() const;
  /// Index into mounts of the limb's proximal or distal mount, -1 when absent.
  int find(int limb, MountRole role) const;
};

/// Parses and validates (unique ids, one proximal and one distal mount per limb 0..n-1, positive
/// sizes, non-negative uncertainties, known families). `source` names the file in messages.
/// `family`: the tag family of the mounts when neither the mount nor the file's root names one
/// (InputError when it is not a known family).
MountLayout parse_mounts(const std::string& json_text, const std::string& source,
                         const std::string& family = kDefaultTagFamily);
MountLayout load_mounts(const std::string& path, const std::string& family = kDefaultTagFamily);

/// The default robot's layout (data/mounts-femto-3pf.json, compiled in).
MountLayout default_mounts();

}  // namespace pcr::vision
