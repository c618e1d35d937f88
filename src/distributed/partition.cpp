#include "distributed/partition.hpp"

#include <petscmat.h>

#include <algorithm>
#include <cassert>
#include <cstring>
#include <new>
#include <string>

#include "core/errors.hpp"

namespace crackle::distributed {
namespace {

void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw SolverError(std::string("distributed transient: PETSc failed in ") + what);
}

/// Local indices of the corner nodes of an element (face adjacency is decided on them).
std::vector<int> corner_nodes(const mesh::Mesh& mesh) {
  if (mesh.shape == mesh::ElementShape::tetrahedron) return {0, 1, 2, 3};
  const int p = mesh.order, n = p + 1;
  std::vector<int> corners;
  for (int k : {0, p})
    for (int j : {0, p})
      for (int i : {0, p}) corners.push_back(i + n * (j + n * k));
  return corners;
}

}  // namespace

int world_rank() {
  int rank = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  return rank;
}

int world_size() {
  int size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  return size;
}

std::vector<int> partition_elements(const mesh::Mesh& mesh, int ranks) {
  const Index n_elements = mesh.n_elements();
  if (ranks > n_elements) {
    throw InputError("mpirun -np " + std::to_string(ranks) + ": more ranks than the " + std::to_string(n_elements) +
                     " elements of the mesh; expected at most " + std::to_string(n_elements) +
                     " ranks (use fewer ranks or a finer mesh)");
  }
  const int rank = world_rank();
  // Dual graph rows of this rank: an even block of the elements (every rank holds the mesh).
  const Index begin = n_elements * rank / ranks, end = n_elements * (rank + 1) / ranks;
  const std::vector<int> corners = corner_nodes(mesh);
  const int shared_for_face = mesh.shape == mesh::ElementShape::tetrahedron ? 3 : 4;
  std::vector<Index> first(mesh.n_nodes() + 1, 0), elements_of;
  for (Index e = 0; e < n_elements; ++e)
    for (int a : corners) ++first[mesh.element_nodes(e)[a] + 1];
  for (Index i = 0; i < mesh.n_nodes(); ++i) first[i + 1] += first[i];
  elements_of.resize(first.back());
  {
    std::vector<Index> next(first.begin(), first.end() - 1);
    for (Index e = 0; e < n_elements; ++e)
      for (int a : corners) elements_of[next[mesh.element_nodes(e)[a]]++] = e;
  }
  std::vector<PetscInt> rows{0}, columns;
  std::vector<Index> neighbours;
  for (Index e = begin; e < end; ++e) {
    neighbours.clear();
    for (int a : corners) {
      const Index node = mesh.element_nodes(e)[a];
      for (Index k = first[node]; k < first[node + 1]; ++k)
        if (elements_of[k] != e) neighbours.push_back(elements_of[k]);
    }
    std::sort(neighbours.begin(), neighbours.end());
    for (std::size_t k = 0; k < neighbours.size();) {
      std::size_t same = k;
      while (same < neighbours.size() && neighbours[same] == neighbours[k]) ++same;
      if (static_cast<int>(same - k) >= shared_for_face) columns.push_back(static_cast<PetscInt>(neighbours[k]));
      k = same;
    }
    rows.push_back(static_cast<PetscInt>(columns.size()));
  }
  // MatCreateMPIAdj takes the arrays (PetscMalloc'd) and frees them with the matrix.
  PetscInt *ia = nullptr, *ja = nullptr;
  check(PetscMalloc1(rows.size(), &ia), "PetscMalloc1");
  check(PetscMalloc1(std::max<std::size_t>(1, columns.size()), &ja), "PetscMalloc1");
  std::copy(rows.begin(), rows.end(), ia);
  std::copy(columns.begin(), columns.end(), ja);
  Mat adjacency = nullptr;
  check(MatCreateMPIAdj(PETSC_COMM_WORLD, static_cast<PetscInt>(end - begin), static_cast<PetscInt>(n_elements), ia, ja,
                        nullptr, &adjacency),
        "MatCreateMPIAdj");
  MatPartitioning partitioning = nullptr;
  check(MatPartitioningCreate(PETSC_COMM_WORLD, &partitioning), "MatPartitioningCreate");
  check(MatPartitioningSetAdjacency(partitioning, adjacency), "MatPartitioningSetAdjacency");
  check(MatPartitioningSetNParts(partitioning, ranks), "MatPartitioningSetNParts");
#if defined(PETSC_HAVE_PTSCOTCH)
  check(MatPartitioningSetType(partitioning, MATPARTITIONINGPTSCOTCH), "MatPartitioningSetType");
#endif
  check(MatPartitioningSetFromOptions(partitioning), "MatPartitioningSetFromOptions");
  IS parts = nullptr, all = nullptr;
  check(MatPartitioningApply(partitioning, &parts), "MatPartitioningApply");
  check(ISAllGather(parts, &all), "ISAllGather");
  const PetscInt* values = nullptr;
  check(ISGetIndices(all, &values), "ISGetIndices");
  std::vector<int> element_rank(values, values + n_elements);
  check(ISRestoreIndices(all, &values), "ISRestoreIndices");
  ISDestroy(&all);
  ISDestroy(&parts);
  MatPartitioningDestroy(&partitioning);
  MatDestroy(&adjacency);
  return element_rank;
}

