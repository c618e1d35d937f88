#include "mesh/topology.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>

#include "core/quadrature.hpp"

namespace crackle::mesh {

void triangle_shape(int order, double s, double t, double* values, double* gradients) {
  const double lambda[3] = {1.0 - s - t, s, t};
  static const double dlambda[3][2] = {{-1, -1}, {1, 0}, {0, 1}};
  if (order == 1) {
    for (int a = 0; a < 3; ++a) {
      values[a] = lambda[a];
      for (int j = 0; j < 2; ++j) gradients[2 * a + j] = dlambda[a][j];
    }
    return;
  }
  for (int a = 0; a < 3; ++a) {
    values[a] = lambda[a] * (2.0 * lambda[a] - 1.0);
    for (int j = 0; j < 2; ++j) gradients[2 * a + j] = (4.0 * lambda[a] - 1.0) * dlambda[a][j];
  }
  for (int k = 0; k < 3; ++k) {
    const int i = k, l = (k + 1) % 3;
    values[3 + k] = 4.0 * lambda[i] * lambda[l];
    for (int j = 0; j < 2; ++j) gradients[2 * (3 + k) + j] = 4.0 * (dlambda[i][j] * lambda[l] + lambda[i] * dlambda[l][j]);
  }
}

namespace {

/// x_s x x_t of a triangle face at (s, t).
Vec3 triangle_normal(int order, const std::vector<Vec3>& x, double s, double t) {
  double values[6], gradients[12];
  triangle_shape(order, s, t, values, gradients);
  Vec3 ds = Vec3::Zero(), dt = Vec3::Zero();
  for (std::size_t a = 0; a < x.size(); ++a) {
    ds += gradients[2 * a] * x[a];
    dt += gradients[2 * a + 1] * x[a];
  }
  return ds.cross(dt);
}

}  // namespace

std::size_t FaceKeyHash::operator()(const FaceKey& key) const {
  std::size_t hash = 1469598103934665603ull;
  for (Index v : key) hash = (hash ^ static_cast<std::size_t>(static_cast<std::uint32_t>(v))) * 1099511628211ull;
  return hash;
}

FaceKey face_key(const Index* corners, int n_corners) {
  FaceKey key{-1, -1, -1, -1};
  // Insertion sort of at most 4 entries.
  for (int i = 0; i < n_corners; ++i) {
    int j = i;
    for (; j > 0 && key[j - 1] > corners[i]; --j) key[j] = key[j - 1];
    key[j] = corners[i];
  }
  return key;
}

std::vector<int> face_corner_positions(ElementShape shape, int order) {
  if (shape == ElementShape::tetrahedron) return {0, 1, 2};
  const int n = order + 1;
  return {0, order, n * n - 1, n * order};
}

std::vector<std::vector<int>> face_edge_positions(ElementShape shape, int order) {
  std::vector<std::vector<int>> edges;
  if (shape == ElementShape::tetrahedron) {
    for (int k = 0; k < 3; ++k) {
      if (order == 2) {
        edges.push_back({k, 3 + k, (k + 1) % 3});
      } else {
        edges.push_back({k, (k + 1) % 3});
      }
    }
    return edges;
  }
  const int n = order + 1;
  edges.resize(4);
  for (int i = 0; i < n; ++i) {
    edges[0].push_back(i);                          // t = -1, s increasing
    edges[1].push_back(order + n * i);              // s = +1, t increasing
    edges[2].push_back((n - 1 - i) + n * order);    // t = +1, s decreasing
    edges[3].push_back(n * (n - 1 - i));            // s = -1, t decreasing
  }
  return edges;
}

std::vector<Index> face_nodes(const Mesh& mesh, const FaceRef& face) {
  const std::vector<int> local = face_local_nodes(mesh.shape, mesh.order, face.local_face);
  const Index* nodes = mesh.element_nodes(face.element);
  std::vector<Index> result(local.size());
  for (std::size_t a = 0; a < local.size(); ++a) result[a] = nodes[local[a]];
  return result;
}

FaceKey face_key(const Mesh& mesh, const FaceRef& face) {
  const std::vector<int> local = face_local_nodes(mesh.shape, mesh.order, face.local_face);
  const std::vector<int> corners = face_corner_positions(mesh.shape, mesh.order);
  const Index* nodes = mesh.element_nodes(face.element);
  Index ids[4];
  for (std::size_t c = 0; c < corners.size(); ++c) ids[c] = nodes[local[corners[c]]];
  return face_key(ids, static_cast<int>(corners.size()));
}

FaceTable face_table(const Mesh& mesh) {
  FaceTable table;
  table.reserve(static_cast<std::size_t>(mesh.n_elements()) * mesh.faces_per_element());
  std::vector<std::vector<int>> local(mesh.faces_per_element());
  for (int f = 0; f < mesh.faces_per_element(); ++f) local[f] = face_local_nodes(mesh.shape, mesh.order, f);
  const std::vector<int> corners = face_corner_positions(mesh.shape, mesh.order);
  const int n_corners = static_cast<int>(corners.size());
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    for (int f = 0; f < mesh.faces_per_element(); ++f) {
      Index ids[4];
      for (int c = 0; c < n_corners; ++c) ids[c] = nodes[local[f][corners[c]]];
      table[face_key(ids, n_corners)].push_back({e, f});
    }
  }
  return table;
}

