#pragma once
/// \file What the reduced integrator's translation units share (integrator.cpp: the steps and the
/// frictionless contact; integrator_friction.cpp: Coulomb friction). Private to src/reduced.
#include <vector>

#include "core/types.hpp"

namespace crackle::reduced::detail {

/// The pair's local frame in row order (normal, tangent 1, tangent 2): the normal is the x axis.
inline const Vec3 kLocalNormal = Vec3::UnitX();

/// Indices of the nonzero entries of p.
inline std::vector<Index> nonzero_rows(const VectorX& p) {
  std::vector<Index> rows;
  for (Index i = 0; i < p.size(); ++i)
    if (p[i] != 0.0) rows.push_back(i);
  return rows;
}

}  // namespace crackle::reduced::detail
