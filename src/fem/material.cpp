#include "fem/material.hpp"

#include <utility>

#include "core/errors.hpp"

namespace crackle::fem {

Material isotropic(double young, double poisson, double density, std::string name) {
  if (!(young > 0.0) || !(poisson > -1.0 && poisson < 0.5) || !(density >= 0.0)) {
    throw InputError("material '" + name +
                     "': need E > 0, -1 < nu < 0.5 and rho >= 0, got E = " + format_number(young) +
                     ", nu = " + format_number(poisson) + ", rho = " + format_number(density));
  }
  // Lamé constants; D in Voigt form with engineering shear strains (MODEL.md eq. 2).
  const double lambda = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
  const double mu = young / (2.0 * (1.0 + poisson));
  Material material;
  material.name = std::move(name);
  material.density = density;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) material.stiffness(i, j) = lambda;
    material.stiffness(i, i) = lambda + 2.0 * mu;
    material.stiffness(i + 3, i + 3) = mu;
  }
  return material;
}

}  // namespace crackle::fem
