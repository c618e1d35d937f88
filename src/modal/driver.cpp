/// \file Modal driver: per-variant assembly and solve, open-to-uncracked mode pairing.
#include "modal/modal.hpp"

#include "linalg/cholmod_factor.hpp"
#include "modal/stiffness_factors.hpp"
#include "modal/cache.hpp"

#include <algorithm>
#include <map>
#include <cmath>
#include <numeric>
#include <string>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "fem/system.hpp"

namespace crackle::modal {

Factorization parse_factorization(const std::string& name, const std::string& key) {
  return parse_word(kFactorizationWords, name, key);
}

MacWeighting parse_mac_weighting(const std::string& name, const std::string& key) {
  return parse_word(kMacWeightingWords, name, key);
}

VariantResult::VariantResult(VariantResult&& other) noexcept
    : variant(other.variant),
      dofs(std::move(other.dofs)),
      constraints(std::move(other.constraints)),
      modes(std::move(other.modes)),
      n_pieces(other.n_pieces),
      assembly_s(other.assembly_s),
      cache_key(other.cache_key) {
  mass.swap(other.mass);
}

VariantResult& VariantResult::operator=(VariantResult&& other) noexcept {
  variant = other.variant;
  dofs = std::move(other.dofs);
  constraints = std::move(other.constraints);
  mass.swap(other.mass);
  modes = std::move(other.modes);
  n_pieces = other.n_pieces;
  assembly_s = other.assembly_s;
  cache_key = other.cache_key;
  return *this;
}

VariantResult* ModalResult::find(mesh::Variant variant) {
  return const_cast<VariantResult*>(static_cast<const ModalResult&>(*this).find(variant));
}

const VariantResult* ModalResult::find(mesh::Variant variant) const {
  for (const VariantResult& result : variants) {
    if (result.variant == variant) return &result;
  }
  return nullptr;
}

Index ModalResult::free_dofs() const {
  Index free = 0;
  for (const VariantResult& result : variants) free = std::max(free, result.constraints.n_free());
  return free;
}

MatrixX open_on_uncracked_dofs(const MatrixX& open_shapes, const VariantResult& open,
                               const VariantResult& uncracked) {
  // Mesh node standing for each uncracked DOF node: the original (lowest-numbered) one.
  std::vector<Index> node_of(uncracked.dofs.n_dof_nodes, -1);
  for (Index node = static_cast<Index>(uncracked.dofs.dof_node.size()) - 1; node >= 0; --node) {
    node_of[uncracked.dofs.dof_node[node]] = node;
  }
  const std::vector<Index>& free_dofs = uncracked.constraints.free_dofs;
  MatrixX mapped = MatrixX::Zero(static_cast<Index>(free_dofs.size()), open_shapes.cols());
  for (std::size_t row = 0; row < free_dofs.size(); ++row) {
    const Index node = node_of[free_dofs[row] / 3];
    if (node < 0) continue;
    const Index open_free = open.constraints.free_index[open.dofs.dof(node, free_dofs[row] % 3)];
    if (open_free >= 0) mapped.row(static_cast<Index>(row)) = open_shapes.row(open_free);
  }
  return mapped;
}

std::vector<double> nodal_shape(const mesh::Mesh& mesh, const VariantResult& variant, int mode) {
  std::vector<double> values(3 * static_cast<std::size_t>(mesh.n_nodes()), 0.0);
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    for (int c = 0; c < 3; ++c) {
      const Index free = variant.constraints.free_index[variant.dofs.dof(node, c)];
      if (free >= 0) values[3 * static_cast<std::size_t>(node) + c] = variant.modes.shapes(free, mode);
    }
  }
  return values;
}

