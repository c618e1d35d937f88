#pragma once
/// \file Helpers of the Gmsh and composite tests: mesh files, node matching by coordinates, matrices
/// compared under a node permutation, and a small shift-invert subspace eigen-solver (Eigen's
/// CHOLMOD wrapper; independent of the modal module), compiled once in crackle_test_support.
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "fem/material.hpp"
#include "mesh/mesh.hpp"

namespace crackle::testing {

inline std::string mesh_file(const std::string& name) { return std::string(CRACKLE_SOURCE_DIR) + "/data/meshes/" + name; }

inline fem::Materials steel() { return {fem::isotropic(210e9, 0.3, 7850.0, "steel")}; }

/// For each node of `a`, the node of `b` at the same place (-1 if none); coordinates rounded to
/// 1e-9 m. Among coincident nodes (a crack's copies) the first is taken.
std::vector<Index> match_nodes(const mesh::Mesh& a, const mesh::Mesh& b);

/// max |A(i, j) - B(p(i), p(j))| / max |B| over DOFs, with p the DOF permutation of `dof_match`.
double permuted_difference(const SparseMatrix& a, const SparseMatrix& b, const std::vector<Index>& dof_match);

/// The DOF of `b` for each DOF of `a`, from a node match (every node must match).
std::vector<Index> dof_match(const mesh::DofMap& a_dofs, const mesh::DofMap& b_dofs, const std::vector<Index>& nodes);

/// The `count` lowest eigenvalues of K x = lambda M x (K, M symmetric, K - shift M positive
/// definite) by shift-invert subspace iteration with Rayleigh–Ritz, converged to ~1e-11 (enough for 1e-10 comparisons: Ritz values converge quadratically).
VectorX lowest_eigenvalues(const SparseMatrix& stiffness, const SparseMatrix& mass, int count, double shift = 0.0);

/// The `count` lowest frequencies [Hz] of a constrained body: K phi = omega^2 M phi over the free DOFs.
VectorX lowest_frequencies(const mesh::Mesh& mesh, mesh::Variant variant, const fem::Materials& materials,
                           const std::vector<fem::DirichletCondition>& conditions, int count);

fem::DirichletCondition clamp(const std::vector<Index>& nodes, std::vector<int> components = {0, 1, 2});

}  // namespace crackle::testing
