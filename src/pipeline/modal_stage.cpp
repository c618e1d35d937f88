/// \file The modal stage of `crackle run` and `crackle sweep` (stages.hpp): solved only for the
/// variants something in the scene refers to.
#include <algorithm>
#include <set>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/reduced_model.hpp"
#include "pipeline/route.hpp"
#include "pipeline/stages.hpp"
#include "output/modal_json.hpp"

namespace crackle::pipeline {

std::vector<mesh::Variant> needed_variants(const scene::Scene& scene, std::string& reason) {
  std::set<mesh::Variant> variants;
  const scene::TransientSection& transient = *scene.transient;
  if (transient.excitation && transient.excitation->mode > 0) {
    const scene::ModeOf of = transient.excitation->of;
    if (of != scene::ModeOf::open) variants.insert(mesh::Variant::uncracked);
    if (of != scene::ModeOf::uncracked) variants.insert(mesh::Variant::open);
    reason = "transient.excitation.frequency refers to mode " + std::to_string(transient.excitation->mode);
  }
  if (transient.release && transient.release->kind == scene::ReleaseKind::mode) {
    variants.insert(transient.release->variant);
    if (reason.empty()) reason = "transient.release.mode refers to mode " + std::to_string(transient.release->mode);
  }
  if (transient.damping.at_mode > 0) {
    variants.insert(mesh::Variant::uncracked);
    if (reason.empty()) reason = "transient.damping.at refers to mode " + std::to_string(transient.damping.at_mode);
  }
  if (scene.sweep) {
    for (const scene::SweepFrequencySection* end : {&scene.sweep->from, &scene.sweep->to}) {
      if (end->mode == 0) continue;
      if (end->of != scene::ModeOf::open) variants.insert(mesh::Variant::uncracked);
      if (end->of != scene::ModeOf::uncracked) variants.insert(mesh::Variant::open);
      if (reason.empty()) reason = "sweep.frequency refers to mode " + std::to_string(end->mode);
    }
  }
  if (scene.has_modal_section) {
    variants.insert(scene.modal.variants.begin(), scene.modal.variants.end());
    if (reason.empty()) reason = "the scene has a modal: section";
  }
  // Keep the uncracked limit first, as the modal module lists it.
  std::vector<mesh::Variant> ordered;
  for (mesh::Variant variant : {mesh::Variant::uncracked, mesh::Variant::open}) {
    if (variants.count(variant)) ordered.push_back(variant);
  }
  return ordered;
}

/// Frequency [Hz] of elastic mode `mode` (1-based) of the given kind from a modal result.
double mode_frequency(const modal::ModalResult& result, int mode, scene::ModeOf of, const std::string& key) {
  const int index = mode - 1;
  if (of == scene::ModeOf::bilinear) {
    if (index >= static_cast<int>(result.pairs.size())) {
      throw InputError(key + ": mode " + std::to_string(mode) + " asked, but only " +
                       std::to_string(result.pairs.size()) + " modes were paired (raise modal.modes)");
    }
    const modal::ModePair& pair = result.pairs[index];
    if (!pair.paired) {
      throw InputError(key + ": mode " + std::to_string(mode) + " has no open partner among the " +
                       std::to_string(result.mac.cols()) + " open modes computed (best MAC " +
                       format_number(pair.mac) + " < " + format_number(modal::kPairingMac) +
                       "), so its bilinear frequency is undefined (raise modal.modes)");
    }
    return pair.f_bilinear_hz;
  }
  const modal::VariantResult* variant =
      result.find(of == scene::ModeOf::open ? mesh::Variant::open : mesh::Variant::uncracked);
  if (!variant || index >= variant->modes.n_modes()) {
    throw InputError(key + ": mode " + std::to_string(mode) + " of the " + scene::mode_of_name(of) + " body asked, but only " +
                     std::to_string(variant ? variant->modes.n_modes() : 0) + " modes were computed");
  }
  return variant->modes.frequencies_hz[index];
}

std::optional<modal::ModalResult> run_modal_stage(const scene::Scene& scene, const Model& model,
                                                  const std::filesystem::path& output_directory, const std::filesystem::path& modal_cache,
                                                  Stage& stage, std::ostream& out, bool reduced_follows) {
  const std::vector<mesh::Variant> variants = needed_variants(scene, stage.reason);
  if (variants.empty()) {
    stage.reason = "nothing refers to a mode";
    return std::nullopt;
  }
  const scene::TransientSection& section = *scene.transient;
  Stopwatch clock;
  modal::ModalOptions modal_settings = modal_options(scene.modal);
  modal_settings.variants = variants;
  int highest = scene.has_modal_section ? scene.modal.modes : 1;
  if (section.excitation) highest = std::max(highest, section.excitation->mode);
  if (section.release) highest = std::max(highest, section.release->mode);
  if (scene.sweep) highest = std::max({highest, scene.sweep->from.mode, scene.sweep->to.mode});
  modal_settings.modes = std::max(highest, section.damping.at_mode);
  modal_settings.cache_directory = modal_cache;
  // The reduced model solves with the transient variant's K again: its factor is kept.
  if (reduced_follows) {
    modal_settings.factors = &model.factors();
    modal_settings.factors_variant = transient_variant(scene, model);  // the reduced model's system
  }
  modal::ModalResult modes = modal::run_modal(
      [&model](mesh::Variant variant) -> const fem::System& { return *model.system(variant); }, modal_settings);
  on_writer_rank([&] { output::write_modal_outputs(output_directory, model.mesh, modes); });
  stage.ran = true;
  stage.seconds = clock.seconds();
  out << modal::modal_table(modes);
  return modes;
}

}  // namespace crackle::pipeline
