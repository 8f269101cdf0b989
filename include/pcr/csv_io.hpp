#pragma once
// Small numeric CSV tables (joint values, poses, calibration datasets).
// Compiled in pcr::io. Format documented in docs/formats.md.
//
// Reading rules:
// - blank lines and lines whose first non-blank character is '#' are skipped;
// - the first remaining line is a header when none of its fields is a number;
// - a column whose header name starts with '#' is a comment column: its values are not parsed;
// - every other field must be a finite decimal number (not "nan", "inf", "1e999" nor a
//   hexadecimal float such as "0x1p-8"); fields are not quoted.
// Any violation throws InputError naming the source, the line and the column (both 1-based).

#include <algorithm>
#include <cstddef>
#include <fstream>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "pcr/files.hpp"  // OutputFile, open_input_file
#include "pcr/input_error.hpp"
#include "pcr/robot_description.hpp"

namespace pcr {

struct CsvReadOptions {
  /// The expected column names, in order. Without a header line, every row must have exactly
  /// this many fields (comment columns can only be declared by a header). With a header line,
  /// columns are picked by name and every other column must be a '#' comment column.
  /// Empty: the columns are whatever the header says, or the first row's count without a header.
  std::vector<std::string> columns;
  /// With a header line and expected columns: skip (do not parse) columns not in `columns`
  /// instead of rejecting them. For reading tables written by other tools (e.g. `pcr fk` output).
  bool ignore_other_columns{false};
  /// Columns kept as text, not parsed (a file name per row), picked by their header name: the
  /// header is then required and must name each of them; an empty field is an error.
  std::vector<std::string> text_columns;
};

/// One row of a CsvTable: a view of its numeric fields, valid while the table lives.
class CsvRow {
 public:
  CsvRow(const double* values, std::size_t size) : values_(values), size_(size) {}
  std::size_t size() const { return size_; }
  const double& operator[](std::size_t column) const { return values_[column]; }
  const double* data() const { return values_; }
  const double* begin() const { return values_; }
  const double* end() const { return values_ + size_; }
  friend bool operator==(const CsvRow& row, const std::vector<double>& values) {
    return std::equal(row.begin(), row.end(), values.begin(), values.end());
  }

 private:
  const double* values_;
  std::size_t size_;
};

/// The rows of a CsvTable, stored one after another in one array, so that reading a row
/// allocates nothing once the array has grown.
class CsvRows {
 public:
  class Iterator {
   public:
    Iterator(const CsvRows& rows, std::size_t index) : rows_(&rows), index_(index) {}
    CsvRow operator*() const { return (*rows_)[index_]; }
    Iterator& operator++() {
      ++index_;
      return *this;
    }
    bool operator!=(const Iterator& other) const { return index_ != other.index_; }

   private:
    const CsvRows* rows_;
    std::size_t index_;
  };

  explicit CsvRows(std::size_t width = 0) : width_(width) {}
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  CsvRow operator[](std::size_t row) const { return {values_.data() + row * width_, width_}; }
  Iterator begin() const { return {*this, 0}; }
  Iterator end() const { return {*this, size_}; }
  bool operator==(const CsvRows& other) const {
    return width_ == other.width_ && size_ == other.size_ && values_ == other.values_;
  }

  /// Room for `rows` rows in all, so that appending them copies nothing.
  void reserve(std::size_t rows) { values_.reserve(rows * width_); }
  /// A new last row of zeros, for the reader to fill.
  double* append() {
    values_.resize(values_.size() + width_, 0.0);
    ++size_;
    return values_.data() + values_.size() - width_;
  }

 private:
  std::size_t width_;
  std::size_t size_{0};
  std::vector<double> values_;
};

struct CsvTable {
  std::string source;  ///< file name, or "<stdin>"
  bool has_header{false};
  std::vector<std::string> columns;  ///< names of the numeric columns (expected or read)
  CsvRows rows;                      ///< numeric columns only, in `columns` order
  /// Per row, the fields of CsvReadOptions::text_columns in their order.
  std::vector<std::vector<std::string>> texts;
  std::vector<int> line_numbers;  ///< 1-based source line of each row
  /// 1-based field of each of `columns` in the source's lines (a header may reorder them), for
  /// messages naming a value's line and column; 0 for a column the source did not have.
  std::vector<int> source_columns;
};

/// The size limits of a table (docs/formats.md): a larger input, or a line longer than a line of
/// numbers can be (an endless input such as /dev/zero has no newline), is an InputError naming the
/// source, read no further than the limit.
inline constexpr std::size_t kMaxCsvBytes = std::size_t{1} << 30;
inline constexpr std::size_t kMaxCsvLineBytes = std::size_t{1} << 20;

/// The whole text of a table from `in`, within the limits above (InputError naming `source`).
std::string read_table_text(std::istream& in, const std::string& source);

/// Parses CSV text; `source` names it in error messages.
CsvTable parse_csv(std::istream& in, const std::string& source,
                   const CsvReadOptions& options = CsvReadOptions());
/// Reads a CSV file (InputError naming the file when it cannot be opened).
CsvTable read_csv(const std::string& path, const CsvReadOptions& options = CsvReadOptions());

/// Shortest decimal form that reads back to the same double (at most 17 significant digits),
/// laid out as printf's %.15g would ("0.0001", "69000000000", "1e-05", "1.2345678901234568e+17");
/// "nan", "inf", "-inf" for non-finite values.
std::string format_double(double value);

/// The longest text of format_double: "-2.2250738585072014e-308".
inline constexpr std::size_t kMaxFormattedDoubleChars = 24;
/// format_double into `out` (room for kMaxFormattedDoubleChars); returns the end of the text.
char* format_double(double value, char* out);

/// Joins fields with commas and a trailing newline.
std::string csv_line(const std::vector<std::string>& fields);

/// Writes CSV rows to a stream; numbers are written as format_double. The fields are recorded as
/// they are added and formatted later: once a few hundred rows are waiting, a second thread formats
/// and writes them while the caller computes the next ones (formatting 8 numbers costs about a
/// fifth of a warm FK solve). Nothing is allocated per row: the rows go through three recycled
/// batches, the text through one buffer handed to the stream in 64 kB chunks. Only flush() (and the
/// destructor) guarantees that the rows added so far have reached the stream; until then the
/// stream belongs to the writer.
class CsvWriter {
 public:
  explicit CsvWriter(std::ostream& out);
  /// Flushes.
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  void add(double value);
  void add(int value);
  void add(std::string_view text);
  /// Ends the row (a newline); the next add starts a new one.
  void end_row();
  /// Writes every row added so far to the stream (waiting for the second thread, if any).
  void flush();

 private:
  struct Batch;
  class Formatter;
  std::unique_ptr<Batch> batch_;  ///< the rows being added
  std::unique_ptr<Formatter> formatter_;
};

}  // namespace pcr
