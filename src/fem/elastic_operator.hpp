#pragma once
/// \file Matrix-free internal forces f_int = K u, MODEL.md eq. (25a), element by element without
/// assembling K (an operator is an action, STYLE.md: interchangeable with an assembled matrix).
///
/// Three kernels, chosen at construction:
/// - **brick**: for meshes of axis-aligned bricks (mesh.axis_aligned_bricks), the element matrix
///   depends only on (hx, hy, hz, region); it is computed once per distinct brick (sizes equal to
///   1e-10 relative) with fem::element_stiffness. If the material is invariant under the three
///   reflections of the brick (isotropic, or orthotropic along the axes), the element matrix is
///   stored block-diagonalised by those symmetries: sums and differences of mirror nodes (a
///   butterfly per direction) split it into 8 dense blocks with 1/8 of the entries in total.
///   Otherwise the whole K_e is kept. Elements are processed in SIMD batches of 8 of the same
///   brick: gather, butterfly, small dense products, butterfly, scatter. At order 1, a batch of 8
///   elements consecutive along x whose nodes are consecutive too (the box generator's numbering)
///   is gathered and scattered with vector loads and shuffles. At orders 1 and 2, a blocked matrix
///   runs in a kernel compiled for that order's layout (rows at compile-time indices: in registers
///   at order 1), with the same operations in the same order as the general brick kernel. The hot
///   loop is built for AVX-512, AVX2+FMA and the baseline, picked at run time.
/// - **general**: any hexahedra: sum factorisation on the (p+1)^3 Gauss points (the quadrature of
///   fem::element_stiffness), with the inverse Jacobian and w det J of every Gauss point stored
///   (10 doubles per point); checks that every Jacobian is positive.
/// - **assembled**: tetrahedral meshes (4- and 10-node): K assembled once by fem::assemble_stiffness
///   and applied as a CSR matrix, rows split over the threads.
///
/// Threads (OpenMP, omp_get_max_threads() at the call): the elements are cut into chunks of
/// consecutive elements, and the chunks coloured so that no two chunks of a colour share a DOF
/// node; one colour at a time, threads take whole chunks, split statically: a thread gets the same
/// chunks at every application, so it keeps working on the same part of the vectors (the
/// integrator's static split of the update works on much the same DOFs). With one thread the chunks run in
/// element order; below 20000 DOFs an application always runs on one thread. Results are
/// independent of the thread count up to summation order. Chunks can be made to begin at given
/// elements (ElasticOperatorOptions::element_cuts), and a range of whole chunks applied alone
/// (apply_add_elements): a distributed run applies its boundary elements, starts the halo, then
/// applies its interior ones.
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "fem/assembly.hpp"
#include "linalg/linear_operator.hpp"
#include "mesh/mesh.hpp"

namespace crackle::fem {

struct ElasticOperatorOptions {
  /// Use the brick kernel when the mesh allows it (false forces the general kernel, for tests).
  bool brick_kernel = true;
  /// At orders 1 and 2, run blocked bricks with the kernel compiled for that order's layout (false
  /// forces the kernel that reads the layout at run time, for tests and benchmarks).
  bool fixed_order_kernel = true;
  /// Elements per chunk (the unit of work of a thread); 0 = automatic.
  Index chunk_elements = 0;
  /// Elements at which a chunk must begin (ascending), so that the element ranges between them can
  /// be applied alone (apply_add_elements): a distributed run's boundary and interior elements.
  std::vector<Index> element_cuts;
};

/// What the operator chose, for logs and benchmarks.
struct ElasticOperatorInfo {
  std::string kernel;        ///< "brick-blocked", "brick-dense", "general" or "assembled"
  std::string instruction_set = "baseline";  ///< build of the brick kernel in use: "avx512", "avx2", "baseline"
  Index n_elements = 0;
  Index n_dofs = 0;
  int n_element_matrices = 0;  ///< distinct bricks (brick kernel)
  Index n_chunks = 0;
  int n_colours = 0;           ///< colour classes of chunks
  Index n_batches = 0;          ///< SIMD batches of the brick kernel
  Index n_lattice_batches = 0;  ///< of which gathered and scattered with vector moves (order 1)
  Index n_fixed_order_batches = 0;  ///< of which run by the kernel compiled for the order's layout (orders 1, 2)
  /// Multiply-adds per element application in the brick kernel (block entries, or (3n)^2 dense).
  long long element_multiply_adds = 0;
};

/// y = K x over the DOFs of a DOF map (constraints not applied: every DOF, fixed ones included).
class ElasticOperator final : public linalg::LinearOperator {
 public:
  ElasticOperator(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                  const ElasticOperatorOptions& options = {});
  ~ElasticOperator();
  ElasticOperator(ElasticOperator&&) noexcept;
  ElasticOperator& operator=(ElasticOperator&&) noexcept;

  Index n_dofs() const;
  Index n_rows() const override { return n_dofs(); }
  const ElasticOperatorInfo& info() const;

  /// y += scale K x (x and y of size n_dofs(); y is not cleared).
  void apply_add(double scale, const VectorX& x, VectorX& y) const override;
  /// y = K x.
  void apply(const VectorX& x, VectorX& y) const override;

  /// True when the elements [begin, end) can be applied alone: a matrix-free kernel (the assembled
  /// one of tetrahedra has no elements left) and chunks that begin at `begin` and at `end` (or end
  /// there: end = n_elements); see ElasticOperatorOptions::element_cuts.
  bool can_apply_elements(Index begin, Index end) const;
  /// y += scale K_[begin, end) x: the share of the elements [begin, end) only (can_apply_elements;
  /// InputError otherwise). The chunks run in the order of apply_add (one thread: element order;
  /// threads: colour by colour), so the ranges of a split applied in turn give, on one thread,
  /// bitwise the result of apply_add.
  void apply_add_elements(double scale, const VectorX& x, VectorX& y, Index begin, Index end) const;

 private:
  /// y += scale K x over the chunks [first_chunk, end_chunk).
  void apply_chunks(double scale, const VectorX& x, VectorX& y, Index first_chunk, Index end_chunk) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace crackle::fem
