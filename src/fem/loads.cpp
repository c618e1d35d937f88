#include "fem/loads.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "fem/element_basis.hpp"

namespace crackle::fem {
namespace {

/// A zero vector over all DOFs if `force` is still empty; otherwise it must already fit.
void prepare(const mesh::DofMap& dofs, VectorX& force) {
  if (force.size() == 0) force = VectorX::Zero(dofs.n_dofs());
  assert(force.size() == dofs.n_dofs());
}

/// Gauss quadrature of one element face: shape values of the face nodes and the area element.
/// Face nodes are a (p+1) x (p+1) tensor grid (mesh::face_local_nodes); the face is parametrised by
/// (s, t) in [-1, 1]^2, dGamma = |dx/ds x dx/dt| ds dt.
class FaceRule {
 public:
  explicit FaceRule(int order)
      : m_(order + 1), gauss_(gauss_legendre(order + 1)), gll_(gauss_lobatto(order + 1)) {
    values_.resize(m_ * m_);
    derivatives_.resize(m_ * m_);
    for (int q = 0; q < m_; ++q) {
      lagrange_basis(gll_.points, gauss_.points[q], &values_[q * m_], &derivatives_[q * m_]);
    }
  }
  int n_points() const { return m_ * m_; }
  int n_nodes() const { return m_ * m_; }

  /// For face nodes `x` (n_nodes, ordered s fastest): shape values N_a (n_nodes) at point q and
  /// the weighted area element w_q |dx/ds x dx/dt|.
  double evaluate(const std::vector<Vec3>& x, int q, double* shape) const {
    const int qs = q % m_, qt = q / m_;
    Vec3 ds = Vec3::Zero(), dt = Vec3::Zero();
    for (int t = 0; t < m_; ++t) {
      for (int s = 0; s < m_; ++s) {
        const int a = s + m_ * t;
        shape[a] = values_[qs * m_ + s] * values_[qt * m_ + t];
        ds += derivatives_[qs * m_ + s] * values_[qt * m_ + t] * x[a];
        dt += values_[qs * m_ + s] * derivatives_[qt * m_ + t] * x[a];
      }
    }
    return gauss_.weights[qs] * gauss_.weights[qt] * ds.cross(dt).norm();
  }

 private:
  int m_;
  Rule1D gauss_, gll_;
  std::vector<double> values_, derivatives_;  ///< [q][a] of the 1D basis at the Gauss points
};

/// Gauss quadrature of one triangular face of a tetrahedron (3 or 6 nodes, mesh::face_local_nodes),
/// parametrised by (s, t) on the reference triangle: same interface as FaceRule.
class TriangleFaceRule {
 public:
  explicit TriangleFaceRule(int order) : order_(order), n_nodes_(order == 2 ? 6 : 3), rule_(triangle_rule(order + 2)) {}
  int n_points() const { return rule_.size(); }
  int n_nodes() const { return n_nodes_; }
  double evaluate(const std::vector<Vec3>& x, int q, double* shape) const {
    double gradients[12];
    triangle_shape(order_, rule_.s[q], rule_.t[q], shape, gradients);
    Vec3 ds = Vec3::Zero(), dt = Vec3::Zero();
    for (int a = 0; a < n_nodes_; ++a) {
      ds += gradients[2 * a] * x[a];
      dt += gradients[2 * a + 1] * x[a];
    }
    return rule_.weights[q] * ds.cross(dt).norm();
  }

