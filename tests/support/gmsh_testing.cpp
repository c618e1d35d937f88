#include "gmsh_testing.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <algorithm>

namespace crackle::testing {

std::vector<Index> match_nodes(const mesh::Mesh& a, const mesh::Mesh& b) {
  auto key = [](const Vec3& x) {
    return std::array<long long, 3>{std::llround(x[0] * 1e9), std::llround(x[1] * 1e9), std::llround(x[2] * 1e9)};
  };
  std::map<std::array<long long, 3>, Index> index;
  for (Index n = 0; n < b.n_nodes(); ++n) index.emplace(key(b.nodes[n]), n);
  std::vector<Index> match(a.n_nodes(), -1);
  for (Index n = 0; n < a.n_nodes(); ++n) {
    const auto found = index.find(key(a.nodes[n]));
    if (found != index.end()) match[n] = found->second;
  }
  return match;
}

double permuted_difference(const SparseMatrix& a, const SparseMatrix& b, const std::vector<Index>& dof_match) {
  const MatrixX dense_b = MatrixX(b);
  MatrixX dense_a = MatrixX(a);
  double difference = 0.0;
  for (Index i = 0; i < dense_a.rows(); ++i) {
    for (Index j = 0; j < dense_a.cols(); ++j) {
      difference = std::max(difference, std::abs(dense_a(i, j) - dense_b(dof_match[i], dof_match[j])));
    }
  }
  return difference / dense_b.cwiseAbs().maxCoeff();
}

std::vector<Index> dof_match(const mesh::DofMap& a_dofs, const mesh::DofMap& b_dofs, const std::vector<Index>& nodes) {
  std::vector<Index> match(a_dofs.n_dofs(), -1);
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    for (int c = 0; c < 3; ++c) match[a_dofs.dof(static_cast<Index>(n), c)] = b_dofs.dof(nodes[n], c);
  }
  return match;
}

VectorX lowest_eigenvalues(const SparseMatrix& stiffness, const SparseMatrix& mass, int count, double shift) {
  using ColumnMatrix = Eigen::SparseMatrix<double>;
  const ColumnMatrix k = stiffness, m = mass;
  const ColumnMatrix shifted = k - shift * m;
  Eigen::CholmodSupernodalLLT<ColumnMatrix> solver(shifted);
  if (solver.info() != Eigen::Success) return VectorX();
  const Index n = static_cast<Index>(k.rows());
  const int block = static_cast<int>(std::min<Index>(n, 2 * count + 8));
  MatrixX x(n, block);
  unsigned state = 12345;
  for (Index i = 0; i < n; ++i) {
    for (int j = 0; j < block; ++j) {
      state = state * 1664525u + 1013904223u;
      x(i, j) = (state >> 8) / double(1u << 24) - 0.5;
    }
  }
  VectorX previous = VectorX::Constant(count, 0.0), values;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const MatrixX mx = m * x;
    const MatrixX y = solver.solve(mx);
    // (K - shift M) y = M x: the reduced stiffness y^T (K - shift M) y is y^T M x, without the
    // rounding that multiplying by a stiff K would add.
    const MatrixX reduced_k = y.transpose() * mx, reduced_m = y.transpose() * (m * y);
    const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> ritz(0.5 * (reduced_k + reduced_k.transpose()),
                                                                 0.5 * (reduced_m + reduced_m.transpose()));
    x = y * ritz.eigenvectors();
    values = ritz.eigenvalues().head(count).array() + shift;
    // Ritz values jitter at ~1e-13 from rounding: stop at a change of 1e-11.
    const double change = ((values - previous).cwiseAbs().array() / values.cwiseAbs().array()).maxCoeff();
    if (iteration > 3 && change <= 1e-11) break;
    previous = values;
  }
  return values;
}

VectorX lowest_frequencies(const mesh::Mesh& mesh, mesh::Variant variant, const fem::Materials& materials,
                           const std::vector<fem::DirichletCondition>& conditions, int count) {
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, variant);
  const fem::Constraints constraints = fem::make_constraints(dofs, conditions);
  const SparseMatrix k = fem::restrict_to_free(fem::assemble_stiffness(mesh, dofs, materials), constraints);
  const SparseMatrix m = fem::restrict_to_free(fem::assemble_consistent_mass(mesh, dofs, materials), constraints);
  const VectorX lambda = lowest_eigenvalues(k, m, count);
  return lambda.cwiseSqrt() / (2.0 * M_PI);
}

fem::DirichletCondition clamp(const std::vector<Index>& nodes, std::vector<int> components) {
  fem::DirichletCondition condition;
  condition.nodes = nodes;
  condition.components = components;
  condition.values.assign(components.size(), 0.0);
  condition.source = "test";
  return condition;
}

}  // namespace crackle::testing
