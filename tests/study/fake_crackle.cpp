// A stand-in for the `crackle` executable in study tests: `fake_crackle modal|run SCENE -o DIR
// [--modal-cache C] [--overwrite] [--accuracy-start FILE]` validates the scene like crackle does and writes modal.json (modal) or
// spectrum.json and run.json, and modal.json if the scene has a modal: section (run), with the
// JSON contracts of the real commands, from closed-form
// "frequencies" of the scene. Test hooks, by environment:
//   CRACKLE_FAKE_MARKER    file to which each run appends "<command> <case folder> <parent pid>",
//                          each modal cache access "cache-solve|cache-hit <cache folder>" and each
//                          --accuracy-start "accuracy-start <case folder> <file>"
// With accuracy.tolerance, run.json's accuracy says the setting its tolerance loop reached: the
// --accuracy-start file's (which must hold one), else one element order above the scene's.
//   CRACKLE_FAKE_SLEEP_MS  time each run takes
//   CRACKLE_FAKE_TRAILER   a line written to stderr after the error line of a failing command
// `run` writes progress lines to stderr the way crackle does ('\r', no line end), so a failure's
// `crackle: error: ...` line follows a progress line.
// A scene with material.nu = 0.333 fails like a solver failure (exit 3, one line on stderr); a
// leaked MPI launcher variable (OMPI_COMM_WORLD_SIZE) fails too.
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "core/errors.hpp"
#include "io/files.hpp"
#include "scene/scene.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void mark(const std::string& line) {
  const char* marker = std::getenv("CRACKLE_FAKE_MARKER");
  if (!marker || !*marker) return;
  const std::string text = line + "\n";
  const int fd = ::open(marker, O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) return;
  const ssize_t written = ::write(fd, text.data(), text.size());  // one write: lines never interleave
  (void)written;
  ::close(fd);
}

/// Fraction of the cross-section the crack cuts.
double crack_fraction(const crackle::scene::Scene& scene) {
  if (!scene.crack) return 0.0;
  double crack = 1.0, section = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == scene.crack->normal) continue;
    crack *= scene.crack->region[axis][1] - scene.crack->region[axis][0];
    section *= scene.box.size[axis];
  }
  return crack / section;
}

