// The reference hexahedron and element matrices (MODEL.md eqs. 25a, 25c).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>

#include "core/errors.hpp"
#include "fem/element.hpp"
#include "fem_meshes.hpp"

namespace crackle::fem {
namespace {

using testing::anisotropic_material;
using testing::pseudo_random;
using testing::skew_map;

/// Node coordinates of one element: trilinear map of 8 vertices (lexicographic) at the GLL nodes.
std::vector<double> element_coords(const HexBasis& basis, const std::array<Vec3, 8>& vertices) {
  const int m = basis.order + 1;
  std::vector<double> coords(3 * basis.n_nodes);
  for (int k = 0; k < m; ++k) {
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        const double xi[3] = {basis.gll.points[i], basis.gll.points[j], basis.gll.points[k]};
        Vec3 x = Vec3::Zero();
        for (int corner = 0; corner < 8; ++corner) {
          double weight = 1.0;
          for (int c = 0; c < 3; ++c) weight *= ((corner >> c) & 1) ? 0.5 * (1 + xi[c]) : 0.5 * (1 - xi[c]);
          x += weight * vertices[corner];
        }
        for (int c = 0; c < 3; ++c) coords[3 * (i + m * (j + m * k)) + c] = x[c];
      }
    }
  }
  return coords;
}

/// Vertices of the reference cube [-1,1]^3 mapped by `affine`, optionally moved by `distortion`.
std::array<Vec3, 8> vertices(const Eigen::Matrix3d& affine, double distortion, unsigned seed = 3) {
  std::array<Vec3, 8> result;
  unsigned state = seed;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 x(((corner & 1) ? 1.0 : -1.0), ((corner & 2) ? 1.0 : -1.0), ((corner & 4) ? 1.0 : -1.0));
    for (int c = 0; c < 3; ++c) x[c] += distortion * pseudo_random(state);
    result[corner] = affine * x + Vec3(0.3, -0.2, 0.5);
  }
  return result;
}

/// Volume by a 6-point Gauss rule of det J of the trilinear map (independent of the element code).
double trilinear_volume(const std::array<Vec3, 8>& v) {
  const Rule1D rule = gauss_legendre(6);
  double volume = 0.0;
  for (int a = 0; a < 6; ++a) {
    for (int b = 0; b < 6; ++b) {
      for (int c = 0; c < 6; ++c) {
        const double xi[3] = {rule.points[a], rule.points[b], rule.points[c]};
        Eigen::Matrix3d jac = Eigen::Matrix3d::Zero();
        for (int corner = 0; corner < 8; ++corner) {
          for (int d = 0; d < 3; ++d) {
            double derivative = 1.0;
            for (int e = 0; e < 3; ++e) {
              const double sign = ((corner >> e) & 1) ? 1.0 : -1.0;
              derivative *= e == d ? 0.5 * sign : 0.5 * (1 + sign * xi[e]);
            }
            jac.col(d) += derivative * v[corner];
          }
        }
        volume += rule.weights[a] * rule.weights[b] * rule.weights[c] * jac.determinant();
      }
    }
  }
  return volume;
}

class ElementOrder : public ::testing::TestWithParam<int> {};

TEST_P(ElementOrder, BasisIsPartitionOfUnityAndGradientsSumToZero) {
  const HexBasis basis(GetParam());
  ASSERT_EQ(basis.n_nodes, (GetParam() + 1) * (GetParam() + 1) * (GetParam() + 1));
  ASSERT_EQ(basis.n_points, basis.n_nodes);
  double weight_sum = 0.0;
  for (int q = 0; q < basis.n_points; ++q) {
    weight_sum += basis.weights[q];
    double sum = 0.0, gradient_sum[3] = {0, 0, 0};
    for (int a = 0; a < basis.n_nodes; ++a) {
      sum += basis.values[q * basis.n_nodes + a];
      for (int j = 0; j < 3; ++j) gradient_sum[j] += basis.gradients[3 * (q * basis.n_nodes + a) + j];
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(gradient_sum[j], 0.0, 1e-12);
  }
  EXPECT_NEAR(weight_sum, 8.0, 1e-13);
}

TEST_P(ElementOrder, StiffnessIsSymmetricWithSixZeroModesOnDistortedElement) {
  const HexBasis basis(GetParam());
  const std::vector<double> coords = element_coords(basis, vertices(skew_map(), 0.15));
  MatrixX stiffness;
  element_stiffness(basis, coords.data(), anisotropic_material(), stiffness);
  ASSERT_EQ(stiffness.rows(), 3 * basis.n_nodes);
  EXPECT_EQ((stiffness - stiffness.transpose()).norm(), 0.0);
  Eigen::SelfAdjointEigenSolver<MatrixX> solver(stiffness, Eigen::EigenvaluesOnly);
  const VectorX& lambda = solver.eigenvalues();
  const double largest = lambda.maxCoeff();
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(lambda[i]), 1e-11 * largest) << "mode " << i;
  EXPECT_GT(lambda[6], 1e-6 * largest);
}

