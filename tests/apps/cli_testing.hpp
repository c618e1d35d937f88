#pragma once
/// \file Running the built `crackle` executable from the end-to-end tests.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace cli_testing {

struct Result {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};

/// Runs `crackle ARGUMENTS` with an optional environment prefix ("A=1 B=2"), capturing its output.
inline Result crackle(const std::string& arguments, const std::string& environment = "") {
  const std::string command =
      environment + " " + std::string(CRACKLE_BINARY_DIR) + "/apps/crackle " + arguments + " 2>&1";
  Result result;
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

/// The steel cantilever 0.2 x 0.02 x 0.01 m of p = 1 clamped at x = 0 that the end-to-end tests
/// share, meshed with `cells` ("[10, 1, 1]"), with a half-depth edge crack from the top face at
/// x = 0.04 unless `with_crack` is false: the start of a scene, the sections after `boundary`.
/// Ungraded (`grading: none`), so that the full and the reduced model run on the same mesh.
inline std::string cantilever(const std::string& cells, bool with_crack = true) {
  std::string text = "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: " + cells + ", order: 1, grading: none}\n"
                     "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
                     "boundary:\n  - {face: x-, fix: [x, y, z]}\n";
  if (with_crack) text += "crack:\n  plane: {normal: x, at: 0.04}\n  region: {y: [0.0, 0.02], z: [0.005, 0.01]}\n";
  return text;
}

/// The forced run after cantilever("[10, 2, 1]"): a harmonic tip load of 20 N at 150 Hz (f1 about 200 Hz:
/// the crack breathes every period), 5 % damping, 40 periods, the spectrum (3 harmonics, no
/// steady-state stop) over the last 10; `probes` the entries of transient.probes.
inline std::string forced_tip(const std::string& probes) {
  return R"(transient:
  model: full
  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 20.0, frequency: 150}
  damping: {ratio: 0.05, at: 150}
  periods: 40
  progress: false
  probes:
)" + probes + R"(spectrum:
  harmonics: 3
  subharmonics: false
  steady_state: {tolerance: 0, window_periods: 10}
  plots: false
)";
}

/// The cracked cantilever of cantilever("[10, 1, 2]") released from a static tip load of 50 N (the
/// top crack pressed shut), no damping, crack.contact.model `contact`; modal with the lumped mass, the
/// ring-down analysed (the pluck tests of the full and of the reduced transient).
inline std::string cracked_release(const std::string& contact) {
  return cantilever("[10, 1, 2]") + "  contact: {model: " + contact + "}\n" + R"(modal: {modes: 2, mass: lumped}
transient:
  model: full
  release:
    static: {face: x+, direction: z, amplitude: 50.0}
  duration: 0.15
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
spectrum: {harmonics: 3, subharmonics: false, ringdown: {window_periods: 2}}
)";
}

/// A deep steel cantilever 0.2 x 0.02 x 0.04 m (f1 about 740 Hz: 20 crack closures in 0.03 s), p = 1,
/// [10, 1, 2] cells, clamped at x = 0, with a half-depth edge crack from the top face at x = 0.04: the
/// start of a scene up to the crack's region (its gap and contact may follow).
inline std::string deep_cracked_cantilever() {
  return "mesh:\n  box: {size: [0.2, 0.02, 0.04], cells: [10, 1, 2], order: 1}\n"
         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
         "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
         "crack:\n  plane: {normal: x, at: 0.04}\n  region: {y: [0.0, 0.02], z: [0.02, 0.04]}\n";
}

/// A scene of the repository's data/ folder.
inline std::string data(const std::string& name) { return std::string(CRACKLE_SOURCE_DIR) + "/data/" + name; }

}  // namespace cli_testing
