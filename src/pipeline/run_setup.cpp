/// \file The transient stage's setup from the scene (run_stages.hpp): loads, damping, contact,
/// release and initial fields, probes, and the run's length.
#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "pipeline/placement.hpp"
#include "pipeline/run_stages.hpp"
#include "pipeline/stages.hpp"
#include "transient/damping.hpp"
#include "transient/excitation.hpp"

namespace crackle::pipeline {
namespace {

std::vector<Index> nodes_in_range(const mesh::Mesh& mesh, const scene::InitialSection& initial) {
  std::vector<Index> nodes;
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    bool inside = true;
    for (int axis = 0; axis < 3; ++axis) {
      if (!initial.range[axis]) continue;
      const double x = mesh.nodes[node][axis];
      inside = inside && x >= (*initial.range[axis])[0] && x <= (*initial.range[axis])[1];
    }
    if (inside) nodes.push_back(node);
  }
  return nodes;
}

/// The excitation as a load, and its frequency (0 for a pulse).
transient::ExternalLoad excitation_load(const scene::Scene& scene, const Model& model,
                                        const std::optional<modal::ModalResult>& modes, double& frequency) {
  const scene::ExcitationSection& excitation = *scene.transient->excitation;
  transient::ExternalLoad load;
  load.name = "transient.excitation";
  if (!excitation.face.empty()) load.faces = model.mesh.face_sets.at(excitation.face);
  if (!excitation.group.empty()) load.nodes = model.mesh.node_sets.at(excitation.group);  // checked by build_model
  if (excitation.point) {
    load.nodes = {PointPlacer(scene, model.mesh).place(*excitation.point, "transient.excitation.point").node};
  }
  load.direction = Vec3::Unit(excitation.direction);
  load.amplitude = excitation.amplitude;
  if (excitation.kind == scene::ExcitationKind::harmonic) {
    frequency = excitation.frequency_hz ? *excitation.frequency_hz
                                        : excitation.ratio * mode_frequency(*modes, excitation.mode, excitation.of,
                                                                            scene.file + ": transient.excitation.frequency.mode");
    load.signal.kind = transient::SignalKind::harmonic;
    load.signal.frequency = frequency;
    load.signal.ramp_periods = excitation.ramp_periods;
  } else {
    load.signal.kind = transient::SignalKind::pulse;
    load.signal.duration = excitation.duration;
  }
  return load;
}

}  // namespace

/// Rayleigh damping from a ratio at a frequency (or a mode), or from alpha and beta.
transient::RayleighDamping scene_damping(const scene::Scene& scene, const std::optional<modal::ModalResult>& modes) {
  const scene::DampingSection& damping = scene.transient->damping;
  const double at_hz = !damping.ratio ? 0.0
                       : damping.at_hz ? *damping.at_hz
                                       : mode_frequency(*modes, damping.at_mode, scene::ModeOf::uncracked,
                                                        scene.file + ": transient.damping.at.mode");
  return transient::stated_damping(damping.ratio, damping.type == scene::DampingType::stiffness, at_hz, damping.alpha, damping.beta);
}

namespace {

/// Initial fields (uniform per coordinate box) over the run's DOFs.
void add_initial_fields(const scene::TransientSection& section, const Model& model, const mesh::DofMap& dofs,
                        transient::InitialConditions& initial) {
  for (const scene::InitialSection& box : section.initial) {
    const std::vector<Index> nodes = nodes_in_range(model.mesh, box);
    if (initial.velocity.size() == 0) initial.velocity = VectorX::Zero(dofs.n_dofs());
    if (initial.displacement.size() == 0) initial.displacement = VectorX::Zero(dofs.n_dofs());
    initial.velocity += transient::uniform_on_nodes(dofs, nodes, box.velocity);
    initial.displacement += transient::uniform_on_nodes(dofs, nodes, box.displacement);
  }
}

}  // namespace

