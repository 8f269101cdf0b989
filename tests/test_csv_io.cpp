// Numeric CSV tables: header detection, comment columns, selection by name, and error messages
// that name the source, the line and the column.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

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
