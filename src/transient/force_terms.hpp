#pragma once
/// \file The force terms of the full transient besides the crack contact (which plugs in from the
/// contact module): stiffness-proportional damping -beta K U' and external loads f_hat a(t)
/// (MODEL.md eqs. 25b, 26). The elastic force -K U is the integrator's own term (its dot products
/// come from the fused step sums, see TransientSolver).
#include "fem/elastic_operator.hpp"
#include "fem/force_term.hpp"
#include "linalg/linear_operator.hpp"
#include "fem/system.hpp"
#include "transient/excitation.hpp"

namespace crackle::transient {

/// \f$-\beta K \dot U\f$ with K an operator (MODEL.md eq. 26), velocity at V(i-1/2).
class StiffnessDamping final : public fem::ForceTerm {
 public:
  StiffnessDamping(const linalg::LinearOperator& stiffness, double beta)
      : stiffness_(stiffness), beta_(beta), force_(VectorX::Zero(stiffness.n_rows())) {}
  std::string name() const override { return "damping"; }
  fem::EnergyRole role() const override { return fem::EnergyRole::dissipative; }
  void add_force(const fem::StepInput& input, VectorX& force) override {
    force_.setZero();
    stiffness_.apply_add(-beta_, input.velocity, force_);
    force += force_;
  }
  double force_dot(const VectorX& x) const override { return force_.dot(x); }

  /// The same force in parts over ranges of elements (a distributed run's overlapped halo, see
  /// TransientSolver): clear_parts(), then add_part() for each range adds its share to `force`
  /// and to the term's own force (for force_dot).
  void clear_parts() { force_.setZero(); }
  void add_part(const fem::ElasticOperator& stiffness, const fem::StepInput& input, VectorX& force, Index begin,
                Index end) {
    part_.setZero(force_.size());
    stiffness.apply_add_elements(-beta_, input.velocity, part_, begin, end);
    force += part_;
    force_ += part_;
  }

 private:
  const linalg::LinearOperator& stiffness_;
  double beta_;
  VectorX force_;  ///< -beta K V(i-1/2) of the last step
  VectorX part_;   ///< add_part's share
};

/// A load shape times a signal, eq. (25b).
class ExternalForce final : public fem::ForceTerm {
 public:
  ExternalForce(fem::LoadShape shape, Signal signal) : shape_(std::move(shape)), signal_(signal) {}
  std::string name() const override { return "load"; }
  fem::EnergyRole role() const override { return fem::EnergyRole::external; }
  void add_force(const fem::StepInput& input, VectorX& force) override {
    current_ = signal_.value(input.time);
    if (current_ == 0.0) return;
    for (std::size_t k = 0; k < shape_.dofs.size(); ++k) force[shape_.dofs[k]] += current_ * shape_.values[k];
  }
  double force_dot(const VectorX& x) const override { return current_ == 0.0 ? 0.0 : current_ * shape_.dot(x); }
  const fem::LoadShape& shape() const { return shape_; }

 private:
  fem::LoadShape shape_;
  Signal signal_;
  double current_ = 0.0;  ///< signal value at the last add_force
};

}  // namespace crackle::transient
