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
  // The counts of the uniform mesh (crackle run's and sweep's under grading: auto); the graded one below.
  Result result = crackle("check " + data("beam.yaml") + " --set mesh.box.grading=none");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("grading      none (crackle modal, check), none (crackle run, sweep)"), std::string::npos)
      << result.output;
  // 40 x 4 x 2 cells, plus a grid line at z = 0.007 for the crack edge: 40 x 4 x 3 elements of p = 2.
  EXPECT_NE(result.output.find("elements     480\n"), std::string::npos) << result.output;
  // (2*40+1) x (2*4+1) x (2*3+1) = 5103 lattice nodes; 9 x 3 crack-face nodes, 9 on the front.
  EXPECT_NE(result.output.find("nodes        5121 (5103 + 18 crack-face copies)"), std::string::npos);
  EXPECT_NE(result.output.find("dofs         15363 open, 15309 uncracked, 189 constrained"), std::string::npos);
  EXPECT_NE(result.output.find("crack pairs  27 (18 split, 9 on the front)"), std::string::npos);
  EXPECT_NE(result.output.find("crack area   6e-05 m^2 (pairs sum to 6e-05 m^2)"), std::string::npos);
  EXPECT_NE(result.output.find("total mass   0.314 kg"), std::string::npos);  // 7850 * 0.2 * 0.02 * 0.01

  // Default grading (p = 2, h = 5 mm, D = 10 mm: 1 + 1 = 2 layers of 0.2) for modal and check: x
  // gets 4 lines around 0.05, z 4 around 0.007 (0.005 and 0.01 are the neighbours): 44 x 4 x 7.
  result = crackle("check " + data("beam.yaml"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("grading      2 layers of ratio 0.2 (crackle modal, check), none (crackle run, sweep)"),
            std::string::npos) << result.output;
  EXPECT_NE(result.output.find("elements     1232\n"), std::string::npos) << result.output;
  // Longest x width 5 mm over the thinnest z layer 0.08 mm (0.002 * 0.2^2).
  EXPECT_NE(result.output.find("aspect ratio 62.5 max (crackle modal, check), 2.5 max (crackle run, sweep)"),
            std::string::npos) << result.output;
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
