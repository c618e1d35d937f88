#pragma once
/// \file The scene's reduced model (HYBRID.md §2): the pipeline-level builder over reduction/reduction.hpp,
/// shared by the reduced transient of `crackle run` and by `crackle sweep`. The expensive part (modes,
/// static solves) is cached by fingerprint in the --modal-cache folder, so a study over excitation
/// frequency, amplitude or damping computes it once.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "pipeline/model.hpp"
#include "reduction/reduction.hpp"
#include "reduced/system.hpp"
#include "scene/scene.hpp"
#include "transient/excitation.hpp"
#include "transient/solver.hpp"

namespace crackle::pipeline {

/// Factor of the automatic transient.reduced.max_frequency: kAutoFrequencyFactor x spectrum.harmonics
/// (kDefaultHarmonics without spectrum:) x the excitation frequency.
inline constexpr double kAutoFrequencyFactor = 4.0;
inline constexpr int kDefaultHarmonics = 5;

/// The scene's reduced model (HYBRID.md §2) of the open variant: modes, residual flexibility at the
/// crack pairs, the excitation's load shape (its amplitude included: a(t) is the dimensionless signal)
/// and the probes (output row 3 p + c = probe p, component c: a node's u_c, or for a crack-opening
/// probe its gap less g0 (c = 0) and its two slips, in the full model's probe frame).
struct ReducedModel {
  reduced::ReducedSystem system;
  std::vector<std::string> output_names;  ///< "tip u_x", "tip u_y", ... ("mouth gap", "mouth slip_1", ...) per output row
  VectorX output_offsets;   ///< added to the outputs: g0 on an opening probe's gap row, else 0
  /// Per probe: the reduced model's pair of a crack-opening probe (its contact state), -1 for a node
  /// probe or a model without pair rows (crack.contact.model: none: the state follows the gap).
  std::vector<Index> probe_pairs;
  /// Displacement fields over the DOFs for snapshots (made only when transient.snapshots.count > 0;
  /// its factor of K is made at the first snapshot).
  std::unique_ptr<reduced::FieldRecovery> fields;
  double max_frequency_hz = 0.0;
  int modes = 0;
  Index pairs = 0;
  double setup_s = 0.0;
  bool from_cache = false;
  double modes_s = 0.0;        ///< eigen-solve time of the reduction (when computed, or when it was cached)
  double flexibility_s = 0.0;  ///< factorisation and static solves of the reduction
  int computed_modes = 0;      ///< modes in the reduction (>= modes: a cached one may hold more)
  /// Initial modal state (MODEL.md eq. 6) q(0) = Phi^T M U(0), q'(0) = Phi^T M V(0): the reduced state
  /// nearest to the initial fields in the mass norm; zero without initial fields.
  VectorX initial_displacement, initial_velocity;
  /// Mass-norm share of U(0) (and of V(0)) outside the retained modes, ||u - Phi q||_M / ||u||_M
  /// (0 for a field in their span, NaN for a zero field): what the truncation leaves out of the start.
  double initial_displacement_lost = 0.0, initial_velocity_lost = 0.0;
};

/// Builds (or reads from `cache_directory`, when not empty) the reduced model of the scene's
/// transient variant (open with a crack: pairs and the contact of crack.contact, penalty auto via
/// contact::choose_penalty; uncracked: no pairs). Damping: alpha and beta, or a ratio at a frequency
/// in Hz; a ratio at a mode leaves alpha = beta = 0 for the caller (it needs the uncracked modes).
/// `excitation_frequency_hz` (0 for a pulse) sets the automatic max_frequency. `initial`, when given,
/// holds U(0), V(0) over the DOFs of the transient variant (transient.release, transient.initial):
/// projected onto the retained modes. With crack.contact.model: none the pairs are left out (the open
/// body alone). `probes`, when given, are the scene's probes placed as the full model places them
/// (`side` copies, crack-opening pairs and frames); without them each probe is its nearest node.
/// InputError for a scene without transient:, or an automatic max_frequency without a harmonic excitation.
ReducedModel build_reduced_model(const scene::Scene& scene, const Model& model, double excitation_frequency_hz,
                                 const std::filesystem::path& cache_directory,
                                 const transient::InitialConditions* initial = nullptr,
                                 const std::vector<transient::Probe>* probes = nullptr);

}  // namespace crackle::pipeline
