// Stability of the crack contact in free vibration (issue 15, part 2): the plucked cantilever with a
// breathing edge crack, no damping, released from the static deflection under a tip load, over more
// than 20 closures with penalties 0.01-100 x the automatic one, for both contact integrations. The
// energy balance must stay below the run's tolerance (the health check stops the run at 5 %) and
// the breathing must not be lost to chatter.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

/// The deep cracked cantilever of cli_testing (f1 about 740 Hz), no damping.
std::string scene_text(const std::string& integration, const std::string& penalty) {
  return cli_testing::deep_cracked_cantilever() + "  contact: {integration: " + integration + ", penalty: " + penalty +
         "}\n" + R"(transient:
  model: full
  release:
    static: {point: [0.2, 0.01, 0.04], direction: z, amplitude: 2000}
  duration: 0.032
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.04]}
spectrum: {harmonics: 3, subharmonics: false, plots: false}
)";
}

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-stability-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

struct Outcome {
  int exit_code = -1;
  std::string log;
  nlohmann::json transient;
  int closures = 0;  ///< rises of the stored contact energy from zero (energy.csv rows)
};

Outcome run(const std::string& name, const std::string& integration, const std::string& penalty) {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << scene_text(integration, penalty);
  const fs::path out = scratch() / name;
  const cli_testing::Result result = cli_testing::crackle("run " + scene.string() + " -o " + out.string() + " -q");
  Outcome outcome;
  outcome.exit_code = result.exit_code;
  outcome.log = result.output;
  std::ifstream json(out / "transient.json");
  if (json) outcome.transient = nlohmann::json::parse(json);
  std::ifstream energy(out / "energy.csv");
  std::string line;
  std::getline(energy, line);
  int column = -1;
  {
    std::stringstream names(line);
    std::string header;
    for (int c = 0; std::getline(names, header, ','); ++c) {
      if (header == "contact [J]") column = c;
    }
  }
  bool closed = false;
  while (column >= 0 && std::getline(energy, line)) {
    std::stringstream fields(line);
    std::string field;
    for (int c = 0; std::getline(fields, field, ','); ++c) {
      if (c != column) continue;
      const bool now = std::stod(field) > 0.0;
      if (now && !closed) ++outcome.closures;
      closed = now;
    }
  }
  return outcome;
}

void check_stable_over_penalties(const std::string& integration) {
  const Outcome automatic = run(integration + "-auto", integration, "auto");
  ASSERT_EQ(automatic.exit_code, 0) << automatic.log;
  const double penalty_auto = automatic.transient.at("penalty").get<double>();
  for (double multiple : {0.01, 0.1, 1.0, 10.0, 100.0}) {
    char penalty[32];
    std::snprintf(penalty, sizeof penalty, "%.6e", multiple * penalty_auto);
    const Outcome outcome = run(integration + "-" + std::to_string(multiple), integration, penalty);
    ASSERT_EQ(outcome.exit_code, 0) << integration << " x" << multiple << ": " << outcome.log;
    const nlohmann::json& t = outcome.transient;
    const double error = t.at("energy_error").get<double>();
    std::printf("%s contact, penalty %g x auto (%.3e Pa/m): %lld steps of %.3e s, energy error %.2e, closures %d, "
                "closed fraction %.3f, %.2f s\n",
                integration.c_str(), multiple, t.at("penalty").get<double>(), t.at("steps").get<long long>(),
                t.at("dt").get<double>(), error, outcome.closures, t.at("contact_fraction").get<double>(),
                t.at("wall_s").get<double>());
    EXPECT_EQ(t.at("status"), "completed");
    EXPECT_LT(error, 0.05) << "the run's energy tolerance";
    // Measured: at most 2.3e-2 (implicit at 0.01 x auto: its inelastic pair impacts lose energy) and
    // 5.5e-3 (explicit at 100 x auto).
    EXPECT_LT(error, 0.03);
    // The release opens the crack; it closes once per period (f1 about 740 Hz over 0.032 s), more
    // often where pairs bounce on stiff explicit springs.
    EXPECT_GE(outcome.closures, 20);
    // Breathing, not stuck open or shut: the crack is closed 15-55 % of the time (measured 0.43 implicit;
    // 0.49 down to 0.18 explicit, whose stiff springs let the lumped pair masses bounce).
    EXPECT_GT(t.at("contact_fraction").get<double>(), 0.15);
    EXPECT_LT(t.at("contact_fraction").get<double>(), 0.55);
  }
}

}  // namespace

TEST(ContactStability, ImplicitPenaltyStaysBalancedOverTwentyClosures) { check_stable_over_penalties("implicit"); }

TEST(ContactStability, ExplicitPenaltyStaysBalancedOverTwentyClosures) { check_stable_over_penalties("explicit"); }
