#include "pcr/csv_io.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <istream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

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
  // double range (as inf, or 0 and subnormals). A hexadecimal field counts as a number here (a
  // line of them is data, not a header); the reader then refuses it as not decimal.
  const std::string copy(field);
  char* copy_end = nullptr;
  value = std::strtod(copy.c_str(), &copy_end);
  if (copy_end != copy.c_str() + copy.size()) return std::nullopt;
  return value;
}

/// A number strtod reads that is not decimal: hexadecimal ("0x1p-8", "-0X1.8P1").
bool is_hexadecimal(std::string_view field) {
  if (!field.empty() && (field[0] == '+' || field[0] == '-')) field.remove_prefix(1);
  return field.size() > 1 && field[0] == '0' && (field[1] == 'x' || field[1] == 'X');
}

[[noreturn]] void fail(const std::string& source, int line, int column, const std::string& what) {
  std::ostringstream msg;
  msg << source << ":" << line;
  if (column > 0) msg << ":" << column;
  msg << ": " << what;
  throw InputError(msg.str());
}

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

}  // namespace

std::string read_table_text(std::istream& in, const std::string& source) {
  std::string text;
  char block[1 << 16];         // large blocks: std::cin reads a character at a time otherwise
  std::size_t line_start = 0;  // of the line being read
  int lines = 1;
  do {
    in.read(block, sizeof block);
    const std::size_t before = text.size();
    text.append(block, static_cast<std::size_t>(in.gcount()));
    for (std::size_t newline = text.find('\n', before); newline != std::string::npos;
         newline = text.find('\n', newline + 1)) {
      line_start = newline + 1;
      ++lines;
    }
    if (text.size() - line_start > kMaxCsvLineBytes) {
      fail(source, lines, 0,
           "a line longer than " + std::to_string(kMaxCsvLineBytes >> 20) +
               " MiB, the limit of a CSV line: not a table (an endless input such as /dev/zero?)");
    }
    if (text.size() > kMaxCsvBytes) {
      fail(source, lines, 0,
           "more than " + std::to_string(kMaxCsvBytes >> 20) + " MiB, the limit of a CSV table");
    }
  } while (in);
  if (in.bad()) fail(source, lines, 0, "read error");
  return text;
}

