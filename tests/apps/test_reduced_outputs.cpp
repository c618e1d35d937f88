// The reduced transient's outputs (transient.model: reduced) against the full explicit model on the
// same mesh: the crack-opening probe of a breathing cantilever (gap harmonics, mean, contact
// fraction, slip), the two faces' side probes, displacement snapshots of a slow load (the field
// recovered from the modes and the residual flexibility), and the cached reduction's key.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

/// A 10 x 2 x 1 cantilever of p = 1 with a half-depth edge crack from the top face at x = 0.04.
const std::string kBody = cli_testing::cantilever("[10, 2, 1]");

/// The forced tip load of cli_testing (150 Hz, the crack breathing every period). Probes at the crack
/// mouth: the opening of the pair there, and the two copies of its node.
const std::string kBreathing = cli_testing::forced_tip(R"(    - {name: mouth, crack_opening: [0.04, 0.01, 0.01]}
    - {name: lower, point: [0.04, 0.01, 0.01], side: lower, component: x}
    - {name: upper, point: [0.04, 0.01, 0.01], side: upper, component: x}
)");

/// A slow tip load (20 Hz, a tenth of f1) for one period from t = 0, snapshots at each quarter: the
/// first (load up: the top crack pressed shut) and the third (load down: open) are at the load's peaks.
const char* kSlow = R"(transient:
  model: full
  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 20.0, frequency: 20, ramp_periods: 0}
  damping: {ratio: 0.05, at: 200}
  periods: 1
  progress: false
  snapshots: {count: 4}
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
)";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-reduced-outputs-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

/// `crackle run` of kBody + `rest` with `arguments`, into scratch()/name; its output.
std::string crackle_run(const std::string& name, const std::string& rest, const std::string& arguments) {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << kBody << rest;
  const std::string command = "run " + scene.string() + " -o " + (scratch() / name).string() + " -q " + arguments;
  const cli_testing::Result result = cli_testing::crackle(command);
  EXPECT_EQ(result.exit_code, 0) << command << "\n" << result.output;
  return result.output;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// Every column of probes.csv by header, rows from `from_time` on.
std::map<std::string, std::vector<double>> read_probes(const std::string& name, double from_time) {
  std::ifstream in(scratch() / name / "probes.csv");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> headers;
  std::stringstream names(line);
  for (std::string header; std::getline(names, header, ',');) headers.push_back(header);
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::vector<double> row;
    for (std::string field; std::getline(fields, field, ',');) row.push_back(std::stod(field));
    if (row.empty() || row[0] < from_time) continue;
    for (std::size_t c = 0; c < headers.size() && c < row.size(); ++c) columns[headers[c]].push_back(row[c]);
  }
  return columns;
}

/// Amplitude of harmonic `order` (0: the mean) of a probe in spectrum.json.
double harmonic(const std::string& name, const std::string& probe, double order) {
  const nlohmann::json spectrum = read_json(scratch() / name / "spectrum.json");
  for (const nlohmann::json& entry : spectrum["probes"][probe]["harmonics"]) {
    if (entry["order"].get<double>() == order) return entry["amplitude"].get<double>();
  }
  ADD_FAILURE() << name << ": no harmonic " << order << " of " << probe;
  return 0.0;
}

double mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

double rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

/// The "displacement" point field of a VTU file of io::write_vtu (raw appended data, UInt64 headers).
std::vector<double> vtu_displacement(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::smatch match;
  const std::regex array("Name=\"displacement\" NumberOfComponents=\"3\" format=\"appended\" offset=\"([0-9]+)\"");
  if (!std::regex_search(text, match, array)) {
    ADD_FAILURE() << path << ": no displacement array";
    return {};
  }
  const std::size_t offset = std::stoull(match[1].str());
  const std::size_t data = text.find('_', text.find("<AppendedData encoding=\"raw\">")) + 1;
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, text.data() + data + offset, sizeof bytes);
  std::vector<double> values(bytes / sizeof(double));
  std::memcpy(values.data(), text.data() + data + offset + sizeof bytes, bytes);
  return values;
}

double relative_difference(const std::vector<double>& value, const std::vector<double>& reference) {
  EXPECT_EQ(value.size(), reference.size());
  double difference = 0.0, size = 0.0;
  for (std::size_t i = 0; i < value.size() && i < reference.size(); ++i) {
    difference += (value[i] - reference[i]) * (value[i] - reference[i]);
    size += reference[i] * reference[i];
  }
  return std::sqrt(difference / size);
}

