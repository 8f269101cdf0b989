// The attachment layout file (pcr/vision/attachment_points.hpp), read with pcr::io's JSON reader
// and the tag board file's conventions (file-wide family and tag_size defaults, "comment" fields).
#include <map>
#include <utility>

#include "json_reader.hpp"
#include "pcr/files.hpp"
#include "pcr/vision/attachment_points.hpp"
#include "tag_file_fields.hpp"

namespace pcr::vision {

using json_io::Json;
using json_io::JsonReader;

AttachmentLayout parse_attachment_layout(const std::string& json_text, const std::string& source,
                                         const std::string& family) {
  const Json root = json_io::parse_json(json_text, source);
  const JsonReader r(source);
  r.check_object(root, "", {"format", "version", "comment", "family", "tag_size", "rods"});
  const tag_file::TagDefaults defaults = tag_file::header(r, root, "pcr-attachment-points", family);
  const auto check_size = [&](const Json& object, const std::string& path, double size) {
    if (!(size > 0 && size < 10)) r.fail(path, "expected a tag size in (0, 10) m", object);
  };
  if (defaults.size) check_size(root["tag_size"], "tag_size", *defaults.size);
  const Json& rods = r.required(root, "", "rods");
  if (!rods.is_array() || rods.empty())
    r.fail("rods", "expected a non-empty array (one object per rod)", rods);
  AttachmentLayout layout;
  layout.source = source;
  std::map<std::pair<std::string, int>, std::string> seen;  // family and id -> its field
  const auto point = [&](const Json& object, const std::string& path, const std::string& name) {
    r.check_object(object, path,
                   {"id", "family", "tag_size", "offset", "offset_uncertainty", "comment"});
    TagPoint p;
    p.name = name;
    p.tag = tag_file::tag(r, object, path, defaults);
    if (!is_known_family(p.tag.family)) {
      r.fail(object.contains("family") ? json_io::join(path, "family")
             : root.contains("family") ? std::string("family")
                                       : json_io::join(path, "id"),
             "unknown tag family '" + p.tag.family + "' (known: " + known_families() + ")");
    }
    const std::string id_path = json_io::join(path, "id");
    try {
      int total = 0, border = 0;
      tag_bitmap(p.tag.family, p.tag.id, &total, &border);
    } catch (const InputError& e) {
      r.fail(id_path, e.what(), object["id"]);
    }
    const auto [at, inserted] = seen.emplace(std::make_pair(p.tag.family, p.tag.id), id_path);
    if (!inserted) {
      r.fail(id_path,
             p.tag.family + " id " + std::to_string(p.tag.id) + " is given twice (also " +
                 at->second + "): each point needs a tag of its own",
             object["id"]);
    }
    if (object.contains("tag_size"))
      check_size(object["tag_size"], json_io::join(path, "tag_size"), p.tag.size_m);
    p.offset = r.point(r.required(object, path, "offset"), json_io::join(path, "offset"));
    if (object.contains("offset_uncertainty")) {
      p.offset_uncertainty = r.half_widths<3>(
          object["offset_uncertainty"], json_io::join(path, "offset_uncertainty"), 1e-12, 0.1, "m");
    }
    return p;
  };
  for (std::size_t i = 0; i < rods.size(); ++i) {
    const std::string path = json_io::index("rods", i);
    r.check_object(rods[i], path, {"A", "B", "comment"});
    const std::string rod = std::to_string(i + 1);
    layout.holes.push_back(
        point(r.required(rods[i], path, "A"), json_io::join(path, "A"), "A" + rod));
    layout.attachments.push_back(
        point(r.required(rods[i], path, "B"), json_io::join(path, "B"), "B" + rod));
  }
  return layout;
}

AttachmentLayout load_attachment_layout(const std::string& path, const std::string& family) {
  return parse_attachment_layout(read_input_file(path, kMaxJsonFileBytes, "an attachment layout"),
                                 path, family);
}

}  // namespace pcr::vision
