/// \file Stage 2 of `crackle run` with the full model (run_stages.hpp): the explicit transient, on
/// one process or distributed under mpirun, and its snapshots.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "core/errors.hpp"
#include "io/files.hpp"
#include "io/vtu.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/run_stages.hpp"
#include "output/transient_json.hpp"

namespace crackle::pipeline {

void SnapshotWriter::on_step(const transient::StepView& view) {
  if (!due(view.step)) return;
  io::PointField field{"displacement", 3, std::vector<double>(3 * static_cast<std::size_t>(mesh_.n_nodes()))};
  for (Index node = 0; node < mesh_.n_nodes(); ++node) {
    for (int c = 0; c < 3; ++c) field.values[3 * node + c] = view.displacement[dofs_.dof(node, c)];
  }
  char stem[32];
  std::snprintf(stem, sizeof stem, "snapshot_%04d", next_);
  std::string name = std::string(stem) + ".vtu";
  if (partition_) {
    name = write_snapshot_pieces(directory_, stem, *partition_, field);
  } else {
    io::write_vtu(directory_ / name, mesh_, {field});
  }
  // The displacement is U(i+1), at t_(i+1).
  collection_ += "    <DataSet timestep=\"" + format_number(view.time + view.dt) + "\" group=\"\" part=\"0\" file=\"" +
                 name + "\"/>\n";
  on_writer_rank([&] {
    io::write_file_atomic(directory_ / "snapshots.pvd",
                          "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n" +
                              collection_ + "  </Collection>\n</VTKFile>\n");
  });
  ++next_;
}

/// Stage 2: the transient, with the harmonic accumulators fed every step when a spectrum is asked;
/// probes.csv, energy.csv and transient.json written once, when it ends (also when it fails).
std::unique_ptr<transient::TransientSolver> run_transient_stage(const scene::Scene& scene, const Model& model,
                                                                TransientSetup& setup, const std::filesystem::path& directory,
                                                                std::optional<SpectrumMonitor>& spectrum) {
  const scene::TransientSection& section = *scene.transient;
  std::unique_ptr<transient::TransientSolver> solver;
  const distributed::MeshPartition* partition = nullptr;
  if (run_ranks() > 1) {
    if (setup.variant != mesh::Variant::open && model.mesh.has_crack()) {
      throw InputError(scene.where("transient.variant") + ": expected open under mpirun -np " +
                       std::to_string(run_ranks()) + " (the distributed run keeps the crack faces split), got uncracked");
    }
    const contact::ContactOptions contact_options = scene_contact_options(scene);
    setup.distributed = std::make_unique<DistributedTransient>(
        distribute_transient(model, setup.problem, setup.contact ? &contact_options : nullptr));
    partition = setup.distributed->partition.get();
    setup.settings.overlap_halo = halo_overlap_option();
    solver = std::make_unique<transient::TransientSolver>(partition->local_mesh(), setup.distributed->problem,
                                                          setup.settings);
  } else {
    solver = std::make_unique<transient::TransientSolver>(model.system(setup.variant), setup.problem, setup.settings);
  }
  // The time step is known once the solver is set up: decimate probes.csv, and check the histories
  // and the snapshots against the memory and the disk before the first step.
  const Index finished_interval = probe_interval(scene, setup.frequency, solver->dt());
  solver->set_probe_interval(finished_interval);
  const double steps = static_cast<double>(solver->n_steps());
  on_every_rank([&] { check_run_outputs(scene, estimate_mesh(scene), steps, std::ceil(steps / finished_interval), directory); });
  if (scene.spectrum && setup.frequency > 0.0) spectrum.emplace(scene, setup.frequency, solver->dt());
  SnapshotWriter snapshots(directory, partition ? partition->local_mesh() : model.mesh, solver->dofs(),
                           section.snapshots, solver->n_steps(), partition);
  transient::TransientCallbacks callbacks;
  callbacks.on_step = [&](const transient::StepView& view) {
    snapshots.on_step(view);
    return spectrum ? spectrum->add(view) : false;
  };
  if (spectrum) callbacks.progress_note = [&](double elapsed) { return spectrum->progress_note(elapsed); };
  if (is_writer_rank()) {
    for (const std::string& warning : setup.warnings) std::cerr << "crackle: warning: " << warning << "\n";
  }
  const transient::TransientSolver& finished = *solver;
  callbacks.on_finish = [&](const transient::TransientSummary& summary) {
    nlohmann::json extra = setup.contact ? output::contact_json(setup.contact->contact()) : nlohmann::json::object();
    extra["probes"] = setup.probes_json;
    extra["probe_interval"] = finished_interval;
    if (setup.distributed) extra["partition"] = setup.distributed->partition_json;
    std::vector<std::string> warnings = setup.warnings;
    warnings.insert(warnings.end(), summary.warnings.begin(), summary.warnings.end());
    extra["warnings"] = warnings;
    // Every rank holds the same records (summed each step): rank 0 writes them.
    on_writer_rank([&] { output::write_transient_outputs(directory, finished, extra); });
  };
  solver->run(callbacks);
  return solver;
}

}  // namespace crackle::pipeline
