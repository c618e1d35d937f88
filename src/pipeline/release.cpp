#include "pipeline/release.hpp"

#include <cmath>
#include <vector>

#include "core/errors.hpp"
#include "linalg/cholmod_factor.hpp"

namespace crackle::pipeline {
namespace {

/// The active springs as a matrix over all DOFs, and their gap forces added to `rhs`.
SparseMatrix active_springs(const mesh::DofMap& dofs, const StaticContact& contact, const std::vector<char>& closed,
                            VectorX& rhs) {
  std::vector<Eigen::Triplet<double, Index>> entries;
  for (std::size_t p = 0; p < contact.pairs.size(); ++p) {
    if (!closed[p]) continue;
    const mesh::CrackPair& pair = contact.pairs[p];
    const double k = contact.penalty * pair.area;
    const Vec3& n = pair.normal;
    for (int a = 0; a < 3; ++a) {
      // Force on minus -k g n, on plus +k g n, g = g0 + n.(u_minus - u_plus): the g0 part is a load.
      rhs[dofs.dof(pair.minus, a)] -= k * contact.gap * n[a];
      rhs[dofs.dof(pair.plus, a)] += k * contact.gap * n[a];
      for (int b = 0; b < 3; ++b) {
        const double value = k * n[a] * n[b];
        entries.emplace_back(dofs.dof(pair.minus, a), dofs.dof(pair.minus, b), value);
        entries.emplace_back(dofs.dof(pair.plus, a), dofs.dof(pair.plus, b), value);
        entries.emplace_back(dofs.dof(pair.minus, a), dofs.dof(pair.plus, b), -value);
        entries.emplace_back(dofs.dof(pair.plus, a), dofs.dof(pair.minus, b), -value);
      }
    }
  }
  SparseMatrix springs(dofs.n_dofs(), dofs.n_dofs());
  springs.setFromTriplets(entries.begin(), entries.end());
  return springs;
}

}  // namespace

StaticSolution solve_static(const fem::System& system, const VectorX& force, const StaticContact* contact) {
  const fem::Constraints& constraints = system.constraints();
  const mesh::DofMap& dofs = system.dofs();
  const SparseMatrix stiffness = system.assemble_stiffness();
  std::vector<mesh::CrackPair> pairs;
  if (contact) {
    for (const mesh::CrackPair& pair : contact->pairs) {
      if (pair.minus != pair.plus && dofs.dof_node[pair.minus] != dofs.dof_node[pair.plus]) pairs.push_back(pair);
    }
  }
  StaticContact split{pairs, contact ? contact->penalty : 0.0, contact ? contact->gap : 0.0};
  StaticSolution solution;
  solution.n_pairs = static_cast<Index>(pairs.size());
  std::vector<char> closed(pairs.size(), 0);
  std::vector<std::vector<char>> seen;
  const Index n_free = constraints.n_free();
  const SparseMatrix no_mass(n_free, n_free);
  for (int iteration = 1;; ++iteration) {
    VectorX rhs = force;
    const SparseMatrix matrix = stiffness + active_springs(dofs, split, closed, rhs);
    const SparseMatrix free_matrix = fem::restrict_to_free(matrix, constraints);
    const VectorX free_rhs = fem::free_right_hand_side(matrix, rhs, constraints);
    VectorX free_solution(n_free);
    try {
      linalg::CholmodFactor factor(free_matrix, no_mass, 0.0, "static release");
      factor.solve(free_rhs.data(), free_solution.data());
    } catch (const SolverError& error) {
      throw SolverError(std::string(error.what()) + " (a static deflection needs boundary conditions that hold "
                        "every rigid-body motion)");
    }
    solution.displacement = fem::expand_from_free(free_solution, constraints, true);
    solution.iterations = iteration;
    std::vector<char> next(pairs.size(), 0);
    Index n_closed = 0;
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      double gap = split.gap;
      for (int a = 0; a < 3; ++a) {
        gap += pairs[p].normal[a] * (solution.displacement[dofs.dof(pairs[p].minus, a)] -
                                     solution.displacement[dofs.dof(pairs[p].plus, a)]);
      }
      next[p] = gap < 0.0;
      n_closed += next[p];
    }
    solution.n_closed = n_closed;
    if (next == closed) return solution;
    for (const std::vector<char>& earlier : seen) {
      if (earlier == next) {
        throw SolverError("static release: the contact active set cycles after " + std::to_string(iteration) +
                          " iterations (" + std::to_string(n_closed) + " of " + std::to_string(pairs.size()) +
                          " pairs closed)");
      }
    }
    seen.push_back(closed);
    closed = next;
    if (iteration >= 100) {
      throw SolverError("static release: the contact active set did not settle in 100 iterations");
    }
  }
}

