// Numeric CSV tables: header detection, comment columns, selection by name, and error messages
// that name the source, the line and the column.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <streambuf>

#include "allocation_counter.hpp"
#include "pcr/csv_io.hpp"
#include "scratch_directory.hpp"

namespace {

pcr::CsvTable parse(const std::string& text, const std::vector<std::string>& columns = {}) {
  std::istringstream in(text);
  pcr::CsvReadOptions options;
  options.columns = columns;
  return pcr::parse_csv(in, "data.csv", options);
}

/// The InputError message of parsing `text`, or "" when it parses.
std::string error_of(const std::string& text, const std::vector<std::string>& columns = {}) {
  try {
    parse(text, columns);
  } catch (const pcr::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CsvIo, ReadsRowsWithoutHeader) {
  const pcr::CsvTable t = parse("1,2.5,-3e-3\n\n 4 , 5,6\n", {"a", "b", "c"});
  EXPECT_FALSE(t.has_header);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0], (std::vector<double>{1, 2.5, -3e-3}));
  EXPECT_EQ(t.rows[1], (std::vector<double>{4, 5, 6}));
  EXPECT_EQ(t.line_numbers, (std::vector<int>{1, 3}));
}

// The first data row is the last line, without its newline: the rows are sized from the text
// after it, which is empty (the sanitizer build checks that nothing beyond the text is read).
TEST(CsvIo, ReadsAFirstRowWithoutNewline) {
  for (const char* text : {"1,2", "a,b\n1,2", "# comment\na,b\r\n1,2"}) {
    const pcr::CsvTable t = parse(text);
    ASSERT_EQ(t.rows.size(), 1u) << text;
    EXPECT_EQ(t.rows[0], (std::vector<double>{1, 2})) << text;
  }
}

TEST(CsvIo, HeaderSelectsColumnsByNameAndSkipsCommentColumns) {
  const pcr::CsvTable t =
      parse("# a comment line\r\ntheta,#note,x,y\r\n0.5,hello world,1,2\r\n", {"x", "y", "theta"});
  EXPECT_TRUE(t.has_header);
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0], (std::vector<double>{1, 2, 0.5}));
  EXPECT_EQ(t.line_numbers[0], 3);
}

TEST(CsvIo, ColumnsFromHeaderWhenNoneExpected) {
  const pcr::CsvTable t = parse("q1,q2,#c\n1,2,x\n");
  EXPECT_EQ(t.columns, (std::vector<std::string>{"q1", "q2"}));
  EXPECT_EQ(t.rows[0], (std::vector<double>{1, 2}));
}