TransientSetup transient_setup(const scene::Scene& scene, const Model& model,
                               const std::optional<modal::ModalResult>& modes, const RunCommandOptions& options) {
  const scene::TransientSection& section = *scene.transient;
  TransientSetup setup;
  if (section.excitation) setup.problem.loads.push_back(excitation_load(scene, model, modes, setup.frequency));
  transient::TransientOptions& settings = setup.settings;
  settings.damping = scene_damping(scene, modes);
  setup.variant = section.variant;
  settings.variant = setup.variant;
  const fem::System& system = *model.system(setup.variant);
  const bool with_contact =
      setup.variant == mesh::Variant::open && model.mesh.has_crack() && scene.contact.model != scene::ContactModel::none;
  const contact::ContactOptions contact_options = scene_contact_options(scene);
  if (with_contact) {
    setup.contact = std::make_shared<contact::ContactForce>(model.mesh, system.dofs(), model.materials, contact_options);
    setup.problem.terms.push_back(setup.contact);
  }
  if (section.release) {
    ReleaseReport report;
    setup.problem.initial =
        release_state(*section.release, model, setup.variant, with_contact ? &contact_options : nullptr,
                      modes ? &*modes : nullptr, scene.file, &report);
    setup.release = report;
  }
  add_initial_fields(section, model, system.dofs(), setup.problem.initial);
  const PointPlacer placer(scene, model.mesh);
  for (std::size_t p = 0; p < section.probes.size(); ++p) {
    const scene::ProbeSection& probe = section.probes[p];
    const transient::Probe placed = place_probe(scene, model, system.dofs(), placer, p, setup.contact.get());
    setup.problem.probes.push_back(placed);
    const Vec3& x = model.mesh.nodes[placed.node];
    setup.probes_json.push_back({{"name", probe.name},
                                 {"point", {probe.point[0], probe.point[1], probe.point[2]}},
                                 {"node", placed.node},
                                 {"node_point", {x[0], x[1], x[2]}},
                                 {"distance_m", (x - probe.point).norm()}});
    if (placed.opening()) {
      setup.probes_json.back()["kind"] = "crack_opening";
      setup.probes_json.back()["minus_node"] = placed.minus_node;
      setup.probes_json.back()["normal"] = {placed.frame(0, 0), placed.frame(0, 1), placed.frame(0, 2)};
      continue;
    }
    if (probe.side) setup.probes_json.back()["side"] = text_of(scene::kFaceSideWords, *probe.side);
    // A probe whose analysed component is held (a clamped face) has A1 = 0: its ratios are NaN.
    const int component = probe.component >= 0 ? probe.component
                          : section.excitation  ? section.excitation->direction
                                                : -1;
    const fem::Constraints& constraints = system.constraints();
    for (int c = 0; c < 3; ++c) {
      if (c != component || !constraints.fixed[system.dofs().dof(placed.node, c)]) continue;
      setup.warnings.push_back("probe '" + probe.name + "' (node " + std::to_string(placed.node) + ") has its u_" +
                               axis_name(c) + " held by a boundary condition: its response is the prescribed value" +
                               (scene.spectrum ? ", so A1 = 0 and its damage indices are undefined (NaN)" : ""));
    }
  }
  // A hair beyond the last period, so that rounding in n dt cannot leave it one step short.
  settings.end_time = section.periods ? *section.periods / setup.frequency * (1.0 + 1e-9) : *section.duration;
  settings.run_length_key = scene.where(section.periods ? "transient.periods" : "transient.duration");
  settings.time_step_key = scene.where("transient.time_step");
  settings.time_step = section.time_step.value_or(0.0);
  settings.time_step_options.safety_factor = section.safety_factor;
  settings.force_time_step = section.force_time_step;
  if (setup.frequency > 0.0) settings.whole_steps_per_period = 1.0 / setup.frequency;
  settings.progress = section.progress && options.progress;
  return setup;
}

/// Steps between probes.csv rows: transient.history.samples_per_period rows per excitation period
/// (per pulse duration), every step when it is `all` or without an excitation.
Index probe_interval(const scene::Scene& scene, double frequency, double dt) {
  const scene::TransientSection& section = *scene.transient;
  if (section.history_samples_per_period <= 0) return 1;
  double period = 0.0;
  if (frequency > 0.0) period = 1.0 / frequency;
  if (section.excitation && section.excitation->kind == scene::ExcitationKind::pulse) period = section.excitation->duration;
  if (!(period > 0.0)) return 1;
  const double steps = std::floor(period / dt / section.history_samples_per_period);
  return static_cast<Index>(std::clamp(steps, 1.0, 1e9));
}

}  // namespace crackle::pipeline