/// The breathing runs of both models, once for the tests that read them.
void run_breathing_once() {
  static bool done = false;
  if (done) return;
  done = true;
  crackle_run("breathing-full", kBreathing, "");
  crackle_run("breathing-reduced", kBreathing, "--set transient.model=reduced");
}

constexpr double kSteadyFrom = 30.0 / 150.0;  // the last 10 periods [s]

}  // namespace

// With Coulomb friction on the crack (mu = 0.3), the reduced model's pair solve (semi-smooth Newton
// on the condensed pair equations) gives the opening probe and its stick/open states of the full
// model: the same signature targets, and the shares of open and stuck rows within 2 %.
TEST(ReducedOutputs, OpeningProbeWithFrictionMatchesTheFullModel) {
  const std::string rest = "  contact: {friction: 0.3}\n" + kBreathing;  // kBody ends with the crack
  crackle_run("friction-full", rest, "");
  crackle_run("friction-reduced", rest, "--set transient.model=reduced");
  const double a1_full = harmonic("friction-full", "mouth", 1), a1 = harmonic("friction-reduced", "mouth", 1);
  const double r2_full = harmonic("friction-full", "mouth", 2) / a1_full;
  const double r2 = harmonic("friction-reduced", "mouth", 2) / a1;
  auto full = read_probes("friction-full", kSteadyFrom), reduced = read_probes("friction-reduced", kSteadyFrom);
  const std::string state = "mouth state [0 open 1 stick 2 slip]";
  auto share = [&](const std::vector<double>& states, double value) {
    return static_cast<double>(std::count(states.begin(), states.end(), value)) / static_cast<double>(states.size());
  };
  std::printf("friction: gap A1 %.5e / %.5e, A2/A1 %.5f / %.5f, open %.4f / %.4f, stick %.4f / %.4f (reduced / full)\n",
              a1, a1_full, r2, r2_full, share(reduced[state], 0.0), share(full[state], 0.0), share(reduced[state], 1.0),
              share(full[state], 1.0));
  EXPECT_LT(std::abs(a1 / a1_full - 1.0), 1e-2);
  EXPECT_LT(std::abs(r2 / r2_full - 1.0), 2e-2);
  EXPECT_GT(share(full[state], 1.0), 0.1) << "the closed faces must stick";
  EXPECT_LT(std::abs(share(reduced[state], 0.0) - share(full[state], 0.0)), 2e-2);
  EXPECT_LT(std::abs(share(reduced[state], 1.0) - share(full[state], 1.0)), 2e-2);
  const nlohmann::json transient = read_json(scratch() / "friction-reduced" / "transient.json");
  EXPECT_EQ(transient["status"], "completed");
  EXPECT_GT(transient["penalty"]["friction"].get<double>(), 0.0);
}

