#include "pipeline/reduced_model.hpp"
#include "pipeline/stages.hpp"

#include <cmath>

#include "contact/contact.hpp"
#include "core/errors.hpp"
#include "core/resources.hpp"
#include "reduction/reduction.hpp"
#include "transient/damping.hpp"
#include "transient/excitation.hpp"

namespace crackle::pipeline {
namespace {


/// The excitation's load shape for a unit total force (the amplitude scales it afterwards).
fem::LoadShape unit_load(const scene::Scene& scene, const Model& model, const fem::System& system) {
  if (!scene.transient->excitation) return fem::LoadShape{"none", {}, {}};
  const scene::ExcitationSection& excitation = *scene.transient->excitation;
  fem::LoadPlacement placement;
  placement.name = "transient.excitation";
  if (!excitation.face.empty()) placement.faces = model.mesh.face_sets.at(excitation.face);
  if (!excitation.group.empty()) placement.nodes = model.mesh.node_sets.at(excitation.group);
  if (excitation.point) placement.nodes = {transient::nearest_node(model.mesh, *excitation.point)};
  placement.total = Vec3::Unit(excitation.direction);
  return system.load_shape(placement);
}

double max_frequency(const scene::Scene& scene, double excitation_frequency_hz) {
  const scene::ReducedSection& reduced = scene.transient->reduced;
  if (reduced.max_frequency_hz > 0.0) return reduced.max_frequency_hz;
  const int harmonics = scene.spectrum ? scene.spectrum->harmonics : kDefaultHarmonics;
  if (excitation_frequency_hz > 0.0) return kAutoFrequencyFactor * harmonics * excitation_frequency_hz;
  if (reduced.modes > 0) return 0.0;  // the time step follows the highest retained mode
  throw InputError(scene.file + ": transient.reduced.max_frequency: expected a frequency in Hz (or "
                   "transient.reduced.modes) without a harmonic excitation, got auto");
}

/// The cached reduction when it holds the modes asked.
std::optional<reduced::Reduction> cached(const std::filesystem::path& directory, std::uint64_t key, int modes,
                                         double max_frequency_hz) {
  if (directory.empty()) return std::nullopt;
  std::optional<reduced::Reduction> reduction = reduced::load_cached_reduction(directory, key);
  if (!reduction) return std::nullopt;
  const bool enough = modes > 0 ? reduction->n_computed_modes() >= modes
                                : reduction->modes_up_to(max_frequency_hz).has_value();
  if (!enough) return std::nullopt;
  return reduction;
}

/// Removes the pair rows (the open body without contact).
void drop_pairs(reduced::ReducedSystem& system) {
  const Index m = system.n_modes(), o = system.n_outputs();
  system.friction = false;
  system.pair_area.resize(0);
  system.initial_gap.resize(0);
  system.pair_modes.resize(0, m);
  system.residual.resize(0, 0);
  system.load_residual.resize(0);
  system.output_residual_pairs.resize(o, 0);
}

/// q = Phi_m^T M u of a field over all DOFs of `system`, and the mass-norm share of u it leaves out.
VectorX project(const reduced::Reduction& reduction, Index modes, const fem::System& system, const VectorX& field,
                double& lost) {
  const VectorX free_field = fem::restrict_to_free(field, system.constraints());
  const VectorX q = reduction.modal_coordinates(free_field, modes);
  const VectorX rest = free_field - reduction.shapes.leftCols(modes) * q;
  lost = std::sqrt(rest.dot(reduction.mass.cwiseProduct(rest)) / free_field.dot(reduction.mass.cwiseProduct(free_field)));
  return q;
}

/// The output points of the probes (3 rows each) and their names and offsets: the placed probes'
/// nodes, copies and opening pairs (frame n+, t1, t2), or each probe's nearest node.
std::vector<reduced::OutputPoint> output_points(const scene::Scene& scene, const Model& model,
                                                const std::vector<transient::Probe>* probes, ReducedModel& result) {
  const std::vector<scene::ProbeSection>& sections = scene.transient->probes;
  std::vector<reduced::OutputPoint> outputs;
  result.output_offsets = VectorX::Zero(3 * static_cast<Index>(sections.size()));
  for (std::size_t p = 0; p < sections.size(); ++p) {
    reduced::OutputPoint point;
    if (probes) {
      const transient::Probe& placed = (*probes)[p];
      point.node = placed.node;
      point.minus_node = placed.minus_node;
      point.frame = placed.frame;
      if (placed.opening()) result.output_offsets[3 * static_cast<Index>(p)] = placed.initial_gap;
    } else {
      point.node = transient::nearest_node(model.mesh, sections[p].point);
    }
    outputs.push_back(point);
    static const char* opening_names[3] = {"gap", "slip_1", "slip_2"};
    for (int c = 0; c < 3; ++c) {
      result.output_names.push_back(sections[p].name + " " +
                                    (point.minus_node >= 0 ? std::string(opening_names[c]) : std::string("u_") + axis_name(c)));
    }
  }
  return outputs;
}

/// Per probe, the index of an opening probe's pair among the reduced model's pairs (-1 otherwise).
void find_probe_pairs(const mesh::Mesh& mesh, bool with_pairs, const std::vector<transient::Probe>* probes,
                      ReducedModel& result) {
  const std::vector<mesh::CrackPair> pairs = with_pairs ? reduced::split_pairs(mesh) : std::vector<mesh::CrackPair>{};
  const std::size_t n_probes = result.output_names.size() / 3;
  result.probe_pairs.assign(n_probes, -1);
  for (std::size_t p = 0; probes && p < n_probes; ++p) {
    for (std::size_t i = 0; i < pairs.size() && (*probes)[p].opening(); ++i) {
      if (pairs[i].minus == (*probes)[p].minus_node) result.probe_pairs[p] = static_cast<Index>(i);
    }
  }
}

}  // namespace

ReducedModel build_reduced_model(const scene::Scene& scene, const Model& model, double excitation_frequency_hz,
                                 const std::filesystem::path& cache_directory,
                                 const transient::InitialConditions* initial,
                                 const std::vector<transient::Probe>* probes) {
  if (!scene.transient) throw InputError(scene.file + ": transient: expected a section for the reduced model");
  Stopwatch clock;
  const scene::TransientSection& section = *scene.transient;
  const bool with_crack = transient_variant(scene, model) == mesh::Variant::open;
  const fem::System& system = *model.system(transient_variant(scene, model));
  const contact::ContactOptions contact_options = scene_contact_options(scene);
  const bool friction = with_crack && scene.contact.model != scene::ContactModel::none && contact_options.friction_coefficient > 0.0;

  ReducedModel result;
  const std::vector<reduced::OutputPoint> outputs = output_points(scene, model, probes, result);
  const fem::LoadShape load = unit_load(scene, model, system);
  result.max_frequency_hz = max_frequency(scene, excitation_frequency_hz);

  reduced::ReductionOptions options;
  options.modes = section.reduced.modes;
  options.max_frequency_hz = result.max_frequency_hz;
  options.friction = friction;
  const std::uint64_t key = reduced::reduction_key(system, outputs, load, friction);
  std::optional<reduced::Reduction> reduction = cached(cache_directory, key, options.modes, options.max_frequency_hz);
  result.from_cache = reduction.has_value();
  if (!reduction) {
    reduction = reduced::compute_reduction(system, options, outputs, load, &model.factors());
    if (!cache_directory.empty()) reduced::store_cached_reduction(cache_directory, key, *reduction);
  }
  Index modes = reduction->n_computed_modes();
  if (options.modes > 0) modes = options.modes;
  else if (const std::optional<Index> up_to = reduction->modes_up_to(options.max_frequency_hz)) modes = *up_to;
  const double amplitude = section.excitation ? section.excitation->amplitude : 0.0;
  result.system = reduced::reduced_system(*reduction, modes, amplitude);
  if (!section.reduced.residual_flexibility) {
    // Modes only: pairs and outputs see no static correction (a massless boundary needs R > 0, so the
    // pairs keep a tiny compliance of 1e-9 of their static one).
    result.system.residual = 1e-9 * reduction->pair_static.diagonal().asDiagonal();
    result.system.load_residual.setZero();
    result.system.output_residual_pairs.setZero();
    result.system.output_residual_load.setZero();
  }
  const bool with_pairs = with_crack && scene.contact.model != scene::ContactModel::none;
  if (!with_pairs) drop_pairs(result.system);
  find_probe_pairs(model.mesh, with_pairs, probes, result);
  if (section.snapshots > 0) {
    result.fields = std::make_unique<reduced::FieldRecovery>(system, *reduction, modes, load, amplitude, with_pairs,
                                                             section.reduced.residual_flexibility);
  }
  if (with_pairs) {
    const contact::PenaltyChoice penalty = contact::choose_penalty(model.mesh, model.materials, contact_options);
    result.system.normal_penalty = penalty.normal_penalty;
    result.system.tangential_penalty = penalty.tangential_penalty;
    result.system.friction_coefficient = contact_options.friction_coefficient;
    result.system.initial_gap.setConstant(contact_options.initial_gap);
  }
  // Damping from alpha/beta or a ratio at a frequency in Hz; a ratio at a mode is left to the caller
  // (who has the modes: scene_damping with them).
  const scene::DampingSection& scene_ratio = section.damping;
  const transient::RayleighDamping damping =
      scene_ratio.ratio && !scene_ratio.at_hz ? transient::RayleighDamping{} : scene_damping(scene, std::nullopt);
  result.system.rayleigh_alpha = damping.alpha;
  result.system.rayleigh_beta = damping.beta;
  result.initial_displacement = VectorX::Zero(modes);
  result.initial_velocity = VectorX::Zero(modes);
  if (initial && initial->displacement.size() > 0 && initial->displacement.squaredNorm() > 0.0) {
    result.initial_displacement =
        project(*reduction, modes, system, initial->displacement, result.initial_displacement_lost);
  }
  if (initial && initial->velocity.size() > 0 && initial->velocity.squaredNorm() > 0.0) {
    result.initial_velocity = project(*reduction, modes, system, initial->velocity, result.initial_velocity_lost);
  }
  result.modes = static_cast<int>(modes);
  result.pairs = result.system.n_pairs();
  result.computed_modes = static_cast<int>(reduction->n_computed_modes());
  result.modes_s = reduction->modes_s;
  result.flexibility_s = reduction->flexibility_s;
  result.setup_s = clock.seconds();
  return result;
}

}  // namespace crackle::pipeline
