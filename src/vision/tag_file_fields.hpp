#pragma once
// What the vision JSON files that list tags share (the tag board file, the attachment layout
// file; internal): their header ("format", "version" 1) and each tag's "family", "id" and
// "tag_size" with the file-wide defaults of the root, every error naming the file and the field.
#include <cmath>
#include <optional>
#include <string>

#include "json_reader.hpp"
#include "pcr/vision/tag_board.hpp"

namespace pcr::vision::tag_file {

/// The root's defaults for its tags.
struct TagDefaults {
  std::string family;
  std::optional<double> size;  ///< m; none: every tag gives its own
};

/// A string field, `fallback` when absent.
inline std::string text(const json_io::JsonReader& r, const json_io::Json& object,
                        const std::string& path, const char* key, const std::string& fallback) {
  if (!object.contains(key)) return fallback;
  if (!object[key].is_string()) r.fail(json_io::join(path, key), "expected a string", object[key]);
  return object[key].get<std::string>();
}

/// Checks the root's "format" (when given: `format`) and "version" (when given: 1) and reads its
/// "family" (default `family`) and "tag_size".
inline TagDefaults header(const json_io::JsonReader& r, const json_io::Json& root,
                          const char* format, const std::string& family) {
  if (root.contains("format") && root["format"] != format)
    r.fail("format", std::string("expected \"") + format + "\"", root["format"]);
  if (root.contains("version") && root["version"] != 1)
    r.fail("version", "unsupported version (this build reads version 1)", root["version"]);
  TagDefaults out{text(r, root, "", "family", family), std::nullopt};
  if (root.contains("tag_size")) out.size = r.number(root["tag_size"], "tag_size");
  return out;
}

/// The family, id and size of the tag `object` at `path` (its pose left as is).
inline BoardTag tag(const json_io::JsonReader& r, const json_io::Json& object,
                    const std::string& path, const TagDefaults& defaults) {
  BoardTag tag;
  tag.family = text(r, object, path, "family", defaults.family);
  const json_io::Json& id = r.required(object, path, "id");
  const double value = r.number(id, json_io::join(path, "id"));
  if (!(value >= 0 && value <= 1e6 && value == std::floor(value)))
    r.fail(json_io::join(path, "id"), "expected a tag id (an integer from 0)", id);
  tag.id = static_cast<int>(value);
  if (object.contains("tag_size")) {
    tag.size_m = r.number(object["tag_size"], json_io::join(path, "tag_size"));
  } else if (defaults.size) {
    tag.size_m = *defaults.size;
  } else {
    r.fail(json_io::join(path, "tag_size"), "missing (and no default tag_size at the root)");
  }
  return tag;
}

}  // namespace pcr::vision::tag_file
