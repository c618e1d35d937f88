// CSV fields per RFC 4180: headers that hold commas, quotes or line breaks are quoted.
#include <gtest/gtest.h>

#include "io/csv.hpp"

using namespace crackle;

TEST(Csv, FieldsAreQuotedPerRfc4180) {
  EXPECT_EQ(io::csv_field("tip.u_z [m]"), "tip.u_z [m]");
  EXPECT_EQ(io::csv_field(""), "");
  EXPECT_EQ(io::csv_field("a,b"), "\"a,b\"");
  EXPECT_EQ(io::csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(io::csv_field("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(io::csv_field("cr\rlf"), "\"cr\rlf\"");
}

TEST(Csv, HeadersAreQuotedAndNumbersAreNot) {
  io::CsvTable table;
  table.add("time [s]", {0.5});
  table.add("p,q \"x\" [m]", {-1.0});
  EXPECT_EQ(io::to_csv(table), "time [s],\"p,q \"\"x\"\" [m]\"\n0.5,-1\n");
}
