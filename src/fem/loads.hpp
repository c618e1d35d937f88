#pragma once
/// \file External loads, MODEL.md eq. (25b), added into a global force vector of a DOF map.
#include <vector>

#include "core/types.hpp"
#include "fem/assembly.hpp"

namespace crackle::fem {

/// A force `total` [N] spread evenly over the DOF nodes of a node set.
void add_point_force(const mesh::DofMap& dofs, const std::vector<Index>& nodes, const Vec3& total,
                     VectorX& force);

/// A uniform traction [Pa] on a set of element faces: f_a = \int N_a t dGamma.
void add_face_traction(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                       const std::vector<mesh::FaceRef>& faces, const Vec3& traction, VectorX& force);

/// Total area [m^2] of a set of element faces.
double face_area(const mesh::Mesh& mesh, const std::vector<mesh::FaceRef>& faces);

/// A body force per unit mass b [m/s^2]: f_a = \int N_a rho b dOmega.
void add_body_force(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                    const Vec3& acceleration, VectorX& force);

}  // namespace crackle::fem