// The reduced model's opening probe is the gap of one of its own pairs (g0 + B Phi q + R p + r_f a):
// its harmonics, mean and contact fraction meet the signature targets against the full model
// (A1 1 %, A2/A1 2 %, A3/A1 5 %), and the slip (a relative output row: the model is frictionless,
// so B has no tangential rows) follows the full model's too.
TEST(ReducedOutputs, OpeningProbeOfABreathingCantileverMatchesTheFullModel) {
  run_breathing_once();
  const double a1_full = harmonic("breathing-full", "mouth", 1), a1 = harmonic("breathing-reduced", "mouth", 1);
  const double mean_full = harmonic("breathing-full", "mouth", 0), mean_reduced = harmonic("breathing-reduced", "mouth", 0);
  const double r2_full = harmonic("breathing-full", "mouth", 2) / a1_full;
  const double r2 = harmonic("breathing-reduced", "mouth", 2) / a1;
  const double r3_full = harmonic("breathing-full", "mouth", 3) / a1_full;
  const double r3 = harmonic("breathing-reduced", "mouth", 3) / a1;
  auto full = read_probes("breathing-full", kSteadyFrom), reduced = read_probes("breathing-reduced", kSteadyFrom);
  const std::string state = "mouth state [0 open 1 stick 2 slip]";
  auto closed_fraction = [&](const std::vector<double>& states) {
    return static_cast<double>(std::count_if(states.begin(), states.end(), [](double s) { return s != 0.0; })) /
           static_cast<double>(states.size());
  };
  const double closed_full = closed_fraction(full[state]), closed = closed_fraction(reduced[state]);
  const double slip_full = rms(full["mouth slip_2 [m]"]), slip = rms(reduced["mouth slip_2 [m]"]);
  std::printf("gap: A1 %.5e / %.5e (%.2e), mean %.5e / %.5e (%.2e), A2/A1 %.5f / %.5f, A3/A1 %.5f / %.5f, "
              "closed %.4f / %.4f, rms slip_2 %.4e / %.4e (%.2e) (reduced / full)\n",
              a1, a1_full, a1 / a1_full - 1.0, mean_reduced, mean_full, mean_reduced / mean_full - 1.0, r2, r2_full,
              r3, r3_full, closed, closed_full, slip, slip_full, slip / slip_full - 1.0);
  EXPECT_LT(std::abs(a1 / a1_full - 1.0), 1e-2);
  EXPECT_LT(std::abs(mean_reduced / mean_full - 1.0), 2e-2);
  EXPECT_GT(r2_full, 0.2) << "the crack must breathe";
  EXPECT_LT(std::abs(r2 / r2_full - 1.0), 2e-2);
  EXPECT_LT(std::abs(r3 / r3_full - 1.0), 5e-2);
  EXPECT_GT(closed_full, 0.2);
  EXPECT_LT(closed_full, 0.8);
  EXPECT_LT(std::abs(closed - closed_full), 2e-2);
  EXPECT_GT(slip_full, 1e-3 * a1_full) << "the faces must slide";
  EXPECT_LT(std::abs(slip / slip_full - 1.0), 5e-2);
  // The state is the pair's: open exactly when its gap is not negative (frictionless: closed is slip).
  const std::vector<double>& gap = reduced["mouth gap [m]"];
  ASSERT_EQ(reduced[state].size(), gap.size());
  for (std::size_t i = 0; i < gap.size(); ++i) {
    ASSERT_EQ(reduced[state][i] == 0.0, gap[i] >= 0.0) << "row " << i << ": gap " << gap[i];
    ASSERT_NE(reduced[state][i], 1.0);
  }
  const nlohmann::json spectrum = read_json(scratch() / "breathing-reduced" / "spectrum.json");
  EXPECT_EQ(spectrum["probes"]["mouth"]["component"], "gap");
  const nlohmann::json transient = read_json(scratch() / "breathing-reduced" / "transient.json");
  EXPECT_EQ(transient["probes"][0]["kind"], "crack_opening");
  EXPECT_EQ(transient["probes"][0]["minus_node"], read_json(scratch() / "breathing-full" / "transient.json")["probes"][0]["minus_node"]);
}

// The side probes are the two copies of the mouth node: they part where the crack opens (their
// difference along n+ = x is the opening probe's gap, g0 = 0), and each follows the full model's.
TEST(ReducedOutputs, SideProbesSeeTheTwoFacesAsTheFullModel) {
  run_breathing_once();
  auto reduced = read_probes("breathing-reduced", 0.0);
  const std::vector<double>& gap = reduced["mouth gap [m]"];
  const std::vector<double>& lower = reduced["lower u_x [m]"];
  const std::vector<double>& upper = reduced["upper u_x [m]"];
  ASSERT_EQ(lower.size(), gap.size());
  const double opening = *std::max_element(gap.begin(), gap.end());
  double mismatch = 0.0, parted = 0.0;
  for (std::size_t i = 0; i < gap.size(); ++i) {
    mismatch = std::max(mismatch, std::abs(upper[i] - lower[i] - gap[i]));
    parted = std::max(parted, upper[i] - lower[i]);
  }
  const double lower_full = harmonic("breathing-full", "lower", 1), upper_full = harmonic("breathing-full", "upper", 1);
  const double lower_a1 = harmonic("breathing-reduced", "lower", 1), upper_a1 = harmonic("breathing-reduced", "upper", 1);
  std::printf("faces: largest opening %.4e m, parted %.4e m, |u+ - u- - g| <= %.1e m; A1 lower %.5e / %.5e, "
              "upper %.5e / %.5e (reduced / full)\n",
              opening, parted, mismatch, lower_a1, lower_full, upper_a1, upper_full);
  EXPECT_GT(opening, 1e-7);
  EXPECT_GT(parted, 0.99 * opening);
  EXPECT_LE(mismatch, 1e-9 * opening);
  EXPECT_GT(std::abs(upper_full / lower_full - 1.0), 0.1) << "the faces must move differently";
  EXPECT_LT(std::abs(lower_a1 / lower_full - 1.0), 1e-2);
  EXPECT_LT(std::abs(upper_a1 / upper_full - 1.0), 1e-2);
}

