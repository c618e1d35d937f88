#pragma once
/// \file Linear elastic materials (MODEL.md eq. 2) as a Voigt stiffness, so that isotropic,
/// orthotropic and rotated layered materials all fit one type.
#include <Eigen/Core>
#include <string>

namespace crackle::fem {

/// Voigt order of stress and strain: xx, yy, zz, yz, xz, xy, with engineering shear strains
/// (gamma_yz = 2 eps_yz), so that sigma = D eps.
using Voigt = Eigen::Matrix<double, 6, 1>;
using VoigtMatrix = Eigen::Matrix<double, 6, 6>;

struct Material {
  std::string name;
  double density = 0.0;  ///< rho [kg/m^3]
  VoigtMatrix stiffness = VoigtMatrix::Zero();  ///< D [Pa], symmetric positive definite
};

/// Isotropic material from Young's modulus E [Pa], Poisson's ratio nu and density rho [kg/m^3].
Material isotropic(double young, double poisson, double density, std::string name = "isotropic");

}  // namespace crackle::fem
