#include "json_reader.hpp"

#include <cctype>
#include <cstring>
#include <set>
#include <vector>

#include "pcr/csv_io.hpp"
#include "pcr/robot_io.hpp"

namespace pcr::json_io {

namespace {

// nlohmann refuses numbers that overflow a double (1e999) without saying where they are. The
// parse is retried with such a literal replaced by this marker string, so that validation reports
// it with its field path like any other non-finite number.
const std::string kOverflowMarker = std::string(1, '\x01') + "pcr-overflow:";

}  // namespace

bool is_overflow(const Json& value) {
  return value.is_string() && value.get_ref<const std::string&>().rfind(kOverflowMarker, 0) == 0;
}

std::string show(const Json& value) {
  if (is_overflow(value)) return value.get<std::string>().substr(kOverflowMarker.size());
  if (value.is_number_float()) return format_double(value.get<double>());
  return excerpt(value.dump());
}

namespace {

/// 1-based line and column of a byte offset in `text`.
std::pair<int, int> line_column(const std::string& text, std::size_t offset) {
  int line = 1, column = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

/// Offset of `token` in `text` standing alone as a number literal, or npos.
std::size_t find_number_literal(const std::string& text, const std::string& token) {
  auto part_of_number = [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == 'e' || c == 'E' ||
           c == '+' || c == '-';
  };
  for (std::size_t at = text.find(token); at != std::string::npos; at = text.find(token, at + 1)) {
    std::size_t before = at;
    while (before > 0 && std::isspace(static_cast<unsigned char>(text[before - 1]))) --before;
    const bool left = before > 0 && (text[before - 1] == ':' || text[before - 1] == ',' ||
                                     text[before - 1] == '[');
    const std::size_t after = at + token.size();
    const bool right = after >= text.size() || !part_of_number(text[after]);
    if (left && right) return at;
  }
  return std::string::npos;
}

}  // namespace

Json parse_json(const std::string& json_text, const std::string& source) {
  check_json_nesting(json_text, source);
  // Duplicate keys would otherwise silently keep the last value: reject them while parsing.
  std::vector<std::set<std::string>> keys;
  const Json::parser_callback_t check_duplicates = [&](int, Json::parse_event_t event,
                                                       Json& parsed) {
    if (event == Json::parse_event_t::object_start) keys.emplace_back();
    if (event == Json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
    if (event == Json::parse_event_t::key && !keys.empty()) {
      const std::string key = parsed.get<std::string>();
      if (!keys.back().insert(key).second) {
        throw InputError(source + ": duplicate field \"" + key + "\"");
      }
    }
    return true;
  };
  Json root;
  std::string text = json_text;
  try {
    for (int attempt = 0;; ++attempt) {
      try {
        keys.clear();
        root = Json::parse(text, check_duplicates);
        break;
      } catch (const Json::out_of_range& e) {
        // 406: a number literal overflows a double. Mark it and parse again (see kOverflowMarker).
        const std::string what = e.what();
        const std::size_t begin = what.find("parsing '");
        const std::size_t end = what.rfind('\'');
        if (e.id != 406 || begin == std::string::npos || end <= begin + 9 || attempt > 1000) throw;
        const std::string token = what.substr(begin + 9, end - begin - 9);
        const std::size_t at = find_number_literal(text, token);
        if (at == std::string::npos) throw;
        text.replace(at, token.size(), Json(kOverflowMarker + token).dump());
      }
    }
  } catch (const Json::out_of_range& e) {
    throw InputError(source + ": " + e.what());
  } catch (const Json::parse_error& e) {
    const std::size_t offset = e.byte > 0 ? e.byte - 1 : 0;
    const auto [line, column] = line_column(text, offset);
    std::string what = e.what();
    const std::size_t colon = what.find(": ");  // drop nlohmann's "[json.exception...] at ...:"
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw InputError(source + ":" + std::to_string(line) + ":" + std::to_string(column) +
                     ": JSON syntax error: " + what);
  }
  return root;
}

// ---- JsonReader ----

void JsonReader::fail(const std::string& path, const std::string& what) const {
  throw InputError(source_ + ": " + (path.empty() ? "" : path + ": ") + what);
}
void JsonReader::fail(const std::string& path, const std::string& what, const Json& value) const {
  fail(path, what + ", got " + show(value));
}

void JsonReader::check_object(const Json& object, const std::string& path,
                              std::initializer_list<const char*> allowed) const {
  if (!object.is_object()) fail(path.empty() ? "<root>" : path, "expected an object", object);
  for (auto it = object.begin(); it != object.end(); ++it) {
    bool known = false;
    for (const char* name : allowed) known = known || it.key() == name;
    if (!known) {
      std::string names;
      for (const char* name : allowed) names += (names.empty() ? "" : ", ") + std::string(name);
      fail(join(path, it.key()), "unknown field (allowed here: " + names + ")");
    }
  }
}

const Json& JsonReader::required(const Json& object, const std::string& path,
                                 const char* key) const {
  const auto it = object.find(key);
  if (it == object.end()) fail(join(path, key), "missing required field");
  return *it;
}

double JsonReader::number(const Json& value, const std::string& path) const {
  if (is_overflow(value)) {
    fail(path, "expected a finite number (this one overflows a double)", value);
  }
  if (!value.is_number()) fail(path, "expected a number", value);
  const double x = value.get<double>();
  if (!std::isfinite(x)) fail(path, "expected a finite number", value);
  return x;
}

double JsonReader::in_range(const Json& value, const std::string& path, double lo, double hi,
                            const char* unit) const {
  const double x = number(value, path);
  if (!(x >= lo && x <= hi)) {
    fail(path,
         std::string("outside its physical range [") + format_double(lo) + ", " +
             format_double(hi) + "] " + unit,
         value);
  }
  return x;
}

double JsonReader::half_width(const Json& value, const std::string& path, double min, double max,
                              const char* unit) const {
  const double x = number(value, path);
  if (x == 0.0) return x;
  if (!(x >= min && x <= max)) {
    fail(path,
         std::string("a half-width must be 0 or in [") + format_double(min) + ", " +
             format_double(max) + "] " + unit,
         value);
  }
  return x;
}

RobotKind robot_kind(const JsonReader& reader, const Json& root) {
  if (!root.is_object() || !root.contains("kind")) return RobotKind::kPlanar;
  const Json& kind = root["kind"];
  if (kind == "planar") return RobotKind::kPlanar;
  if (kind == "spatial") return RobotKind::kSpatial;
  reader.fail("kind", "expected \"planar\" or \"spatial\"", kind);
}

void require_kind(const JsonReader& reader, const Json& root, RobotKind kind) {
  const RobotKind found = robot_kind(reader, root);
  if (found == kind) return;
  const bool planar = kind == RobotKind::kPlanar;
  reader.fail("kind",
              std::string("this command takes a ") + (planar ? "planar" : "spatial") +
                  " robot file (kind \"" + (planar ? "planar" : "spatial") + "\"" +
                  (planar ? ", or no kind" : "") + "), not a " + (planar ? "spatial" : "planar") +
                  " one",
              root.contains("kind") ? root["kind"] : Json("planar (no kind field)"));
}

// ---- writing ----

void print(const Ordered& value, int indent, std::ostringstream& out) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  if (value.is_object()) {
    if (value.empty()) {
      out << "{}";
      return;
    }
    out << "{\n";
    std::size_t k = 0;
    for (auto it = value.begin(); it != value.end(); ++it, ++k) {
      out << pad << "  " << Ordered(it.key()).dump() << ": ";
      print(*it, indent + 2, out);
      out << (k + 1 < value.size() ? ",\n" : "\n");
    }
    out << pad << "}";
  } else if (value.is_array()) {
    bool flat = true;
    for (const Ordered& v : value) flat = flat && v.is_primitive();
    if (flat) {
      out << "[";
      for (std::size_t i = 0; i < value.size(); ++i) out << (i ? ", " : "") << value[i].dump();
      out << "]";
      return;
    }
    out << "[\n";
    for (std::size_t i = 0; i < value.size(); ++i) {
      out << pad << "  ";
      print(value[i], indent + 2, out);
      out << (i + 1 < value.size() ? ",\n" : "\n");
    }
    out << pad << "]";
  } else {
    out << value.dump();
  }
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

}  // namespace pcr::json_io