// A snapshot of the reduced model is its whole displacement field, u = Phi q + G_res (B^T p + f a):
// at the peaks of a slow load (crack shut, then open) it equals the full model's to 1e-3. The
// modes alone (residual_flexibility: false, here the one mode below 400 Hz) miss the static part.
TEST(ReducedOutputs, SnapshotsOfASlowLoadEqualTheFullModelsField) {
  crackle_run("slow-full", kSlow, "");
  crackle_run("slow-reduced", kSlow, "--set transient.model=reduced");
  crackle_run("slow-modes-only", kSlow, "--set transient.model=reduced --set transient.reduced.residual_flexibility=false");
  for (const char* snapshot : {"snapshot_0000.vtu", "snapshot_0002.vtu"}) {
    const std::vector<double> full = vtu_displacement(scratch() / "slow-full" / snapshot);
    const double error = relative_difference(vtu_displacement(scratch() / "slow-reduced" / snapshot), full);
    const double modes_only = relative_difference(vtu_displacement(scratch() / "slow-modes-only" / snapshot), full);
    std::printf("%s: relative difference to the full field %.2e, modes only %.2e\n", snapshot, error, modes_only);
    EXPECT_LT(error, 1e-3);
    EXPECT_GT(modes_only, 10.0 * error);
  }
  std::ifstream full_pvd(scratch() / "slow-full" / "snapshots.pvd"), reduced_pvd(scratch() / "slow-reduced" / "snapshots.pvd");
  const std::string full_text((std::istreambuf_iterator<char>(full_pvd)), std::istreambuf_iterator<char>());
  const std::string reduced_text((std::istreambuf_iterator<char>(reduced_pvd)), std::istreambuf_iterator<char>());
  const std::regex dataset("timestep=\"([0-9.e-]+)\"");
  std::vector<double> full_times, reduced_times;
  for (auto it = std::sregex_iterator(full_text.begin(), full_text.end(), dataset); it != std::sregex_iterator(); ++it)
    full_times.push_back(std::stod((*it)[1].str()));
  for (auto it = std::sregex_iterator(reduced_text.begin(), reduced_text.end(), dataset); it != std::sregex_iterator(); ++it)
    reduced_times.push_back(std::stod((*it)[1].str()));
  ASSERT_EQ(full_times.size(), 4u);
  ASSERT_EQ(reduced_times.size(), 4u);
  // Each model's snapshot k is at its step nearest k/4 of the run: the same time to one reduced step.
  const nlohmann::json transient = read_json(scratch() / "slow-reduced" / "transient.json");
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(reduced_times[k], full_times[k], transient["dt"].get<double>());
  EXPECT_TRUE(transient["snapshots"]["static_factor"].get<bool>());
}

// The cached reduction is keyed by its output rows: a reduction made for a node probe is not reused
// for a crack-opening probe at the same place (whose rows are the pair's relative motion), and the
// field of a snapshot needs no cached factor (it factors K itself).
TEST(ReducedOutputs, CacheKeepsReductionsOfDifferentOutputRowsApart) {
  const std::string cache = "--modal-cache " + (scratch() / "cache").string() + " --set transient.model=reduced";
  const std::string node = std::string(kSlow);
  std::string opening = node;
  opening.replace(opening.find("{name: tip, point:"), 18, "{name: tip, crack_opening:");
  opening.replace(opening.find("[0.2, 0.01, 0.01]}"), 18, "[0.04, 0.01, 0.01]}");
  auto cached = [](const std::string& name) {
    return read_json(scratch() / name / "transient.json")["reduction_cached"].get<bool>();
  };
  crackle_run("cache-node", node, cache);
  crackle_run("cache-opening", opening, cache);
  crackle_run("cache-opening-again", opening, cache);
  crackle_run("cache-node-again", node, cache);
  EXPECT_FALSE(cached("cache-node"));
  EXPECT_FALSE(cached("cache-opening")) << "a node probe's reduction reused for an opening probe";
  EXPECT_TRUE(cached("cache-opening-again"));
  EXPECT_TRUE(cached("cache-node-again"));
  const std::vector<double> fresh = vtu_displacement(scratch() / "cache-node" / "snapshot_0002.vtu");
  const std::vector<double> from_cache = vtu_displacement(scratch() / "cache-node-again" / "snapshot_0002.vtu");
  EXPECT_LT(relative_difference(from_cache, fresh), 1e-12);
  EXPECT_TRUE(read_json(scratch() / "cache-node-again" / "transient.json")["snapshots"]["static_factor"].get<bool>());
  auto columns = read_probes("cache-opening", 0.0);
  EXPECT_FALSE(columns["tip gap [m]"].empty());
  EXPECT_FALSE(columns["tip slip_1 [m]"].empty());
}
