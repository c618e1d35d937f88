// Probes that see the crack (issue 15, part 3): the crack-opening probe against the two faces' point
// probes (side: lower / upper) on the plucked cracked cantilever, its contact state against its gap,
// its spectrum, and the errors for probes that cannot see a crack.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

/// The deep cracked cantilever of cli_testing (f1 about 740 Hz) with friction and an initial gap,
/// plucked by a static tip load.
std::string scene_text(const std::string& probes, const std::string& extra = "") {
  return cli_testing::deep_cracked_cantilever() + "  gap: 2.0e-7\n  contact: {friction: 0.3}\n" + R"(transient:
  model: full
  release:
    static: {point: [0.2, 0.01, 0.04], direction: z, amplitude: 2000}
  duration: 0.02
  progress: false
  probes:
)" + probes + extra + "spectrum: {harmonics: 3, subharmonics: false, plots: false}\n";
}

const std::string kProbes = R"(    - {name: mouth, crack_opening: [0.041, 0.001, 0.039]}
    - {name: lower, point: [0.04, 0.0, 0.04], side: lower}
    - {name: upper, point: [0.04, 0.0, 0.04], side: upper}
)";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-crack-probes-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

cli_testing::Result run(const std::string& name, const std::string& text, const std::string& arguments = "") {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << text;
  return cli_testing::crackle("run " + scene.string() + " -o " + (scratch() / name).string() + " -q " + arguments);
}

/// Every column of a CSV file by header.
std::map<std::string, std::vector<double>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> headers;
  std::stringstream names(line);
  for (std::string name; std::getline(names, name, ',');) headers.push_back(name);
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string field;
    for (std::size_t c = 0; std::getline(fields, field, ',') && c < headers.size(); ++c) {
      columns[headers[c]].push_back(std::stod(field));
    }
  }
  return columns;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace

// g_N = g0 + (u_upper - u_lower) . n+ at every row (n+ = +x), with the lower and upper copies of the
// mouth node chosen by side; the state is open exactly when g_N >= 0, and closed pairs penetrate
// less than the penalty allows; the gap's ring-down has the breathing harmonics.
TEST(CrackProbes, OpeningEqualsTheFacesDifferenceAndItsStateFollowsTheGap) {
  for (const std::string integration : {"implicit", "explicit"}) {
    const std::string name = "opening-" + integration;
    const cli_testing::Result result = run(name, scene_text(kProbes), "--set crack.contact.integration=" + integration);
    ASSERT_EQ(result.exit_code, 0) << result.output;
    auto columns = read_csv(scratch() / name / "probes.csv");
    const std::vector<double>& gap = columns["mouth gap [m]"];
    const std::vector<double>& state = columns["mouth state [0 open 1 stick 2 slip]"];
    const std::vector<double>& lower = columns["lower u_x [m]"];
    const std::vector<double>& upper = columns["upper u_x [m]"];
    ASSERT_GT(gap.size(), 1000u);
    ASSERT_EQ(columns["mouth slip_1 [m]"].size(), gap.size());
    ASSERT_EQ(columns["mouth gap_rate [m/s]"].size(), gap.size());
    ASSERT_EQ(state.size(), gap.size());
    const double opening = *std::max_element(gap.begin(), gap.end());
    double mismatch = 0.0, penetration = 0.0;
    int open = 0, stick = 0, slip = 0, wrong_state = 0;
    for (std::size_t i = 0; i < gap.size(); ++i) {
      mismatch = std::max(mismatch, std::abs(gap[i] - (2.0e-7 + upper[i] - lower[i])));
      penetration = std::max(penetration, -gap[i]);
      open += state[i] == 0.0;
      stick += state[i] == 1.0;
      slip += state[i] == 2.0;
      if ((state[i] == 0.0) != (gap[i] >= 0.0)) ++wrong_state;
    }
    std::printf("%s: %zu rows, largest opening %.3e m, deepest penetration %.3e m, |g - (g0 + du.n)| <= %.1e m, "
                "open %d stick %d slip %d rows\n",
                integration.c_str(), gap.size(), opening, penetration, mismatch, open, stick, slip);
    EXPECT_LE(mismatch, 1e-12 * opening);
    EXPECT_GT(opening, 1e-5);
    EXPECT_GT(penetration, 0.0) << "the crack must close";
    // Penetration tolerance: p/eps_N. Measured 3.1e-9 m implicit (1000 E/h), 3.2e-6 m explicit (E/h).
    EXPECT_LT(penetration, (integration == "implicit" ? 1e-3 : 0.2) * opening);
    EXPECT_EQ(wrong_state, 0);
    EXPECT_GT(open, 0);
    EXPECT_GT(stick, 0);
    EXPECT_GT(slip, 0);
    const nlohmann::json spectrum = read_json(scratch() / name / "spectrum.json");
    const nlohmann::json& mouth = spectrum["probes"]["mouth"];
    EXPECT_EQ(mouth["component"], "gap");
    // A half-wave-rectified opening: strong second and third harmonics (measured A2/A1 = 0.29).
    const nlohmann::json& harmonics = mouth["ringdown"]["harmonics"];
    ASSERT_GE(harmonics.size(), 3u);
    EXPECT_GT(harmonics[1]["relative_amplitude"].get<double>(), 0.1);
    EXPECT_GT(harmonics[2]["relative_amplitude"].get<double>(), 0.01);
    // The two sides are different nodes at the same point.
    const nlohmann::json transient = read_json(scratch() / name / "transient.json");
    const nlohmann::json& probes = transient["probes"];
    ASSERT_EQ(probes.size(), 3u);
    EXPECT_NE(probes[1]["node"], probes[2]["node"]);
    EXPECT_EQ(probes[1]["node_point"], probes[2]["node_point"]);
    EXPECT_EQ(probes[0]["node"], probes[1]["node"]) << "the opening's plus node is the lower copy";
    EXPECT_EQ(probes[0]["minus_node"], probes[2]["node"]);
  }
}

