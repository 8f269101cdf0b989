// The tag board file (pcr/vision/tag_board.hpp), read with pcr::io's JSON reader.
#include "json_reader.hpp"
#include "pcr/files.hpp"
#include "pcr/vision/tag_board.hpp"
#include "tag_file_fields.hpp"

namespace pcr::vision {

using json_io::Json;
using json_io::JsonReader;

TagBoard parse_tag_board(const std::string& json_text, const std::string& source) {
  const Json root = json_io::parse_json(json_text, source);
  const JsonReader r(source);
  r.check_object(root, "",
                 {"format", "version", "comment", "family", "tag_size", "marker", "tags"});
  const tag_file::TagDefaults defaults =
      tag_file::header(r, root, "pcr-tag-board", kDefaultTagFamily);
  TagBoard board;
  if (root.contains("marker")) board.marker_T_platform = r.frame(root["marker"], "marker");
  const Json& tags = r.required(root, "", "tags");
  if (!tags.is_array() || tags.empty()) r.fail("tags", "expected a non-empty array of tags", tags);
  for (std::size_t i = 0; i < tags.size(); ++i) {
    const std::string path = json_io::index("tags", i);
    const Json& t = tags[i];
    r.check_object(t, path, {"id", "family", "tag_size", "pose", "comment"});
    BoardTag tag = tag_file::tag(r, t, path, defaults);
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
