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

/// Engineering constants of an orthotropic material in its own axes 1, 2, 3 (nu_ij: contraction
/// along j under stress along i, so nu_ji = nu_ij E_j / E_i).
struct OrthotropicConstants {
  double e1 = 0.0, e2 = 0.0, e3 = 0.0;        ///< Young's moduli [Pa]
  double g12 = 0.0, g13 = 0.0, g23 = 0.0;     ///< shear moduli [Pa]
  double nu12 = 0.0, nu13 = 0.0, nu23 = 0.0;  ///< Poisson's ratios
};

/// Orthotropic material with axes 1, 2, 3 along x, y, z: D = S^-1 with the compliance
/// S = [[1/E1, -nu12/E1, -nu13/E1], [., 1/E2, -nu23/E2], [., ., 1/E3]] (+ 1/G23, 1/G13, 1/G12 on the
/// shear diagonal). InputError naming the material if the constants are not positive or S is not
/// positive definite (e.g. 1 - nu12 nu21 - nu23 nu32 - nu13 nu31 - 2 nu21 nu32 nu13 <= 0).
Material orthotropic(const OrthotropicConstants& constants, double density, std::string name = "orthotropic");

/// Voigt stiffness of the same material seen in the global axes when its own axes are the columns
/// of `axes` (a rotation): C'_ijkl = A_ip A_jq A_kr A_ls C_pqrs.
VoigtMatrix rotate_stiffness(const VoigtMatrix& stiffness, const Eigen::Matrix3d& axes);

/// A ply: the material with its axis 1 turned by `degrees` about z (the layer normal), from x
/// towards y: axis 1 = (cos a, sin a, 0).
Material rotated_about_z(const Material& material, double degrees);

/// InputError naming the material unless D is symmetric positive definite.
void check_positive_definite(const Material& material);

}  // namespace crackle::fem