json uncracked_frequencies(const crackle::scene::Scene& scene) {
  json list = json::array();
  const double base = std::sqrt(scene.material.young / scene.material.density) / scene.box.size[0] * 0.01;
  for (int k = 0; k < scene.modal.modes; ++k)
    list.push_back(base * (k + 1) * (k + 1) / (1.0 + scene.material.poisson));
  return list;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 5 || std::string(argv[3]) != "-o")
      throw crackle::InputError("usage: fake_crackle modal|run SCENE -o DIR [--modal-cache C]");
    const std::string command = argv[1], scene_path = argv[2];
    const fs::path out = argv[4];
    fs::path cache, accuracy_start;
    for (int i = 5; i + 1 < argc; ++i) {
      if (std::string(argv[i]) == "--modal-cache") cache = argv[i + 1];
      if (std::string(argv[i]) == "--accuracy-start") accuracy_start = argv[i + 1];
    }
    mark(command + " " + fs::path(scene_path).parent_path().string() + " " + std::to_string(::getppid()));
    if (!accuracy_start.empty())
      mark("accuracy-start " + fs::path(scene_path).parent_path().string() + " " + accuracy_start.string());
    if (std::getenv("OMPI_COMM_WORLD_SIZE"))
      throw crackle::InputError("the MPI launcher's environment leaked into a case");
    if (const char* sleep = std::getenv("CRACKLE_FAKE_SLEEP_MS"))
      std::this_thread::sleep_for(std::chrono::milliseconds(std::atoi(sleep)));
    const crackle::scene::Scene scene = crackle::scene::load_scene(scene_path);
    std::cerr << "fake_crackle " << command << ": " << scene_path << "\n";
    if (command == "run") std::cerr << "\rtransient  50% step 1/2 ETA 1s\rtransient 100% step 2/2 ETA 0s" << std::flush;
    if (scene.material.poisson == 0.333) throw crackle::SolverError("fake solver failure: nu = 0.333");

    json uncracked;
    if (!cache.empty()) {
      crackle::io::ensure_directory(cache);
      if (fs::exists(cache / "uncracked.json")) {
        uncracked = json::parse(crackle::io::read_file(cache / "uncracked.json"));
        mark("cache-hit " + cache.string());
      } else {
        uncracked = uncracked_frequencies(scene);
        crackle::io::write_json(cache / "uncracked.json", uncracked);
        mark("cache-solve " + cache.string());
      }
    } else {
      uncracked = uncracked_frequencies(scene);
    }
    const double fraction = crack_fraction(scene);
    json open = json::array(), pairs = json::array();
    for (std::size_t k = 0; k < uncracked.size(); ++k) {
      const double f_u = uncracked[k].get<double>(), f_o = f_u * (1.0 - 0.5 * fraction);
      open.push_back(f_o);
      pairs.push_back({{"uncracked_mode", k + 1},
                       {"open_mode", k + 1},
                       {"f_uncracked_hz", f_u},
                       {"f_open_hz", f_o},
                       {"ratio", f_o / f_u},
                       {"mac", 1.0 - 0.1 * fraction},
                       {"f_bilinear_hz", 2 * f_u * f_o / (f_u + f_o)}});
    }
    crackle::io::ensure_directory(out);
    // `crackle run` writes modal.json too when the scene has a modal: section.
    if (command == "modal" || (command == "run" && scene.has_modal_section)) {
      json variants = {{"uncracked", {{"frequencies_hz", uncracked}}}};
      if (scene.crack) variants["open"] = {{"frequencies_hz", open}};
      json document = {{"dofs", 123}, {"variants", variants}, {"pairs", scene.crack ? pairs : json::array()}};
      if (command == "modal") {
        // crackle modal's accuracy block (issue 23): relative errors 1e-3 (k + 1) uncracked, 2e-3 (k + 1)
        // open, 1.5e-3 (k + 1) bilinear at the place of each value.
        const auto estimates = [&](double scale) {
          json list = json::array();
          for (std::size_t k = 0; k < uncracked.size(); ++k) list.push_back({{"error", scale * (k + 1)}});
          return list;
        };
        json estimated = {{"uncracked", {{"frequencies_hz", estimates(1e-3)}}}};
        if (scene.crack) estimated["open"] = {{"frequencies_hz", estimates(2e-3)}};
        json estimated_pairs = json::array();
        for (const json& bilinear : estimates(1.5e-3)) estimated_pairs.push_back({{"f_bilinear_hz", bilinear}});
        document["accuracy"] = {{"estimated", true}, {"variants", estimated}, {"pairs", estimated_pairs}};
      }
      crackle::io::write_json(out / "modal.json", document);
    }
    if (command == "run") {
      const double excitation = 0.5 * pairs.at(0)["f_bilinear_hz"].get<double>();
      const double a1 = 1e-6, a2 = a1 * 0.2 * fraction, a3 = a1 * 0.05 * fraction,
                   a_half = a1 * 0.01 * fraction;
      json harmonics = json::array();
      for (const auto& [order, amplitude] :
           std::vector<std::pair<double, double>>{{0.5, a_half}, {1, a1}, {2, a2}, {3, a3}})
        harmonics.push_back({{"order", order},
                             {"frequency_hz", order * excitation},
                             {"amplitude", amplitude},
                             {"phase_rad", 0.0}});
      json indices = {
          {"A2/A1", a2 / a1}, {"A3/A1", a3 / a1}, {"A1/2/A1", a_half / a1}, {"beta", a2 / (a1 * a1)}};
      // The accuracy block of crackle run (issue 23): a relative error per signature.
      const json accuracy = {{"estimated", true},
                             {"probes", {{"tip", {{"A1", {{"error", 1e-4}}}, {"A2/A1", {{"error", 0.002 * fraction}}}}}}}};
      crackle::io::write_json(
          out / "spectrum.json",
          {{"excitation_hz", excitation},
           {"probes", {{"tip", {{"component", "z"}, {"harmonics", harmonics}, {"indices", indices}}}}},
           {"accuracy", accuracy}});
      json run = {{"steps", 100}};
      if (scene.accuracy.tolerance) {
        json reached = {{"order", scene.box.order + 1}, {"layers", 0}, {"band", 0},  {"steps", 0},
                        {"penalty", 0}, {"harmonics", 0}, {"window", 0}};
        if (!accuracy_start.empty())  // the leader's run.json, read as crackle reads it
          reached = json::parse(crackle::io::read_file(accuracy_start)).at("accuracy").at("reached");
        run["accuracy"] = {{"estimated", true}, {"met", true}, {"reached", reached}};  // run.json's summary
      }
      crackle::io::write_json(out / "run.json", run);
    } else if (command != "modal") {
      throw crackle::InputError("unknown command '" + command + "'");
    }
    return 0;
  } catch (const std::exception& error) {
    std::cerr << "crackle: error: " << error.what() << "\n";
    if (const char* trailer = std::getenv("CRACKLE_FAKE_TRAILER")) std::cerr << trailer << "\n";
    return crackle::exit_code_for(error);
  }
}
