#pragma once
/// \file The crack-face contact as a force term of the semi-discrete system (fem::ForceTerm): the
/// time integrator plugs it in from outside and never names contact (STYLE.md).

#include "contact/contact.hpp"
#include "fem/force_term.hpp"

namespace crackle::contact {

/// PenaltyContact as a force term. Implicit integration (the default) evaluates the pair springs
/// at U(i+1) through the integrator's velocity update carried by fem::StepInput, so it needs the
/// other forces of the step and is evaluated last; explicit forces are those of U(i) and their
/// closed springs bound the stable step, resolved (kExplicitSpringResolution).
class ContactForce final : public fem::ForceTerm {
 public:
  ContactForce(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const fem::Materials& materials,
               const ContactOptions& options)
      : contact_(mesh, dofs, materials, options) {}
  /// With penalties chosen elsewhere (PenaltyContact's second constructor).
  ContactForce(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const ContactOptions& options,
               const PenaltyChoice& penalty)
      : contact_(mesh, dofs, options, penalty) {}

  const PenaltyContact& contact() const { return contact_; }
  /// PenaltyContact::count_owned_pairs_only (one rank of a distributed run).
  void count_owned_pairs_only(Index n_owned_dofs, double total_area) {
    contact_.count_owned_pairs_only(n_owned_dofs, total_area);
  }

  std::string name() const override { return "contact"; }
  fem::EnergyRole role() const override { return fem::EnergyRole::potential; }
  bool needs_other_forces() const override { return contact_.implicit(); }
  void add_force(const fem::StepInput& input, VectorX& force) override {
    if (contact_.implicit()) {
      contact_.add_implicit_force(input.displacement, input.velocity,
                                  {input.dt, input.step, input.mass_damping, &input.inverse_mass}, force);
    } else {
      contact_.add_force(input.displacement, force);
    }
  }
  double force_dot(const VectorX& x) const override { return contact_.force_dot(x); }
  double stored_energy() const override { return contact_.stored_energy(); }
  bool explicit_in_time() const override { return !contact_.implicit(); }
  double dissipated_energy() const override { return contact_.dissipated_energy(); }
  double active_fraction() const override {
    return contact_.total_area() > 0.0 ? contact_.closed_area() / contact_.total_area() : 0.0;
  }
  void add_stiffness_bound(const VectorX& x, VectorX& y) const override {
    // Explicit springs count at kExplicitSpringResolution times their frequency (contact.hpp).
    if (!contact_.implicit()) {
      contact_.add_closed_stiffness(x, y, kExplicitSpringResolution * kExplicitSpringResolution);
    }
  }
  void start(const VectorX& displacement) override { contact_.reset(displacement); }

 private:
  PenaltyContact contact_;
};


}  // namespace crackle::contact
