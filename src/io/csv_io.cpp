#include "pcr/csv_io.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
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

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n";
  const std::size_t begin = s.find_first_not_of(ws);
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(ws) - begin + 1);
}

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos
                                                                         : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

/// A decimal number consuming the whole field, or nothing. Non-finite values are returned too,
/// so the caller can tell "not a number" from "not finite".
std::optional<double> parse_number(const std::string& field) {
  if (field.empty()) return std::nullopt;
  const char* begin = field.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (end != begin + field.size()) return std::nullopt;
  return value;
}

[[noreturn]] void fail(const std::string& source, int line, int column, const std::string& what) {
  std::ostringstream msg;
  msg << source << ":" << line;
  if (column > 0) msg << ":" << column;
  msg << ": " << what;
  throw InputError(msg.str());
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

CsvTable parse_csv(std::istream& in, const std::string& source, const CsvReadOptions& options) {
  CsvTable table;
  table.source = source;
  table.columns = options.columns;
  // Field index in the source line -> position in the numeric row (-1: comment column).
  std::vector<int> mapping;
  std::vector<std::string> header_names;
  bool first = true;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string stripped = trim(line);
    if (stripped.empty() || stripped[0] == '#') continue;
    const std::vector<std::string> fields = split_fields(line);
    if (first) {
      first = false;
      bool any_number = false;
      for (const std::string& f : fields) any_number = any_number || parse_number(f).has_value();
      if (!any_number) {
        table.has_header = true;
        header_names = fields;
        std::vector<std::string> numeric;
        for (std::size_t j = 0; j < fields.size(); ++j) {
          if (fields[j].empty()) {
            fail(source, line_number, static_cast<int>(j) + 1, "empty column name in the header");
          }
          if (fields[j][0] != '#') numeric.push_back(fields[j]);
        }
        if (options.columns.empty()) {
          table.columns = numeric;
          for (const std::string& f : fields) {
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
            for (const std::string& f : fields) present = present || f == c;
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
    std::vector<double> row(table.columns.size(), 0.0);
    for (std::size_t j = 0; j < fields.size(); ++j) {
      if (mapping[j] < 0) continue;
      const std::string name = table.has_header ? " (" + header_names[j] + ")" : "";
      const std::optional<double> value = parse_number(fields[j]);
      const int column = static_cast<int>(j) + 1;
      if (!value) {
        fail(source, line_number, column,
             "column " + std::to_string(column) + name + ": expected a number, got " +
                 quoted(fields[j]));
      }
      if (!std::isfinite(*value)) {
        fail(source, line_number, column,
             "column " + std::to_string(column) + name + ": non-finite value " + quoted(fields[j]));
      }
      row[static_cast<std::size_t>(mapping[j])] = *value;
    }
    table.rows.push_back(std::move(row));
    table.line_numbers.push_back(line_number);
  }
  if (in.bad()) fail(source, line_number, 0, "read error");
  return table;
}

CsvTable read_csv(const std::string& path, const CsvReadOptions& options) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open for reading: " + std::strerror(errno));
  return parse_csv(in, path, options);
}

std::string format_double(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  for (int precision = 15; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  return buffer;
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

OutputFile::OutputFile(const std::string& path) : path_(path) {
  if (path.empty() || path == "-") {
    to_stdout_ = true;
    return;
  }
  // mkstemp gives a unique name in the target's directory, so rename() stays on one filesystem.
  std::string pattern = path + ".tmp-XXXXXX";
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    throw std::runtime_error(path + ": cannot create a temporary file: " + std::strerror(errno));
  }
  // mkstemp creates the file 0600; give it the permissions a plain open() would have.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  ::close(fd);
  temp_path_ = name.data();
  file_.open(temp_path_, std::ios::out | std::ios::trunc);
  if (!file_) {
    std::remove(temp_path_.c_str());
    throw std::runtime_error(path + ": cannot open " + temp_path_ + " for writing");
  }
}

OutputFile::~OutputFile() {
  if (!to_stdout_ && !committed_) {
    file_.close();
    std::remove(temp_path_.c_str());
  }
}

std::ostream& OutputFile::stream() { return to_stdout_ ? std::cout : file_; }

void OutputFile::commit() {
  if (committed_) return;
  if (to_stdout_) {
    std::cout.flush();
    committed_ = true;
    return;
  }
  file_.flush();
  file_.close();
  if (file_.fail()) throw std::runtime_error(path_ + ": write error on " + temp_path_);
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error(path_ + ": cannot rename " + temp_path_ + ": " + std::strerror(errno));
  }
  committed_ = true;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  if (path.empty()) throw std::invalid_argument("write_file_atomically: empty path");
  OutputFile out(path);
  out.stream() << text;
  out.commit();
}

}  // namespace pcr