void agree(std::exception_ptr error) {
  const int rank = world_rank(), size = world_size();
  int code = 0;
  std::string text;
  if (error) {
    try {
      std::rethrow_exception(error);
    } catch (const std::bad_alloc&) {
      code = -1;  // rethrown as std::bad_alloc on every rank
    } catch (const std::exception& failure) {
      code = exit_code_for(failure);
      text = failure.what();
    } catch (...) {
      code = 1;
      text = "unknown error";
    }
  }
  int mine = error ? rank : size, first = size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD);
  if (first == size) return;
  if (rank == first) text = first > 0 ? "rank " + std::to_string(first) + ": " + text : text;
  int header[2] = {code, static_cast<int>(text.size())};
  MPI_Bcast(header, 2, MPI_INT, first, PETSC_COMM_WORLD);
  text.resize(static_cast<std::size_t>(header[1]));
  MPI_Bcast(text.data(), header[1], MPI_CHAR, first, PETSC_COMM_WORLD);
  if (rank == first) std::rethrow_exception(error);
  switch (header[0]) {  // exit_code_for's codes
    case 2: throw InputError(text);
    case 3: throw SolverError(text);
    case 4: throw IoError(text);
    case -1: throw std::bad_alloc();
    default: throw Error(text);
  }
}

PartitionBalance MeshPartition::balance() const {
  const HaloCounts counts = halo_counts();
  const std::vector<double> mine{static_cast<double>(local_.n_elements()), static_cast<double>(counts.owned_dofs),
                                 static_cast<double>(counts.ghost_dofs), counts.bytes_per_step,
                                 static_cast<double>(counts.boundary_elements)};
  const int n = static_cast<int>(mine.size());
  std::vector<double> low(mine.size()), high(mine.size()), total(mine.size());
  MPI_Allreduce(mine.data(), low.data(), n, MPI_DOUBLE, MPI_MIN, PETSC_COMM_WORLD);
  MPI_Allreduce(mine.data(), high.data(), n, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
  MPI_Allreduce(mine.data(), total.data(), n, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  const auto spread = [&](int k) { return Spread{low[k], high[k], total[k] / ranks_}; };
  return {spread(0), spread(1), spread(2), spread(3), spread(4)};
}

MeshPartition::MeshPartition(const mesh::Mesh& global, std::vector<int> element_rank)
    : global_(&global), element_rank_(std::move(element_rank)), rank_(world_rank()), ranks_(world_size()) {
  const Index n_elements = global.n_elements(), n_nodes = global.n_nodes();
  if (static_cast<Index>(element_rank_.size()) != n_elements) {
    throw InputError("distributed transient: " + std::to_string(element_rank_.size()) + " element ranks for " +
                     std::to_string(n_elements) + " elements");
  }
  std::vector<Index> per_rank(ranks_, 0);
  for (int r : element_rank_) {
    if (r < 0 || r >= ranks_) throw InputError("distributed transient: element rank " + std::to_string(r) + " outside 0.." + std::to_string(ranks_ - 1));
    ++per_rank[r];
  }
  for (int r = 0; r < ranks_; ++r) {
    if (per_rank[r] == 0) {
      throw InputError("mpirun -np " + std::to_string(ranks_) + ": the partition left rank " + std::to_string(r) +
                       " without elements (" + std::to_string(n_elements) + " elements); use fewer ranks");
    }
  }
  // Node owners: the lowest rank touching the node; both nodes of a crack pair go to the plus node's.
  const int npe = global.nodes_per_element();
  std::vector<int> owner(n_nodes, ranks_);
  for (Index e = 0; e < n_elements; ++e)
    for (int a = 0; a < npe; ++a) {
      int& o = owner[global.element_nodes(e)[a]];
      o = std::min(o, element_rank_[e]);
    }
  for (const mesh::CrackPair& pair : global.crack_pairs) owner[pair.minus] = owner[pair.plus];
  // Local nodes: touched by own elements, plus the partners of their crack pairs.
  std::vector<char> held(n_nodes, 0);
  for (Index e = 0; e < n_elements; ++e)
    if (element_rank_[e] == rank_)
      for (int a = 0; a < npe; ++a) held[global.element_nodes(e)[a]] = 1;
  for (const mesh::CrackPair& pair : global.crack_pairs)
    if (held[pair.minus] || held[pair.plus]) held[pair.minus] = held[pair.plus] = 1;
  for (Index i = 0; i < n_nodes; ++i)
    if (owner[i] == rank_) held[i] = 1;
  local_of_.assign(n_nodes, -1);
  for (int pass = 0; pass < 2; ++pass) {  // owned first, then ghosts
    for (Index i = 0; i < n_nodes; ++i) {
      if (!held[i] || (owner[i] == rank_) != (pass == 0)) continue;
      local_of_[i] = static_cast<Index>(global_nodes_.size());
      global_nodes_.push_back(i);
    }
    if (pass == 0) n_owned_nodes_ = static_cast<Index>(global_nodes_.size());
  }
  // The PETSc numbering: ranks in order, each rank's owned nodes in increasing global number.
  std::vector<Index> offset(ranks_ + 1, 0), petsc_node(n_nodes, 0);
  for (Index i = 0; i < n_nodes; ++i) ++offset[owner[i] + 1];
  for (int r = 0; r < ranks_; ++r) offset[r + 1] += offset[r];
  for (Index i = 0; i < n_nodes; ++i) petsc_node[i] = offset[owner[i]]++;
  for (Index node : global_nodes_)
    for (int c = 0; c < 3; ++c) global_dofs_.push_back(3 * node + c);

  // Boundary elements (touching a node that another rank holds: a ghost, or an owned node that
  // another rank's elements or crack pairs reach) first, then the interior; each in global order.
  std::vector<char> touched_elsewhere(n_nodes, 0);
  for (Index e = 0; e < n_elements; ++e)
    if (element_rank_[e] != rank_)
      for (int a = 0; a < npe; ++a) touched_elsewhere[global.element_nodes(e)[a]] = 1;
  std::vector<char> shared(n_nodes, 0);
  for (Index i = 0; i < n_nodes; ++i) shared[i] = held[i] && (owner[i] != rank_ || touched_elsewhere[i]);
  for (const mesh::CrackPair& pair : global.crack_pairs) {
    if (touched_elsewhere[pair.minus] || touched_elsewhere[pair.plus]) {
      shared[pair.minus] = held[pair.minus];
      shared[pair.plus] = held[pair.plus];
    }
  }
  std::vector<Index> own_elements;
  for (int pass = 0; pass < 2; ++pass) {
    for (Index e = 0; e < n_elements; ++e) {
      if (element_rank_[e] != rank_) continue;
      bool boundary = false;
      for (int a = 0; a < npe && !boundary; ++a) boundary = shared[global.element_nodes(e)[a]] != 0;
      if (boundary == (pass == 0)) own_elements.push_back(e);
    }
    if (pass == 0) n_boundary_elements_ = static_cast<Index>(own_elements.size());
  }

  // The local mesh.
  local_.shape = global.shape;
  local_.order = global.order;
  local_.axis_aligned_bricks = global.axis_aligned_bricks;
  local_.crack_area = global.crack_area;
  for (Index node : global_nodes_) local_.nodes.push_back(global.nodes[node]);
  local_.n_original_nodes = local_.n_nodes();
  std::vector<Index> local_element(n_elements, -1);
  for (Index e : own_elements) {
    local_element[e] = static_cast<Index>(local_.element_region.size());
    for (int a = 0; a < npe; ++a) local_.connectivity.push_back(local_of_[global.element_nodes(e)[a]]);
    local_.element_region.push_back(global.element_region[e]);
  }
  for (const auto& [name, nodes] : global.node_sets) {
    std::vector<Index>& set = local_.node_sets[name];
    for (Index node : nodes)
      if (local_of_[node] >= 0) set.push_back(local_of_[node]);
  }
  for (const auto& [name, faces] : global.face_sets) {
    std::vector<mesh::FaceRef>& set = local_.face_sets[name];
    for (const mesh::FaceRef& face : faces)
      if (local_element[face.element] >= 0) set.push_back({local_element[face.element], face.local_face});
  }
  for (const auto& [name, elements] : global.element_sets) {
    std::vector<Index>& set = local_.element_sets[name];
    for (Index e : elements)
      if (local_element[e] >= 0) set.push_back(local_element[e]);
  }
  for (const mesh::CrackPair& pair : global.crack_pairs) {
    if (local_of_[pair.minus] < 0) continue;
    mesh::CrackPair copy = pair;
    copy.minus = local_of_[pair.minus];
    copy.plus = local_of_[pair.plus];
    local_.crack_pairs.push_back(copy);
  }

  // The halo: a ghosted Vec over the PETSc numbering of the DOFs.
  std::vector<PetscInt> ghosts;
  for (Index l = n_owned_nodes_; l < static_cast<Index>(global_nodes_.size()); ++l)
    for (int c = 0; c < 3; ++c) ghosts.push_back(static_cast<PetscInt>(3 * petsc_node[global_nodes_[l]] + c));
  check(VecCreateGhost(PETSC_COMM_WORLD, static_cast<PetscInt>(3 * n_owned_nodes_), PETSC_DECIDE,
                       static_cast<PetscInt>(ghosts.size()), ghosts.data(), &halo_),
        "VecCreateGhost");
  // The boundary: owned entries that another rank holds as a ghost (found by scattering ones).
  Vec form = nullptr;
  PetscScalar* array = nullptr;
  check(VecGhostGetLocalForm(halo_, &form), "VecGhostGetLocalForm");
  check(VecGetArray(form, &array), "VecGetArray");
  const Index owned = n_owned_dofs(), n_local = static_cast<Index>(global_dofs_.size());
  for (Index k = 0; k < n_local; ++k) array[k] = k < owned ? 0.0 : 1.0;
  check(VecRestoreArray(form, &array), "VecRestoreArray");
  check(VecGhostUpdateBegin(halo_, ADD_VALUES, SCATTER_REVERSE), "VecGhostUpdateBegin");
  check(VecGhostUpdateEnd(halo_, ADD_VALUES, SCATTER_REVERSE), "VecGhostUpdateEnd");
  check(VecGetArray(form, &array), "VecGetArray");
  for (Index k = 0; k < owned; ++k) {
    if (array[k] != 0.0) boundary_.push_back(k);
    array[k] = 0.0;
  }
  check(VecRestoreArray(form, &array), "VecRestoreArray");
  check(VecGhostRestoreLocalForm(halo_, &form), "VecGhostRestoreLocalForm");
#ifndef NDEBUG
  // The interior touches no DOF another rank holds (what the overlapped halo relies on).
  std::vector<char> boundary_node(local_.n_nodes(), 0);
  for (Index k : boundary_) boundary_node[k / 3] = 1;
  for (Index e = n_boundary_elements_; e < local_.n_elements(); ++e)
    for (int a = 0; a < npe; ++a) {
      const Index node = local_.element_nodes(e)[a];
      assert(node < n_owned_nodes_ && !boundary_node[node]);
    }
#endif
}

MeshPartition::~MeshPartition() {
  if (halo_) VecDestroy(&halo_);
}

Index MeshPartition::owned_node(Index global_node) const {
  const Index local = local_of_.at(global_node);
  return local >= 0 && local < n_owned_nodes_ ? local : -1;
}

HaloCounts MeshPartition::halo_counts() const {
  HaloCounts counts;
  counts.owned_dofs = 3 * n_owned_nodes_;
  counts.ghost_dofs = 3 * (static_cast<Index>(global_nodes_.size()) - n_owned_nodes_);
  counts.boundary_dofs = static_cast<Index>(boundary_.size());
  counts.boundary_elements = n_boundary_elements_;
  counts.interior_elements = local_.n_elements() - n_boundary_elements_;
  counts.bytes_per_step = 2.0 * 8.0 * static_cast<double>(counts.ghost_dofs);
  return counts;
}

void MeshPartition::complete(VectorX& local) const {
  send_shares(local);
  receive_sums(local);
  receive_ghosts(local);
}

// Only the ghosts and the owned entries that are ghosts elsewhere (the boundary) are copied: the
// PETSc Vec's owned part stays zero between completions, so the scatter-add leaves there the sum of
// the other ranks' shares.

void MeshPartition::send_shares(VectorX& local) const {
  const Stopwatch watch;
  const Index n = static_cast<Index>(local.size()), owned = n_owned_dofs();
  if (n != static_cast<Index>(global_dofs_.size())) throw InputError("distributed transient: a local vector of the wrong size");
  Vec form = nullptr;
  PetscScalar* array = nullptr;
  check(VecGhostGetLocalForm(halo_, &form), "VecGhostGetLocalForm");
  check(VecGetArray(form, &array), "VecGetArray");
  std::memcpy(array + owned, local.data() + owned, (n - owned) * sizeof(double));
  check(VecRestoreArray(form, &array), "VecRestoreArray");
  check(VecGhostRestoreLocalForm(halo_, &form), "VecGhostRestoreLocalForm");
  check(VecGhostUpdateBegin(halo_, ADD_VALUES, SCATTER_REVERSE), "VecGhostUpdateBegin");
  communication_seconds_ += watch.seconds();
}

void MeshPartition::receive_sums(VectorX& local) const {
  const Stopwatch watch;
  check(VecGhostUpdateEnd(halo_, ADD_VALUES, SCATTER_REVERSE), "VecGhostUpdateEnd");
  Vec form = nullptr;
  PetscScalar* array = nullptr;
  check(VecGhostGetLocalForm(halo_, &form), "VecGhostGetLocalForm");
  check(VecGetArray(form, &array), "VecGetArray");
  for (Index k : boundary_) array[k] = local[k] += array[k];
  check(VecRestoreArray(form, &array), "VecRestoreArray");
  check(VecGhostRestoreLocalForm(halo_, &form), "VecGhostRestoreLocalForm");
  check(VecGhostUpdateBegin(halo_, INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateBegin");
  communication_seconds_ += watch.seconds();
}

void MeshPartition::receive_ghosts(VectorX& local) const {
  const Stopwatch watch;
  const Index n = static_cast<Index>(local.size()), owned = n_owned_dofs();
  check(VecGhostUpdateEnd(halo_, INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateEnd");
  Vec form = nullptr;
  PetscScalar* array = nullptr;
  check(VecGhostGetLocalForm(halo_, &form), "VecGhostGetLocalForm");
  check(VecGetArray(form, &array), "VecGetArray");
  std::memcpy(local.data() + owned, array + owned, (n - owned) * sizeof(double));
  for (Index k : boundary_) array[k] = 0.0;
  check(VecRestoreArray(form, &array), "VecRestoreArray");
  check(VecGhostRestoreLocalForm(halo_, &form), "VecGhostRestoreLocalForm");
  communication_seconds_ += watch.seconds();
}

void MeshPartition::sum(std::vector<double>& values) const {
  const Stopwatch watch;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  communication_seconds_ += watch.seconds();
}

VectorX MeshPartition::local_field(const VectorX& global_field) const {
  if (global_field.size() == 0) return global_field;
  VectorX local(global_dofs_.size());
  for (std::size_t k = 0; k < global_dofs_.size(); ++k) local[k] = global_field[global_dofs_[k]];
  return local;
}

std::vector<fem::DirichletCondition> MeshPartition::local_dirichlet(
    const std::vector<fem::DirichletCondition>& global) const {
  std::vector<fem::DirichletCondition> local = global;
  for (fem::DirichletCondition& condition : local) {
    std::vector<Index> nodes;
    for (Index node : condition.nodes)
      if (local_of_.at(node) >= 0) nodes.push_back(local_of_[node]);
    condition.nodes = std::move(nodes);
  }
  return local;
}

std::shared_ptr<contact::ContactForce> MeshPartition::local_contact(const fem::Materials& materials,
                                                                    const contact::ContactOptions& options) const {
  const contact::PenaltyChoice choice = contact::choose_penalty(*global_, materials, options);
  double split_area = 0.0;
  for (const mesh::CrackPair& pair : global_->crack_pairs)
    if (!pair.on_front()) split_area += pair.area;
  auto term = std::make_shared<contact::ContactForce>(local_, mesh::make_dof_map(local_, mesh::Variant::open),
                                                      options, choice);
  term->count_owned_pairs_only(n_owned_dofs(), split_area);
  return term;
}

}  // namespace crackle::distributed
