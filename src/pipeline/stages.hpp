#pragma once
/// \file Stages shared by the commands of the pipeline (`crackle run`, `crackle sweep`): the modal
/// stage that runs only when a key refers to a mode, and the frequency of a mode it found.
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "modal/modal.hpp"
#include "output/run_json.hpp"
#include "pipeline/model.hpp"
#include "scene/scene.hpp"
#include "transient/damping.hpp"

namespace crackle::pipeline {

/// One line of run.json / sweep.json: a stage, whether it ran, why, and its time.
using Stage = output::Stage;

/// Frequency [Hz] of elastic mode `mode` (1-based) of the given kind (bilinear, uncracked, open)
/// from a modal result. InputError naming `key` when that mode was not computed or not paired.
double mode_frequency(const modal::ModalResult& result, int mode, scene::ModeOf of, const std::string& key);

/// Rayleigh damping of transient.damping: a ratio at a frequency (or a mode of `modes`), or alpha and beta.
transient::RayleighDamping scene_damping(const scene::Scene& scene, const std::optional<modal::ModalResult>& modes);

/// The modal variants the scene needs, uncracked first (empty: no modal stage), and in `reason`
/// what refers to a mode.
std::vector<mesh::Variant> needed_variants(const scene::Scene& scene, std::string& reason);

/// The modal stage: the variants the scene needs (a mode referred to by transient.excitation,
/// transient.damping or sweep.frequency, or a modal: section), with modal.json etc. written to
/// `output_directory`; std::nullopt (and `stage.reason` says why) when nothing needs modes.
/// Needs a transient: section. `reduced_follows`: the reduced model is built next, so the factor of
/// the transient variant's K is left in model.factors() for it.
std::optional<modal::ModalResult> run_modal_stage(const scene::Scene& scene, const Model& model,
                                                  const std::filesystem::path& output_directory,
                                                  const std::filesystem::path& modal_cache, Stage& stage,
                                                  std::ostream& out, bool reduced_follows);

}  // namespace crackle::pipeline
