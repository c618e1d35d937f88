#pragma once
/// \file The stages of `crackle run`, which pipeline/run.cpp wires together: the transient's setup
/// from the scene (run_setup.cpp), the full transient and its snapshots (run_transient.cpp), the
/// reduced transient (run_reduced.cpp), and the spectrum of a harmonic run or the ring-down of a free
/// one (run_spectrum.cpp). The modal stage is stages.hpp's (modal_stage.cpp).
#include <algorithm>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "contact/contact_force.hpp"
#include "modal/modal.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/model.hpp"
#include "pipeline/release.hpp"
#include "pipeline/run_scene.hpp"
#include "scene/scene.hpp"
#include "spectral/harmonics.hpp"
#include "spectral/steady_monitor.hpp"
#include "transient/solver.hpp"

namespace crackle::pipeline {

/// The transient stage's inputs, from the scene and the modes.
struct TransientSetup {
  transient::TransientProblem problem;
  transient::TransientOptions settings;
  mesh::Variant variant = mesh::Variant::open;
  double frequency = 0.0;  ///< excitation frequency [Hz], 0 without a harmonic excitation
  std::shared_ptr<contact::ContactForce> contact;  ///< null without contact
  std::optional<ReleaseReport> release;            ///< how U(0) was made from transient.release
  nlohmann::json probes_json = nlohmann::json::array();  ///< per probe: name, node, snapping distance
  std::vector<std::string> warnings;  ///< found while setting up (for transient.json and stderr)
  /// Under mpirun -np N > 1: this rank's share of the full transient (the problem above is the
  /// whole body's, from which it is made).
  std::unique_ptr<DistributedTransient> distributed;
};

/// The transient stage's setup: the excitation as a load, the damping, contact, release, initial
/// fields and probes (their placement in transient.json's `probes`), and the run's length and step.
TransientSetup transient_setup(const scene::Scene& scene, const Model& model,
                               const std::optional<modal::ModalResult>& modes, const RunCommandOptions& options);

/// Steps between probes.csv rows: transient.history.samples_per_period rows per excitation period
/// (per pulse duration), every step when it is `all` or without an excitation.
Index probe_interval(const scene::Scene& scene, double frequency, double dt);

/// Per probe: the analysed component's accumulator, and that component at every step (probes.csv
/// holds decimated rows; the amplitude spectra and the history plots take every step).
struct ProbeSpectrum {
  std::string name;
  std::string quantity;  ///< "u_x" ... or "gap" (an opening probe), for messages and plot titles
  std::string label;     ///< spectrum.json's "component": the axis, or "gap"
  int component = 2;
};

/// The probes' spectra of a run: spectral::SteadyStateMonitor over the analysed component of each
/// probe (fed every step), and the spectrum stage's files.
class SpectrumMonitor {
 public:
  /// InputError naming the keys when the highest harmonic lies at or above the Nyquist frequency of
  /// the time step.
  SpectrumMonitor(const scene::Scene& scene, double frequency, double dt);

  std::string progress_note(double elapsed) const { return monitor_.progress_note(elapsed); }

  /// Feeds one step; true when every probe's table has settled (the run may stop).
  bool add(const transient::StepView& view) {
    return monitor_.add(view.time, [&](std::size_t p) { return view.probe_sample[9 * p + probes_[p].component]; });
  }

  /// Stage 3: closes the records, writes the spectra and the plots; returns spectrum.json's content
  /// (written by the command once the accuracy is known) and the probes' signatures.
  /// draw_plots false: the figures' data and scripts only (plot::PlotOptions::draw).
  nlohmann::json write(const scene::Scene& scene, const std::filesystem::path& directory, double dt,
                       std::vector<ProbeSignature>& signatures, std::ostream& out, bool draw_plots = true);

 private:
  const scene::SpectrumSection& spectrum_;
  spectral::HarmonicOptions options_;
  spectral::SteadyStateMonitor monitor_;
  std::vector<ProbeSpectrum> probes_;
};

/// Stage 3 without a harmonic excitation (free vibration, a pulse, or none): per probe a ring-down
/// analysis (spectral::analyse_ringdown) compared with the modal frequencies when they are at hand,
/// the envelope of its orders plotted; after a pulse also the FRF estimate H = X/F (CSV and plot).
void write_ringdown_spectrum(const scene::Scene& scene, const std::filesystem::path& directory, const transient::ProbeHistory& history,
                             const TransientSetup& setup, const std::optional<modal::ModalResult>& modes,
                             std::ostream& out, bool draw_plots = true);

/// Displacement snapshots (VTU) at evenly spaced steps of a run, only when asked, and
/// snapshots.pvd: the collection with their times, rewritten after each one (ParaView plays it as
/// a time series, also of a run that failed halfway).
class SnapshotWriter {
 public:
  /// `mesh` and `dofs`: the run's (a distributed run's: the rank's local mesh and DOF map, whose
  /// `partition` then writes one piece per rank and a .pvtu per snapshot).
  SnapshotWriter(const std::filesystem::path& directory, const mesh::Mesh& mesh, const mesh::DofMap& dofs, int count,
                 Index n_steps, const distributed::MeshPartition* partition = nullptr)
      : directory_(directory), mesh_(mesh), dofs_(dofs), count_(count), n_steps_(n_steps), partition_(partition) {}
  /// Whether on_step at this step writes a snapshot (a model that computes its field only when written asks first).
  bool due(Index step) const { return next_ < count_ && step >= step_of(next_); }
  /// Writes the snapshot that is due at this step, if one is.
  void on_step(const transient::StepView& view);

 private:
  /// The step of snapshot k (0-based): evenly spread, the last at the last step.
  Index step_of(int k) const {
    const long long step = static_cast<long long>(n_steps_) * (k + 1) / count_;
    return static_cast<Index>(std::max<long long>(1, step) - 1);
  }

  std::filesystem::path directory_;
  const mesh::Mesh& mesh_;
  const mesh::DofMap& dofs_;
  int count_ = 0;
  Index n_steps_ = 0;
  const distributed::MeshPartition* partition_ = nullptr;
  int next_ = 0;
  std::string collection_;
};

/// Stage 2: the transient, with the harmonic accumulators fed every step when a spectrum is asked;
/// probes.csv, energy.csv and transient.json written once, when it ends (also when it fails).
std::unique_ptr<transient::TransientSolver> run_transient_stage(const scene::Scene& scene, const Model& model,
                                                                TransientSetup& setup, const std::filesystem::path& directory,
                                                                std::optional<SpectrumMonitor>& spectrum);

/// Stage 2 with transient.model: reduced: the same callbacks and files as the full transient (probes.csv,
/// energy.csv of the reduced model's energy balance, transient.json with the reduction's fields);
/// `dt` the reduced model's time step, `outcome` its model's figures.
transient::ProbeHistory run_reduced_stage(const scene::Scene& scene, const Model& model, TransientSetup& setup,
                                          const RunCommandOptions& options, std::optional<SpectrumMonitor>& spectrum,
                                          double& dt, RunOutcome& outcome, std::ostream& out);

}  // namespace crackle::pipeline
