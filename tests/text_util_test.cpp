#include "io/common/text_util.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "io/common/io_error.h"
#include "io/common/line_source.h"

namespace tolver {
namespace {

std::vector<std::string> streamedLines(LineSource source) {
  std::vector<std::string> lines;
  std::string l;
  while (source.next(l)) lines.push_back(l);
  return lines;
}

std::vector<std::string> fileLines(const std::string& text) {
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("tolver_line_source_" + std::to_string(::getpid()) + ".txt"))
          .string();  // one per process: the tests of this file run concurrently under ctest
  std::ofstream(path, std::ios::binary) << text;
  std::vector<std::string> lines = streamedLines(LineSource::file(path));
  std::filesystem::remove(path);
  return lines;
}

// LineSource gives the lines splitLines gives (the independent truth: one pass over the whole
// text), from memory and from a file read in 64 kB blocks, for texts with LF, CR and CRLF endings
// mixed, blank lines, a CRLF cut by a block's end, lines longer than several blocks, and with
// and without a last line ending.
TEST(LineSource, GivesTheLinesOfSplitLinesAcrossBlocks) {
  std::mt19937 rng(17);
  const char* endings[] = {"\n", "\r", "\r\n", "\n\n", "\r\r\n"};
  for (int trial = 0; trial < 40; ++trial) {
    std::string text;
    const size_t target = trial < 10 ? 200 : 150000 + 4000 * trial;
    while (text.size() < target) {
      const size_t len = (rng() % 50 == 0) ? 70000 + rng() % 100000 : rng() % 80;
      for (size_t k = 0; k < len; ++k) text += static_cast<char>('a' + rng() % 26);
      text += endings[rng() % 5];
    }
    if (trial % 2) text += "last";
    const std::vector<std::string> truth = splitLines(text);
    EXPECT_EQ(streamedLines(LineSource(text)), truth) << trial;
    EXPECT_EQ(fileLines(text), truth) << trial;
  }
  // CRLF split between two blocks: one line ending, not two.
  std::string cut(65535, 'x');
  cut += "\r\nnext\n";
  EXPECT_EQ(fileLines(cut), (std::vector<std::string>{std::string(65535, 'x'), "next"}));
  EXPECT_EQ(fileLines(""), std::vector<std::string>{});
}

TEST(LineSource, DropsALeadingByteOrderMarkOnly) {
  EXPECT_EQ(fileLines("\xEF\xBB\xBFUNITS/INCHES\nGOTO/1,2,3\n"),
            (std::vector<std::string>{"UNITS/INCHES", "GOTO/1,2,3"}));
  EXPECT_EQ(streamedLines(LineSource("\xEF\xBB\xBF")), std::vector<std::string>{});
  EXPECT_EQ(streamedLines(LineSource("a\n\xEF\xBB\xBF")),
            (std::vector<std::string>{"a", "\xEF\xBB\xBF"}));
}

TEST(LineSource, AMissingFileIsAnInputErrorNamingIt) {
  try {
    LineSource::file("/nonexistent/tolver.apt");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/tolver.apt"), std::string::npos) << e.what();
  }
}

// RFC 4648 section 10 test vectors, and bytes above 127.
TEST(TextUtil, Base64MatchesRfc4648) {
  EXPECT_EQ(base64Encode(""), "");
  EXPECT_EQ(base64Encode("f"), "Zg==");
  EXPECT_EQ(base64Encode("fo"), "Zm8=");
  EXPECT_EQ(base64Encode("foo"), "Zm9v");
  EXPECT_EQ(base64Encode("foob"), "Zm9vYg==");
  EXPECT_EQ(base64Encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64Encode("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64Encode(std::string("\x89PNG", 4)), "iVBORw==");
}

// RFC 4180 quoting: what csvField writes, splitCsvLine reads back, cell for cell, for cells with
// commas, quotes, edge spaces and nothing special; unquoted cells are trimmed.
TEST(TextUtil, CsvCellsRoundTripThroughQuoting) {
  const std::vector<std::string> cells = {"plain", "a,b",    "say \"hi\"", "  edge ",
                                          "",      "x\"\"y", "1.5"};
  EXPECT_EQ(splitCsvLine(csvLine(cells)), cells);
  EXPECT_EQ(csvField("plain"), "plain");
  EXPECT_EQ(csvField("a,b"), "\"a,b\"");
  EXPECT_EQ(csvField("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(splitCsvLine(" a , b ,c"), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(splitCsvLine("\"x, y\" , z"), (std::vector<std::string>{"x, y", "z"}));
}

// formatNumber: the shortest text that reads back to the same double, for random doubles over
// many magnitudes; the short forms a file reader expects for round values.
TEST(TextUtil, FormatNumberRoundTripsWithTheShortestText) {
  EXPECT_EQ(formatNumber(0.1), "0.1");
  EXPECT_EQ(formatNumber(120.0), "120");
  EXPECT_EQ(formatNumber(-2.5), "-2.5");
  EXPECT_EQ(formatNumber(1e-5), "1e-05");
  unsigned s = 12345;
  for (int i = 0; i < 20000; ++i) {
    s = s * 1103515245u + 12345u;
    const double v = (static_cast<double>(s % 100000) / 7.0 - 7000.0) *
                     std::pow(10.0, static_cast<int>(s % 21) - 10);
    EXPECT_EQ(std::stod(formatNumber(v)), v) << formatNumber(v);
  }
}

// One header policy: comments and blank lines skipped, names lowercased, a name given twice or a
// required one missing is an error naming the header line.
TEST(TextUtil, CsvHeaderIsReadOnePolicy) {
  const std::string text = "# comment\n\nName,Value\na,1\n# again\nb,2\n";
  std::vector<std::string> got;
  int header_line = 0;
  forEachCsvRow(
      text, "t.csv", {"name", "value"}, "missing",
      [&](const CsvRow& r) { got.push_back(r.cell("name") + r.cell("value")); },
      [&](const CsvHeader& h) { header_line = h.line; });
  EXPECT_EQ(got, (std::vector<std::string>{"a1", "b2"}));
  EXPECT_EQ(header_line, 3);
  try {
    forEachCsvRow("a,b,A\n1,2,3\n", "t.csv", {}, "missing", [](const CsvRow&) {});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("named twice"), std::string::npos) << e.what();
  }
  EXPECT_THROW(forEachCsvRow("a\n1\n", "t.csv", {"b"}, "missing", [](const CsvRow&) {}),
               InputError);
  EXPECT_THROW(forEachCsvRow("# only\n", "t.csv", {}, "missing", [](const CsvRow&) {}), InputError);
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// LineBuilder::fixed writes the bytes printf's "%.<n>f" writes (the predicted CL and the point
// table read back bit for bit as before): random values over every magnitude a file holds, both
// signs, negative zero, values that round to zero, halfway cases in binary, and huge ones.
TEST(LineBuilder, FixedWritesThePrintfBytes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-12, 8);
  std::vector<double> values = {0.0,
                                -0.0,
                                1e-300,
                                -1e-300,
                                0.5e-6,
                                -0.5e-6,
                                0.0000005,
                                2.5e-7,
                                1.0000005,
                                0.125,
                                1e15,
                                -1e15,
                                1e300,
                                -1.7976931348623157e308,
                                123456.7890125,
                                0.1,
                                0.7};
  for (int k = 0; k < 200000; ++k) values.push_back(mantissa(rng) * std::pow(10.0, exponent(rng)));
  char expected[512];
  LineBuilder line;
  for (double v : values)
    for (int decimals : {4, 6, 8, 9}) {
      std::snprintf(expected, sizeof expected, "%.*f", decimals, v);
      line.clear();
      line.fixed(v, decimals);
      ASSERT_EQ(line.view(), std::string_view(expected)) << v << " with " << decimals;
    }
  // Exact halves (j / 2^(d+1), j odd: v 10^d = j 5^d / 2, a tie at d decimals), rounded to even
  // as printf does, and their neighbours one ulp away, at every precision the writers use.
  std::uniform_int_distribution<long long> odd(0, 1LL << 40);
  for (int k = 0; k < 20000; ++k)
    for (int decimals = 0; decimals <= 9; ++decimals) {
      const double tie = std::ldexp(
          static_cast<double>(2 * odd(rng) % (1LL << (52 - decimals)) + 1), -(decimals + 1));
      for (double v : {tie, -tie, std::nextafter(tie, 0.0), std::nextafter(tie, 1e300)}) {
        std::snprintf(expected, sizeof expected, "%.*f", decimals, v);
        line.clear();
        line.fixed(v, decimals);
        ASSERT_EQ(line.view(), std::string_view(expected)) << v << " with " << decimals;
      }
    }
  for (double v : values)
    for (int decimals : {0, 1, 2, 3, 12, 15, 17}) {
      std::snprintf(expected, sizeof expected, "%.*f", decimals, v);
      line.clear();
      line.fixed(v, decimals);
      ASSERT_EQ(line.view(), std::string_view(expected)) << v << " with " << decimals;
    }
  line.clear();
  line.text("GOTO").character('/').integer(-42).character(',').fixed(1.5, 2);
  EXPECT_EQ(line.view(), "GOTO/-42,1.50");
}

TEST(TextUtil, OperationNamesFromCamComments) {
  EXPECT_EQ(operationName("begin operation: Profile)"), "Profile");
  EXPECT_EQ(operationName("finish operation: Profile"), "");
  EXPECT_EQ(operationName("End Operation: Profile"), "");
  EXPECT_EQ(operationName("Operation : CURVE_DRIVE"), "CURVE_DRIVE");
  EXPECT_EQ(operationName(" OPERATION=  ROUGH7  Z LEVEL  SRF_MILL1  )"),
            "ROUGH7 Z LEVEL SRF_MILL1");
  EXPECT_EQ(operationName("OPERATION NAME : Sweeping.1"), "Sweeping.1");
  EXPECT_EQ(operationName("operations follow"), "");
  EXPECT_EQ(operationName("T1 D=6 CR=0"), "");
  EXPECT_EQ(operationName("Operation:" + std::string(100, 'x')).size(), 60u);
}

}  // namespace
}  // namespace tolver