TEST(CsvIo, ErrorsNameLineAndColumn) {
  std::string m = error_of("1,2,3\n4,5\n", {"a", "b", "c"});
  EXPECT_NE(m.find("data.csv:2"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 3 columns, got 2"), std::string::npos) << m;

  m = error_of("x,y,theta\n1,2,3\n1,abc,3\n", {"x", "y", "theta"});
  EXPECT_NE(m.find("data.csv:3:2"), std::string::npos) << m;
  EXPECT_NE(m.find("'abc'"), std::string::npos) << m;
  EXPECT_NE(m.find("(y)"), std::string::npos) << m;

  m = error_of("1,2,nan\n", {"a", "b", "c"});
  EXPECT_NE(m.find("data.csv:1:3"), std::string::npos) << m;
  EXPECT_NE(m.find("non-finite"), std::string::npos) << m;

  m = error_of("1,2,3\n1,-inf,3\n", {"a", "b", "c"});
  EXPECT_NE(m.find("data.csv:2:2"), std::string::npos) << m;
  m = error_of("1,2,3\n1,1e999,3\n", {"a", "b", "c"});
  EXPECT_NE(m.find("data.csv:2:2"), std::string::npos) << m;
  m = error_of("1,,3\n", {"a", "b", "c"});
  EXPECT_NE(m.find("data.csv:1:2"), std::string::npos) << m;
  m = error_of("1,2 3,3\n", {"a", "b", "c"});
  EXPECT_NE(m.find("data.csv:1:2"), std::string::npos) << m;
}

TEST(CsvIo, HeaderErrors) {
  std::string m = error_of("x,y,tehta\n1,2,3\n", {"x", "y", "theta"});
  EXPECT_NE(m.find("data.csv:1:3"), std::string::npos) << m;
  EXPECT_NE(m.find("'tehta'"), std::string::npos) << m;
  m = error_of("x,y\n1,2\n", {"x", "y", "theta"});
  EXPECT_NE(m.find("missing column 'theta'"), std::string::npos) << m;
  m = error_of("x,y,x\n1,2,3\n", {"x", "y", "theta"});
  EXPECT_NE(m.find("duplicate column 'x'"), std::string::npos) << m;
}

// A text column (an image's file name) is kept per row, in any position of the header, with the
// numeric columns read around it; without a header, without the column or with an empty field,
// an error naming the line (and column).
TEST(CsvIo, TextColumnsAreKeptPerRow) {
  pcr::CsvReadOptions options;
  options.columns = {"q1", "q2"};
  options.text_columns = {"image"};
  const auto read = [&](const std::string& text) {
    std::istringstream in(text);
    return pcr::parse_csv(in, "rows.csv", options);
  };
  const pcr::CsvTable t = read("q2,image,#note,q1\n2,a b.png,x,1\n4,dir/c.png,y,3\n");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_TRUE(t.rows[0] == std::vector<double>({1, 2}));
  EXPECT_TRUE(t.rows[1] == std::vector<double>({3, 4}));
  ASSERT_EQ(t.texts.size(), 2u);
  EXPECT_EQ(t.texts[0], std::vector<std::string>{"a b.png"});
  EXPECT_EQ(t.texts[1], std::vector<std::string>{"dir/c.png"});
  const auto error = [&](const std::string& text) {
    try {
      read(text);
    } catch (const pcr::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string m = error("1,2,a.png\n");
  EXPECT_NE(m.find("rows.csv:1"), std::string::npos) << m;
  EXPECT_NE(m.find("header"), std::string::npos) << m;
  m = error("q1,q2\n1,2\n");
  EXPECT_NE(m.find("missing column 'image'"), std::string::npos) << m;
  m = error("q1,q2,image\n1,2,a.png\n1,2,\n");
  EXPECT_NE(m.find("rows.csv:3:3"), std::string::npos) << m;
  EXPECT_NE(m.find("empty"), std::string::npos) << m;
}

TEST(CsvIo, FormatDoubleRoundTripsBitForBit) {
  std::mt19937_64 rng(42);
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t bits = rng();
    double x;
    std::memcpy(&x, &bits, sizeof x);
    if (!std::isfinite(x)) continue;
    const std::string text = pcr::format_double(x);
    const double back = std::strtod(text.c_str(), nullptr);
    ASSERT_EQ(std::memcmp(&x, &back, sizeof x), 0) << text;
  }
  EXPECT_EQ(pcr::format_double(0.1), "0.1");  // shortest form, not %.17g's 0.10000000000000001
  EXPECT_EQ(pcr::format_double(std::numeric_limits<double>::quiet_NaN()), "nan");
}

TEST(CsvIo, FormatDoubleKeepsThePrintfLayout) {
  // The text of the first of %.15g, %.16g, %.17g that reads back exactly (subnormals aside,
  // where the shortest digits are fewer than %.15g's).
  const auto printf_text = [](double x) {
    char text[32];
    for (int precision = 15; precision <= 17; ++precision) {
      std::snprintf(text, sizeof text, "%.*g", precision, x);
      if (std::strtod(text, nullptr) == x) break;
    }
    return std::string(text);
  };
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t bits = rng();
    double x;
    std::memcpy(&x, &bits, sizeof x);
    if (!std::isfinite(x) || std::fpclassify(x) == FP_SUBNORMAL) continue;
    ASSERT_EQ(pcr::format_double(x), printf_text(x));
  }
  for (double x : {0.0, -0.0, 1.0, 69e9, 1e15, 0.0001, 1e-05, -2.5e-3, 123456789012345680.0,
                   -2.2250738585072014e-308, 1.7976931348623157e308}) {
    EXPECT_EQ(pcr::format_double(x), printf_text(x));
  }
  EXPECT_EQ(pcr::format_double(69e9), "69000000000");
  EXPECT_EQ(pcr::format_double(1e-05), "1e-05");
  EXPECT_EQ(pcr::format_double(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(pcr::format_double(5e-324), "5e-324");  // %.15g: 4.94065645841247e-324
  char text[pcr::kMaxFormattedDoubleChars];
  const double longest = -2.2250738585072014e-308;
  EXPECT_EQ(pcr::format_double(longest, text) - text, 24);
}

TEST(CsvIo, NumbersReadAsStrtodReadsDecimals) {
  // What from_chars alone would refuse: a leading '+', an underflow.
  const pcr::CsvTable t = parse("a,b,c\n+1.5,1e-400,-.5e-3\n");
  EXPECT_EQ(t.rows[0], (std::vector<double>{1.5, 0.0, -0.5e-3}));
  EXPECT_NE(error_of("a\n+-1\n").find("data.csv:2:1: column 1 (a): expected a number, got '+-1'"),
            std::string::npos);
  EXPECT_NE(error_of("a\nNaN(1)\n").find("data.csv:2:1: column 1 (a): non-finite value 'NaN(1)'"),
            std::string::npos);
  // Decimal only (docs/formats.md): strtod's hexadecimal floats are refused by file, line,
  // column and text, with a header or without.
  for (const char* hex : {"0x1p-8", "-0X1.8P1", "+0x10"}) {
    EXPECT_NE(error_of(std::string("a,b\n0.5,") + hex + "\n")
                  .find(std::string("data.csv:2:2: column 2 (b): expected a decimal number, got "
                                    "the hexadecimal '") +
                        hex + "'"),
              std::string::npos)
        << hex;
    EXPECT_NE(error_of(std::string("# no header\n") + hex + ",1\n")
                  .find("data.csv:2:1: column 1: expected a decimal number"),
              std::string::npos)
        << error_of(std::string("# no header\n") + hex + ",1\n");
  }
  for (const char* text : {"inf", "-inf", "nan", "1e999", "Infinity"}) {
    EXPECT_NE(error_of(std::string("a\n") + text + "\n")
                  .find("data.csv:2:1: column 1 (a): non-finite value"),
              std::string::npos)
        << text;
  }
}

TEST(CsvIo, ReadsInputLongerThanOneReadBlock) {
  std::string text = "q1,q2\r\n";
  const int rows = 20000;  // about 400 kB, so lines straddle the 64 kB blocks
  for (int i = 0; i < rows; ++i) {
    text += pcr::format_double(i * 1e-7) + ", " + pcr::format_double(-i * 3e-7) + "\r\n";
  }
  const pcr::CsvTable t = parse(text + "1,2");  // the last line without its newline
  ASSERT_EQ(t.rows.size(), static_cast<std::size_t>(rows) + 1);
  for (int i = 0; i < rows; ++i) {
    ASSERT_EQ(t.rows[i], (std::vector<double>{i * 1e-7, -i * 3e-7})) << i;
  }
  EXPECT_EQ(t.line_numbers.back(), rows + 2);
}

TEST(CsvIo, WriterWritesRowsAsCsvLine) {
  std::ostringstream text;
  {
    pcr::CsvWriter out(text);
    for (int r = 0; r < 5000; ++r) {  // more than one 64 kB chunk
      out.add(r);
      out.add(r * 0.1);
      out.add("converged");
      out.add(std::nan(""));
      out.end_row();
    }
  }  // the destructor flushes
  std::string expected;
  for (int r = 0; r < 5000; ++r) {
    expected += pcr::csv_line({std::to_string(r), pcr::format_double(r * 0.1), "converged", "nan"});
  }
  EXPECT_EQ(text.str(), expected);
}

TEST(CsvIo, WriterAllocatesNothingPerRow) {
  struct Discard : std::streambuf {
    std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
    int overflow(int c) override { return c; }
  } discard;
  std::ostream stream(&discard);
  pcr::CsvWriter out(stream);
  const auto add_rows = [&out](int rows) {
    for (int r = 0; r < rows; ++r) {
      out.add(-1.2345678901234567e-300 * r);
      out.add(r);
      out.add("max_iterations");
      out.end_row();
    }
  };
  add_rows(5000);  // more than a batch: the formatting thread has started (its one allocation)
  g_allocations = 0;
  g_counting = true;
  add_rows(100000);
  out.flush();
  g_counting = false;
  EXPECT_EQ(g_allocations, 0);
}

// Rows handed to the formatting thread and rows formatted by flush() on the caller's thread, a
// flush in the middle of a row, and a stream that is read between flushes: the text is what
// the rows say, in order.
TEST(CsvIo, WriterKeepsTheOrderAcrossFlushes) {
  std::ostringstream text;
  std::string expected;
  {
    pcr::CsvWriter out(text);
    for (int r = 0; r < 30000; ++r) {
      out.add(r);
      out.add(r * 1e-7);
      expected += std::to_string(r) + "," + pcr::format_double(r * 1e-7);
      if (r % 7919 == 0) {
        out.flush();
        ASSERT_EQ(text.str(), expected) << "row " << r;
      }
      out.add(std::string(static_cast<std::size_t>(r % 5), 'x'));
      out.end_row();
      expected += "," + std::string(static_cast<std::size_t>(r % 5), 'x') + "\n";
    }
    out.flush();
    EXPECT_EQ(text.str(), expected);
    out.add("last");
  }
  EXPECT_EQ(text.str(), expected + "last");
}

TEST(CsvIo, OutputFileIsAtomic) {
  const pcr::test::ScratchDirectory scratch("csv_io");
  const std::string path = scratch.file("out.csv");
  {
    pcr::OutputFile out(path);
    out.stream() << "a,b\n1,2\n";
    EXPECT_FALSE(std::filesystem::exists(path));  // not visible before commit
    out.commit();
  }
  EXPECT_EQ(parse("a,b\n1,2\n").rows, pcr::read_csv(path).rows);
  {
    pcr::OutputFile out(path);
    out.stream() << "garbage\n";
  }  // dropped without commit: the old file stays, no temporary is left
  EXPECT_EQ(pcr::read_csv(path).rows.size(), 1u);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(scratch.path())) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(CsvIo, MissingFileNamesIt) {
  try {
    pcr::read_csv("/nonexistent/poses.csv");
    FAIL();
  } catch (const pcr::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/poses.csv"), std::string::npos);
  }
}

}  // namespace
