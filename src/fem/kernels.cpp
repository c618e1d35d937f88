#include "fem/kernels.hpp"

namespace crackle::fem {

Voigt strain_from_gradient(const double grad[3][3]) {
  // eq. (3), Voigt order xx, yy, zz, yz, xz, xy with engineering shear strains.
  Voigt strain;
  strain << grad[0][0], grad[1][1], grad[2][2], grad[1][2] + grad[2][1], grad[0][2] + grad[2][0],
      grad[0][1] + grad[1][0];
  return strain;
}

void stress_from_strain(const Material& material, int n, const double* strain, double* stress) {
  // eq. (2): sigma = D eps, point by point.
  const VoigtMatrix& d = material.stiffness;
  for (int point = 0; point < n; ++point) {
    const double* e = strain + 6 * point;
    double* s = stress + 6 * point;
    for (int i = 0; i < 6; ++i) {
      double sum = 0.0;
      for (int j = 0; j < 6; ++j) sum += d(i, j) * e[j];
      s[i] = sum;
    }
  }
}

}  // namespace crackle::fem
