#include "pipeline/distributed_run.hpp"

#include <petscsys.h>

#include "core/errors.hpp"
#include "io/files.hpp"

namespace crackle::pipeline {
namespace {

nlohmann::json spread_json(const distributed::Spread& spread) {
  return {{"min", spread.min}, {"max", spread.max}, {"mean", spread.mean}};
}

/// A load's nodal forces placed on the whole body, restricted to the DOFs this rank owns.
transient::ExternalLoad local_load(const Model& model, const distributed::MeshPartition& partition,
                                   const transient::ExternalLoad& load, std::size_t index) {
  transient::ExternalLoad local = load;
  const std::string where = "load '" + (load.name.empty() ? std::to_string(index) : load.name) + "'";
  const fem::LoadPlacement placement{where, load.nodes, load.faces, load.amplitude * load.direction.normalized()};
  const fem::LoadShape shape = model.system(mesh::Variant::open)->load_shape(placement);
  transient::ExternalLoad::NodalForces forces;
  for (std::size_t k = 0; k < shape.dofs.size(); ++k) {
    const Index node = shape.dofs[k] / 3;  // the open DOF map: DOF = 3 node + component
    const Index owned = partition.owned_node(node);
    if (owned < 0) continue;
    forces.dofs.push_back(3 * owned + shape.dofs[k] % 3);
    forces.values.push_back(shape.values[k]);
  }
  local.nodal_forces = std::move(forces);
  return local;
}

/// A probe on the rank that owns its node (an opening probe: its pair); node -1 elsewhere. An
/// opening probe keeps its kind on every rank and reads its pair's state from the local contact
/// on the owner, 0 elsewhere (the ranks' states are summed).
transient::Probe local_probe(const distributed::MeshPartition& partition, const transient::Probe& probe,
                             const std::shared_ptr<contact::ContactForce>& contact) {
  transient::Probe local = probe;
  local.node = partition.owned_node(probe.node);
  if (!probe.opening()) return local;
  if (local.node < 0) {
    local.minus_node = 0;  // any local node: the kind is kept, the reading is zero
    if (probe.state) local.state = [] { return 0; };
    return local;
  }
  local.minus_node = partition.local_node(probe.minus_node);
  local.state = nullptr;
  if (probe.state && contact) {
    const Index k = contact->contact().find_pair(3 * local.node);
    if (k >= 0) local.state = [contact, k] { return contact->contact().pair_state(k); };
  }
  if (probe.state && !local.state) local.state = [] { return 0; };
  return local;
}

}  // namespace

int run_ranks() {
  PetscBool started = PETSC_FALSE;
  PetscInitialized(&started);
  return started ? distributed::world_size() : 1;
}

bool is_writer_rank() { return run_ranks() == 1 || distributed::world_rank() == 0; }

bool halo_overlap_option() {
  PetscBool value = PETSC_FALSE, set = PETSC_FALSE;
  if (PetscOptionsGetBool(nullptr, nullptr, "-crackle_halo_overlap", &value, &set) != 0)
    throw SolverError("PETSc: cannot read the option -crackle_halo_overlap");
  return set && value;
}

DistributedTransient distribute_transient(const Model& model, const transient::TransientProblem& global,
                                          const contact::ContactOptions* contact_options) {
  DistributedTransient run;
  run.partition = std::make_unique<distributed::MeshPartition>(
      model.mesh, distributed::partition_elements(model.mesh, distributed::world_size()));
  const distributed::MeshPartition& partition = *run.partition;
  transient::TransientProblem& problem = run.problem;
  on_every_rank([&] {
    problem.materials = model.materials;
    problem.dirichlet = partition.local_dirichlet(model.dirichlet);
    for (std::size_t k = 0; k < global.loads.size(); ++k)
      problem.loads.push_back(local_load(model, partition, global.loads[k], k));
    problem.initial.displacement = partition.local_field(global.initial.displacement);
    problem.initial.velocity = partition.local_field(global.initial.velocity);
    if (contact_options) {
      run.contact = partition.local_contact(model.materials, *contact_options);
      problem.terms.push_back(run.contact);
    }
    for (const transient::Probe& probe : global.probes) problem.probes.push_back(local_probe(partition, probe, run.contact));
  });
  problem.distribution = std::shared_ptr<const transient::Distribution>(run.partition.get(), [](const auto*) {});
  const distributed::PartitionBalance balance = partition.balance();
  run.partition_json = {{"ranks", partition.ranks()},
                        {"partitioner", "PT-Scotch (PETSc MatPartitioning), crack pairs on one rank"},
                        {"mesh", "replicated on every rank"},
                        {"elements", spread_json(balance.elements)},
                        {"owned_dofs", spread_json(balance.owned_dofs)},
                        {"ghost_dofs", spread_json(balance.ghost_dofs)},
                        {"halo_bytes_per_step", spread_json(balance.halo_bytes_per_step)},
                        {"boundary_elements", spread_json(balance.boundary_elements)}};
  return run;
}

std::string write_snapshot_pieces(const std::filesystem::path& directory, const std::string& stem,
                                  const distributed::MeshPartition& partition, const io::PointField& field) {
  const auto piece = [&stem](int rank) { return stem + "_" + std::to_string(rank) + ".vtu"; };
  on_every_rank([&] { io::write_vtu(directory / piece(partition.rank()), partition.local_mesh(), {field}); });
  const std::string name = stem + ".pvtu";
  on_writer_rank([&] {
    std::string text =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n    <PPointData>\n"
        "      <PDataArray type=\"Float64\" Name=\"" + field.name + "\" NumberOfComponents=\"" +
        std::to_string(field.components) + "\"/>\n    </PPointData>\n    <PCellData>\n"
        "      <PDataArray type=\"Int32\" Name=\"element\" NumberOfComponents=\"1\"/>\n"
        "      <PDataArray type=\"Int32\" Name=\"region\" NumberOfComponents=\"1\"/>\n    </PCellData>\n"
        "    <PPoints>\n      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
    for (int rank = 0; rank < partition.ranks(); ++rank) text += "    <Piece Source=\"" + piece(rank) + "\"/>\n";
    text += "  </PUnstructuredGrid>\n</VTKFile>\n";
    io::write_file_atomic(directory / name, text);
  });
  return name;
}

}  // namespace crackle::pipeline
