// The tag board file (pcr/vision/tag_board.hpp), read with pcr::io's JSON reader.
#include <cmath>

#include "json_reader.hpp"
#include "pcr/files.hpp"
#include "pcr/vision/tag_board.hpp"

namespace pcr::vision {

using json_io::Json;
using json_io::JsonReader;

TagBoard parse_tag_board(const std::string& json_text, const std::string& source) {
  const Json root = json_io::parse_json(json_text, source);
  const JsonReader r(source);
  r.check_object(root, "",
                 {"format", "version", "comment", "family", "tag_size", "marker", "tags"});
  if (root.contains("format") && root["format"] != "pcr-tag-board")
    r.fail("format", "expected \"pcr-tag-board\"", root["format"]);
  if (root.contains("version") && root["version"] != 1)
    r.fail("version", "unsupported version (this build reads version 1)", root["version"]);
  const auto text = [&](const Json& object, const std::string& path, const char* key,
                        const std::string& fallback) {
    if (!object.contains(key)) return fallback;
    if (!object[key].is_string())
      r.fail(json_io::join(path, key), "expected a string", object[key]);
    return object[key].get<std::string>();
  };
  const std::string family = text(root, "", "family", kDefaultTagFamily);
  const double size = root.contains("tag_size") ? r.number(root["tag_size"], "tag_size") : 0.0;
  TagBoard board;
  if (root.contains("marker")) board.marker_T_platform = r.frame(root["marker"], "marker");
  const Json& tags = r.required(root, "", "tags");
  if (!tags.is_array() || tags.empty()) r.fail("tags", "expected a non-empty array of tags", tags);
  for (std::size_t i = 0; i < tags.size(); ++i) {
    const std::string path = json_io::index("tags", i);
    const Json& t = tags[i];
    r.check_object(t, path, {"id", "family", "tag_size", "pose", "comment"});
    BoardTag tag;
    tag.family = text(t, path, "family", family);
    const Json& id = r.required(t, path, "id");
    const double value = r.number(id, json_io::join(path, "id"));
    if (!(value >= 0 && value <= 1e6 && value == std::floor(value)))
      r.fail(json_io::join(path, "id"), "expected a tag id (an integer from 0)", id);
    tag.id = static_cast<int>(value);
    if (t.contains("tag_size")) {
      tag.size_m = r.number(t["tag_size"], json_io::join(path, "tag_size"));
    } else if (root.contains("tag_size")) {
      tag.size_m = size;
    } else {
      r.fail(json_io::join(path, "tag_size"), "missing (and no default tag_size at the root)");
    }
    tag.pose =
        board.marker_T_platform * r.frame(r.required(t, path, "pose"), json_io::join(path, "pose"));
    board.tags.push_back(tag);
  }
  check_board(board, source);  // families, ids in their family, sizes, a tag given twice
  return board;
}

TagBoard load_tag_board(const std::string& path) {
  return parse_tag_board(read_input_file(path, kMaxJsonFileBytes, "a tag board"), path);
}

}  // namespace pcr::vision