namespace {

/// The variant's mass matrix over its free DOFs (consistent or lumped, as the options say).
void assemble_mass(const fem::System& system, const ModalOptions& options, VariantResult& solved) {
  if (options.lumped_mass) {
    const VectorX lumped = fem::restrict_to_free(system.lumped_mass(), solved.constraints);
    solved.mass.resize(lumped.size(), lumped.size());
    solved.mass.reserve(Eigen::VectorXi::Ones(lumped.size()));
    for (Index i = 0; i < lumped.size(); ++i) solved.mass.insert(i, i) = lumped[i];
    solved.mass.makeCompressed();
  } else {
    SparseMatrix restricted = fem::restrict_to_free(system.assemble_consistent_mass(), solved.constraints);
    solved.mass.swap(restricted);
  }
}

/// The open modes' MAC against the uncracked ones: read from the cache where both mode sets were
/// (then no mass is assembled), else computed (the uncracked mass assembled first if the modes came
/// from the cache) and stored.
MatrixX open_mac(VariantResult& uncracked, const VariantResult& open, const fem::System& uncracked_system,
                 const ModalOptions& options) {
  const bool cached = uncracked.cache_key != 0 && open.cache_key != 0;
  const std::uint64_t key = cached ? mac_key(uncracked.cache_key, open.cache_key, options.mac) : 0;
  const Index rows = uncracked.modes.shapes.cols(), cols = open.modes.shapes.cols();
  if (cached) {
    if (std::optional<MatrixX> mac = load_cached_mac(options.cache_directory, key, rows, cols)) return std::move(*mac);
  }
  const bool weighted = options.mac == MacWeighting::mass;
  if (weighted && uncracked.mass.size() == 0) {
    Stopwatch watch;
    assemble_mass(uncracked_system, options, uncracked);
    uncracked.assembly_s += watch.seconds();
  }
  const MatrixX open_shapes = open_on_uncracked_dofs(open.modes.shapes, open, uncracked);
  MatrixX mac = mac_matrix(uncracked.modes.shapes, open_shapes, weighted ? &uncracked.mass : nullptr);
  if (cached && is_output_rank()) store_cached_mac(options.cache_directory, key, mac);
  return mac;
}

/// Assembles and solves one variant.
VariantResult solve_variant(const fem::System& system, const ModalOptions& options) {
  const mesh::Mesh& mesh = system.mesh();
  const mesh::Variant variant = system.variant();
  VariantResult solved;
  solved.variant = variant;
  Stopwatch watch;
  solved.dofs = system.dofs();
  solved.constraints = system.constraints();
  // Both variants are cached: the key is what K and M are made from (fem::System::fingerprint), so
  // an open solve is shared by the cases that keep the crack (a study over excitation frequency,
  // amplitude or damping) and simply misses when the crack changes. A hit assembles no K.
  const bool cached = !options.cache_directory.empty();
  const std::uint64_t key = cached ? problem_key(system.fingerprint(), options) : 0;
  std::optional<ModeSet> from_cache;
  if (cached) from_cache = load_cached_modes(options.cache_directory, key, solved.constraints.n_free());
  // Eigen 3.4's SparseMatrix has no move assignment: a result assigned to an existing matrix is a
  // deep copy (hundreds of MB at order 4, seconds under load with no place to poll), so it is swapped in.
  SparseMatrix stiffness;
  if (!from_cache) {
    SparseMatrix restricted = fem::restrict_to_free(system.assemble_stiffness(), solved.constraints);
    stiffness.swap(restricted);
  }
  poll_interrupt();
  solved.cache_key = key;
  if (!from_cache) assemble_mass(system, options, solved);  // else only if the MAC needs it (run_modal)
  solved.n_pieces = count_pieces(mesh, solved.dofs);
  const int n_rigid = count_rigid_body_modes(mesh, solved.dofs, solved.constraints);
  solved.assembly_s = watch.seconds();
  poll_interrupt();
  try {
    if (from_cache) {
      solved.modes = std::move(*from_cache);
    } else {
      ModalOptions settings = options;
      double shared_factor_s = 0.0;
      if (options.factors && variant == options.factors_variant && n_rigid == 0 && options.solver == Solver::arpack) {
        // A held body: K itself is positive definite, and its factor serves later solves too.
        Stopwatch factor_watch;
        if (CholmodFactor* factor = options.factors->factor(variant, stiffness)) {
          settings.factor = factor;
          settings.shift = 0.0;
        }
        shared_factor_s = factor_watch.seconds();
      }
      solved.modes = solve_modes(stiffness, solved.mass, settings, n_rigid);
      solved.modes.report.factorization_s += shared_factor_s;
      solved.modes.report.solve_s += shared_factor_s;
      if (cached && is_output_rank()) store_cached_modes(options.cache_directory, key, solved.modes);
    }
  } catch (const InputError& error) {
    throw InputError(std::string("variant ") + mesh::variant_name(variant) + ": " + error.what());
  } catch (const SolverError& error) {
    throw SolverError(std::string("variant ") + mesh::variant_name(variant) + ": " + error.what());
  }
  return solved;
}

}  // namespace

ModalResult run_modal(const mesh::Mesh& mesh, const fem::Materials& materials,
                      const std::vector<fem::DirichletCondition>& conditions, const ModalOptions& options) {
  std::map<mesh::Variant, fem::System> systems;
  return run_modal(
      [&](mesh::Variant variant) -> const fem::System& {
        auto found = systems.find(variant);
        if (found == systems.end()) found = systems.emplace(variant, fem::System(mesh, materials, conditions, variant)).first;
        return found->second;
      },
      options);
}

ModalResult run_modal(const std::function<const fem::System&(mesh::Variant)>& system_for, const ModalOptions& options) {
  Stopwatch total;
  ModalResult result;
  result.options = options;
  if (result.options.variants.empty()) {
    result.options.variants = {mesh::Variant::uncracked};
    if (system_for(mesh::Variant::uncracked).mesh().has_crack()) result.options.variants.push_back(mesh::Variant::open);
  }
  result.variants.reserve(result.options.variants.size());
  for (const mesh::Variant variant : result.options.variants) {
    if (result.find(variant)) {
      throw InputError(std::string("modal.variants lists '") + mesh::variant_name(variant) + "' twice");
    }
    result.variants.push_back(solve_variant(system_for(variant), options));
  }

  VariantResult* uncracked = result.find(mesh::Variant::uncracked);
  const VariantResult* open = result.find(mesh::Variant::open);
  if (uncracked && open) {
    result.mac = open_mac(*uncracked, *open, system_for(mesh::Variant::uncracked), options);
    result.pairs = pair_modes(uncracked->modes.frequencies_hz, open->modes.frequencies_hz, result.mac);
  }
  result.total_s = total.seconds();
  return result;
}

}  // namespace crackle::modal
