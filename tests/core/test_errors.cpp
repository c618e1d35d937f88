#include <gtest/gtest.h>

#include "core/errors.hpp"

using namespace crackle;

TEST(Errors, NumbersPrintAsPeopleWriteThem) {
  EXPECT_EQ(format_number(-2e11), "-2e11");
  EXPECT_EQ(format_number(0.3), "0.3");
  EXPECT_EQ(format_number(1e-5), "1e-5");
  EXPECT_EQ(format_number(0.05 + 0.005), "0.055");
  EXPECT_EQ(format_number(7850.0), "7850");
  EXPECT_EQ(format_number(0.0), "0");
}

TEST(Errors, ExitCodesByKind) {
  EXPECT_EQ(exit_code_for(InputError("x")), 2);
  EXPECT_EQ(exit_code_for(SolverError("x")), 3);
  EXPECT_EQ(exit_code_for(IoError("x")), 4);
  EXPECT_EQ(exit_code_for(std::runtime_error("x")), 1);
}
