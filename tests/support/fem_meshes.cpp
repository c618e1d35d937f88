#include "fem_meshes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace crackle::fem::testing {

double GridMesh::volume() const { return std::abs(affine.determinant()) * lengths.prod(); }

std::vector<mesh::FaceRef> GridMesh::box_faces(int f) const {
  std::vector<mesh::FaceRef> faces;
  const int axis = f / 2;
  const bool upper = f % 2 == 1;
  for (int ez = 0; ez < cells[2]; ++ez) {
    for (int ey = 0; ey < cells[1]; ++ey) {
      for (int ex = 0; ex < cells[0]; ++ex) {
        const int e[3] = {ex, ey, ez};
        if (e[axis] == (upper ? cells[axis] - 1 : 0))
          faces.push_back({ex + cells[0] * (ey + cells[1] * ez), f});
      }
    }
  }
  return faces;
}

Vec3 GridMesh::box_normal(int f) const {
  Vec3 reference = Vec3::Zero();
  reference[f / 2] = f % 2 == 1 ? 1.0 : -1.0;
  return (affine.inverse().transpose() * reference).normalized();
}

double pseudo_random(unsigned& state) {
  state = state * 1664525u + 1013904223u;
  return (state >> 8) / double(1u << 24) * 2.0 - 1.0;  // in [-1, 1)
}

GridMesh grid_mesh(int order, std::array<int, 3> cells, Vec3 lengths, double distortion,
                   const Eigen::Matrix3d& affine, const Vec3& offset, unsigned seed) {
  GridMesh grid;
  grid.cells = cells;
  grid.affine = affine;
  grid.lengths = lengths;
  const int p = order, m = order + 1;
  const std::vector<double> gll = gauss_lobatto(m).points;
  // vertices
  const int vx = cells[0] + 1, vy = cells[1] + 1, vz = cells[2] + 1;
  std::vector<Vec3> vertices(vx * vy * vz);
  unsigned state = seed;
  for (int k = 0; k < vz; ++k) {
    for (int j = 0; j < vy; ++j) {
      for (int i = 0; i < vx; ++i) {
        const int index[3] = {i, j, k};
        Vec3 x;
        for (int c = 0; c < 3; ++c) {
          const double h = lengths[c] / cells[c];
          x[c] = index[c] * h;
          const double shift = distortion * h * pseudo_random(state);
          if (index[c] > 0 && index[c] < cells[c]) x[c] += shift;
        }
        vertices[i + vx * (j + vy * k)] = x;
      }
    }
  }
  const int nx = cells[0] * p + 1, ny = cells[1] * p + 1, nz = cells[2] * p + 1;
  mesh::Mesh& mesh = grid.mesh;
  mesh.order = order;
  mesh.nodes.resize(nx * ny * nz);
  for (int kk = 0; kk < nz; ++kk) {
    for (int jj = 0; jj < ny; ++jj) {
      for (int ii = 0; ii < nx; ++ii) {
        const int global[3] = {ii, jj, kk};
        int element[3], local[3];
        for (int c = 0; c < 3; ++c) {
          element[c] = std::min(global[c] / p, cells[c] - 1);
          local[c] = global[c] - element[c] * p;
        }
        Vec3 x = Vec3::Zero();
        for (int corner = 0; corner < 8; ++corner) {
          const int bits[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
          double weight = 1.0;
          for (int c = 0; c < 3; ++c) {
            const double xi = gll[local[c]];
            weight *= bits[c] ? 0.5 * (1.0 + xi) : 0.5 * (1.0 - xi);
          }
          x += weight *
               vertices[(element[0] + bits[0]) + vx * ((element[1] + bits[1]) + vy * (element[2] + bits[2]))];
        }
        mesh.nodes[ii + nx * (jj + ny * kk)] = affine * x + offset;
      }
    }
  }
  for (int ez = 0; ez < cells[2]; ++ez) {
    for (int ey = 0; ey < cells[1]; ++ey) {
      for (int ex = 0; ex < cells[0]; ++ex) {
        for (int k = 0; k < m; ++k) {
          for (int j = 0; j < m; ++j) {
            for (int i = 0; i < m; ++i) {
              mesh.connectivity.push_back((ex * p + i) + nx * ((ey * p + j) + ny * (ez * p + k)));
            }
          }
        }
        mesh.element_region.push_back(0);
      }
    }
  }
  mesh.n_original_nodes = mesh.n_nodes();
  mesh.axis_aligned_bricks = distortion == 0.0 && affine.isDiagonal(0.0) && affine.diagonal().minCoeff() > 0;
  return grid;
}

mesh::DofMap identity_dofs(const mesh::Mesh& mesh) {
  mesh::DofMap dofs;
  dofs.n_dof_nodes = mesh.n_nodes();
  dofs.dof_node.resize(mesh.n_nodes());
  for (Index i = 0; i < mesh.n_nodes(); ++i) dofs.dof_node[i] = i;
  return dofs;
}

Material anisotropic_material(double density) {
  Material material = isotropic(200e9, 0.3, density, "anisotropic");
  VoigtMatrix perturbation;
  unsigned state = 7;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) perturbation(i, j) = pseudo_random(state);
  }
  material.stiffness += 20e9 * perturbation * perturbation.transpose();
  return material;
}

Eigen::Matrix3d skew_map() {
  Eigen::Matrix3d affine;
  affine << 1.1, 0.2, -0.1,  //
      0.05, 0.9, 0.15,       //
      -0.1, 0.1, 1.2;
  return affine;
}

}  // namespace crackle::fem::testing
