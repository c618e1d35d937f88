/// \file Rigid-body modes a mesh and its supports allow: pieces and the rank of their supports.
#include <Eigen/Eigenvalues>

#include "modal/modal.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/errors.hpp"
#include "core/resources.hpp"

namespace crackle::modal {
namespace {

/// Union-find root with path halving.
Index find_root(std::vector<Index>& parent, Index i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

/// Piece index (0..n_pieces-1) of every DOF node (-1 for DOF nodes no element touches).
std::vector<Index> piece_of_dof_nodes(const mesh::Mesh& mesh, const mesh::DofMap& dofs, int& n_pieces) {
  std::vector<Index> parent(dofs.n_dof_nodes);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(dofs.n_dof_nodes, 0);
  const int per_element = mesh.nodes_per_element();
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    const Index first = find_root(parent, dofs.dof_node[nodes[0]]);
    used[dofs.dof_node[nodes[0]]] = 1;
    for (int a = 1; a < per_element; ++a) {
      const Index dof_node = dofs.dof_node[nodes[a]];
      used[dof_node] = 1;
      const Index root = find_root(parent, dof_node);
      if (root != first) parent[root] = first;
    }
  }
  std::vector<Index> piece(dofs.n_dof_nodes, -1);
  std::vector<Index> root_piece(dofs.n_dof_nodes, -1);
  n_pieces = 0;
  for (Index i = 0; i < dofs.n_dof_nodes; ++i) {
    if (!used[i]) continue;
    const Index root = find_root(parent, i);
    if (root_piece[root] < 0) root_piece[root] = n_pieces++;
    piece[i] = root_piece[root];
  }
  return piece;
}

}  // namespace

int count_pieces(const mesh::Mesh& mesh, const mesh::DofMap& dofs) {
  int n_pieces = 0;
  piece_of_dof_nodes(mesh, dofs, n_pieces);
  return n_pieces;
}

int count_rigid_body_modes(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                           const fem::Constraints& constraints) {
  int n_pieces = 0;
  const std::vector<Index> piece = piece_of_dof_nodes(mesh, dofs, n_pieces);
  // Coordinates of each DOF node (any mesh node mapped to it: tied nodes coincide).
  std::vector<Vec3> position(dofs.n_dof_nodes, Vec3::Zero());
  for (Index node = mesh.n_nodes() - 1; node >= 0; --node) position[dofs.dof_node[node]] = mesh.nodes[node];
  std::vector<Vec3> centre(n_pieces, Vec3::Zero());
  std::vector<double> count(n_pieces, 0.0);
  for (Index i = 0; i < dofs.n_dof_nodes; ++i) {
    if (piece[i] < 0) continue;
    centre[piece[i]] += position[i];
    count[piece[i]] += 1.0;
  }
  for (int p = 0; p < n_pieces; ++p) centre[p] /= count[p];
  std::vector<double> radius(n_pieces, 0.0);
  for (Index i = 0; i < dofs.n_dof_nodes; ++i) {
    if (piece[i] >= 0) radius[piece[i]] = std::max(radius[piece[i]], (position[i] - centre[piece[i]]).norm());
  }
  // Gram matrix of the six rigid motions (3 translations, 3 rotations scaled by the piece radius)
  // sampled at the piece's fixed DOFs: its rank is the number of rigid motions the supports stop.
  std::vector<Eigen::Matrix<double, 6, 6>> gram(n_pieces, Eigen::Matrix<double, 6, 6>::Zero());
  for (Index dof = 0; dof < dofs.n_dofs(); ++dof) {
    if (!constraints.fixed[dof]) continue;
    const Index dof_node = dof / 3;
    const int component = static_cast<int>(dof % 3);
    const int p = piece[dof_node];
    if (p < 0) continue;
    Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
    row[component] = 1.0;
    const Vec3 arm = (position[dof_node] - centre[p]) / std::max(radius[p], 1e-300);
    for (int axis = 0; axis < 3; ++axis) row[3 + axis] = Vec3::Unit(axis).cross(arm)[component];
    gram[p] += row * row.transpose();
  }
  int n_rigid = 0;
  for (int p = 0; p < n_pieces; ++p) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> solver(gram[p]);
    const auto values = solver.eigenvalues();
    const double largest = values.maxCoeff();
    int rank = 0;
    for (int i = 0; i < 6; ++i) rank += values[i] > 1e-9 * largest && largest > 0.0 ? 1 : 0;
    n_rigid += 6 - rank;
  }
  return n_rigid;
}

}  // namespace crackle::modal