transient::InitialConditions release_state(const scene::ReleaseSection& release, const Model& model,
                                           mesh::Variant variant, const contact::ContactOptions* contact,
                                           const modal::ModalResult* modes, const std::string& where,
                                           ReleaseReport* report) {
  const fem::System& system = *model.system(variant);
  const mesh::Mesh& mesh = model.mesh;
  transient::InitialConditions initial;
  initial.velocity = VectorX::Zero(system.n_dofs());
  ReleaseReport local;
  local.kind = release.kind;
  if (release.kind == scene::ReleaseKind::static_deflection) {
    fem::LoadPlacement placement;
    placement.name = where + ": transient.release.static";
    if (!release.face.empty()) placement.faces = mesh.face_sets.at(release.face);
    if (!release.group.empty()) placement.nodes = mesh.node_sets.at(release.group);
    if (release.point) placement.nodes = {transient::nearest_node(mesh, *release.point)};
    placement.total = release.amplitude * Vec3::Unit(release.direction);
    const VectorX force = system.load_shape(placement).dense(system.n_dofs());
    std::optional<StaticContact> springs;
    if (contact && variant == mesh::Variant::open && mesh.has_crack()) {
      const contact::PenaltyChoice penalty = contact::choose_penalty(mesh, model.materials, *contact);
      springs = StaticContact{mesh.crack_pairs, penalty.normal_penalty, contact->initial_gap};
    }
    const StaticSolution solution = solve_static(system, force, springs ? &*springs : nullptr);
    initial.displacement = solution.displacement;
    local.iterations = solution.iterations;
    local.n_pairs = springs ? solution.n_pairs : 0;
    local.n_closed = solution.n_closed;
  } else {
    const mesh::Variant of = release.variant;
    const modal::VariantResult* result = modes ? modes->find(of) : nullptr;
    if (!result || release.mode > result->modes.n_modes()) {
      throw InputError(where + ": transient.release.mode.number: mode " + std::to_string(release.mode) + " of the " +
                       mesh::variant_name(release.variant) + " body asked, but only " +
                       std::to_string(result ? result->modes.n_modes() : 0) + " modes were computed");
    }
    const std::vector<double> shape = modal::nodal_shape(mesh, *result, release.mode - 1);
    // Scale: the largest nodal displacement becomes the amplitude, its largest component positive.
    double largest = 0.0;
    double sign = 1.0;
    for (Index node = 0; node < mesh.n_nodes(); ++node) {
      const Vec3 value(shape[3 * node], shape[3 * node + 1], shape[3 * node + 2]);
      if (value.norm() > largest) {
        largest = value.norm();
        Index component = 0;
        value.cwiseAbs().maxCoeff(&component);
        sign = value[component] < 0.0 ? -1.0 : 1.0;
      }
    }
    if (!(largest > 0.0)) throw SolverError(where + ": transient.release.mode: the mode shape is zero");
    const double scale = sign * release.amplitude / largest;
    initial.displacement = transient::nodal_field(mesh, system.dofs(), [&](Index node, const Vec3&) {
      return Vec3(scale * shape[3 * node], scale * shape[3 * node + 1], scale * shape[3 * node + 2]);
    });
  }
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    Vec3 value;
    for (int c = 0; c < 3; ++c) value[c] = initial.displacement[system.dofs().dof(node, c)];
    local.largest_displacement = std::max(local.largest_displacement, value.norm());
  }
  if (report) *report = local;
  return initial;
}

}  // namespace crackle::pipeline
