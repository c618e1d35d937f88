#pragma once
/// \file Pure pointwise physics kernels (libCEED QFunction style): no mesh access, plain inputs,
/// testable alone.
#include "fem/material.hpp"

namespace crackle::fem {

/// Small-strain tensor in Voigt form from a displacement gradient grad[i][j] = du_i/dx_j
/// (MODEL.md eq. 3).
Voigt strain_from_gradient(const double grad[3][3]);

/// Hooke's law sigma = D eps (MODEL.md eq. 2) for n points: strain and stress are n x 6, row-major.
void stress_from_strain(const Material& material, int n, const double* strain, double* stress);

/// Lumped nodal mass of one quadrature point: rho * weight * det(J) (MODEL.md eq. 25c, GLL rule).
inline double point_mass(double density, double weight_times_jacobian) {
  return density * weight_times_jacobian;
}

}  // namespace crackle::fem
