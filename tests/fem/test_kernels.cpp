// Pointwise kernels and materials (MODEL.md eqs. 2, 3), tested alone.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "fem/kernels.hpp"
#include "fem/material.hpp"

namespace crackle::fem {
namespace {

TEST(Kernels, StrainFromGradientIsSymmetricPartWithEngineeringShear) {
  const double grad[3][3] = {{1.0, 2.0, 3.0}, {4.0, 5.0, 6.0}, {7.0, 8.0, 9.0}};
  const Voigt strain = strain_from_gradient(grad);
  Voigt expected;
  expected << 1.0, 5.0, 9.0, 6.0 + 8.0, 3.0 + 7.0, 2.0 + 4.0;  // xx yy zz yz xz xy
  EXPECT_EQ(strain, expected);
}

TEST(Kernels, InfinitesimalRotationHasNoStrain) {
  const double w[3] = {0.3, -0.7, 1.1};
  const double grad[3][3] = {{0.0, -w[2], w[1]}, {w[2], 0.0, -w[0]}, {-w[1], w[0], 0.0}};
  EXPECT_EQ(strain_from_gradient(grad).norm(), 0.0);
}

TEST(Kernels, IsotropicHookeUniaxialStressAndShear) {
  const double young = 70e9, poisson = 0.33;
  const Material material = isotropic(young, poisson, 2700.0, "aluminium");
  EXPECT_EQ(material.name, "aluminium");
  EXPECT_EQ(material.density, 2700.0);
  // Uniaxial stress sigma_xx = s: eps = (s/E)(1, -nu, -nu, 0, 0, 0); shear gamma_yz = g: tau = mu g.
  const double s = 1e6, g = 1e-4;
  double strain[12] = {s / young,
                       -poisson * s / young,
                       -poisson * s / young,
                       0,
                       0,
                       0,  //
                       0,
                       0,
                       0,
                       g,
                       0,
                       0};
  double stress[12];
  stress_from_strain(material, 2, strain, stress);
  EXPECT_NEAR(stress[0], s, 1e-9 * s);
  for (int i = 1; i < 6; ++i) EXPECT_NEAR(stress[i], 0.0, 1e-9 * s);
  const double mu = young / (2.0 * (1.0 + poisson));
  EXPECT_NEAR(stress[6 + 3], mu * g, 1e-12 * mu * g);
  for (int i : {0, 1, 2, 4, 5}) EXPECT_EQ(stress[6 + i], 0.0);
}

TEST(Kernels, IsotropicBulkModulus) {
  // Hydrostatic strain e(1,1,1): p = 3K e with K = E / (3 (1 - 2 nu)).
  const double young = 200e9, poisson = 0.28;
  const Material material = isotropic(young, poisson, 7800.0);
  const double e = 1e-3;
  double strain[6] = {e, e, e, 0, 0, 0}, stress[6];
  stress_from_strain(material, 1, strain, stress);
  const double bulk = young / (3.0 * (1.0 - 2.0 * poisson));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(stress[i], 3.0 * bulk * e, 1e-12 * bulk);
  EXPECT_TRUE(material.stiffness.isApprox(material.stiffness.transpose(), 0.0));
}

TEST(Kernels, GeneralVoigtStiffnessIsUsedAsGiven) {
  Material material;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) material.stiffness(i, j) = 1.0 + i + 10.0 * j;
  }
  Voigt strain;
  strain << 1, -2, 3, -4, 5, -6;
  Voigt stress;
  stress_from_strain(material, 1, strain.data(), stress.data());
  EXPECT_EQ(stress, material.stiffness * strain);
}

TEST(Kernels, PointMass) { EXPECT_EQ(point_mass(7800.0, 0.25), 1950.0); }

TEST(Kernels, IsotropicRejectsBadParameters) {
  EXPECT_THROW(isotropic(200e9, 0.5, 7800.0), InputError);
  EXPECT_THROW(isotropic(-1.0, 0.3, 7800.0), InputError);
  EXPECT_THROW(isotropic(200e9, 0.3, -1.0), InputError);
  try {
    isotropic(200e9, 0.7, 7800.0, "steel");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("steel"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("0.7"), std::string::npos);
  }
}

}  // namespace
}  // namespace crackle::fem
