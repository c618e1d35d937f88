#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using cli_testing::crackle;
using cli_testing::data;
using cli_testing::Result;

}  // namespace

TEST(Cli, CheckPrintsTheExpectedCountsForTheDefaultBeam) {
  Result result = crackle("check " + data("beam.yaml"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  // 40 x 4 x 2 cells, plus a grid line at z = 0.007 for the crack edge: 40 x 4 x 3 elements of p = 2.
  EXPECT_NE(result.output.find("elements     480\n"), std::string::npos) << result.output;
  // (2*40+1) x (2*4+1) x (2*3+1) = 5103 lattice nodes; 9 x 3 crack-face nodes, 9 on the front.
  EXPECT_NE(result.output.find("nodes        5121 (5103 + 18 crack-face copies)"), std::string::npos);
  EXPECT_NE(result.output.find("dofs         15363 open, 15309 uncracked, 189 constrained"), std::string::npos);
  EXPECT_NE(result.output.find("crack pairs  27 (18 split, 9 on the front)"), std::string::npos);
  EXPECT_NE(result.output.find("crack area   6e-05 m^2 (pairs sum to 6e-05 m^2)"), std::string::npos);
  EXPECT_NE(result.output.find("total mass   0.314 kg"), std::string::npos);  // 7850 * 0.2 * 0.02 * 0.01
}

TEST(Cli, BadSceneIsOneLineAndExitCode2) {
  const fs::path path = fs::temp_directory_path() / "crackle-cli-bad.yaml";
  std::ofstream(path) << "mesh:\n  box: {size: [1, 1, 1], cells: [1, 1, 1], order: 1}\n"
                         "material: {E: -2.0e11, nu: 0.3, rho: 7850}\n";
  Result result = crackle("check " + path.string());
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.output, "crackle: error: " + path.string() + ":3: material.E: expected a positive number, got -2e11\n");
  Result missing = crackle("check /nonexistent/scene.yaml");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("/nonexistent/scene.yaml"), std::string::npos) << missing.output;
}

TEST(Cli, HelpOnEveryCommand) {
  for (const std::string command : {"", "check ", "scene-format "}) {
    Result result = crackle(command + "--help");
    EXPECT_EQ(result.exit_code, 0) << command;
    EXPECT_NE(result.output.find("Usage"), std::string::npos) << command << result.output;
  }
  EXPECT_NE(crackle("").exit_code, 0);  // a subcommand is required
}
