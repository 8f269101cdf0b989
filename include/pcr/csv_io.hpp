#pragma once
// Small numeric CSV tables (joint values, poses, calibration datasets).
// Compiled in pcr::io. Format documented in docs/formats.md.
//
// Reading rules:
// - blank lines and lines whose first non-blank character is '#' are skipped;
// - the first remaining line is a header when none of its fields is a number;
// - a column whose header name starts with '#' is a comment column: its values are not parsed;
// - every other field must be a finite decimal number; fields are not quoted.
// Any violation throws InputError naming the source, the line and the column (both 1-based).

#include <cstddef>
#include <fstream>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

#include "pcr/files.hpp"  // OutputFile, open_input_file
#include "pcr/robot_io.hpp"

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
};

struct CsvTable {
  std::string source;  ///< file name, or "<stdin>"
  bool has_header{false};
  std::vector<std::string> columns;       ///< names of the numeric columns (expected or read)
  std::vector<std::vector<double>> rows;  ///< numeric columns only, in `columns` order
  std::vector<int> line_numbers;          ///< 1-based source line of each row
};

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

/// Writes CSV rows to a stream through one buffer, handed over in 64 kB chunks, so that writing a
/// row allocates nothing. Numbers are written as format_double.
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
  /// Writes the buffered rows to the stream.
  void flush();

 private:
  void separate();

  std::ostream& out_;
  std::string buffer_;
  bool row_started_{false};
};

}  // namespace pcr