 private:
  int order_, n_nodes_;
  TriangleRule rule_;
};

void check_face(const mesh::Mesh& mesh, const mesh::FaceRef& face) {
  if (face.element < 0 || face.element >= mesh.n_elements() || face.local_face < 0 ||
      face.local_face >= mesh.faces_per_element()) {
    throw InputError("face (element " + std::to_string(face.element) + ", local face " +
                     std::to_string(face.local_face) + ") does not exist in a mesh of " +
                     std::to_string(mesh.n_elements()) + " elements");
  }
}

}  // namespace

void add_point_force(const mesh::DofMap& dofs, const std::vector<Index>& nodes, const Vec3& total,
                     VectorX& force) {
  prepare(dofs, force);
  std::vector<Index> dof_nodes;
  dof_nodes.reserve(nodes.size());
  for (Index node : nodes) {
    if (node < 0 || node >= static_cast<Index>(dofs.dof_node.size())) {
      throw InputError("point force on node " + std::to_string(node) + " of a mesh of " +
                       std::to_string(dofs.dof_node.size()) + " nodes");
    }
    dof_nodes.push_back(dofs.dof_node[node]);
  }
  std::sort(dof_nodes.begin(), dof_nodes.end());
  dof_nodes.erase(std::unique(dof_nodes.begin(), dof_nodes.end()), dof_nodes.end());
  if (dof_nodes.empty()) throw InputError("point force on an empty node set");
  const Vec3 share = total / static_cast<double>(dof_nodes.size());
  for (Index r : dof_nodes) {
    for (int c = 0; c < 3; ++c) force[3 * r + c] += share[c];
  }
}

namespace {

template <class Rule>
void face_traction(const Rule& rule, const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                   const std::vector<mesh::FaceRef>& faces, const Vec3& traction, VectorX& force) {
  std::vector<Vec3> x(rule.n_nodes());
  std::vector<double> shape(rule.n_nodes()), integral(rule.n_nodes());
  std::vector<std::vector<int>> local(mesh.faces_per_element());
  for (int f = 0; f < mesh.faces_per_element(); ++f) {
    local[f] = mesh::face_local_nodes(mesh.shape, mesh.order, f);
    assert(static_cast<int>(local[f].size()) == rule.n_nodes());
  }
  for (const mesh::FaceRef& face : faces) {
    check_face(mesh, face);
    const Index* nodes = mesh.element_nodes(face.element);
    const std::vector<int>& face_nodes = local[face.local_face];
    for (int a = 0; a < rule.n_nodes(); ++a) x[a] = mesh.nodes[nodes[face_nodes[a]]];
    std::fill(integral.begin(), integral.end(), 0.0);
    for (int q = 0; q < rule.n_points(); ++q) {
      const double area = rule.evaluate(x, q, shape.data());
      for (int a = 0; a < rule.n_nodes(); ++a) integral[a] += area * shape[a];
    }
    for (int a = 0; a < rule.n_nodes(); ++a) {
      const Index node = nodes[face_nodes[a]];
      for (int c = 0; c < 3; ++c) force[dofs.dof(node, c)] += integral[a] * traction[c];
    }
  }
}

template <class Rule>
double faces_area(const Rule& rule, const mesh::Mesh& mesh, const std::vector<mesh::FaceRef>& faces) {
  std::vector<Vec3> x(rule.n_nodes());
  std::vector<double> shape(rule.n_nodes());
  std::vector<std::vector<int>> local(mesh.faces_per_element());
  for (int f = 0; f < mesh.faces_per_element(); ++f) local[f] = mesh::face_local_nodes(mesh.shape, mesh.order, f);
  double area = 0.0;
  for (const mesh::FaceRef& face : faces) {
    check_face(mesh, face);
    const Index* nodes = mesh.element_nodes(face.element);
    for (int a = 0; a < rule.n_nodes(); ++a) x[a] = mesh.nodes[nodes[local[face.local_face][a]]];
    for (int q = 0; q < rule.n_points(); ++q) area += rule.evaluate(x, q, shape.data());
  }
  return area;
}

}  // namespace

void add_face_traction(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                       const std::vector<mesh::FaceRef>& faces, const Vec3& traction, VectorX& force) {
  // Second term of eq. (25b) with a uniform traction: f_a = t \int_face N_a dGamma.
  prepare(dofs, force);
  if (mesh.shape == mesh::ElementShape::tetrahedron) {
    face_traction(TriangleFaceRule(mesh.order), mesh, dofs, faces, traction, force);
  } else {
    face_traction(FaceRule(mesh.order), mesh, dofs, faces, traction, force);
  }
}

double face_area(const mesh::Mesh& mesh, const std::vector<mesh::FaceRef>& faces) {
  if (mesh.shape == mesh::ElementShape::tetrahedron) return faces_area(TriangleFaceRule(mesh.order), mesh, faces);
  return faces_area(FaceRule(mesh.order), mesh, faces);
}

void add_body_force(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                    const Vec3& acceleration, VectorX& force) {
  // First term of eq. (25b): f_a = rho b \int N_a dOmega (consistent, Gauss rule).
  prepare(dofs, force);
  const ElementBasis basis(mesh);
  const int npe = basis.n_nodes();
  std::vector<double> coords(3 * npe), integrals(npe);
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const int region = e < static_cast<Index>(mesh.element_region.size()) ? mesh.element_region[e] : -1;
    if (region < 0 || region >= static_cast<int>(materials.size())) {
      throw InputError("element " + std::to_string(e) + " has region " + std::to_string(region) + " but " +
                       std::to_string(materials.size()) + " materials are given");
    }
    const Index* nodes = mesh.element_nodes(e);
    for (int a = 0; a < npe; ++a) {
      for (int c = 0; c < 3; ++c) coords[3 * a + c] = mesh.nodes[nodes[a]][c];
    }
    try {
      basis.shape_integrals(coords.data(), integrals.data());
    } catch (const InputError& exception) {
      throw InputError("element " + std::to_string(e) + ": " + exception.what());
    }
    const double density = materials[region].density;
    for (int a = 0; a < npe; ++a) {
      for (int c = 0; c < 3; ++c) force[dofs.dof(nodes[a], c)] += density * integrals[a] * acceleration[c];
    }
  }
}

}  // namespace crackle::fem
