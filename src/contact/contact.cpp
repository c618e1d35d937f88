#include "contact/contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "contact_law/penalty.hpp"
#include "core/errors.hpp"

namespace crackle::contact {

double normal_modulus(const fem::VoigtMatrix& stiffness, const Vec3& normal) {
  // Strain n (x) n in Voigt form (engineering shears), stress D eps, then sigma_ij n_i n_j.
  fem::Voigt strain;
  strain << normal[0] * normal[0], normal[1] * normal[1], normal[2] * normal[2], 2.0 * normal[1] * normal[2],
      2.0 * normal[0] * normal[2], 2.0 * normal[0] * normal[1];
  const fem::Voigt stress = stiffness * strain;
  return stress[0] * normal[0] * normal[0] + stress[1] * normal[1] * normal[1] + stress[2] * normal[2] * normal[2] +
         2.0 * (stress[3] * normal[1] * normal[2] + stress[4] * normal[0] * normal[2] + stress[5] * normal[0] * normal[1]);
}

PenaltyChoice choose_penalty(const mesh::Mesh& mesh, const fem::Materials& materials, const ContactOptions& options) {
  if (!mesh.has_crack()) throw InputError("contact: the mesh has no crack");
  if (!(options.normal_penalty >= 0.0) || !(options.tangential_penalty >= 0.0) ||
      !(options.friction_coefficient >= 0.0) || !(options.penalty_factor >= 0.0) || !std::isfinite(options.initial_gap)) {
    throw InputError("contact: expected penalty >= 0, tangential_penalty >= 0, friction >= 0, penalty_factor >= 0 and "
                     "a finite gap, got penalty = " + format_number(options.normal_penalty) +
                     ", tangential_penalty = " + format_number(options.tangential_penalty) +
                     ", friction = " + format_number(options.friction_coefficient) +
                     ", penalty_factor = " + format_number(options.penalty_factor) +
                     ", gap = " + format_number(options.initial_gap));
  }
  PenaltyChoice choice;
  if (options.normal_penalty > 0.0) {
    choice.normal_penalty = options.normal_penalty;
  } else {
    // eps_N = c C_nnnn / h over the elements touching a crack-face node.
    std::vector<char> on_crack(mesh.n_nodes(), 0);
    std::vector<Vec3> node_normal(mesh.n_nodes(), Vec3::Zero());
    for (const mesh::CrackPair& pair : mesh.crack_pairs) {
      on_crack[pair.minus] = on_crack[pair.plus] = 1;
      node_normal[pair.minus] = node_normal[pair.plus] = pair.normal;
    }
    double modulus = 0.0, size = std::numeric_limits<double>::infinity();
    const int npe = mesh.nodes_per_element();
    for (Index e = 0; e < mesh.n_elements(); ++e) {
      const Index* nodes = mesh.element_nodes(e);
      Index touching = -1;
      for (int a = 0; a < npe && touching < 0; ++a) {
        if (on_crack[nodes[a]]) touching = nodes[a];
      }
      if (touching < 0) continue;
      const Vec3& normal = node_normal[touching];
      double low = std::numeric_limits<double>::infinity(), high = -low;
      for (int a = 0; a < npe; ++a) {
        const double s = mesh.nodes[nodes[a]].dot(normal);
        low = std::min(low, s);
        high = std::max(high, s);
      }
      size = std::min(size, high - low);
      const int region = mesh.element_region.at(e);
      if (region < 0 || region >= static_cast<int>(materials.size())) {
        throw InputError("contact: element " + std::to_string(e) + " has region " + std::to_string(region) + " but " +
                         std::to_string(materials.size()) + " materials are given");
      }
      modulus = std::max(modulus, normal_modulus(materials[region].stiffness, normal));
    }
    if (!(size > 0.0) || !std::isfinite(size) || !(modulus > 0.0)) {
      throw InputError("contact: cannot choose the penalty automatically (element size " + format_number(size) +
                       " m, modulus " + format_number(modulus) + " Pa); give contact.penalty");
    }
    choice.automatic = true;
    choice.factor = options.penalty_factor > 0.0 ? options.penalty_factor
                    : options.integration == ContactIntegration::implicit ? kDefaultPenaltyFactor
                                                                           : kDefaultExplicitPenaltyFactor;
    choice.modulus = modulus;
    choice.element_size = size;
    choice.normal_penalty = choice.factor * modulus / size;
  }
  choice.tangential_penalty = options.tangential_penalty > 0.0 ? options.tangential_penalty : choice.normal_penalty;
  return choice;
}

PenaltyContact::PenaltyContact(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const fem::Materials& materials,
                               const ContactOptions& options)
    : PenaltyContact(mesh, dofs, options, choose_penalty(mesh, materials, options)) {}

PenaltyContact::PenaltyContact(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const ContactOptions& options,
                               const PenaltyChoice& penalty)
    : options_(options), penalty_(penalty) {
  if (static_cast<Index>(dofs.dof_node.size()) != mesh.n_nodes()) {
    throw InputError("contact: DOF map has " + std::to_string(dofs.dof_node.size()) + " entries for a mesh of " +
                     std::to_string(mesh.n_nodes()) + " nodes");
  }
  for (const mesh::CrackPair& source : mesh.crack_pairs) {
    if (source.on_front()) continue;
    Pair pair;
    pair.minus_dof = dofs.dof(source.minus, 0);
    pair.plus_dof = dofs.dof(source.plus, 0);
    if (pair.minus_dof == pair.plus_dof) continue;  // tied by the DOF map (uncracked variant)
    pair.normal = source.normal.normalized();
    pair.area = source.area;
    total_area_ += source.area;
    pairs_.push_back(pair);
  }
}

void PenaltyContact::count_owned_pairs_only(Index n_owned_dofs, double total_area) {
  for (Pair& pair : pairs_) pair.counted = pair.minus_dof < n_owned_dofs;
  total_area_ = total_area;
}

void PenaltyContact::reset(const VectorX& displacement) {
  for (Pair& pair : pairs_) {
    pair.previous_relative = displacement.segment<3>(pair.minus_dof) - displacement.segment<3>(pair.plus_dof);
    pair.traction.setZero();
    pair.force.setZero();
  }
  dissipated_energy_ = 0.0;
  stored_energy_ = 0.0;
}

void PenaltyContact::finish_step(double stored, double dissipated, Index closed, double closed_area, Index slipping) {
  stored_energy_ = stored;
  dissipated_energy_ += dissipated;
  n_closed_ = closed;
  closed_area_ = closed_area;
  n_slipping_ = slipping;
}

void PenaltyContact::add_force(const VectorX& displacement, VectorX& force) {
  const double normal_penalty = penalty_.normal_penalty;
  const double tangential_penalty = penalty_.tangential_penalty;
  const double mu = options_.friction_coefficient;
  const bool friction = mu > 0.0;
  double stored = 0.0, dissipated = 0.0, closed_area = 0.0;
  Index closed = 0, slipping = 0;
  for (Pair& pair : pairs_) {
    const Vec3 relative = displacement.segment<3>(pair.minus_dof) - displacement.segment<3>(pair.plus_dof);
    const double gap = options_.initial_gap + relative.dot(pair.normal);  // eq. (9)
    const double pressure = penalty_pressure(gap, normal_penalty);        // eq. (25d)
    Vec3 traction = pressure * pair.normal;
    const double counted = pair.counted ? 1.0 : 0.0;
    stored += counted * pair.area * normal_penalty_energy(gap, normal_penalty);
    pair.state = gap < 0.0 ? 2 : 0;
    if (gap < 0.0 && pair.counted) {
      ++closed;
      closed_area += pair.area;
    }
    if (friction) {
      const CoulombUpdate update = coulomb_return_mapping(pair.traction, relative - pair.previous_relative, pair.normal,
                                                          tangential_penalty, mu, pressure);  // eq. (15)
      pair.traction = update.traction;
      if (update.slipping && pressure > 0.0 && pair.counted) ++slipping;
      if (gap < 0.0 && !update.slipping) pair.state = 1;
      dissipated += counted * pair.area * update.dissipation;
      stored += counted * pair.area * tangential_penalty_energy(update.traction, tangential_penalty);
      traction += update.traction;
    }
    pair.previous_relative = relative;
    pair.force = pair.area * traction;
    force.segment<3>(pair.minus_dof) += pair.force;
    force.segment<3>(pair.plus_dof) -= pair.force;
  }
  finish_step(stored, dissipated, closed, closed_area, slipping);
}

void PenaltyContact::add_implicit_force(const VectorX& displacement, const VectorX& velocity,
                                        const VelocityUpdate& update, VectorX& force) {
  const VectorX& inverse_mass = *update.inverse_mass;
  const double scale = 1.0 / (1.0 + 0.5 * update.alpha * update.step);
  const double decay = 1.0 - 0.5 * update.alpha * update.step;
  const double normal_penalty = penalty_.normal_penalty;
  const double tangential_penalty = penalty_.tangential_penalty;
  const double mu = options_.friction_coefficient;
  double stored = 0.0, dissipated = 0.0, closed_area = 0.0;
  Index closed = 0, slipping = 0;
  for (Pair& pair : pairs_) {
    // Per-component inverse masses (0 where a component is held).
    const Vec3 inverse_sum = inverse_mass.segment<3>(pair.minus_dof) + inverse_mass.segment<3>(pair.plus_dof);
    // Relative motion the update gives without this pair's force, and how the pair's own force
    // moves it: d_end = d_free + (dt s h (a- + a+)) f.
    const Vec3 relative = displacement.segment<3>(pair.minus_dof) - displacement.segment<3>(pair.plus_dof);
    const Vec3 relative_velocity = velocity.segment<3>(pair.minus_dof) - velocity.segment<3>(pair.plus_dof);
    const Vec3 relative_force = inverse_mass.segment<3>(pair.minus_dof).cwiseProduct(force.segment<3>(pair.minus_dof)) -
                                inverse_mass.segment<3>(pair.plus_dof).cwiseProduct(force.segment<3>(pair.plus_dof));
    const Vec3 free_end = relative + update.dt * scale * (decay * relative_velocity + update.step * relative_force);
    // End-of-step relative displacement per unit traction: along n, and (mean) in the tangent plane;
    // the two agree unless a node has some components held.
    const double factor = update.dt * scale * update.step * pair.area;
    const double normal_inverse = pair.normal.cwiseAbs2().dot(inverse_sum);
    const double compliance = factor * normal_inverse;
    const double tangential_compliance = factor * 0.5 * (inverse_sum.sum() - normal_inverse);
    const PairResponse response =
        implicit_pair_response(options_.initial_gap + free_end.dot(pair.normal), free_end - pair.previous_relative,
                               pair.normal, pair.traction, compliance, tangential_compliance, normal_penalty,
                               tangential_penalty, mu);
    pair.traction = response.traction;
    pair.force = pair.area * (response.pressure * pair.normal + response.traction);
    pair.previous_relative = free_end + factor * inverse_sum.cwiseProduct(pair.force / pair.area);
    force.segment<3>(pair.minus_dof) += pair.force;
    force.segment<3>(pair.plus_dof) -= pair.force;
    if (!pair.counted) continue;  // a ghost pair: its owner counts it
    stored += pair.area * (normal_penalty_energy(response.gap, normal_penalty) +
                           tangential_penalty_energy(response.traction, tangential_penalty));
    dissipated += pair.area * response.dissipation;
    pair.state = 0;
    if (response.gap < 0.0) {
      ++closed;
      closed_area += pair.area;
      if (response.slipping) ++slipping;
      pair.state = response.slipping || !(mu > 0.0) ? 2 : 1;
    }
  }
  finish_step(stored, dissipated, closed, closed_area, slipping);
}

double PenaltyContact::force_dot(const VectorX& x) const {
  double sum = 0.0;
  for (const Pair& pair : pairs_) {
    if (pair.counted) sum += pair.force.dot(x.segment<3>(pair.minus_dof) - x.segment<3>(pair.plus_dof));
  }
  return sum;
}

Index PenaltyContact::find_pair(Index plus_dof) const {
  for (std::size_t k = 0; k < pairs_.size(); ++k) {
    if (pairs_[k].plus_dof == plus_dof) return static_cast<Index>(k);
  }
  return -1;
}

Vec3 PenaltyContact::total_force() const {
  Vec3 total = Vec3::Zero();
  for (const Pair& pair : pairs_) {
    if (pair.counted) total += pair.force;
  }
  return total;
}

void PenaltyContact::add_closed_stiffness(const VectorX& x, VectorX& y, double scale) const {
  const bool friction = has_friction();
  for (const Pair& pair : pairs_) {
    const Vec3 relative = x.segment<3>(pair.minus_dof) - x.segment<3>(pair.plus_dof);
    const double normal_part = relative.dot(pair.normal);
    Vec3 spring = penalty_.normal_penalty * normal_part * pair.normal;
    if (friction) spring += penalty_.tangential_penalty * (relative - normal_part * pair.normal);
    spring *= scale * pair.area;
    y.segment<3>(pair.minus_dof) += spring;
    y.segment<3>(pair.plus_dof) -= spring;
  }
}

}  // namespace crackle::contact
