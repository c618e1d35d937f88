#pragma once
/// \file One run of a scene's stages (modal -> transient -> spectrum) and what it computed, for
/// `crackle run` and for the refinement runs of its accuracy estimate (pipeline/accuracy.hpp).
#include <array>
#include <limits>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/commands.hpp"
#include "pipeline/model.hpp"
#include "pipeline/stages.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// The signatures of one probe: A1 [m], A2/A1, A3/A1, A1/2/A1 of the last window, and of the two
/// windows before it (NaN when the run had fewer windows).
struct ProbeSignature {
  static constexpr std::array<const char*, 4> kNames = {"A1", "A2/A1", "A3/A1", "A1/2/A1"};
  std::string name;
  std::array<double, 4> value{};
  std::array<double, 4> previous_window{};
  std::array<double, 4> window_before{};
  double window_s = 0.0;  ///< the length of each analysis window [s]
};

/// The uncracked, open and bilinear frequencies [Hz] of the mode the excitation refers to.
struct ModeSignature {
  int mode = 0;
  double f_uncracked = 0.0, f_open = 0.0, f_bilinear = 0.0;
  double dofs = 0.0;  ///< free DOFs of the largest variant's eigenproblem (the mesh levels' size)
};

/// What one run computed.
struct RunOutcome {
  std::vector<Stage> stages;
  double frequency = 0.0;                     ///< excitation [Hz]
  std::optional<nlohmann::json> spectrum;     ///< spectrum.json of a harmonic run (the caller writes it)
  std::vector<ProbeSignature> probes;         ///< of a harmonic run with a spectrum
  std::optional<ModeSignature> mode;          ///< when the excitation refers to a paired mode
  double normal_penalty = 0.0;                ///< [Pa/m] (reduced model)
  double max_frequency_hz = 0.0;              ///< reduced model's band
  int modes = 0;                              ///< reduced model's retained modes
  int pairs = 0;
  /// The least modal decay rate of the damping, alpha/2 + beta omega_1^2/2 [1/s] over the reduced
  /// model's modes (MODEL.md eq. 26): its start transient decays no faster; NaN where not known.
  double slowest_decay_per_s = std::numeric_limits<double>::quiet_NaN();
  double wall_s = 0.0;
};

/// What runs of one scene on the same mesh share within one process (the accuracy's refinement
/// runs of the time step, penalty and band): the model (mesh, systems and their operators) and the
/// modal stage's result, under a key the caller gives the mesh.
struct RunReuse {
  std::string key;
  std::map<std::string, std::unique_ptr<Model>> models;
  std::map<std::string, std::optional<modal::ModalResult>> modes;
};

/// Runs the scene's stages into options.output_directory (every file but spectrum.json of a
/// harmonic run and run.json, which the caller writes once it knows the accuracy).
RunOutcome run_scene(const scene::Scene& scene, const RunCommandOptions& options, std::ostream& out,
                     RunReuse* reuse = nullptr);

/// run.json: the stages, the route (when given) and the accuracy summary (when given).
void write_run_json(const scene::Scene& scene, const std::filesystem::path& directory, const RunOutcome& outcome,
                    const nlohmann::json& route, const nlohmann::json& accuracy, double wall_s);

}  // namespace crackle::pipeline
