// The CSV reader of recorded data (mjukf/io/csv_reader.hpp, docs/real-data.md). Every malformed file is
// reported with its line and column, never read in part; what the reader accepts (CRLF, blank lines,
// separators at the end of a line, quoted names, missing cells) reads as written; and the Cascaded Tanks
// benchmark file (tests/data/cascaded_tanks/) reads whole. Built twice: csv_reader_test, and
// csv_reader_noexcept_test with -fno-exceptions, where the problem is only returned.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <locale>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mjukf/io/csv_reader.hpp"

namespace {

namespace fs = std::filesystem;
using mjukf::io::CsvProblem;
using mjukf::io::CsvTable;

#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
static_assert(MJUKF_EXCEPTIONS == 1, "exceptions on: readCsv(path) throws");
#else
static_assert(MJUKF_EXCEPTIONS == 0, "-fno-exceptions: the problem is only returned");
#endif

// A file of its own per test, written byte for byte (CRLF stays CRLF).
std::string writeFile(const std::string& name, const std::string& text) {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() / ("mjukf_csv_reader_test_" + std::string(test->name()));
  std::error_code ignored;
  fs::create_directories(dir, ignored);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Reads `text` from a file both ways: the problem returned, and (exceptions on) the CsvError thrown,
// which must say the same.
CsvProblem problemOf(const std::string& text, std::string* path = nullptr) {
  const std::string file = writeFile("bad.csv", text);
  if (path != nullptr) *path = file;
  CsvProblem problem;
  const CsvTable table = mjukf::io::readCsv(file, problem);
  EXPECT_TRUE(problem) << "read without a problem: " << text;
  EXPECT_TRUE(table.names().empty() && table.rows() == 0) << "a table in part";
#if MJUKF_EXCEPTIONS
  try {
    mjukf::io::readCsv(file);
    ADD_FAILURE() << "readCsv(path) did not throw";
  } catch (const mjukf::io::CsvError& e) {
    EXPECT_EQ(std::string(e.what()), problem.message());
    EXPECT_EQ(e.line(), problem.line);
    EXPECT_EQ(e.column(), problem.column);
    EXPECT_EQ(e.columnName(), problem.columnName);
  }
#endif
  return problem;
}

CsvTable tableOf(const std::string& text) {
  const std::string file = writeFile("good.csv", text);
  CsvProblem problem;
  CsvTable table = mjukf::io::readCsv(file, problem);
  EXPECT_FALSE(problem) << problem.message();
  return table;
}

// ---------------------------------------------------------------------------------------------
// Malformed files: the line, the column (index and name) and what is wrong.

struct Malformed {
  const char* name;
  const char* text;
  long line;
  long column;             // 0: none
  const char* columnName;  // "": none
  const char* reason;      // a part of the reason
};
void PrintTo(const Malformed& c, std::ostream* os) { *os << c.name; }

class MalformedFile : public ::testing::TestWithParam<Malformed> {};

TEST_P(MalformedFile, IsReportedWithItsLineAndColumn) {
  const Malformed& c = GetParam();
  std::string path;
  const CsvProblem problem = problemOf(c.text, &path);
  EXPECT_EQ(problem.source, path);
  EXPECT_EQ(problem.line, c.line);
  EXPECT_EQ(problem.column, c.column);
  EXPECT_EQ(problem.columnName, c.columnName);
  EXPECT_NE(problem.reason.find(c.reason), std::string::npos) << problem.reason;

  // The message holds all of it: "<path>:<line>: column <index> '<name>': <reason>".
  std::string where = path + ":" + std::to_string(c.line) + ": ";
  if (c.column > 0) where += "column " + std::to_string(c.column);
  if (std::strlen(c.columnName) > 0) where += " '" + std::string(c.columnName) + "'";
  EXPECT_EQ(problem.message().rfind(where, 0), 0u) << problem.message();
}

INSTANTIATE_TEST_SUITE_P(
    Cases, MalformedFile,
    ::testing::Values(
        Malformed{"NotANumber", "a,b,c\n1,2,3\n4,x5,6\n", 3, 2, "b", "'x5' is not a number"},
        Malformed{"NotAMissingValueEither", "a,b\n1,NA\n", 2, 2, "b", "'NA' is not a number"},
        Malformed{"TrailingGarbage", "a,b\n1,2.5abc\n", 2, 2, "b", "'abc' follows '2.5'"},
        Malformed{"SpaceInsideANumber", "a,b\n1,2 5\n", 2, 2, "b", "' 5' follows '2'"},
        Malformed{"Hexadecimal", "a\n0x1A\n", 2, 1, "a", "'x1A' follows '0'"},
        Malformed{"TwoSigns", "a,b\n+-1,2\n", 2, 1, "a", "'+-1' is not a number"},
        Malformed{"DecimalComma", "a;b\n1,5;2\n", 2, 2, "",
                  "too many cells: the line has 2 cells, the header 1 column"},
        Malformed{"TooManyCells", "a,b\n1,2\n1,2,3\n", 3, 3, "",
                  "too many cells: the line has 3 cells, the header 2 columns"},
        Malformed{"TooManyCellsAndASeparator", "a,b\n1,2,3,\n", 2, 3, "", "the line has 4 cells, the header 2 columns"},
        Malformed{"TooFewCells", "a,b,c\n1,2,3\n4,5\n", 3, 3, "c", "missing: the line has 2 cells"},
        Malformed{"TruncatedLastLine", "a,b,c\n1,2,3\n4", 3, 2, "b",
                  "missing: the line has 1 cell, the header 3 columns"},
        Malformed{"OutOfRange", "a,b\n1,1e400\n", 2, 2, "b", "'1e400' is out of the range of double"},
        Malformed{"NegativeOutOfRange", "a,b\n-1e999,1\n", 2, 1, "a", "out of the range of double"},
        Malformed{"Underflow", "a,b\n1,1e-400\n", 2, 2, "b", "out of the range of double"},
        // Physical lines are counted: blank ones, CRLF endings and a header after blank lines included.
        Malformed{"LineNumberAfterBlankLinesCrlf", "a,b\r\n\r\n1,2\r\n  \r\n3,oops\r\n", 5, 2, "b", "'oops'"},
        Malformed{"LineNumberAfterBlankLinesBeforeTheHeader", "\n\na,b\n1,zz\n", 4, 2, "b", "'zz'"},
        Malformed{"UnclosedQuoteInHeader", "\"a,b\n1,2\n", 1, 1, "", "a quote is not closed"},
        Malformed{"UnclosedQuoteInRow", "a,b\n1,\"2\n", 2, 2, "b", "a quote is not closed"},
        Malformed{"TextAfterQuote", "a,b\n1,\"2\"x\n", 2, 2, "b", "text after the closing quote"},
        Malformed{"UnnamedColumn", "a,,c\n1,2,3\n", 1, 2, "", "no name"},
        Malformed{"QuotedEmptyName", "a,\"\"\n1,2\n", 1, 2, "", "no name"},
        Malformed{"DuplicateName", "a,b,\"a\"\n1,2,3\n", 1, 3, "a", "also that of column 1"},
        Malformed{"Empty", "", 1, 0, "", "no header row"},
        Malformed{"OnlyBlankLines", "\n \r\n\t\n", 1, 0, "", "no header row"}),
    [](const auto& info) { return std::string(info.param.name); });

// A long garbage cell is quoted only in part: a binary file read by mistake gives a readable message.
TEST(MalformedFile, ALongCellIsShortenedInTheMessage) {
  const CsvProblem problem = problemOf("a\n" + std::string(100000, 'x') + "\n");
  EXPECT_EQ(problem.line, 2);
  EXPECT_LT(problem.message().size(), 200u) << problem.message();
}

TEST(MissingFile, IsReportedWithItsPath) {
  CsvProblem problem;
  const CsvTable table = mjukf::io::readCsv("/nonexistent/dir/data.csv", problem);
  EXPECT_EQ(problem.message(), "/nonexistent/dir/data.csv: cannot open the file");
  EXPECT_EQ(problem.line, 0);
  EXPECT_EQ(table.rows(), 0u);
}

TEST(MissingFile, ADirectoryIsNotAFile) {
  const std::string dir = fs::path(writeFile("x.csv", "a\n1\n")).parent_path().string();
  CsvProblem problem;
  (void)mjukf::io::readCsv(dir, problem);
  ASSERT_TRUE(problem);
  EXPECT_EQ(problem.source, dir);
}

// ---------------------------------------------------------------------------------------------
// A column asked for by name that the file lacks: named, with the columns the file has.

TEST(MissingColumn, IsNamedWithTheColumnsPresent) {
  const CsvTable table = tableOf("uEst,yEst\n1,2\n");
  EXPECT_FALSE(table.require({"yEst", "uEst"}));
  const CsvProblem problem = table.require({"uEst", "yVal", "zz"});
  ASSERT_TRUE(problem);
  EXPECT_EQ(problem.columnName, "yVal");
  EXPECT_EQ(problem.line, 1);
  EXPECT_NE(problem.message().find("no column named 'yVal'; the columns are: uEst, yEst"), std::string::npos)
      << problem.message();
  EXPECT_EQ(problem.message().rfind(table.source() + ":1: ", 0), 0u) << problem.message();
  EXPECT_EQ(table.find("yVal"), nullptr);
  EXPECT_FALSE(table.has("yVal"));
  EXPECT_FALSE(table.has("uest")) << "names are case-sensitive";
#if MJUKF_EXCEPTIONS
  try {
    (void)table.column("yVal");
    ADD_FAILURE() << "column() of a missing name did not throw";
  } catch (const mjukf::io::CsvError& e) {
    EXPECT_EQ(std::string(e.what()), problem.message());
  }
#endif
}

// ---------------------------------------------------------------------------------------------
// What the reader accepts.

bool missing(double value) {
  const double quiet = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t bits = 0, quietBits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  std::memcpy(&quietBits, &quiet, sizeof quietBits);
  return bits == quietBits;  // the one quiet NaN, whatever was written
}

TEST(Accepted, CrlfAndLfReadAlike) {
  const CsvTable lf = tableOf("a,b\n1,2\n3,4\n");
  const CsvTable crlf = tableOf("a,b\r\n1,2\r\n3,4\r\n");
  ASSERT_EQ(crlf.names(), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(crlf.column("a"), lf.column("a"));
  EXPECT_EQ(crlf.column("b"), (std::vector<double>{2, 4}));
  EXPECT_EQ(tableOf("a,b\n1,2\n3,4").column("b"), (std::vector<double>{2, 4})) << "no line end at the end";
}

TEST(Accepted, BlankLinesAreSkippedAndRowsKeepTheirLines) {
  const CsvTable table = tableOf("\r\n\na,b\n\n1,2\r\n \t\r\n3,4\n\n\n");
  EXPECT_EQ(table.headerLine(), 3);
  ASSERT_EQ(table.rows(), 2u);
  EXPECT_EQ(table.line(0), 5);
  EXPECT_EQ(table.line(1), 7);
  EXPECT_EQ(table.column("a"), (std::vector<double>{1, 3}));
}

TEST(Accepted, ASeparatorAtTheEndOfALine) {
  const CsvTable table = tableOf("a,b,\n1,2,\n3,4\n5,,\n6,\n");
  ASSERT_EQ(table.names(), (std::vector<std::string>{"a", "b"}));
  ASSERT_EQ(table.rows(), 4u);
  EXPECT_EQ(table.column("a"), (std::vector<double>{1, 3, 5, 6}));
  const auto& b = table.column("b");
  EXPECT_EQ(b[0], 2);
  EXPECT_EQ(b[1], 4);
  EXPECT_TRUE(missing(b[2])) << "5,, is b missing, then a separator";
  EXPECT_TRUE(missing(b[3])) << "6, is b missing";
}

TEST(Accepted, QuotedNamesAndCells) {
  const CsvTable table = tableOf("\"uEst\", \"level, V\" ,\"say \"\"hi\"\"\",plain\n\"1.5\",2,\"\",4\n");
  EXPECT_EQ(table.names(), (std::vector<std::string>{"uEst", "level, V", "say \"hi\"", "plain"}));
  EXPECT_EQ(table.column("uEst"), (std::vector<double>{1.5}));
  EXPECT_EQ(table.column("level, V"), (std::vector<double>{2}));
  EXPECT_TRUE(missing(table.column("say \"hi\"")[0])) << "a quoted empty cell is missing";
}

TEST(Accepted, EmptyCellsAndNanAreMissingAsAQuietNan) {
  const CsvTable table = tableOf("a,b,c,d,e,f\n,NaN,nan,-nan,NAN,  \n1,2,3,4,5,6\n");
  for (const auto& name : table.names()) {
    ASSERT_EQ(table.column(name).size(), 2u);
    EXPECT_TRUE(missing(table.column(name)[0])) << name;
    EXPECT_FALSE(std::isnan(table.column(name)[1])) << name;
  }
}

TEST(Accepted, NumbersAsWritten) {
  const CsvTable table = tableOf("v\n+1.5\n-2e-3\n.5\n1.\n 3 \n1e-320\ninf\n-1.7976931348623157e308\n0.1\n");
  const std::vector<double> expected{
      1.5, -2e-3, 0.5, 1.0, 3.0, 1e-320, std::numeric_limits<double>::infinity(), -1.7976931348623157e308, 0.1};
  EXPECT_EQ(table.column("v"), expected) << "every value exact: std::from_chars rounds correctly";
}

TEST(Accepted, AUtf8ByteOrderMarkIsNotPartOfTheFirstName) {
  const CsvTable table = tableOf("\xEF\xBB\xBFt,y\n0,1\n");
  EXPECT_EQ(table.names().front(), "t");
}

TEST(Accepted, AHeaderWithoutRows) {
  const CsvTable table = tableOf("a,b\n\n");
  EXPECT_EQ(table.rows(), 0u);
  EXPECT_TRUE(table.column("b").empty());
}

// Numbers are read in the C format whatever the program's locale: a global locale with a decimal comma
// (as a German one has) changes nothing.
struct DecimalComma : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
};

TEST(Accepted, TheGlobalLocaleDoesNotChangeNumbers) {
  const std::locale before = std::locale::global(std::locale(std::locale::classic(), new DecimalComma));
  const CsvTable table = tableOf("a,b\n1.25,2\n");
  std::locale::global(before);
  EXPECT_EQ(table.column("a"), (std::vector<double>{1.25}));
}

TEST(Accepted, ParseCsvReadsTextAsReadCsvReadsTheFile) {
  const std::string text = "a,b\r\n1,\r\n\r\n3,4,\r\n";
  CsvProblem problem;
  const CsvTable parsed = mjukf::io::parseCsv(text, "in memory", problem);
  ASSERT_FALSE(problem);
  const CsvTable read = tableOf(text);
  EXPECT_EQ(parsed.source(), "in memory");
  EXPECT_EQ(parsed.column("a"), read.column("a"));
  EXPECT_EQ(parsed.line(1), read.line(1));
  (void)mjukf::io::parseCsv("a\n1\nx\n", "in memory", problem);
  EXPECT_EQ(problem.message(), "in memory:3: column 1 'a': 'x' is not a number");
}

// ---------------------------------------------------------------------------------------------
// The Cascaded Tanks benchmark (tests/data/cascaded_tanks/README.md): quoted names, CRLF, a separator
// at the end of every line, Ts on the first row only, a blank last line.

TEST(CascadedTanks, ReadsWhole) {
  CsvProblem problem;
  const CsvTable table =
      mjukf::io::readCsv(std::string(MJUKF_TEST_DATA_DIR) + "/cascaded_tanks/dataBenchmark.csv", problem);
  ASSERT_FALSE(problem) << problem.message();
  ASSERT_EQ(table.names(), (std::vector<std::string>{"uEst", "uVal", "yEst", "yVal", "Ts"}));
  ASSERT_EQ(table.rows(), 1024u);
  EXPECT_EQ(table.line(1023), 1025);

  const auto& ts = table.column("Ts");
  EXPECT_EQ(ts[0], 4.0);
  for (std::size_t k = 1; k < ts.size(); ++k) ASSERT_TRUE(missing(ts[k])) << "row " << k;

  const std::vector<double> first{3.2567, 0.97619, 5.205, 4.9728};
  const std::vector<double> last{3.2615, 0.94805, 3.6831, 3.7179};
  for (std::size_t c = 0; c < 4; ++c) {
    const auto& column = table.column(table.names()[c]);
    ASSERT_EQ(column.size(), 1024u);
    EXPECT_EQ(column.front(), first[c]) << table.names()[c];
    EXPECT_EQ(column.back(), last[c]) << table.names()[c];
    for (std::size_t k = 0; k < column.size(); ++k)
      ASSERT_TRUE(column[k] >= 0 && column[k] <= 10) << table.names()[c] << " row " << k << ": " << column[k];
  }
  EXPECT_EQ(table.column("yEst")[1], 5.2154);
  const auto& yEst = table.column("yEst");
  EXPECT_NE(std::find(yEst.begin(), yEst.end(), 10.0), yEst.end()) << "the level sensor saturates at 10 V";
}

}  // namespace
