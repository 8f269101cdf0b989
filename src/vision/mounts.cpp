#include "pcr/vision/mounts.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/tags.hpp"

namespace pcr::vision {

using nlohmann::json;

int MountLayout::num_limbs() const {
  int n = 0;
  for (const Mount& m : mounts) n = std::max(n, m.limb + 1);
  return n;
}

int MountLayout::find(int limb, MountRole role) const {
  for (std::size_t i = 0; i < mounts.size(); ++i)
    if (mounts[i].limb == limb && mounts[i].role == role) return static_cast<int>(i);
  return -1;
}

namespace {

const char* const kRootFields[] = {"format", "version", "comment", "family", "tag_size", "mounts"};
const char* const kMountFields[] = {"name",         "role",
                                    "limb",         "id",
                                    "family",       "tag_size",
                                    "clamp_offset", "clamp_offset_uncertainty",
                                    "rod_angle",    "rod_angle_uncertainty",
                                    "comment"};

/// Levenshtein distance: insertions, deletions and substitutions turning `a` into `b`.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

struct Reader {
  const std::string& source;
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw InputError(source + ": " + field + ": " + what);
  }
  /// Every key of the object `j` must be one of `known`: a misspelt field would otherwise be
  /// ignored (or, for an optional one, replaced by its default) without a word.
  template <std::size_t N>
  void check_fields(const json& j, const std::string& path, const char* const (&known)[N]) const {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string& key = it.key();
      if (std::find_if(known, known + N, [&](const char* k) { return key == k; }) != known + N)
        continue;
      const char* closest = known[0];
      for (const char* k : known)
        if (edit_distance(key, k) < edit_distance(key, closest)) closest = k;
      std::string names;
      for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
      fail((path.empty() ? "" : path + ".") + excerpt(key), "unknown field; did you mean \"" +
                                                                std::string(closest) +
                                                                "\"? (known here: " + names + ")");
    }
  }
  double number(const json& j, const std::string& key, const std::string& path) const {
    if (!j.contains(key)) fail(path + "." + key, "missing");
    if (!j[key].is_number())
      fail(path + "." + key, "not a number (" + excerpt(j[key].dump()) + ")");
    const double v = j[key].get<double>();
    if (!std::isfinite(v)) fail(path + "." + key, "not finite");
    return v;
  }
  /// The string field `key` of `j`, or `fallback` when absent.
  std::string text(const json& j, const std::string& key, const std::string& path,
                   const std::string& fallback) const {
    if (!j.is_object() || !j.contains(key)) return fallback;
    if (!j[key].is_string()) {
      fail(path + "." + key, "expected a string, got " + excerpt(j[key].dump()));
    }
    return j[key].get<std::string>();
  }
  Eigen::Vector2d pair(const json& j, const std::string& key, const std::string& path) const {
    if (!j.contains(key)) fail(path + "." + key, "missing");
    const json& a = j[key];
    if (!a.is_array() || a.size() != 2 || !a[0].is_number() || !a[1].is_number()) {
      fail(path + "." + key, "expected [x, y] in metres, got " + excerpt(a.dump()));
    }
    return {a[0].get<double>(), a[1].get<double>()};
  }
};

}  // namespace

MountLayout parse_mounts(const std::string& text, const std::string& source,
                         const std::string& default_family) {
  if (!is_known_family(default_family)) {
    throw InputError(source + ": unknown default tag family '" + default_family +
                     "'; the accepted families are " + known_families());
  }
  check_json_nesting(text, source);
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(source + ": not valid JSON (" + e.what() + ")");
  }
  const Reader r{source};
  if (!root.is_object()) r.fail("(root)", "expected an object");
  r.check_fields(root, "", kRootFields);
  if (root.contains("format") && root["format"] != "pcr-mounts") {
    r.fail("format", "expected \"pcr-mounts\", got " + excerpt(root["format"].dump()));
  }
  const std::string family = r.text(root, "family", "(root)", default_family);
  const double size = root.contains("tag_size") ? r.number(root, "tag_size", "") : 0.0;
  if (!root.contains("mounts") || !root["mounts"].is_array() || root["mounts"].empty()) {
    r.fail("mounts", "missing or empty array");
  }
  MountLayout layout;
  std::set<std::pair<std::string, int>> ids;
  for (std::size_t i = 0; i < root["mounts"].size(); ++i) {
    const json& j = root["mounts"][i];
    const std::string path = "mounts[" + std::to_string(i) + "]";
    if (!j.is_object()) r.fail(path, "expected an object");
    Mount m;
    m.name = r.text(j, "name", path, path);
    const std::string where = path + " (" + m.name + ")";
    r.check_fields(j, where, kMountFields);
    const std::string role = r.text(j, "role", where, std::string());
    if (role == "proximal") {
      m.role = MountRole::kProximal;
    } else if (role == "distal") {
      m.role = MountRole::kDistal;
    } else {
      r.fail(where + ".role", "expected \"proximal\" or \"distal\", got \"" + role + "\"");
    }
    const double limb = r.number(j, "limb", where);
    if (limb < 0 || limb >= 6 || limb != std::floor(limb))
      r.fail(where + ".limb", "expected 0..5, got " + excerpt(j["limb"].dump()));
    m.limb = static_cast<int>(limb);
    m.family = r.text(j, "family", where, family);
    if (!is_known_family(m.family))
      r.fail(where + ".family", "unknown tag family \"" + m.family + "\"");
    const double id = r.number(j, "id", where);
    if (id < 0 || id > 1e6 || id != std::floor(id))
      r.fail(where + ".id",
             "expected a tag id (an integer from 0), got " + excerpt(j["id"].dump()));
    m.id = static_cast<int>(id);
    int total = 0, wab = 0;
    try {
      tag_bitmap(m.family, m.id, &total, &wab);
    } catch (const InputError& e) {
      r.fail(where + ".id", e.what());
    }
    if (!ids.insert({m.family, m.id}).second) {
      r.fail(where + ".id", "duplicated tag id " + std::to_string(m.id) + " (" + m.family + ")");
    }
    m.tag_size = j.contains("tag_size") ? r.number(j, "tag_size", where) : size;
    if (!(m.tag_size > 0))
      r.fail(where + ".tag_size", "must be positive (m), got " + std::to_string(m.tag_size));
    m.clamp_offset = r.pair(j, "clamp_offset", where);
    m.clamp_offset_uncertainty = r.pair(j, "clamp_offset_uncertainty", where);
    m.rod_angle = r.number(j, "rod_angle", where);
    m.rod_angle_uncertainty = r.number(j, "rod_angle_uncertainty", where);
    if (m.clamp_offset_uncertainty.minCoeff() < 0 || m.rod_angle_uncertainty < 0) {
      r.fail(where, "uncertainties must be non-negative");
    }
    layout.mounts.push_back(m);
  }
  const int n = layout.num_limbs();
  for (int limb = 0; limb < n; ++limb) {
    for (MountRole role : {MountRole::kProximal, MountRole::kDistal}) {
      int count = 0;
      for (const Mount& m : layout.mounts) count += (m.limb == limb && m.role == role);
      const std::string name = role == MountRole::kProximal ? "proximal" : "distal";
      if (count != 1) {
        r.fail("mounts", "limb " + std::to_string(limb) + " has " + std::to_string(count) + " " +
                             name + " mounts, expected exactly 1");
      }
    }
  }
  return layout;
}

MountLayout load_mounts(const std::string& path, const std::string& family) {
  return parse_mounts(read_input_file(path, kMaxJsonFileBytes, "a mount layout"), path, family);
}

}  // namespace pcr::vision
