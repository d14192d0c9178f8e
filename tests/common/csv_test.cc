#include "common/csv.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace clogscope {
namespace {

TEST(CsvTest, EscapesOnlyWhenNeeded) {
  EXPECT_EQ(CsvEscape("plain"), "plain");
  EXPECT_EQ(CsvEscape("a,b"), "\"a,b\"");
  EXPECT_EQ(CsvEscape("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(CsvLine({"a", "b,c", ""}), "a,\"b,c\",");
}

TEST(CsvTest, NumbersAndMissingValues) {
  EXPECT_EQ(CsvNumber(1.23456, 3), "1.235");
  EXPECT_EQ(CsvNumber(std::nullopt, 3), "");
  EXPECT_EQ(CsvNumber(std::numeric_limits<double>::quiet_NaN(), 3), "");
}

TEST(CsvTest, ParsesWithCommentsQuotesAndLineNumbers) {
  const std::string text =
      "# provenance\n"
      "step,temperature_c,note\n"
      "1,220,\"a, b\"\n"
      "\n"
      "2,210,\"say \"\"x\"\"\"\r\n";
  const CsvTable t = ParseCsv(text, "table.csv");
  ASSERT_EQ(t.header.size(), 3u);
  EXPECT_EQ(t.Column("temperature_c"), 1);
  EXPECT_EQ(t.Column("missing"), -1);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0][2], "a, b");
  EXPECT_EQ(t.rows[1][2], "say \"x\"");
  EXPECT_EQ(t.row_line_numbers[0], 3);
  EXPECT_EQ(t.row_line_numbers[1], 5);
}

TEST(CsvTest, RejectsRaggedRowNamingTheLine) {
  try {
    ParseCsv("a,b\n1,2\n3\n", "x.csv");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x.csv:3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseCsv("", "empty.csv"), std::invalid_argument);
  EXPECT_THROW(ParseCsv("a\n\"open\n", "q.csv"), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope
