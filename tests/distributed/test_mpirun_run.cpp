/// `crackle run` under `mpirun -np 2` (issue 17) against the same command on one process: the same
/// files (probes.csv to 1e-12 relative, energy.csv, dt), transient.json with ranks = 2 and the
/// partition's balance; node-set loads, a static release and initial fields with their one-process
/// totals; snapshots as .pvtu pieces; one error line and the same exit code on every rank.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};

/// Runs `crackle ARGUMENTS` on `ranks` processes (mpirun -np ranks; 0: without mpirun), within a
/// time limit so that a hang fails the test instead of blocking it. With `each_exit_code`, every
/// rank also prints "rank exit code N" after crackle ends.
Result crackle(int ranks, const std::string& arguments, bool each_exit_code = false) {
  std::string command = "timeout 120 ";
  if (ranks > 0) command += std::string(MPIEXEC) + " --allow-run-as-root --oversubscribe -np " + std::to_string(ranks) + " ";
  const std::string program = std::string(CRACKLE_BINARY_DIR) + "/apps/crackle " + arguments;
  command += each_exit_code ? "sh -c '" + program + "; echo rank exit code $?'" : program;
  command += " 2>&1";
  Result result;
  FILE* pipe = popen(("OMP_NUM_THREADS=1 " + command).c_str(), "r");
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

fs::path temporary(const std::string& name) {
  return fs::temp_directory_path() / ("crackle-mpirun-" + name + "-" + std::to_string(::getpid()));
}

fs::path write_scene(const std::string& name, const std::string& text) {
  const fs::path path = temporary(name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

/// A CSV file as columns (header names, then the values).
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
};

Table read_csv(const fs::path& path) {
  Table table;
  std::ifstream file(path);
  std::string line;
  std::getline(file, line);
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ',');) table.names.push_back(name);
  table.columns.resize(table.names.size());
  while (std::getline(file, line)) {
    std::stringstream row(line);
    std::string cell;
    for (std::size_t c = 0; c < table.columns.size() && std::getline(row, cell, ','); ++c)
      table.columns[c].push_back(std::stod(cell));
  }
  return table;
}

/// The largest |a - b| over columns [first, first + count) relative to their largest |b|.
double group_difference(const Table& a, const Table& b, std::size_t first, std::size_t count) {
  double scale = 0.0, difference = 0.0;
  for (std::size_t c = first; c < first + count && c < a.columns.size() && c < b.columns.size(); ++c) {
    EXPECT_EQ(a.columns[c].size(), b.columns[c].size()) << a.names[c];
    for (std::size_t r = 0; r < a.columns[c].size() && r < b.columns[c].size(); ++r) {
      scale = std::max(scale, std::abs(b.columns[c][r]));
      difference = std::max(difference, std::abs(a.columns[c][r] - b.columns[c][r]));
    }
  }
  return scale > 0.0 ? difference / scale : difference;
}

/// probes.csv of two runs: per probe, the worst difference of its displacements (u_x, u_y, u_z or
/// gap, slip_1, slip_2), velocities and accelerations, each relative to the largest of the three
/// (a component that is only rounding noise is not a scale); contact states must be equal.
std::array<double, 3> probe_differences(const Table& a, const Table& b) {
  EXPECT_EQ(a.names, b.names);
  std::array<double, 3> worst{0.0, 0.0, 0.0};
  for (std::size_t c = 1; c + 9 <= a.columns.size();) {
    for (int q = 0; q < 3; ++q) worst[q] = std::max(worst[q], group_difference(a, b, c + 3 * q, 3));
    c += 9;
    if (c < a.names.size() && a.names[c].find(" state [") != std::string::npos) {
      EXPECT_EQ(a.columns[c], b.columns[c]) << a.names[c];
      ++c;
    }
  }
  return worst;
}

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(std::ifstream(path)); }

/// Runs a scene on 1 process and on 2 ranks (with `two_rank_options` appended); returns the two
/// output folders.
std::array<fs::path, 2> run_both(const std::string& name, const std::string& scene_text,
                                 const std::string& two_rank_options = "") {
  const fs::path scene = write_scene(name, scene_text);
  const std::array<fs::path, 2> out{temporary(name + "-1"), temporary(name + "-2")};
  for (int k = 0; k < 2; ++k) {
    fs::remove_all(out[k]);
    const Result result =
        crackle(k == 0 ? 0 : 2, "run " + scene.string() + " -o " + out[k].string() + " -q" + (k == 0 ? "" : two_rank_options));
    EXPECT_EQ(result.exit_code, 0) << result.output;
  }
  fs::remove(scene);
  return out;
}

/// Probes, energies and dt agree; transient.json says 2 ranks and gives the partition's balance.
void expect_same_run(const std::array<fs::path, 2>& out, bool overlapped = false) {
  const std::array<double, 3> probes = probe_differences(read_csv(out[1] / "probes.csv"), read_csv(out[0] / "probes.csv"));
  const Table energy_two = read_csv(out[1] / "energy.csv"), energy_one = read_csv(out[0] / "energy.csv");
  ASSERT_EQ(energy_two.names, energy_one.names);
  const double energy = group_difference(energy_two, energy_one, 1, energy_two.names.size() - 2);  // J columns
  double relative_error = 0.0;  // absolute: rounding itself in a linear run
  const std::vector<double>& error_two = energy_two.columns.back();
  const std::vector<double>& error_one = energy_one.columns.back();
  for (std::size_t r = 0; r < error_two.size() && r < error_one.size(); ++r)
    relative_error = std::max(relative_error, std::abs(error_two[r] - error_one[r]));
  std::printf("%s: probes.csv u %.2e v %.2e a %.2e, energy.csv %.2e (of the largest energy), relative_error %.2e (absolute)\n",
              out[0].filename().c_str(), probes[0], probes[1], probes[2], energy, relative_error);
  // As the library's test (tests/distributed/test_distributed.cpp): displacements to 1e-12, their
  // differences over dt (velocities) and over dt again (accelerations) amplify the rounding.
  EXPECT_LT(probes[0], 1e-12);
  EXPECT_LT(probes[1], 1e-11);
  EXPECT_LT(probes[2], 1e-9);
  EXPECT_LT(energy, 1e-11);
  EXPECT_LT(relative_error, 1e-9);
  const nlohmann::json one = read_json(out[0] / "transient.json"), two = read_json(out[1] / "transient.json");
  EXPECT_EQ(one["ranks"], 1);
  EXPECT_EQ(two["ranks"], 2);
  EXPECT_EQ(one["steps"], two["steps"]);
  EXPECT_EQ(one["dofs"], two["dofs"]);
  EXPECT_EQ(one["elements"], two["elements"]);
  EXPECT_NEAR(two["dt"].get<double>() / one["dt"].get<double>(), 1.0, 1e-12);
  ASSERT_TRUE(two.contains("partition"));
  const nlohmann::json& partition = two["partition"];
  EXPECT_EQ(partition["ranks"], 2);
  EXPECT_NEAR(2.0 * partition["elements"]["mean"].get<double>(), one["elements"].get<double>(), 1e-9);
  EXPECT_NEAR(2.0 * partition["owned_dofs"]["mean"].get<double>(), one["dofs"].get<double>(), 1e-9);
  EXPECT_GT(partition["halo_bytes_per_step"]["max"].get<double>(), 0.0);
  // Some elements of each rank touch the other's nodes (those go first when the halo is overlapped).
  EXPECT_GT(partition["boundary_elements"]["min"].get<double>(), 0.0);
  EXPECT_LT(partition["boundary_elements"]["max"].get<double>(), partition["elements"]["min"].get<double>());
  EXPECT_EQ(one["halo_overlapped"], false);
  EXPECT_EQ(two["halo_overlapped"], overlapped);  // -crackle_halo_overlap
  EXPECT_TRUE(fs::exists(out[1] / "run.json"));
  // Nothing from rank 1 besides the files rank 0 writes: no stray per-rank files.
  for (const auto& entry : fs::directory_iterator(out[1])) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
  }
}

/// A steel cantilever 0.2 x 0.02 x 0.04 m clamped at x = 0 with a half-depth edge crack from the
/// top at x = 0.04 (p = 1, 20 x 2 x 4 cells, 1 000 DOFs): the scene up to crack.region.
std::string cracked_cantilever() {
  return R"(mesh:
  box: {size: [0.2, 0.02, 0.04], cells: [20, 2, 4], order: 1, grading: none}
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
boundary:
  - {face: x-, fix: [x, y, z]}
crack:
  plane: {normal: x, at: 0.04}
  region: {y: [0.0, 0.02], z: [0.02, 0.04]}
)";
}

/// The chattering cantilever: cracked_cantilever() driven at its tip near the first bending
/// resonance, friction on the crack faces.
std::string chattering_cantilever(const std::string& extra) {
  return cracked_cantilever() + R"(  contact: {friction: 0.3}
transient:
  model: full
  excitation: {face: x+, direction: z, amplitude: 200.0, frequency: {hz: 700.0}}
  periods: 4
  progress: false
  history: {samples_per_period: all}
  probes:
    - {name: tip, point: [0.2, 0.01, 0.04]}
    - {name: root, point: [0.04, 0.0, 0.04]}
    - {name: opening, crack_opening: [0.04, 0.01, 0.035]}
)" + extra;
}

TEST(MpirunRun, ChatteringCrackWithFrictionSameFilesAsOneProcess) {
  // With the halo overlapped with the interior elements (off by default).
  const std::array<fs::path, 2> out = run_both("chatter", chattering_cantilever(""), " -- -crackle_halo_overlap");
  // The crack breathes and slides: the opening probe's state column has open, stick and slip rows.
  const Table probes = read_csv(out[1] / "probes.csv");
  const std::vector<double>& state = probes.columns.back();
  EXPECT_EQ(probes.names.back(), "opening state [0 open 1 stick 2 slip]");
  EXPECT_GT(std::count(state.begin(), state.end(), 0.0), 0);
  EXPECT_GT(std::count(state.begin(), state.end(), 2.0), 0);
  EXPECT_GE(probes.columns.front().size(), 2000u);  // 2000 steps and more
  const Table energy = read_csv(out[1] / "energy.csv");
  EXPECT_GT(energy.columns[6].back(), 0.0);  // friction dissipated
  expect_same_run(out, true);
  const nlohmann::json two = read_json(out[1] / "transient.json");
  EXPECT_GT(two["contact_fraction"].get<double>(), 0.0);
  EXPECT_LT(two["contact_fraction"].get<double>(), 1.0);
  for (const fs::path& folder : out) fs::remove_all(folder);
}

TEST(MpirunRun, ModalStageAndSpectrumAsOneProcess) {
  // The excitation at the bilinear frequency of mode 1 and the damping at mode 1: a modal stage.
  std::string scene_text =
      chattering_cantilever("spectrum: {harmonics: 3, subharmonics: false, steady_state: {window_periods: 1}}\n");
  const std::string hz = "frequency: {hz: 700.0}";
  scene_text.replace(scene_text.find(hz), hz.size(), "frequency: {mode: 1, of: bilinear}");
  scene_text.replace(scene_text.find("  periods: 4"), 12, "  periods: 2\n  damping: {ratio: 0.01, at: {mode: 1}}");
  const fs::path scene = write_scene("modal", scene_text);
  const fs::path cache = temporary("modal-cache");
  const std::array<fs::path, 3> out{temporary("modal-1"), temporary("modal-2"), temporary("modal-2-solved")};
  // One process solves the modes into the cache; 2 ranks read them from it, then solve them (SLEPc
  // with MUMPS over the ranks instead of CHOLMOD: the frequency differs by rounding).
  // SLEPc in all three (modal.solver: auto would take ARPACK on one process, whose cache entry the
  // ranks do not share).
  const std::array<std::string, 3> runs{"--set modal.solver=slepc --modal-cache " + cache.string(),
                                        "--set modal.solver=slepc --modal-cache " + cache.string(), "--set modal.solver=slepc"};
  for (int k = 0; k < 3; ++k) {
    fs::remove_all(out[k]);
    const Result result = crackle(k == 0 ? 0 : 2, "run " + scene.string() + " -o " + out[k].string() + " -q " + runs[k]);
    ASSERT_EQ(result.exit_code, 0) << result.output;
    EXPECT_TRUE(fs::exists(out[k] / "modal.json"));
  }
  expect_same_run({out[0], out[1]});
  const nlohmann::json one = read_json(out[0] / "spectrum.json");
  for (int k = 1; k < 3; ++k) {
    const nlohmann::json two = read_json(out[k] / "spectrum.json");
    const double f1 = read_json(out[0] / "run.json")["excitation_hz"], f2 = read_json(out[k] / "run.json")["excitation_hz"];
    EXPECT_NEAR(f2 / f1, 1.0, k == 1 ? 0.0 : 1e-10);
    for (const std::string probe : {"tip", "root", "opening"}) {
      const nlohmann::json& a = one["probes"][probe]["harmonics"];
      const nlohmann::json& b = two["probes"][probe]["harmonics"];
      ASSERT_EQ(a.size(), b.size()) << probe;
      for (std::size_t h = 0; h < a.size(); ++h) {
        const double reference = a[h]["amplitude"].get<double>();
        EXPECT_NEAR(b[h]["amplitude"].get<double>(), reference, 1e-8 * std::abs(reference) + 1e-20) << probe << " " << h;
      }
    }
  }
  for (const fs::path& path : {scene, cache, out[0], out[1], out[2]}) fs::remove_all(path);
}

TEST(MpirunRun, NodeSetLoadAndInitialFieldKeepTheirTotals) {
  // A Gmsh box (4 x 2 x 2 hexahedra) whose load is a node set along its whole length (its bottom
  // face group, 15 nodes, so both ranks hold some): the force per node is the one-process one,
  // not the total spread over each rank's share of the nodes.
  const std::string scene = "mesh: {gmsh: " + std::string(CRACKLE_SOURCE_DIR) + R"(/data/meshes/box-hex8.msh}
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
boundary:
  - {group: clamp, fix: [x, y, z]}
transient:
  model: full
  excitation: {group: bottom, direction: z, amplitude: 1000.0, frequency: {hz: 900.0}}
  initial:
    - {velocity: [0.0, 0.1, 0.0], x: [0.1, 0.2]}
  periods: 6
  progress: false
  history: {samples_per_period: all}
  probes:
    - {name: tip, point: [0.2, 0.05, 0.04]}
    - {name: middle, point: [0.1, 0.0, 0.0]}
)";
  const std::array<fs::path, 2> out = run_both("nodeset", scene);
  expect_same_run(out);
  for (const fs::path& folder : out) fs::remove_all(folder);
}

TEST(MpirunRun, StaticReleaseAndPointLoadSameAsOneProcess) {
  // The crack pressed shut by a static tip load (solved on the whole body by every rank), released
  // at t = 0, then driven by a point force on one node.
  const std::string scene = cracked_cantilever() + R"(transient:
  model: full
  release:
    static: {face: x+, direction: z, amplitude: 500.0}
  excitation: {point: [0.2, 0.02, 0.04], direction: y, amplitude: 50.0, frequency: {hz: 800.0}}
  periods: 4
  progress: false
  history: {samples_per_period: all}
  snapshots: {count: 3}
  probes:
    - {name: tip, point: [0.2, 0.01, 0.04]}
    - {name: opening, crack_opening: [0.04, 0.01, 0.035]}
)";
  const std::array<fs::path, 2> out = run_both("release", scene);
  expect_same_run(out);
  // Snapshots: one .vtu piece per rank and a .pvtu per snapshot, listed in snapshots.pvd; the
  // pieces' points add up to the mesh's nodes plus the nodes both ranks hold.
  const std::string pvd = [&] {
    std::ifstream file(out[1] / "snapshots.pvd");
    return std::string(std::istreambuf_iterator<char>(file), {});
  }();
  const std::regex dataset("file=\"(snapshot_[0-9]{4}\\.pvtu)\"");
  int snapshots = 0;
  const nlohmann::json one = read_json(out[0] / "transient.json");
  for (std::sregex_iterator it(pvd.begin(), pvd.end(), dataset); it != std::sregex_iterator(); ++it) {
    ++snapshots;
    const fs::path pvtu = out[1] / (*it)[1].str();
    ASSERT_TRUE(fs::exists(pvtu)) << pvtu;
    std::ifstream file(pvtu);
    const std::string text((std::istreambuf_iterator<char>(file)), {});
    const std::regex piece("<Piece Source=\"([^\"]+)\"/>");
    long points = 0;
    int pieces = 0;
    for (std::sregex_iterator p(text.begin(), text.end(), piece); p != std::sregex_iterator(); ++p) {
      ++pieces;
      std::ifstream vtu(out[1] / (*p)[1].str(), std::ios::binary);
      ASSERT_TRUE(vtu) << (*p)[1].str();
      std::string head(4096, '\0');
      vtu.read(head.data(), static_cast<std::streamsize>(head.size()));
      std::smatch count;
      ASSERT_TRUE(std::regex_search(head, count, std::regex("NumberOfPoints=\"([0-9]+)\"")));
      points += std::stol(count[1].str());
    }
    EXPECT_EQ(pieces, 2);
    // 17 x 3 x 5 grid nodes and the crack's copies (dofs / 3); the ranks share at least a layer.
    const long nodes = one["dofs"].get<long>() / 3;
    EXPECT_GT(points, nodes);
    EXPECT_LT(points, 2 * nodes);
  }
  EXPECT_EQ(snapshots, 3);
  EXPECT_TRUE(fs::exists(out[0] / "snapshot_0000.vtu"));  // one process: today's files
  for (const fs::path& folder : out) fs::remove_all(folder);
}

/// The number of occurrences of `text` in `output`.
int count(const std::string& output, const std::string& text) {
  int found = 0;
  for (std::size_t at = output.find(text); at != std::string::npos; at = output.find(text, at + 1)) ++found;
  return found;
}

/// One error line (from rank 0) containing `message`, and `code` as the exit code of both ranks.
void expect_one_error(const Result& result, int code, const std::string& message) {
  EXPECT_EQ(count(result.output, "crackle: error:"), 1) << result.output;
  EXPECT_NE(result.output.find(message), std::string::npos) << result.output;
  EXPECT_EQ(count(result.output, "rank exit code " + std::to_string(code)), 2) << result.output;
}

TEST(MpirunRun, BadInputGivesOneErrorLineAndTheSameExitCodeOnEveryRank) {
  // More ranks than elements (found by the partition, on every rank).
  const fs::path tiny = write_scene("tiny", R"(mesh:
  box: {size: [0.1, 0.01, 0.01], cells: [1, 1, 1], order: 1}
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
boundary:
  - {face: x-, fix: [x, y, z]}
transient:
  model: full
  initial:
    - {velocity: [0.0, 0.0, 1.0]}
  duration: 1.0e-4
  progress: false
)");
  const fs::path out = temporary("bad");
  expect_one_error(crackle(2, "run " + tiny.string() + " -o " + out.string(), true), 2,
                   "mpirun -np 2: more ranks than the 1 elements of the mesh");
  // A probe outside the body (found while placing the probes).
  const fs::path outside = write_scene("outside", chattering_cantilever("    - {name: far, point: [0.5, 0.0, 0.0]}\n"));
  expect_one_error(crackle(2, "run " + outside.string() + " -o " + out.string() + " --overwrite", true), 2,
                   "transient.probes[3].point: expected a point in the body");
  // The reduced model is a one-process run.
  std::string reduced_text = chattering_cantilever("");
  reduced_text.erase(reduced_text.find("    - {name: opening"));
  const fs::path reduced = write_scene("reduced", reduced_text);
  expect_one_error(crackle(2, "run " + reduced.string() + " -o " + out.string() + " --overwrite --set transient.model=reduced", true),
                   2, "transient.model: expected full under mpirun -np 2");
  // A forced time step twice the stable one: the health checks stop both ranks in the time loop
  // with one message (a solver failure, exit 3), and rank 0 still writes transient.json.
  const Result unstable = crackle(2, "run " + reduced.string() + " -o " + out.string() +
                                         " --overwrite --set transient.time_step=3e-6 --set transient.force_time_step=true",
                                  true);
  expect_one_error(unstable, 3, "transient: unstable");
  EXPECT_EQ(read_json(out / "transient.json")["status"], "unstable");
  EXPECT_EQ(read_json(out / "transient.json")["ranks"], 2);
  for (const fs::path& path : {tiny, outside, reduced, out}) fs::remove_all(path);
}

}  // namespace
