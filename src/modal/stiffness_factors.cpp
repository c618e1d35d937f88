#include "modal/stiffness_factors.hpp"

#include "core/errors.hpp"

namespace crackle::modal {

CholmodFactor* StiffnessFactors::factor(mesh::Variant variant, const SparseMatrix& stiffness) {
  const double diagonal_sum = stiffness.diagonal().sum();
  auto found = entries_.find(variant);
  if (found != entries_.end() && found->second.rows == stiffness.rows() &&
      found->second.nonzeros == stiffness.nonZeros() && found->second.diagonal_sum == diagonal_sum) {
    return found->second.factor.get();
  }
  Entry entry{static_cast<Index>(stiffness.rows()), static_cast<Index>(stiffness.nonZeros()), diagonal_sum, nullptr};
  entries_.erase(variant);  // the old factor goes before the new one is made
  try {
    const SparseMatrix no_mass;
    entry.factor = std::make_unique<CholmodFactor>(stiffness, no_mass, 0.0, "the factor of K");
  } catch (const SolverError&) {
    entry.factor.reset();
  }
  return entries_.emplace(variant, std::move(entry)).first->second.factor.get();
}

}  // namespace crackle::modal