// Probes that cannot see a crack are refused with the key and its line.
TEST(CrackProbes, BadCrackProbesAreRefusedWithTheirKey) {
  struct Case {
    std::string name, text, expected;
  };
  const std::string uncracked = R"(mesh:
  box: {size: [0.2, 0.02, 0.04], cells: [10, 1, 2], order: 1}
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
boundary:
  - {face: x-, fix: [x, y, z]}
transient:
  model: full
  duration: 0.001
  progress: false
  probes:
    - {name: mouth, crack_opening: [0.04, 0.0, 0.04]}
)";
  const auto as_reduced = [](std::string text) {
    text.replace(text.find("model: full"), 11, "model: reduced");
    return text;
  };
  const std::vector<Case> cases = {
      {"uncracked", uncracked, "transient.probes[0].crack_opening: expected a scene with a crack"},
      {"away", scene_text("    - {name: tip, point: [0.2, 0.01, 0.04], side: upper}\n"),
       "bad-away.yaml:18: transient.probes[0].side: expected a point on a crack face"},
      {"tied", scene_text(kProbes, "  variant: uncracked\n"),
       "transient.probes[0].crack_opening: expected transient.variant: open"},
      {"tied-reduced", as_reduced(scene_text(kProbes, "  variant: uncracked\n")),
       "transient.probes[0].crack_opening: expected transient.variant: open"},
      {"component", scene_text("    - {name: mouth, crack_opening: [0.04, 0.0, 0.04], component: z}\n"),
       "transient.probes[0].component: expected no component with crack_opening"},
      {"both", scene_text("    - {name: mouth, crack_opening: [0.04, 0.0, 0.04], point: [0.04, 0.0, 0.04]}\n"),
       "transient.probes[0]: expected exactly one of point, crack_opening"},
  };
  for (const Case& c : cases) {
    const cli_testing::Result result = run("bad-" + c.name, c.text);
    EXPECT_EQ(result.exit_code, 2) << c.name << ": " << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << c.name << ": " << result.output;
  }
}
