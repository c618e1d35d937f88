// End to end, the sub-harmonic resonance of data/subharmonic.yaml (a 3D cantilever with a deep
// breathing crack, reduced model): near 2 f_b `crackle sweep` finds the period doubling of the
// period-one branch (Floquet multipliers by the monodromy, confirmed by Hill's method) and, with
// `subharmonic: 2`, the period-two branch; its A1/2 equals the reduced transient's (`crackle run`)
// and the stepped-sine sweep's, which settle on the f/2 response where that branch is stable.
#include <gtest/gtest.h>
#include <unistd.h>

#include "cli_testing.hpp"
#include "identify/forward.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

using Table = std::map<std::string, std::vector<double>>;

const std::string kHalf = "tip u_z A1/2 [m]";
const std::string kFrequency = "excitation frequency [Hz]";
const std::string kStable = "stable [1 yes, 0 no, -1 not computed]";
const std::string kPeriod = "branch period [excitation periods]";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-subharmonic-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

/// `crackle COMMAND data/subharmonic.yaml -o scratch/NAME -q OVERRIDES` with a shared modal cache.
void run(const std::string& command, const std::string& name, const std::string& overrides) {
  const cli_testing::Result result =
      cli_testing::crackle(command + " " + cli_testing::data("subharmonic.yaml") + " -o " + (scratch() / name).string() +
                           " -q --modal-cache " + (scratch() / "cache").string() + " " + overrides);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// The fields of one CSV line (RFC 4180 quoting: headers such as "stable [1 yes, 0 no, ...]").
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (line[i] == '"') {
      if (quoted && i + 1 < line.size() && line[i + 1] == '"') fields.back() += line[++i];
      else quoted = !quoted;
    } else if (line[i] == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += line[i];
    }
  }
  return fields;
}

Table read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> headers = csv_fields(line);
  Table columns;
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = csv_fields(line);
    for (std::size_t i = 0; i < fields.size() && i < headers.size(); ++i) columns[headers[i]].push_back(std::stod(fields[i]));
  }
  return columns;
}

/// A1/2 of the stable period-two branch at `hz`, interpolated between two consecutive stable
/// period-two points around it; NaN where no stable stretch of that branch covers `hz`.
double period_two_half(const Table& branch, double hz) {
  const std::vector<double>& f = branch.at(kFrequency);
  for (std::size_t i = 0; i + 1 < f.size(); ++i) {
    const bool stable_two = branch.at(kPeriod)[i] == 2 && branch.at(kPeriod)[i + 1] == 2 &&
                            branch.at(kStable)[i] == 1 && branch.at(kStable)[i + 1] == 1;
    if (stable_two && std::min(f[i], f[i + 1]) <= hz && hz <= std::max(f[i], f[i + 1]) && f[i] != f[i + 1]) {
      const double a = branch.at(kHalf)[i], b = branch.at(kHalf)[i + 1];
      return a + (b - a) * (hz - f[i]) / (f[i + 1] - f[i]);
    }
  }
  return std::nan("");
}

/// Whether the period-one branch is unstable at `hz` (both points around it).
bool period_one_unstable(const Table& branch, double hz) {
  const std::vector<double>& f = branch.at(kFrequency);
  for (std::size_t i = 0; i + 1 < f.size(); ++i)
    if (branch.at(kPeriod)[i] == 1 && branch.at(kPeriod)[i + 1] == 1 && f[i] <= hz && hz <= f[i + 1])
      return branch.at(kStable)[i] == 0 && branch.at(kStable)[i + 1] == 0;
  return false;
}