void face_nodal_areas(ElementShape shape, int order, const std::vector<Vec3>& x, std::vector<double>& areas,
                      std::vector<Vec3>& normals) {
  areas.assign(x.size(), 0.0);
  normals.assign(x.size(), Vec3::Zero());
  if (shape == ElementShape::hexahedron) {
    // GLL nodal quadrature on the (p+1) x (p+1) face grid: a_ij = w_i w_j |x_s x x_t|(xi_i, xi_j).
    const int n = order + 1;
    const Rule1D gll = gauss_lobatto(n);
    std::vector<double> derivative(n * n), unused(n);
    for (int i = 0; i < n; ++i) lagrange_basis(gll.points, gll.points[i], unused.data(), &derivative[i * n]);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        Vec3 ds = Vec3::Zero(), dt = Vec3::Zero();
        for (int l = 0; l < n; ++l) {
          ds += derivative[i * n + l] * x[l + n * j];
          dt += derivative[j * n + l] * x[i + n * l];
        }
        const Vec3 cross = ds.cross(dt);
        areas[i + n * j] = gll.weights[i] * gll.weights[j] * cross.norm();
        normals[i + n * j] = cross.normalized();
      }
    }
    return;
  }
  static const double node_s[6] = {0, 1, 0, 0.5, 0.5, 0}, node_t[6] = {0, 0, 1, 0, 0.5, 0.5};
  for (std::size_t a = 0; a < x.size(); ++a) normals[a] = triangle_normal(order, x, node_s[a], node_t[a]).normalized();
  if (order == 1) {
    const double area = 0.5 * (x[1] - x[0]).cross(x[2] - x[0]).norm();
    for (int a = 0; a < 3; ++a) areas[a] = area / 3.0;
    return;
  }
  // HRZ: m_a = \int N_a^2 dA, scaled to the face area; collapsed Gauss rule, 4 x 4 points.
  const Rule1D gauss = gauss_legendre(4);
  double total = 0.0, diagonal = 0.0;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double u = 0.5 * (gauss.points[i] + 1.0), v = 0.5 * (gauss.points[j] + 1.0);
      const double s = u, t = (1.0 - u) * v;
      const double weight = 0.25 * gauss.weights[i] * gauss.weights[j] * (1.0 - u);
      double values[6], gradients[12];
      triangle_shape(order, s, t, values, gradients);
      const double jacobian = triangle_normal(order, x, s, t).norm();
      total += weight * jacobian;
      for (int a = 0; a < 6; ++a) areas[a] += weight * jacobian * values[a] * values[a];
    }
  }
  for (int a = 0; a < 6; ++a) diagonal += areas[a];
  for (int a = 0; a < 6; ++a) areas[a] *= total / diagonal;
}

}  // namespace crackle::mesh
