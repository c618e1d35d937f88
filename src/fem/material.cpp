#include "fem/material.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
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

namespace {

/// Voigt index of the symmetric tensor index pair (i, j): xx, yy, zz, yz, xz, xy.
int voigt_index(int i, int j) {
  static const int index[3][3] = {{0, 5, 4}, {5, 1, 3}, {4, 3, 2}};
  return index[i][j];
}

}  // namespace

Material orthotropic(const OrthotropicConstants& c, double density, std::string name) {
  const double moduli[6] = {c.e1, c.e2, c.e3, c.g12, c.g13, c.g23};
  const char* moduli_names[6] = {"E1", "E2", "E3", "G12", "G13", "G23"};
  for (int i = 0; i < 6; ++i) {
    if (!(moduli[i] > 0.0) || !std::isfinite(moduli[i])) {
      throw InputError("material '" + name + "': need " + moduli_names[i] + " > 0, got " + format_number(moduli[i]));
    }
  }
  if (!(density >= 0.0)) {
    throw InputError("material '" + name + "': need rho >= 0, got " + format_number(density));
  }
  // Compliance with engineering shear strains (Voigt xx, yy, zz, yz, xz, xy).
  VoigtMatrix compliance = VoigtMatrix::Zero();
  compliance(0, 0) = 1.0 / c.e1;
  compliance(1, 1) = 1.0 / c.e2;
  compliance(2, 2) = 1.0 / c.e3;
  compliance(0, 1) = compliance(1, 0) = -c.nu12 / c.e1;
  compliance(0, 2) = compliance(2, 0) = -c.nu13 / c.e1;
  compliance(1, 2) = compliance(2, 1) = -c.nu23 / c.e2;
  compliance(3, 3) = 1.0 / c.g23;
  compliance(4, 4) = 1.0 / c.g13;
  compliance(5, 5) = 1.0 / c.g12;
  // Positive definite iff the normal 3x3 block is: scaled by the moduli, that is
  // [[1, -nu21, -nu31], [-nu12, 1, -nu32], [-nu13, -nu23, 1]] with positive leading minors.
  const double nu21 = c.nu12 * c.e2 / c.e1, nu31 = c.nu13 * c.e3 / c.e1, nu32 = c.nu23 * c.e3 / c.e2;
  const double minor2 = 1.0 - c.nu12 * nu21;
  const double minor3 = 1.0 - c.nu12 * nu21 - c.nu23 * nu32 - c.nu13 * nu31 - 2.0 * nu21 * nu32 * c.nu13;
  if (!(minor2 > 0.0) || !(minor3 > 0.0) || compliance.llt().info() != Eigen::Success) {
    throw InputError("material '" + name +
                     "': orthotropic constants do not give a positive definite stiffness (need "
                     "1 - nu12 nu21 > 0 and 1 - nu12 nu21 - nu23 nu32 - nu13 nu31 - 2 nu21 nu32 nu13 > 0, got " +
                     format_number(minor2) + " and " + format_number(minor3) + " with nu12 = " +
                     format_number(c.nu12) + ", nu13 = " + format_number(c.nu13) + ", nu23 = " +
                     format_number(c.nu23) + ")");
  }
  Material material;
  material.name = std::move(name);
  material.density = density;
  material.stiffness = compliance.inverse();
  material.stiffness = 0.5 * (material.stiffness + material.stiffness.transpose()).eval();
  return material;
}

VoigtMatrix rotate_stiffness(const VoigtMatrix& stiffness, const Eigen::Matrix3d& axes) {
  // With engineering shear strains, D_IJ = C_ijkl for I = (ij), J = (kl): rotate the tensor.
  VoigtMatrix rotated = VoigtMatrix::Zero();
  const int pairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
  for (int big_i = 0; big_i < 6; ++big_i) {
    for (int big_j = 0; big_j < 6; ++big_j) {
      const int i = pairs[big_i][0], j = pairs[big_i][1], k = pairs[big_j][0], l = pairs[big_j][1];
      double sum = 0.0;
      for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q)
          for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s) {
              const double factor = axes(i, p) * axes(j, q) * axes(k, r) * axes(l, s);
              if (factor != 0.0) sum += factor * stiffness(voigt_index(p, q), voigt_index(r, s));
            }
      rotated(big_i, big_j) = sum;
    }
  }
  return rotated;
}

Material rotated_about_z(const Material& material, double degrees) {
  const double angle = degrees * M_PI / 180.0;
  // Exact quarter turns keep exact zeros (a 90-degree ply equals the swapped constants bit for bit
  // up to the rounding of the inverse).
  double cosine = std::cos(angle), sine = std::sin(angle);
  const double quarters = degrees / 90.0;
  if (quarters == std::round(quarters)) {
    const int turn = static_cast<int>(((static_cast<long long>(quarters) % 4) + 4) % 4);
    const double cosines[4] = {1, 0, -1, 0}, sines[4] = {0, 1, 0, -1};
    cosine = cosines[turn];
    sine = sines[turn];
  }
  Eigen::Matrix3d axes;
  axes << cosine, -sine, 0.0,  //
      sine, cosine, 0.0,       //
      0.0, 0.0, 1.0;
  Material rotated = material;
  rotated.stiffness = rotate_stiffness(material.stiffness, axes);
  return rotated;
}

void check_positive_definite(const Material& material) {
  const VoigtMatrix& d = material.stiffness;
  const double scale = d.cwiseAbs().maxCoeff();
  if (!((d - d.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale) || !(scale > 0.0)) {
    throw InputError("material '" + material.name + "': stiffness matrix is not symmetric");
  }
  const Eigen::SelfAdjointEigenSolver<VoigtMatrix> eigen(d);
  const double smallest = eigen.eigenvalues().minCoeff();
  if (!(smallest > 0.0)) {
    throw InputError("material '" + material.name + "': stiffness matrix is not positive definite (smallest eigenvalue " +
                     format_number(smallest) + " Pa)");
  }
}

}  // namespace crackle::fem
