// SPDX-License-Identifier: Apache-2.0
// The lab's table reporter: one table of named fields gives the text table and the JSON rows,
// numbers in each form's own printf format, texts escaped in the JSON, formats that do not fit
// a cell refused.
#include "lab/report/report.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace weedspray::lab {
namespace {

Table pressure_table() {
  return Table({{"", "controller", -10, "%-10s", ""},
                {"rise_s", "rise_s", 8, "%8.3f", "%.4f"},
                {"settled", "", 0, "", ""},
                {"samples", "n", 4, "%4zu", ""},
                {"kp", "gains", 0, "Kp=%.4g", "%.4g", "   "},
                {"ki", "", 0, "Ki=%.4g", "%.4g"},
                {"note", "", 0, "", ""}});
}

TEST(ReportTable, TextHasHeadingsWidthsGapsAndSpannedColumns) {
  Table t = pressure_table();
  t.row({std::string("PID"), 0.12345, true, 7LL, 39.31, 392.4, std::string("a")});
  t.row({std::string("fuzzy PID"), 1.5, false, 12LL, 33.38, 352.25, Cell{}});
  const std::vector<std::string> lines = t.text_lines();
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0], "controller   rise_s    n   gains");
  EXPECT_EQ(lines[1], "PID           0.123    7   Kp=39.31 Ki=392.4");
  EXPECT_EQ(lines[2], "fuzzy PID     1.500   12   Kp=33.38 Ki=352.2");
  EXPECT_EQ(t.text_lines(false).size(), 2u);
}

TEST(ReportTable, JsonRowsKeepColumnOrderTheirFormatsAndLeaveOutMissingCells) {
  Table t = pressure_table();
  t.row({std::string("PID"), 0.12345, true, 7LL, 39.31, 392.4, std::string("a \"b\"\\\n")});
  t.row({std::string("fuzzy PID"), 1.5, false, 12LL, 33.38, 352.25, Cell{}});
  EXPECT_EQ(t.json().dump(),
            "[{\"rise_s\": 0.1235, \"settled\": true, \"samples\": 7, \"kp\": 39.31, "
            "\"ki\": 392.4, \"note\": \"a \\\"b\\\"\\\\\\n\"}, "
            "{\"rise_s\": 1.5000, \"settled\": false, \"samples\": 12, \"kp\": 33.38, "
            "\"ki\": 352.2}]");
}

TEST(ReportTable, NamedRowsBecomeMembersOfTheReport) {
  Table t({{"itae", "ITAE", 8, "%8.5f", "%.6f"}});
  t.row("pid", {0.0438831});
  t.row("fuzzy_pid", {0.0429572});
  Report report;
  report.line("start-up 0 -> %.2f MPa", 0.2);
  report.table(t);
  report.json().add("setpoint_mpa", Json::number(0.2, "%.3f"));
  EXPECT_EQ(report.json().dump(),
            "{\"pid\": {\"itae\": 0.043883}, \"fuzzy_pid\": {\"itae\": 0.042957}, "
            "\"setpoint_mpa\": 0.200}");
  EXPECT_EQ(report.text(), "start-up 0 -> 0.20 MPa\n    ITAE\n 0.04388\n 0.04296\n");
}

TEST(ReportTable, UnnamedRowsGoUnderTheirKeyAndTextOnlyColumnsStayOut) {
  Table t({{"", "nozzle", 6, "%6zu", ""}, {"a", "A", 10, "%10.6f", "%.6f"}});
  t.row({1LL, 0.0068});
  t.row({2LL, -0.5});
  Report report;
  report.table(t, "nozzles");
  EXPECT_EQ(report.json().dump(), "{\"nozzles\": [{\"a\": 0.006800}, {\"a\": -0.500000}]}");
  EXPECT_EQ(report.text(), "nozzle          A\n     1   0.006800\n     2  -0.500000\n");
}

TEST(ReportJson, NumbersKeepTheirFormatsAndIntegersTheirDigits) {
  Json j = Json::object();
  j.add("g", Json::number(0.01, "%g"))
      .add("sig", Json::number(123456789.0, "%.6g"))
      .add("fixed", Json::number(2.0 / 3.0, "%.0f"))
      .add("neg", Json::number(-0.00004, "%.4f"))
      .add("n", Json::integer(-3))
      .add("seed", Json::unsigned_integer(18446744073709551615ULL))
      .add("list", Json::array().push(Json::boolean(false)).push(Json::object()))
      .add("key \"q\"", Json::string("tab\there\x01"));
  EXPECT_EQ(j.dump(),
            "{\"g\": 0.01, \"sig\": 1.23457e+08, \"fixed\": 1, \"neg\": -0.0000, \"n\": -3, "
            "\"seed\": 18446744073709551615, \"list\": [false, {}], "
            "\"key \\\"q\\\"\": \"tab\\there\\u0001\"}");
}

TEST(ReportJson, AddToAnArrayOrPushToAnObjectIsRefused) {
  Json object = Json::object();
  Json array = Json::array();
  EXPECT_THROW(object.push(Json::integer(1)), std::logic_error);
  EXPECT_THROW(array.add("k", Json::integer(1)), std::logic_error);
  EXPECT_THROW(object.merge(array), std::logic_error);
}

TEST(ReportCell, IntegerFormatsOfAnyLengthPrintTheValue) {
  EXPECT_EQ(format_cell("%8zu", 12LL), "      12");
  EXPECT_EQ(format_cell("%9d", -4LL), "       -4");
  EXPECT_EQ(format_cell("%llu", 5LL), "5");
  EXPECT_EQ(format_cell("%-5s|", std::string("ab")), "ab   |");
  EXPECT_EQ(format_cell("%12s", true), "        true");
  EXPECT_EQ(format_cell("%5.1f %%", 12.34), " 12.3 %");
  EXPECT_EQ(format_cell("%8.2f", Cell{}), "");
}

TEST(ReportCell, FormatsThatDoNotFitTheCellAreRefused) {
  EXPECT_THROW(format_cell("%8d", 1.5), std::logic_error);
  EXPECT_THROW(format_cell("%8.2f", 3LL), std::logic_error);
  EXPECT_THROW(format_cell("%s", 2.0), std::logic_error);
  EXPECT_THROW(format_cell("%lf", 2.0), std::logic_error);
  EXPECT_THROW(format_cell("%d %d", 2LL), std::logic_error);
  EXPECT_THROW(format_cell("no conversion", 2LL), std::logic_error);
  EXPECT_THROW(format_cell("%8", 2LL), std::logic_error);
  EXPECT_THROW(format_cell("%s", Json::object()), std::logic_error);
  EXPECT_THROW(Json::number(1.0, "%d"), std::logic_error);
}

TEST(ReportTable, RowsOfTheWrongWidthOrNumbersWithoutAJsonFormatAreRefused) {
  Table t({{"a", "A", 4, "%4.1f", ""}});
  EXPECT_THROW(t.row({1.0, 2.0}), std::invalid_argument);
  t.row({1.0});
  EXPECT_THROW(t.json(), std::logic_error);
}

}  // namespace
}  // namespace weedspray::lab