TEST_P(ElementOrder, StrainEnergyOfLinearFieldIsExact) {
  // u = A x: constant strain, so u^T K u = V eps^T D eps (exact Gauss rule, eq. 25a).
  const HexBasis basis(GetParam());
  const Material material = anisotropic_material();
  Eigen::Matrix3d gradient;
  gradient << 1.0, -0.4, 0.3, 0.2, -0.6, 0.5, 0.7, 0.1, 0.9;
  const double grad[3][3] = {{gradient(0, 0), gradient(0, 1), gradient(0, 2)},
                             {gradient(1, 0), gradient(1, 1), gradient(1, 2)},
                             {gradient(2, 0), gradient(2, 1), gradient(2, 2)}};
  Voigt strain;
  strain << grad[0][0], grad[1][1], grad[2][2], grad[1][2] + grad[2][1], grad[0][2] + grad[2][0],
      grad[0][1] + grad[1][0];
  for (double distortion : {0.0, 0.15}) {
    const std::array<Vec3, 8> v = vertices(skew_map(), distortion);
    const std::vector<double> coords = element_coords(basis, v);
    VectorX u(3 * basis.n_nodes);
    for (int a = 0; a < basis.n_nodes; ++a) {
      u.segment<3>(3 * a) = gradient * Vec3(coords[3 * a], coords[3 * a + 1], coords[3 * a + 2]);
    }
    MatrixX stiffness;
    element_stiffness(basis, coords.data(), material, stiffness);
    const double expected = trilinear_volume(v) * strain.dot(material.stiffness * strain);
    EXPECT_NEAR(u.dot(stiffness * u), expected, 1e-11 * expected) << "distortion " << distortion;
  }
}

TEST_P(ElementOrder, BrickStiffnessScalesWithLength) {
  // K ~ h for a uniformly scaled brick (eq. 25a: two gradients, one volume).
  const HexBasis basis(GetParam());
  const Material material = isotropic(200e9, 0.3, 7800.0);
  std::vector<double> coords(3 * basis.n_nodes), scaled(3 * basis.n_nodes);
  brick_coordinates(basis, 0.1, 0.2, 0.3, coords.data());
  brick_coordinates(basis, 0.2, 0.4, 0.6, scaled.data());
  MatrixX small, large;
  element_stiffness(basis, coords.data(), material, small);
  element_stiffness(basis, scaled.data(), material, large);
  EXPECT_LT((large - 2.0 * small).norm(), 1e-13 * large.norm());
  EXPECT_NEAR(coords[3 * (basis.n_nodes - 1) + 2], 0.3, 1e-15);  // last node at (hx, hy, hz)
}

TEST_P(ElementOrder, ConsistentMassIsExactOnBrick) {
  // \int N_a N_b on [0,a]x[0,b]x[0,c]: sum = V and x^T M x = \int x^2 = a^3 b c / 3 (eq. 25c).
  const HexBasis basis(GetParam());
  const double hx = 0.3, hy = 0.5, hz = 0.7;
  std::vector<double> coords(3 * basis.n_nodes);
  brick_coordinates(basis, hx, hy, hz, coords.data());
  MatrixX mass;
  element_mass_scalar(basis, coords.data(), mass);
  EXPECT_EQ((mass - mass.transpose()).norm(), 0.0);
  EXPECT_NEAR(mass.sum(), hx * hy * hz, 1e-15);
  VectorX x(basis.n_nodes);
  for (int a = 0; a < basis.n_nodes; ++a) x[a] = coords[3 * a];
  EXPECT_NEAR(x.dot(mass * x), hx * hx * hx * hy * hz / 3.0, 1e-15);
  Eigen::SelfAdjointEigenSolver<MatrixX> solver(mass, Eigen::EigenvaluesOnly);
  EXPECT_GT(solver.eigenvalues().minCoeff(), 0.0);
}

TEST_P(ElementOrder, LumpedMassIsPositiveAndSumsToVolume) {
  const HexBasis basis(GetParam());
  for (double distortion : {0.0, 0.2}) {
    const std::array<Vec3, 8> v = vertices(skew_map(), distortion);
    const std::vector<double> coords = element_coords(basis, v);
    std::vector<double> lumped(basis.n_nodes), integrals(basis.n_nodes);
    element_lumped_mass_scalar(basis, coords.data(), lumped.data());
    element_shape_integrals(basis, coords.data(), integrals.data());
    double sum = 0.0, integral_sum = 0.0;
    for (int a = 0; a < basis.n_nodes; ++a) {
      EXPECT_GT(lumped[a], 0.0) << "node " << a;
      sum += lumped[a];
      integral_sum += integrals[a];
    }
    const double volume = trilinear_volume(v);
    EXPECT_NEAR(sum, volume, 1e-13 * volume) << "distortion " << distortion;
    EXPECT_NEAR(integral_sum, volume, 1e-13 * volume) << "distortion " << distortion;
    if (distortion == 0.0) {
      // Affine: GLL rule exact to degree 2p-1 >= 1, so the first moment is exact too.
      double moment = 0.0, exact = 0.0;
      for (int a = 0; a < basis.n_nodes; ++a) {
        moment += lumped[a] * coords[3 * a];
        exact += integrals[a] * coords[3 * a];
      }
      EXPECT_NEAR(moment, exact, 1e-13 * volume);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Orders, ElementOrder, ::testing::Values(1, 2, 3, 4));

TEST(Element, InvertedElementThrowsInputError) {
  const HexBasis basis(2);
  Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity();
  mirror(0, 0) = -1.0;
  const std::vector<double> coords = element_coords(basis, vertices(mirror, 0.0));
  MatrixX matrix;
  EXPECT_THROW(element_stiffness(basis, coords.data(), isotropic(1.0, 0.3, 1.0), matrix), InputError);
  EXPECT_THROW(element_mass_scalar(basis, coords.data(), matrix), InputError);
  std::vector<double> lumped(basis.n_nodes);
  EXPECT_THROW(element_lumped_mass_scalar(basis, coords.data(), lumped.data()), InputError);
}

TEST(Element, OrderOutOfRangeThrows) {
  EXPECT_THROW(HexBasis(0), InputError);
  EXPECT_THROW(HexBasis(5), InputError);
}

}  // namespace
}  // namespace crackle::fem