CsvTable parse_csv(std::istream& in, const std::string& source, const CsvReadOptions& options) {
  CsvTable table;
  table.source = source;
  table.columns = options.columns;
  const std::string text = read_table_text(in, source);
  // Field index in the source line -> position in the numeric row (-1: comment column; -2 - k:
  // text column k).
  std::vector<int> mapping;
  const auto text_column = [&](std::string_view name) {
    const auto& t = options.text_columns;
    const auto found = std::find(t.begin(), t.end(), name);
    return found == t.end() ? -1 : static_cast<int>(found - t.begin());
  };
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
          if (fields[j][0] != '#' && text_column(fields[j]) < 0) numeric.emplace_back(fields[j]);
        }
        for (const std::string& c : options.text_columns) {
          if (std::find(fields.begin(), fields.end(), c) == fields.end()) {
            fail(source, line_number, 0, "missing column " + quoted(c) + " in the header");
          }
        }
        if (options.columns.empty()) {
          table.columns = numeric;
          for (std::string_view f : fields) {
            mapping.push_back(f[0] == '#' ? -1 : text_column(f) >= 0 ? -2 - text_column(f) : 0);
          }
          int k = 0;
          for (int& m : mapping) {
            if (m == 0) m = k++;
          }
        } else {
          mapping.assign(fields.size(), -1);
          for (std::size_t j = 0; j < fields.size(); ++j) {
            if (fields[j][0] == '#') continue;
            if (text_column(fields[j]) >= 0) {
              mapping[j] = -2 - text_column(fields[j]);
              continue;
            }
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
      if (!options.text_columns.empty()) {
        fail(source, line_number, 0,
             "expected a header line naming the columns (a text column such as " +
                 quoted(options.text_columns.front()) + " among them)");
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
    if (!options.text_columns.empty()) table.texts.emplace_back(options.text_columns.size());
    for (std::size_t j = 0; j < fields.size(); ++j) {
      if (mapping[j] <= -2) {
        const std::string_view text = trim(fields[j]);
        if (text.empty()) {
          fail(source, line_number, static_cast<int>(j) + 1,
               "column " + std::to_string(j + 1) + " (" + header_names[j] + "): empty field");
        }
        table.texts.back()[static_cast<std::size_t>(-2 - mapping[j])] = std::string(text);
        continue;
      }
      if (mapping[j] < 0) continue;
      const std::optional<double> value = parse_number(fields[j]);
      const int column = static_cast<int>(j) + 1;
      if (!value) {
        fail(source, line_number, column, field_error(j, "expected a number, got "));
      }
      if (is_hexadecimal(fields[j])) {
        fail(source, line_number, column,
             field_error(j, "expected a decimal number, got the hexadecimal "));
      }
      if (!std::isfinite(*value)) {
        fail(source, line_number, column, field_error(j, "non-finite value "));
      }
      row[static_cast<std::size_t>(mapping[j])] = *value;
    }
    table.line_numbers.push_back(line_number);
  }
  table.source_columns.assign(table.columns.size(), 0);
  for (std::size_t j = 0; j < mapping.size(); ++j) {
    if (mapping[j] >= 0 && static_cast<std::size_t>(mapping[j]) < table.source_columns.size()) {
      table.source_columns[static_cast<std::size_t>(mapping[j])] = static_cast<int>(j) + 1;
    }
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
/// The formatted text goes to the stream in chunks of this size.
constexpr std::size_t kCsvWriterChunk = std::size_t{1} << 16;
/// A batch is handed to the second thread at the end of the row that fills this many fields
/// (about 400 rows of pcr fk: a few hundred microseconds of solving).
constexpr std::size_t kBatchFields = 4096;
}  // namespace

/// The fields of some rows, as added.
struct CsvWriter::Batch {
  enum class Kind : unsigned char { kNumber, kInteger, kText, kEndRow };
  struct Field {
    double number;                 ///< kNumber
    std::uint32_t begin;           ///< kText: in `texts`
    std::int32_t size_or_integer;  ///< kText: its size; kInteger: the value
    Kind kind;
  };
  std::vector<Field> fields;
  std::string texts;

  Batch() {
    fields.reserve(kBatchFields + 256);
    texts.reserve(kBatchFields * 4);
  }
  void clear() {
    fields.clear();
    texts.clear();
  }
};

/// Formats batches and writes the text to the stream: on the caller's thread while the rows fit
/// in one batch (a small output starts no thread), then on its own thread, which takes the handed
/// batches in order and gives them back empty.
class CsvWriter::Formatter {
 public:
  explicit Formatter(std::ostream& out) : out_(out) {
    text_.reserve(kCsvWriterChunk + 4096);
    free_.reserve(2);
    free_.push_back(std::make_unique<Batch>());
    free_.push_back(std::make_unique<Batch>());
  }
  ~Formatter() {
    if (!thread_.joinable()) return;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }

  /// Takes `batch` to format on the second thread (started now if it was not) and puts an empty
  /// batch in its place.
  void hand_over(std::unique_ptr<Batch>& batch) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
    changed_.wait(lock, [this] { return handed_ == nullptr && !free_.empty(); });
    handed_ = std::move(batch);
    batch = std::move(free_.back());
    free_.pop_back();
    lock.unlock();
    changed_.notify_all();
  }

  /// Formats `batch` (emptied) and every batch handed over before it, and writes all the text.
  void flush(Batch& batch) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return handed_ == nullptr && !busy_; });
    if (failure_) std::rethrow_exception(std::exchange(failure_, nullptr));
    format(batch);  // the thread, if any, is idle: the caller formats the rest
    batch.clear();
    write();
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      changed_.wait(lock, [this] { return handed_ != nullptr || stop_; });
      if (handed_ == nullptr) return;
      std::unique_ptr<Batch> batch = std::move(handed_);
      busy_ = true;
      lock.unlock();
      changed_.notify_all();  // the slot is free
      try {
        format(*batch);
      } catch (...) {  // a stream that throws: reported by the next flush
        lock.lock();
        failure_ = std::current_exception();
        lock.unlock();
      }
      batch->clear();
      lock.lock();
      free_.push_back(std::move(batch));
      busy_ = false;
      changed_.notify_all();
    }
  }

  void format(const Batch& batch) {
    char number[kMaxFormattedDoubleChars];
    for (const Batch::Field& field : batch.fields) {
      if (field.kind == Batch::Kind::kEndRow) {
        text_ += '\n';
        row_started_ = false;
        if (text_.size() >= kCsvWriterChunk) write();
        continue;
      }
      if (row_started_) text_ += ',';
      row_started_ = true;
      switch (field.kind) {
        case Batch::Kind::kNumber:
          text_.append(number, format_double(field.number, number));
          break;
        case Batch::Kind::kInteger:
          text_.append(number,
                       std::to_chars(number, number + sizeof number, field.size_or_integer).ptr);
          break;
        default:
          text_.append(batch.texts, field.begin, static_cast<std::size_t>(field.size_or_integer));
      }
    }
  }

  void write() {
    out_.write(text_.data(), static_cast<std::streamsize>(text_.size()));
    text_.clear();
  }

  std::ostream& out_;
  std::string text_;          ///< formatted, not yet written
  bool row_started_ = false;  ///< text_ ends inside a row
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  // Under mutex_: the batch handed over and not yet taken, the empty ones, whether the thread is
  // formatting one, and what it threw.
  std::unique_ptr<Batch> handed_;
  std::vector<std::unique_ptr<Batch>> free_;
  bool busy_ = false;
  bool stop_ = false;
  std::exception_ptr failure_;
};

CsvWriter::CsvWriter(std::ostream& out)
    : batch_(std::make_unique<Batch>()), formatter_(std::make_unique<Formatter>(out)) {}

CsvWriter::~CsvWriter() {
  try {
    flush();
  } catch (...) {  // the stream's state reports a write error to whoever checks it
  }
}

void CsvWriter::add(double value) { batch_->fields.push_back({value, 0, 0, Batch::Kind::kNumber}); }

void CsvWriter::add(int value) { batch_->fields.push_back({0.0, 0, value, Batch::Kind::kInteger}); }

void CsvWriter::add(std::string_view text) {
  const std::size_t begin = batch_->texts.size();
  batch_->texts += text;
  batch_->fields.push_back({0.0, static_cast<std::uint32_t>(begin),
                            static_cast<std::int32_t>(text.size()), Batch::Kind::kText});
}

void CsvWriter::end_row() {
  batch_->fields.push_back({0.0, 0, 0, Batch::Kind::kEndRow});
  if (batch_->fields.size() >= kBatchFields) formatter_->hand_over(batch_);
}

void CsvWriter::flush() { formatter_->flush(*batch_); }

}  // namespace pcr
