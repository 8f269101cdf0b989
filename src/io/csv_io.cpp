#include "pcr/csv_io.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <istream>
#include <optional>
#include <sstream>

namespace pcr {
namespace {

std::string_view trim(std::string_view s) {
  const char* ws = " \t\r\n";
  const std::size_t begin = s.find_first_not_of(ws);
  if (begin == std::string_view::npos) return {};
  return s.substr(begin, s.find_last_not_of(ws) - begin + 1);
}

/// The trimmed comma-separated fields of `line`, into `fields` (reused from line to line).
void split_fields(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  while (true) {
    const std::size_t comma = line.find(',');
    fields.push_back(trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return;
    line.remove_prefix(comma + 1);
  }
}

/// A decimal number consuming the whole field, or nothing. Non-finite values are returned too,
/// so the caller can tell "not a number" from "not finite".
std::optional<double> parse_number(std::string_view field) {
  if (field.empty()) return std::nullopt;
  const char* const end = field.data() + field.size();
  double value = 0.0;
  const std::from_chars_result fast = std::from_chars(field.data(), end, value);
  if (fast.ec == std::errc() && fast.ptr == end) return value;
  // strtod also takes what from_chars refuses: a leading '+', hexadecimal, and values beyond the
  // double range (as inf, or 0 and subnormals), so the accepted syntax is strtod's.
  const std::string copy(field);
  char* copy_end = nullptr;
  value = std::strtod(copy.c_str(), &copy_end);
  if (copy_end != copy.c_str() + copy.size()) return std::nullopt;
  return value;
}

[[noreturn]] void fail(const std::string& source, int line, int column, const std::string& what) {
  std::ostringstream msg;
  msg << source << ":" << line;
  if (column > 0) msg << ":" << column;
  msg << ": " << what;
  throw InputError(msg.str());
}

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

/// The whole stream, read in large blocks (std::cin reads a character at a time otherwise).
std::string read_all(std::istream& in) {
  std::string text;
  char block[1 << 16];
  do {
    in.read(block, sizeof block);
    text.append(block, static_cast<std::size_t>(in.gcount()));
  } while (in);
  return text;
}

}  // namespace

CsvTable parse_csv(std::istream& in, const std::string& source, const CsvReadOptions& options) {
  CsvTable table;
  table.source = source;
  table.columns = options.columns;
  const std::string text = read_all(in);
  if (in.bad()) {
    fail(source, static_cast<int>(std::count(text.begin(), text.end(), '\n')), 0, "read error");
  }
  // Field index in the source line -> position in the numeric row (-1: comment column).
  std::vector<int> mapping;
  std::vector<std::string> header_names;
  std::vector<std::string_view> fields;
  bool first = true;
  int line_number = 0;
  for (std::size_t begin = 0; begin < text.size();) {
    const std::size_t newline = text.find('\n', begin);
    const std::size_t end = newline == std::string::npos ? text.size() : newline;
    const std::string_view line(text.data() + begin, end - begin);
    begin = end + 1;
    ++line_number;
    const std::string_view stripped = trim(line);
    if (stripped.empty() || stripped[0] == '#') continue;
    split_fields(line, fields);
    if (first) {
      first = false;
      bool any_number = false;
      for (std::string_view f : fields) any_number = any_number || parse_number(f).has_value();
      if (!any_number) {
        table.has_header = true;
        header_names.assign(fields.begin(), fields.end());
        std::vector<std::string> numeric;
        for (std::size_t j = 0; j < fields.size(); ++j) {
          if (fields[j].empty()) {
            fail(source, line_number, static_cast<int>(j) + 1, "empty column name in the header");
          }
          if (fields[j][0] != '#') numeric.emplace_back(fields[j]);
        }
        if (options.columns.empty()) {
          table.columns = numeric;
          for (std::string_view f : fields) {
            mapping.push_back(f[0] == '#' ? -1 : 0);
          }
          int k = 0;
          for (int& m : mapping) {
            if (m == 0) m = k++;
          }
        } else {
          mapping.assign(fields.size(), -1);
          for (std::size_t j = 0; j < fields.size(); ++j) {
            if (fields[j][0] == '#') continue;
            int found = -1;
            for (std::size_t k = 0; k < options.columns.size(); ++k) {
              if (options.columns[k] == fields[j]) found = static_cast<int>(k);
            }
            if (found < 0 && options.ignore_other_columns) continue;
            if (found < 0) {
              std::string expected;
              for (const std::string& c : options.columns) {
                expected += (expected.empty() ? "" : ",") + c;
              }
              fail(source, line_number, static_cast<int>(j) + 1,
                   "unexpected column " + quoted(fields[j]) + " (expected columns " + expected +
                       "; prefix a column name with '#' to ignore it)");
            }
            for (std::size_t i = 0; i < j; ++i) {
              if (fields[i] == fields[j]) {
                fail(source, line_number, static_cast<int>(j) + 1,
                     "duplicate column " + quoted(fields[j]));
              }
            }
            mapping[j] = found;
          }
          for (const std::string& c : options.columns) {
            bool present = false;
            for (std::string_view f : fields) present = present || f == c;
            if (!present) {
              fail(source, line_number, 0, "missing column " + quoted(c) + " in the header");
            }
          }
        }
        continue;
      }
      if (options.columns.empty()) {
        for (std::size_t j = 0; j < fields.size(); ++j) {
          table.columns.push_back("column " + std::to_string(j + 1));
        }
      }
      mapping.resize(table.columns.size());
      for (std::size_t j = 0; j < mapping.size(); ++j) mapping[j] = static_cast<int>(j);
    }
    if (fields.size() != mapping.size()) {
      fail(source, line_number, 0,
           "expected " + std::to_string(mapping.size()) + " columns, got " +
               std::to_string(fields.size()));
    }
    const auto field_error = [&](std::size_t j, const char* what) {
      const std::string name = table.has_header ? " (" + header_names[j] + ")" : "";
      return "column " + std::to_string(j + 1) + name + ": " + what + quoted(fields[j]);
    };
    if (table.rows.empty()) {
      // Sized once from the lines left (an upper bound on the rows): no copy as the rows grow.
      // `begin` already points past this line, beyond the text when it has no final newline.
      table.rows = CsvRows(table.columns.size());
      const std::string_view rest = std::string_view(text).substr(std::min(begin, text.size()));
      const std::size_t lines_left =
          1 + static_cast<std::size_t>(std::count(rest.begin(), rest.end(), '\n'));
      table.rows.reserve(lines_left);
      table.line_numbers.reserve(lines_left);
    }
    double* const row = table.rows.append();
    for (std::size_t j = 0; j < fields.size(); ++j) {
      if (mapping[j] < 0) continue;
      const std::optional<double> value = parse_number(fields[j]);
      const int column = static_cast<int>(j) + 1;
      if (!value) {
        fail(source, line_number, column, field_error(j, "expected a number, got "));
      }
      if (!std::isfinite(*value)) {
        fail(source, line_number, column, field_error(j, "non-finite value "));
      }
      row[static_cast<std::size_t>(mapping[j])] = *value;
    }
    table.line_numbers.push_back(line_number);
  }
  return table;
}

CsvTable read_csv(const std::string& path, const CsvReadOptions& options) {
  std::ifstream in = open_input_file(path);
  return parse_csv(in, path, options);
}

char* format_double(double value, char* out) {
  const auto put = [&out](std::string_view text) {
    return out = std::copy(text.begin(), text.end(), out);
  };
  if (std::isnan(value)) return put("nan");
  if (std::isinf(value)) return put(value > 0 ? "inf" : "-inf");
  // The shortest digits that read back to the same bits, as "-d.ddde-XX".
  char text[kMaxFormattedDoubleChars];
  const char* const end =
      std::to_chars(text, text + sizeof text, value, std::chars_format::scientific).ptr;
  const char* const e = std::find(static_cast<const char*>(text), end, 'e');
  int exponent = 0;
  std::from_chars(e + (e[1] == '+' ? 2 : 1), end, exponent);
  const char* const mantissa = text[0] == '-' ? text + 1 : text;
  if (mantissa != text) *out++ = '-';
  char digits[17];
  int count = 0;
  for (const char* p = mantissa; p != e; ++p) {
    if (*p != '.') digits[count++] = *p;
  }
  // Laid out as %.15g lays them out, the precision raised to the digits' count: the text of the
  // first of %.15g, %.16g and %.17g that reads back exactly, as pcr has always written numbers.
  if (exponent < -4 || exponent >= std::max(count, 15)) {
    return put({mantissa, static_cast<std::size_t>(end - mantissa)});
  }
  if (exponent < 0) {
    put("0.");
    out = std::fill_n(out, -exponent - 1, '0');
    return put({digits, static_cast<std::size_t>(count)});
  }
  for (int i = 0; i <= exponent; ++i) *out++ = i < count ? digits[i] : '0';
  if (count > exponent + 1) {
    *out++ = '.';
    put({digits + exponent + 1, static_cast<std::size_t>(count - exponent - 1)});
  }
  return out;
}

std::string format_double(double value) {
  char text[kMaxFormattedDoubleChars];
  return std::string(text, format_double(value, text));
}

std::string csv_line(const std::vector<std::string>& fields) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) out += ',';
    out += fields[i];
  }
  out += '\n';
  return out;
}

namespace {
/// CsvWriter hands its buffer to the stream once it holds this much.
constexpr std::size_t kCsvWriterChunk = std::size_t{1} << 16;
}  // namespace

CsvWriter::CsvWriter(std::ostream& out) : out_(out) { buffer_.reserve(kCsvWriterChunk + 4096); }

CsvWriter::~CsvWriter() { flush(); }

void CsvWriter::separate() {
  if (row_started_) buffer_ += ',';
  row_started_ = true;
}

void CsvWriter::add(double value) {
  separate();
  char text[kMaxFormattedDoubleChars];
  buffer_.append(text, format_double(value, text));
}

void CsvWriter::add(int value) {
  separate();
  char text[16];
  buffer_.append(text, std::to_chars(text, text + sizeof text, value).ptr);
}

void CsvWriter::add(std::string_view text) {
  separate();
  buffer_ += text;
}

void CsvWriter::end_row() {
  buffer_ += '\n';
  row_started_ = false;
  if (buffer_.size() >= kCsvWriterChunk) flush();
}

void CsvWriter::flush() {
  out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  buffer_.clear();
}

}  // namespace pcr