TEST(SweepSubharmonic, PeriodDoublingAndThePeriodTwoBranchMatchTheReducedTransient) {
  // The reduced transient at 2 f_b first: the sweep solves each branch at its excitation frequency too
  // (sweep.solve_at), where identify reads A1/2/A1 (identify::subharmonic_value).
  run("run", "transient", "");
  const nlohmann::json spectrum = read_json(scratch() / "transient" / "spectrum.json");
  const double hz = spectrum["excitation_hz"];
  char solve_at[64];
  std::snprintf(solve_at, sizeof solve_at, "%.17g", hz);
  run("sweep", "hb", std::string("--set 'sweep.solve_at=[") + solve_at + "]'");
  const nlohmann::json sweep = read_json(scratch() / "hb" / "sweep.json");
  const Table branch = read_csv(scratch() / "hb" / "sweep.csv");
  const double bilinear = sweep["bilinear_hz"];
  EXPECT_TRUE(sweep["completed"].get<bool>());
  // (a) the period-one branch doubles its period around 2 f_b, on both sides, with Hill's agreement
  std::vector<double> doublings;
  for (const nlohmann::json& event : sweep["events"]) {
    if (event["kind"] != "period_doubling") continue;
    EXPECT_TRUE(event.value("hill_agrees", false)) << event.dump();
    doublings.push_back(event["frequency_hz"].get<double>() / bilinear);
  }
  ASSERT_GE(doublings.size(), 2u) << sweep["events"].dump();
  std::printf("  period doublings at %.4f and %.4f f_b\n", doublings.front(), doublings.back());
  EXPECT_GT(doublings.front(), 1.75);
  EXPECT_LT(doublings.front(), 1.95);
  EXPECT_GT(doublings.back(), 2.05);
  EXPECT_LT(doublings.back(), 2.2);

  // (b) the reduced transient at 2 f_b settles on a clear f/2 response; the period-two branch has its A1/2
  ASSERT_TRUE(spectrum["steady_state"]["settled"].get<bool>()) << spectrum["steady_state"].dump();
  const nlohmann::json& indices = spectrum["probes"]["tip"]["indices"];
  EXPECT_GT(indices["A1/2/A1"].get<double>(), 2.0) << indices.dump();
  double transient_half = 0.0;
  for (const nlohmann::json& harmonic : spectrum["probes"]["tip"]["harmonics"])
    if (harmonic["order"].get<double>() == 0.5) transient_half = harmonic["amplitude"];
  EXPECT_TRUE(period_one_unstable(branch, hz)) << hz << " Hz";
  const double balance_half = period_two_half(branch, hz);
  std::printf("  %.3f Hz A1/2: period-two branch %.6e, reduced transient %.6e (%+.2e)\n", hz, balance_half,
              transient_half, balance_half / transient_half - 1.0);
  EXPECT_NEAR(balance_half / transient_half, 1.0, 0.05);
  // identify's reading of the sweep: a row of each branch at the excitation frequency itself (solve_at);
  // A1/2/A1 on the stable period-two branch there, as the transient's
  const crackle::identify::SweepTable table = crackle::identify::read_sweep_csv(scratch() / "hb" / "sweep.csv");
  int at_hz = 0;
  for (const std::vector<double>& row : table.rows) at_hz += std::abs(row[0] - hz) <= 1e-12 * hz;
  EXPECT_EQ(at_hz, 2) << "the period-one and the period-two branch each solved at " << solve_at << " Hz";
  EXPECT_TRUE(crackle::identify::period_two_exists(table, hz));
  const double identify_ratio = crackle::identify::subharmonic_value(table, "tip", hz);
  std::printf("  %.3f Hz A1/2/A1: identify's reading %.6f, reduced transient %.6f\n", hz, identify_ratio,
              indices["A1/2/A1"].get<double>());
  EXPECT_NEAR(identify_ratio / indices["A1/2/A1"].get<double>(), 1.0, 0.05);

  // the stepped sine (reduced transient at each frequency, up then down) shows the f/2 response where
  // the period-two branch is stable and the period-one branch is not
  run("sweep", "stepped", "--set sweep.method=stepped_sine --set sweep.points=3 --set sweep.harmonics=6 "
                          "--set sweep.frequency.from.ratio=1.9 --set sweep.frequency.to.ratio=2.1 "
                          "--set sweep.tolerance=1e-5");
  const Table stepped = read_csv(scratch() / "stepped" / "sweep.csv");
  ASSERT_EQ(stepped.at(kFrequency).size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    const double f = stepped.at(kFrequency)[i], half = stepped.at(kHalf)[i];
    const double expected = period_two_half(branch, f);
    std::printf("  %.3f Hz (%s) A1/2: stepped sine %.6e, period-two branch %.6e\n", f, i < 3 ? "up" : "down", half,
                expected);
    ASSERT_FALSE(std::isnan(expected)) << f << " Hz: no stable period-two point there";
    EXPECT_TRUE(period_one_unstable(branch, f)) << f << " Hz";
    EXPECT_GT(half, stepped.at("tip u_z A1 [m]")[i]) << f << " Hz";
    EXPECT_NEAR(half / expected, 1.0, 0.05) << f << " Hz";
  }
}

}  // namespace
