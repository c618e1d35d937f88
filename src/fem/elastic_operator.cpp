#include "fem/elastic_operator.hpp"

#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>

#include "core/errors.hpp"
#include "core/quadrature.hpp"
#include "fem/colouring.hpp"
#include "fem/element.hpp"

namespace crackle::fem {
namespace {

/// Elements per SIMD batch of the brick kernel (one AVX-512 register of doubles, two AVX2 ones).
constexpr int kLanes = 8;

/// Below this many DOFs an application runs on one thread.
constexpr Index kParallelMinimumDofs = 20000;

/// Block-diagonalised (or dense) element matrix of one brick, acting on an element buffer whose
/// rows are the 3n element DOFs in `position` order, each row holding kLanes elements.
struct BrickMatrix {
  std::vector<int> position;                     ///< buffer row of element DOF 3a + c
  std::vector<std::array<int, 2>> butterflies;   ///< (row, row): sum into the first, difference into the second
  std::vector<int> block_start;                  ///< first row of each block; back() = 3n
  std::vector<std::size_t> block_offset;         ///< into `entries`
  std::vector<double> entries;                   ///< blocks, row-major, concatenated
  /// The layout is FixedLayout<order>'s (orders 1 and 2): the batch runs the fixed-order kernel.
  bool fixed_layout = false;
  long long multiply_adds() const { return static_cast<long long>(entries.size()); }
};

/// The parity block of element DOF (node (i, j, k), component c) of a brick of the given order
/// under the butterfly transform: per direction d, the node's 1D index is odd (a mirror
/// difference, i > order - i) or even, and a reflection along d also flips component d, so the
/// DOF's character is parity XOR (c == d); the block is those three bits.
constexpr int parity_block(int order, int i, int j, int k, int c) {
  const int parity[3] = {i > order - i ? 1 : 0, j > order - j ? 1 : 0, k > order - k ? 1 : 0};
  int block = 0;
  for (int d = 0; d < 3; ++d) block |= (parity[d] ^ (c == d ? 1 : 0)) << d;
  return block;
}

/// The butterflies' node pairs (a, mirror of a) of a brick of the given order, one direction
/// after the other (they commute), nodes in k, j, i order: visit(a, mirror) for each.
template <class Visit>
constexpr void for_each_mirror_pair(int order, Visit&& visit) {
  const int m = order + 1;
  for (int d = 0; d < 3; ++d)
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
          int ijk[3] = {i, j, k};
          if (ijk[d] >= order - ijk[d]) continue;
          const int a = i + m * (j + m * k);
          ijk[d] = order - ijk[d];
          visit(a, ijk[0] + m * (ijk[1] + m * ijk[2]));
        }
}

/// Builds the brick matrix from K_e (3n x 3n, DOFs interleaved). With reflection symmetry the
/// butterfly H (per direction: mirror sums at i < p/2, differences at i > p/2, middle node kept)
/// block-diagonalises it: K = H Lambda^{-1} H^T K H Lambda^{-1} H^T with Lambda = H^T H, so the stored
/// blocks are B = Lambda^{-1} H^T K H Lambda^{-1} and y = H B H^T x.
BrickMatrix make_brick_matrix(int order, const MatrixX& stiffness, bool try_blocks) {
  const int m = order + 1;
  const int n = m * m * m;
  const int size = 3 * n;
  BrickMatrix result;
  auto dense = [&]() {
    result.position.resize(size);
    for (int r = 0; r < size; ++r) result.position[r] = r;
    result.butterflies.clear();
    result.block_start = {0, size};
    result.block_offset = {0};
    result.entries.assign(static_cast<std::size_t>(size) * size, 0.0);
    for (int r = 0; r < size; ++r)
      for (int c = 0; c < size; ++c) result.entries[static_cast<std::size_t>(r) * size + c] = stiffness(r, c);
    return result;
  };
  if (!try_blocks) return dense();

  // 1D butterfly.
  MatrixX h1 = MatrixX::Zero(m, m);
  for (int i = 0; i < m; ++i) {
    const int mirror = order - i;
    if (i < mirror) {
      h1(i, i) = 1.0;      // column i: e_i + e_mirror (sum, even)
      h1(mirror, i) = 1.0;
      h1(i, mirror) = 1.0;  // column mirror: e_i - e_mirror (difference, odd)
      h1(mirror, mirror) = -1.0;
    } else if (i == mirror) {
      h1(i, i) = 1.0;
    }
  }
  MatrixX h = MatrixX::Zero(size, size);
  std::vector<int> block_of(size);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        const int a = i + m * (j + m * k);
        for (int kk = 0; kk < m; ++kk)
          for (int jj = 0; jj < m; ++jj)
            for (int ii = 0; ii < m; ++ii) {
              const double value = h1(i, ii) * h1(j, jj) * h1(k, kk);
              if (value == 0.0) continue;
              const int b = ii + m * (jj + m * kk);
              for (int c = 0; c < 3; ++c) h(3 * a + c, 3 * b + c) = value;
            }
        for (int c = 0; c < 3; ++c) block_of[3 * a + c] = parity_block(order, i, j, k, c);
      }
  const VectorX lambda_inverse = (h.transpose() * h).diagonal().cwiseInverse();
  const MatrixX transformed =
      lambda_inverse.asDiagonal() * (h.transpose() * stiffness * h) * lambda_inverse.asDiagonal();
  const double largest = transformed.cwiseAbs().maxCoeff();
  double off_block = 0.0;
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c)
      if (block_of[r] != block_of[c]) off_block = std::max(off_block, std::abs(transformed(r, c)));
  if (off_block > 1e-11 * largest) return dense();

  // Rows grouped by block (stable within a block).
  std::vector<std::vector<int>> members(8);
  for (int r = 0; r < size; ++r) members[block_of[r]].push_back(r);
  result.position.assign(size, 0);
  int row = 0;
  result.block_start.clear();
  result.block_offset.clear();
  result.entries.clear();
  for (int b = 0; b < 8; ++b) {
    if (members[b].empty()) continue;
    result.block_start.push_back(row);
    result.block_offset.push_back(result.entries.size());
    for (int r : members[b]) result.position[r] = row++;
    for (int r : members[b])
      for (int c : members[b]) {
        // Entries at rounding level of the largest (e.g. rigid-body combinations) are exact zeros.
        const double value = transformed(r, c);
        result.entries.push_back(std::abs(value) <= 1e-14 * largest ? 0.0 : value);
      }
  }
  result.block_start.push_back(size);
  // Butterflies, per component.
  for_each_mirror_pair(order, [&](int a, int mirror) {
    for (int c = 0; c < 3; ++c)
      result.butterflies.push_back({result.position[3 * a + c], result.position[3 * mirror + c]});
  });
  return result;
}

/// The layout make_brick_matrix gives a blocked matrix of order P, as compile-time data: buffer
/// row of each element DOF, the 8 parity blocks (all non-empty, members in DOF order, entries
/// row-major and concatenated) and the butterflies (direction 0, 1, 2), from the same
/// parity_block and for_each_mirror_pair as make_brick_matrix. The fixed-order kernel
/// indexes its registers with it; a matrix is run by it only where its own layout is this one.
template <int P>
struct FixedLayout {
  static constexpr int m = P + 1;
  static constexpr int n = m * m * m;
  static constexpr int size = 3 * n;
  static constexpr int n_pairs = 3 * 3 * (m / 2) * m * m;
  int position[size] = {};
  int block_start[9] = {};
  int block_offset[8] = {};
  int pairs[n_pairs][2] = {};
};

template <int P>
constexpr FixedLayout<P> make_fixed_layout() {
  using L = FixedLayout<P>;
  FixedLayout<P> layout;
  int block_of[L::size] = {};
  for (int k = 0; k < L::m; ++k)
    for (int j = 0; j < L::m; ++j)
      for (int i = 0; i < L::m; ++i)
        for (int c = 0; c < 3; ++c) block_of[3 * (i + L::m * (j + L::m * k)) + c] = parity_block(P, i, j, k, c);
  int row = 0, offset = 0;
  for (int b = 0; b < 8; ++b) {
    layout.block_start[b] = row;
    layout.block_offset[b] = offset;
    int members = 0;
    for (int r = 0; r < L::size; ++r)
      if (block_of[r] == b) layout.position[r] = row++, ++members;
    offset += members * members;
  }
  layout.block_start[8] = row;
  int next = 0;
  for_each_mirror_pair(P, [&](int a, int mirror) {
    for (int c = 0; c < 3; ++c) {
      layout.pairs[next][0] = layout.position[3 * a + c];
      layout.pairs[next][1] = layout.position[3 * mirror + c];
      ++next;
    }
  });
  return layout;
}

template <int P>
constexpr FixedLayout<P> kFixedLayout = make_fixed_layout<P>();

/// Whether a brick matrix has FixedLayout<P>'s layout (blocked, the same rows, blocks and butterflies).
template <int P>
bool has_fixed_layout(const BrickMatrix& matrix) {
  const FixedLayout<P>& layout = kFixedLayout<P>;
  if (static_cast<int>(matrix.position.size()) != layout.size || matrix.block_start.size() != 9 ||
      matrix.butterflies.size() != static_cast<std::size_t>(layout.n_pairs)) {
    return false;
  }
  for (int r = 0; r < layout.size; ++r)
    if (matrix.position[r] != layout.position[r]) return false;
  for (int b = 0; b < 9; ++b)
    if (matrix.block_start[b] != layout.block_start[b]) return false;
  for (int b = 0; b < 8; ++b)
    if (matrix.block_offset[b] != static_cast<std::size_t>(layout.block_offset[b])) return false;
  for (int k = 0; k < layout.n_pairs; ++k)
    if (matrix.butterflies[k][0] != layout.pairs[k][0] || matrix.butterflies[k][1] != layout.pairs[k][1]) return false;
  return true;
}

/// Everything one run of batches of the brick kernel needs (plain data for the ISA-specific builds).
struct BrickChunkArguments {
  int n;
  const Index* dof_base;
  const BrickMatrix* matrices;
  const int* batch_matrix;
  const int* batch_count;
  const Index* batch_elements;  ///< kLanes elements per batch (padding lanes repeat the first)
  const char* batch_lattice;    ///< per batch: order-1 lattice batch (see gather_lattice_order1)
  Index batch_begin, batch_end;
  const double* x;
  double* y;
  double scale;
  double* in;
  double* out;
};

using BrickBatchesFunction = void (*)(const BrickChunkArguments&);

/// Brick sizes along one axis, equal within a relative 1e-10 (grid lines computed in floating
/// point give sizes that differ in the last bits): the index of a size among the distinct ones.
class DistinctSizes {
 public:
  int index(double size) {
    const double tolerance = 1e-10 * std::abs(size);
    auto it = ids_.lower_bound(size - tolerance);
    if (it != ids_.end() && std::abs(it->first - size) <= tolerance) return it->second;
    const int id = static_cast<int>(values_.size());
    ids_.emplace(size, id);
    values_.push_back(size);
    return id;
  }
  double value(int id) const { return values_[id]; }

 private:
  std::map<double, int> ids_;
  std::vector<double> values_;
};

/// Corner-based size of a brick element.
std::array<double, 3> brick_size(const mesh::Mesh& mesh, Index e) {
  const int p = mesh.order;
  const int m = p + 1;
  const Index* nodes = mesh.element_nodes(e);
  const Vec3& origin = mesh.nodes[nodes[0]];
  return {mesh.nodes[nodes[p]].x() - origin.x(), mesh.nodes[nodes[p * m]].y() - origin.y(),
          mesh.nodes[nodes[p * m * m]].z() - origin.z()};
}

}  // namespace

struct ElasticOperator::Impl {
  int order = 1;
  int m = 2;
  int n = 8;  ///< nodes per element
  Index n_elements = 0;
  Index n_dofs = 0;
  std::vector<Index> dof_base;  ///< n_elements x n: first DOF (3 x DOF node) of each element node
  ElasticOperatorInfo info;

  // Chunks of consecutive elements and their colours.
  std::vector<Index> chunk_begin;               ///< n_chunks + 1
  std::vector<std::vector<Index>> colour_chunks;

  // Brick kernel.
  bool brick = false;
  BrickBatchesFunction batches_function = nullptr;
  std::vector<BrickMatrix> matrices;
  std::vector<Index> chunk_batch_begin;  ///< n_chunks + 1, into the batch arrays
  std::vector<int> batch_matrix;
  std::vector<int> batch_count;
  std::vector<Index> batch_elements;     ///< kLanes per batch (padding lanes repeat the first)
  std::vector<char> batch_lattice;       ///< per batch: full, order 1, nodes consecutive along x

  // Assembled K (tetrahedral meshes): CSR over all DOFs, applied row by row.
  SparseMatrix matrix;

  // General kernel.
  std::vector<fem::VoigtMatrix> stiffness;  ///< per region
  std::vector<int> region;
  std::vector<double> geometry;             ///< n_elements x n Gauss points x (J^{-1} row-major, w det J)
  std::vector<double> interpolation;        ///< [q][i] GLL basis at Gauss points
  std::vector<double> derivative;           ///< [q][i]
  std::vector<double> interpolation_transpose, derivative_transpose;  ///< [i][q]
  std::vector<double> weights;              ///< (p+1)^3 tensor Gauss weights

  void brick_chunk(Index chunk, const double* x, double* y, double scale, double* in, double* out) const;
  void general_chunk(Index chunk, const double* x, double* y, double scale, double* scratch) const;
  std::size_t scratch_size() const {
    return brick ? static_cast<std::size_t>(2 * 3 * n * kLanes) : 0;
  }
};

// ---------------------------------------------------------------------------------------------
// Brick kernel: the hot loop. Compiled for several instruction sets, picked at run time.

namespace {

/// Inlined into each instruction-set clone of brick_batches (a plain call would run the default build).
#define CRACKLE_HOT inline __attribute__((always_inline))

/// Butterflies of the brick transform on a buffer of kLanes-wide rows.
CRACKLE_HOT void butterfly(const std::vector<std::array<int, 2>>& pairs, double* buffer) {
  for (const std::array<int, 2>& pair : pairs) {
    double* first = buffer + static_cast<std::size_t>(pair[0]) * kLanes;
    double* second = buffer + static_cast<std::size_t>(pair[1]) * kLanes;
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const double sum = first[l] + second[l];
      const double difference = first[l] - second[l];
      first[l] = sum;
      second[l] = difference;
    }
  }
}

/// Rows r .. r+R-1 of out = B in (B s x s row-major; rows of in and out kLanes wide).
template <int R>
CRACKLE_HOT void block_rows(int s, int r, const double* matrix, const double* in, double* out) {
  double sum[R][kLanes] = {};
  const double* rows = matrix + static_cast<std::size_t>(r) * s;
  for (int j = 0; j < s; ++j) {
    const double* v = in + static_cast<std::size_t>(j) * kLanes;
    for (int q = 0; q < R; ++q) {
      const double c = rows[static_cast<std::size_t>(q) * s + j];
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) sum[q][l] += c * v[l];
    }
  }
  for (int q = 0; q < R; ++q) {
    double* o = out + static_cast<std::size_t>(r + q) * kLanes;
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) o[l] = sum[q][l];
  }
}

/// out = B in for one dense s x s block, four rows at a time.
CRACKLE_HOT void block_product(int s, const double* matrix, const double* in, double* out) {
  int r = 0;
  for (; r + 4 <= s; r += 4) block_rows<4>(s, r, matrix, in, out);
  switch (s - r) {
    case 3: block_rows<3>(s, r, matrix, in, out); break;
    case 2: block_rows<2>(s, r, matrix, in, out); break;
    case 1: block_rows<1>(s, r, matrix, in, out); break;
    default: break;
  }
}


/// Eight doubles, one per batch lane (GCC/Clang vector extension; lowered to the target's
/// registers: one AVX-512, two AVX2 or four SSE).
typedef double Lanes __attribute__((vector_size(8 * sizeof(double))));
typedef long long LaneIndices __attribute__((vector_size(8 * sizeof(long long))));
static_assert(kLanes == 8, "the lattice gather/scatter works on 8 lanes");

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"  // always inlined: no calls with vector arguments
CRACKLE_HOT Lanes load_lanes(const double* source) {
  Lanes value;
  std::memcpy(&value, source, sizeof value);
  return value;
}
CRACKLE_HOT void store_lanes(double* target, Lanes value) { std::memcpy(target, &value, sizeof value); }

/// 8 consecutive nodes, x y z interleaved (24 doubles), into one vector per component.
CRACKLE_HOT void deinterleave(const double* source, Lanes& x, Lanes& y, Lanes& z) {
  const Lanes a = load_lanes(source), b = load_lanes(source + 8), c = load_lanes(source + 16);
  x = __builtin_shuffle(__builtin_shuffle(a, b, LaneIndices{0, 3, 6, 9, 12, 15, 0, 0}), c, LaneIndices{0, 1, 2, 3, 4, 5, 10, 13});
  y = __builtin_shuffle(__builtin_shuffle(a, b, LaneIndices{1, 4, 7, 10, 13, 0, 0, 0}), c, LaneIndices{0, 1, 2, 3, 4, 8, 11, 14});
  z = __builtin_shuffle(__builtin_shuffle(a, b, LaneIndices{2, 5, 8, 11, 14, 0, 0, 0}), c, LaneIndices{0, 1, 2, 3, 4, 9, 12, 15});
}

/// The inverse of deinterleave, added into `target` (24 doubles).
CRACKLE_HOT void add_interleaved(Lanes x, Lanes y, Lanes z, double* target) {
  const Lanes a = __builtin_shuffle(__builtin_shuffle(x, y, LaneIndices{0, 8, 0, 1, 9, 0, 2, 10}), z, LaneIndices{0, 1, 8, 3, 4, 9, 6, 7});
  const Lanes b = __builtin_shuffle(__builtin_shuffle(x, y, LaneIndices{0, 3, 11, 0, 4, 12, 0, 5}), z, LaneIndices{10, 1, 2, 11, 4, 5, 12, 7});
  const Lanes c = __builtin_shuffle(__builtin_shuffle(x, y, LaneIndices{13, 0, 6, 14, 0, 7, 15, 0}), z, LaneIndices{0, 13, 2, 3, 14, 5, 6, 15});
  store_lanes(target, load_lanes(target) + a);
  store_lanes(target + 8, load_lanes(target + 8) + b);
  store_lanes(target + 16, load_lanes(target + 16) + c);
}

/// Gather of a "lattice" batch of order 1: the 8 elements are consecutive along x and so are
/// their nodes, so each of the 4 node lines (j, k) of the batch is 9 consecutive nodes in x:
/// vector loads and shuffles instead of 192 scalar moves. set_row(3 a + c, lanes) stores element
/// DOF (a, c) of the 8 elements (vectors by reference: no vector arguments across calls).
template <class SetRow>
CRACKLE_HOT void gather_lattice_order1(const double* x, const Index* first_dofs, SetRow&& set_row) {
  for (int line = 0; line < 4; ++line) {
    const int a0 = 2 * line;  // local node (0, j, k); (1, j, k) is a0 + 1
    const double* source = x + first_dofs[a0];
    Lanes c0[3];
    deinterleave(source, c0[0], c0[1], c0[2]);
    for (int c = 0; c < 3; ++c) {
      // Nodes 1..8 of the line: shift by one lane, node 8 comes in at the end.
      const Lanes last = {source[24 + c], 0, 0, 0, 0, 0, 0, 0};
      const Lanes shifted = __builtin_shuffle(c0[c], last, LaneIndices{1, 2, 3, 4, 5, 6, 7, 8});
      set_row(3 * a0 + c, c0[c]);
      set_row(3 * (a0 + 1) + c, shifted);
    }
  }
}

/// Scatter-add of a lattice batch of order 1 (see gather_lattice_order1); row(3 a + c, lanes)
/// reads element DOF (a, c) of the 8 elements.
template <class Row>
CRACKLE_HOT void scatter_lattice_order1(Row&& row, double scale, const Index* first_dofs, double* y) {
  for (int line = 0; line < 4; ++line) {
    const int a0 = 2 * line;
    double* target = y + first_dofs[a0];
    Lanes sum[3];
    double last[3];
    for (int c = 0; c < 3; ++c) {
      Lanes r0, r1;
      row(3 * a0 + c, r0);
      row(3 * (a0 + 1) + c, r1);
      const Lanes zero = {0, 0, 0, 0, 0, 0, 0, 0};
      // Node m of the line gets r0[m] (its element's node i = 0) and r1[m - 1] (node i = 1 of the previous).
      sum[c] = scale * (r0 + __builtin_shuffle(r1, zero, LaneIndices{8, 0, 1, 2, 3, 4, 5, 6}));
      last[c] = scale * r1[7];
    }
    add_interleaved(sum[0], sum[1], sum[2], target);
    target[24] += last[0];
    target[25] += last[1];
    target[26] += last[2];
  }
}

/// visit(a) for the n nodes of an element: fully unrolled where the count N is known at compile
/// time (N > 0), a plain loop over the run-time n otherwise.
template <int N, class Visit>
CRACKLE_HOT void for_each_node(int n, Visit&& visit) {
  if constexpr (N > 0) {
#pragma GCC unroll 128
    for (int a = 0; a < N; ++a) visit(a);
  } else {
    for (int a = 0; a < n; ++a) visit(a);
  }
}

/// Scalar gather of a batch: buffer row position(3 a + c), lane l holds x at DOF c of node a of
/// element l (padding lanes repeat the first element). Scalar loads: hardware gathers are slower.
template <int N, class Position>
CRACKLE_HOT void gather_scalar(const BrickChunkArguments& arguments, const Index* elements, int n, Position&& position,
                               double* buffer) {
  for (int l = 0; l < kLanes; ++l) {
    const Index* base = arguments.dof_base + static_cast<std::size_t>(elements[l]) * n;
    for_each_node<N>(n, [&](int a) __attribute__((always_inline)) {
      const double* source = arguments.x + base[a];
      buffer[static_cast<std::size_t>(position(3 * a)) * kLanes + l] = source[0];
      buffer[static_cast<std::size_t>(position(3 * a + 1)) * kLanes + l] = source[1];
      buffer[static_cast<std::size_t>(position(3 * a + 2)) * kLanes + l] = source[2];
    });
  }
}

/// Scalar scatter-add of a batch's `count` elements, one after the other (elements of a batch
/// may share nodes): y at DOF c of node a of element l += scale * buffer row position(3 a + c), lane l.
template <int N, class Position>
CRACKLE_HOT void scatter_scalar(const BrickChunkArguments& arguments, const Index* elements, int n, int count,
                                Position&& position, const double* buffer) {
  const double scale = arguments.scale;
  for (int l = 0; l < count; ++l) {
    const Index* base = arguments.dof_base + static_cast<std::size_t>(elements[l]) * n;
    for_each_node<N>(n, [&](int a) __attribute__((always_inline)) {
      double* target = arguments.y + base[a];
      target[0] += scale * buffer[static_cast<std::size_t>(position(3 * a)) * kLanes + l];
      target[1] += scale * buffer[static_cast<std::size_t>(position(3 * a + 1)) * kLanes + l];
      target[2] += scale * buffer[static_cast<std::size_t>(position(3 * a + 2)) * kLanes + l];
    });
  }
}

/// One batch of the fixed-order kernel: brick_batches_body's steps on FixedLayout<P>, with every
/// row index known at compile time (the rows live in registers at P = 1, at fixed stack offsets
/// at P = 2) and the same operations in the same order: the same results to the bit.
template <int P>
CRACKLE_HOT void fixed_batch(const BrickChunkArguments& arguments, Index b) {
  constexpr const FixedLayout<P>& L = kFixedLayout<P>;
  constexpr int n = FixedLayout<P>::n;
  constexpr int size = FixedLayout<P>::size;
  const BrickMatrix& matrix = arguments.matrices[arguments.batch_matrix[b]];
  const Index* elements = arguments.batch_elements + static_cast<std::size_t>(b) * kLanes;
  const Index* first_dofs = arguments.dof_base + static_cast<std::size_t>(elements[0]) * n;
  const bool lattice = P == 1 && arguments.batch_lattice[b] != 0;
  Lanes v[size];
  if (lattice) {
    gather_lattice_order1(arguments.x, first_dofs,
                          [&](int r, const Lanes& value) __attribute__((always_inline)) { v[L.position[r]] = value; });
  } else {
    double rows[size][kLanes];
    gather_scalar<n>(arguments, elements, n, [](int r) __attribute__((always_inline)) { return kFixedLayout<P>.position[r]; },
                     rows[0]);
#pragma GCC unroll 512
    for (int r = 0; r < size; ++r) v[r] = load_lanes(rows[r]);
  }
  // Displacements relative to local node 0 (see brick_batches_body).
#pragma GCC unroll 3
  for (int c = 0; c < 3; ++c) {
    const Lanes reference = v[L.position[c]];
#pragma GCC unroll 128
    for (int a = 0; a < n; ++a) v[L.position[3 * a + c]] -= reference;
  }
#pragma GCC unroll 128
  for (int k = 0; k < FixedLayout<P>::n_pairs; ++k) {
    const Lanes first = v[L.pairs[k][0]], second = v[L.pairs[k][1]];
    v[L.pairs[k][0]] = first + second;
    v[L.pairs[k][1]] = first - second;
  }
  Lanes w[size];
  const double* entries = matrix.entries.data();
#pragma GCC unroll 8
  for (int block = 0; block < 8; ++block) {
    const int start = L.block_start[block];
    const int s = L.block_start[block + 1] - start;
    const double* coefficients = entries + L.block_offset[block];
#pragma GCC unroll 128
    for (int r = 0; r < s; ++r) {
      Lanes sum = {0, 0, 0, 0, 0, 0, 0, 0};
#pragma GCC unroll 128
      for (int j = 0; j < s; ++j) sum += coefficients[r * s + j] * v[start + j];
      w[start + r] = sum;
    }
  }
#pragma GCC unroll 128
  for (int k = 0; k < FixedLayout<P>::n_pairs; ++k) {
    const Lanes first = w[L.pairs[k][0]], second = w[L.pairs[k][1]];
    w[L.pairs[k][0]] = first + second;
    w[L.pairs[k][1]] = first - second;
  }
  const double scale = arguments.scale;
  if (lattice) {
    scatter_lattice_order1([&](int r, Lanes& value) __attribute__((always_inline)) { value = w[L.position[r]]; }, scale, first_dofs,
                           arguments.y);
    return;
  }
  double rows[size][kLanes];
#pragma GCC unroll 512
  for (int r = 0; r < size; ++r) store_lanes(rows[r], w[r]);
  scatter_scalar<n>(arguments, elements, n, arguments.batch_count[b],
                    [](int r) __attribute__((always_inline)) { return kFixedLayout<P>.position[r]; }, rows[0]);
}

CRACKLE_HOT void brick_batches_body(const BrickChunkArguments& arguments) {
  const int n = arguments.n;
  double* in = arguments.in;
  double* out = arguments.out;
  for (Index b = arguments.batch_begin; b < arguments.batch_end; ++b) {
    const BrickMatrix& matrix = arguments.matrices[arguments.batch_matrix[b]];
    if (matrix.fixed_layout) {
      if (arguments.n == FixedLayout<1>::n) {
        fixed_batch<1>(arguments, b);
      } else {
        fixed_batch<2>(arguments, b);
      }
      continue;
    }
    const int count = arguments.batch_count[b];
    const Index* elements = arguments.batch_elements + static_cast<std::size_t>(b) * kLanes;
    const int* position = matrix.position.data();
    const bool lattice = arguments.batch_lattice[b] != 0;
    const Index* first_dofs = arguments.dof_base + static_cast<std::size_t>(elements[0]) * n;
    // Gather: scalar loads, or vector loads and shuffles for lattice batches.
    if (lattice) {
      gather_lattice_order1(arguments.x, first_dofs, [&](int r, const Lanes& value) __attribute__((always_inline)) {
        store_lanes(in + static_cast<std::size_t>(position[r]) * kLanes, value);
      });
    } else {
      gather_scalar<0>(arguments, elements, n, [position](int r) __attribute__((always_inline)) { return position[r]; }, in);
    }
    // K annihilates translations: take the displacements relative to local node 0, so that a
    // uniform motion gives exactly zero force and rounding scales with the local variation only.
    for (int c = 0; c < 3; ++c) {
      double reference[kLanes];
      const double* row0 = in + static_cast<std::size_t>(position[c]) * kLanes;
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) reference[l] = row0[l];
      for (int a = 0; a < n; ++a) {
        double* row = in + static_cast<std::size_t>(position[3 * a + c]) * kLanes;
#pragma omp simd
        for (int l = 0; l < kLanes; ++l) row[l] -= reference[l];
      }
    }
    butterfly(matrix.butterflies, in);
    const int n_blocks = static_cast<int>(matrix.block_offset.size());
    for (int k = 0; k < n_blocks; ++k) {
      const int start = matrix.block_start[k];
      const int size = matrix.block_start[k + 1] - start;
      block_product(size, matrix.entries.data() + matrix.block_offset[k], in + static_cast<std::size_t>(start) * kLanes,
                    out + static_cast<std::size_t>(start) * kLanes);
    }
    butterfly(matrix.butterflies, out);
    const double scale = arguments.scale;
    // Scatter-add (scalar, or shuffles and vector stores for lattice batches).
    if (lattice) {
      scatter_lattice_order1(
          [&](int r, Lanes& value) __attribute__((always_inline)) {
            value = load_lanes(out + static_cast<std::size_t>(position[r]) * kLanes);
          },
          scale, first_dofs, arguments.y);
      continue;
    }
    scatter_scalar<0>(arguments, elements, n, count, [position](int r) __attribute__((always_inline)) { return position[r]; },
                      out);
  }
}

#pragma GCC diagnostic pop

__attribute__((target("avx512f,avx512vl,avx512dq,avx2,fma,bmi,bmi2,popcnt")))
void brick_batches_avx512(const BrickChunkArguments& arguments) { brick_batches_body(arguments); }

__attribute__((target("avx2,fma,bmi,bmi2,popcnt")))
void brick_batches_avx2(const BrickChunkArguments& arguments) { brick_batches_body(arguments); }

void brick_batches_baseline(const BrickChunkArguments& arguments) { brick_batches_body(arguments); }

/// The widest build of the hot loop this processor runs (checked once).
BrickBatchesFunction select_brick_batches() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2")) {
    return brick_batches_avx512;
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2")) {
    return brick_batches_avx2;
  }
  return brick_batches_baseline;
}

const char* instruction_set_name(BrickBatchesFunction function) {
  return function == brick_batches_avx512 ? "avx512" : function == brick_batches_avx2 ? "avx2" : "baseline";
}

}  // namespace

void ElasticOperator::Impl::brick_chunk(Index chunk, const double* x, double* y, double scale, double* in,
                                        double* out) const {
  BrickChunkArguments arguments{n,
                                dof_base.data(),
                                matrices.data(),
                                batch_matrix.data(),
                                batch_count.data(),
                                batch_elements.data(),
                                batch_lattice.data(),
                                chunk_batch_begin[chunk],
                                chunk_batch_begin[chunk + 1],
                                x,
                                y,
                                scale,
                                in,
                                out};
  batches_function(arguments);
}

// ---------------------------------------------------------------------------------------------
// General kernel: sum factorisation on the Gauss points, with the inverse Jacobian and the
// weighted determinant of every Gauss point stored (10 doubles per point).

namespace {

/// out = A applied along direction D (0: i, 1: j, 2: k) of an M^3 array [k][j][i]:
/// out[.. q ..] = sum_t A[q][t] in[.. t ..] (A is M x M, row-major).
template <int M, int D>
inline void contract(const double* matrix, const double* in, double* out) {
  if constexpr (D == 0) {
    for (int kj = 0; kj < M * M; ++kj) {
      for (int q = 0; q < M; ++q) {
        double sum = 0.0;
        for (int t = 0; t < M; ++t) sum += matrix[q * M + t] * in[kj * M + t];
        out[kj * M + q] = sum;
      }
    }
  } else if constexpr (D == 1) {
    for (int k = 0; k < M; ++k) {
      for (int q = 0; q < M; ++q) {
        double row[M] = {};
        for (int t = 0; t < M; ++t) {
          const double weight = matrix[q * M + t];
          for (int i = 0; i < M; ++i) row[i] += weight * in[(k * M + t) * M + i];
        }
        for (int i = 0; i < M; ++i) out[(k * M + q) * M + i] = row[i];
      }
    }
  } else {
    for (int q = 0; q < M; ++q) {
      double plane[M * M] = {};
      for (int t = 0; t < M; ++t) {
        const double weight = matrix[q * M + t];
        for (int i = 0; i < M * M; ++i) plane[i] += weight * in[t * M * M + i];
      }
      for (int i = 0; i < M * M; ++i) out[q * M * M + i] = plane[i];
    }
  }
}

/// Reference gradient (d/dxi, d/deta, d/dzeta at the Gauss points) of a nodal field.
template <int M>
inline void reference_gradient(const double* interpolation, const double* derivative, const double* values, double* gradient,
                               double* t0, double* t1, double* t2) {
  constexpr int n = M * M * M;
  contract<M, 2>(interpolation, values, t0);  // B_z
  contract<M, 1>(interpolation, t0, t1);      // B_y B_z
  contract<M, 0>(derivative, t1, gradient);   // G_x B_y B_z
  contract<M, 1>(derivative, t0, t2);         // G_y B_z
  contract<M, 0>(interpolation, t2, gradient + n);
  contract<M, 2>(derivative, values, t0);     // G_z
  contract<M, 1>(interpolation, t0, t1);
  contract<M, 0>(interpolation, t1, gradient + 2 * n);
}

/// y += scale K_e x_e for one element, eq. (25a) by sum factorisation.
template <int M>
void general_element_apply(const double* interpolation, const double* derivative, const double* interpolation_transpose,
                           const double* derivative_transpose, const double* geometry, const fem::VoigtMatrix& d,
                           const Index* base, const double* x, double* y, double scale) {
  constexpr int n = M * M * M;
  double field[3][n], gradient[3][3 * n], flux[3][3 * n], t0[n], t1[n], t2[n], t3[n];
  // Displacements relative to local node 0: K annihilates translations (see the brick kernel).
  for (int a = 0; a < n; ++a)
    for (int c = 0; c < 3; ++c) field[c][a] = x[base[a] + c] - x[base[0] + c];
  for (int c = 0; c < 3; ++c) reference_gradient<M>(interpolation, derivative, field[c], gradient[c], t0, t1, t2);
  for (int q = 0; q < n; ++q) {
    const double* g = geometry + 10 * q;  // inverse Jacobian (d, j) row-major, then w det J
    double grad[3][3];                    // du_i / dx_j
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        grad[i][j] = gradient[i][q] * g[j] + gradient[i][n + q] * g[3 + j] + gradient[i][2 * n + q] * g[6 + j];
    fem::Voigt strain;
    strain << grad[0][0], grad[1][1], grad[2][2], grad[1][2] + grad[2][1], grad[0][2] + grad[2][0], grad[0][1] + grad[1][0];
    const fem::Voigt stress = d * strain;  // eq. (2)
    const double sigma[3][3] = {{stress[0], stress[5], stress[4]}, {stress[5], stress[1], stress[3]}, {stress[4], stress[3], stress[2]}};
    for (int i = 0; i < 3; ++i)
      for (int dd = 0; dd < 3; ++dd)
        flux[i][dd * n + q] = g[9] * (sigma[i][0] * g[3 * dd] + sigma[i][1] * g[3 * dd + 1] + sigma[i][2] * g[3 * dd + 2]);
  }
  for (int i = 0; i < 3; ++i) {
    // y_i = B_z^T [B_y^T G_x^T F_xi + G_y^T B_x^T F_eta] + G_z^T B_y^T B_x^T F_zeta
    contract<M, 0>(derivative_transpose, flux[i], t0);
    contract<M, 1>(interpolation_transpose, t0, t1);
    contract<M, 0>(interpolation_transpose, flux[i] + n, t0);
    contract<M, 1>(derivative_transpose, t0, t2);
    for (int a = 0; a < n; ++a) t1[a] += t2[a];
    contract<M, 2>(interpolation_transpose, t1, t3);
    contract<M, 0>(interpolation_transpose, flux[i] + 2 * n, t0);
    contract<M, 1>(interpolation_transpose, t0, t1);
    contract<M, 2>(derivative_transpose, t1, t2);
    for (int a = 0; a < n; ++a) y[base[a] + i] += scale * (t3[a] + t2[a]);
  }
}

/// Inverse Jacobian and w det J at the Gauss points of one element; the smallest det J.
template <int M>
double general_element_geometry(const double* interpolation, const double* derivative, const double* weights,
                                const double* coords, double* geometry) {
  constexpr int n = M * M * M;
  double field[n], gradient[3][3 * n], t0[n], t1[n], t2[n];
  for (int c = 0; c < 3; ++c) {
    for (int a = 0; a < n; ++a) field[a] = coords[3 * a + c];
    reference_gradient<M>(interpolation, derivative, field, gradient[c], t0, t1, t2);
  }
  double smallest = std::numeric_limits<double>::infinity();
  for (int q = 0; q < n; ++q) {
    Eigen::Matrix3d jacobian;  // dx_i / dxi_d
    for (int i = 0; i < 3; ++i)
      for (int dd = 0; dd < 3; ++dd) jacobian(i, dd) = gradient[i][dd * n + q];
    const double determinant = jacobian.determinant();
    smallest = std::min(smallest, determinant);
    const Eigen::Matrix3d inverse = jacobian.inverse();
    for (int dd = 0; dd < 3; ++dd)
      for (int j = 0; j < 3; ++j) geometry[10 * q + 3 * dd + j] = inverse(dd, j);
    geometry[10 * q + 9] = weights[q] * determinant;
  }
  return smallest;
}

}  // namespace

void ElasticOperator::Impl::general_chunk(Index chunk, const double* x, double* y, double scale, double*) const {
  const double* b = interpolation.data();
  const double* g = derivative.data();
  const double* bt = interpolation_transpose.data();
  const double* gt = derivative_transpose.data();
  for (Index e = chunk_begin[chunk]; e < chunk_begin[chunk + 1]; ++e) {
    const Index* base = dof_base.data() + static_cast<std::size_t>(e) * n;
    const double* geo = geometry.data() + static_cast<std::size_t>(e) * n * 10;
    const fem::VoigtMatrix& d = stiffness[region[e]];
    switch (m) {
      case 2: general_element_apply<2>(b, g, bt, gt, geo, d, base, x, y, scale); break;
      case 3: general_element_apply<3>(b, g, bt, gt, geo, d, base, x, y, scale); break;
      case 4: general_element_apply<4>(b, g, bt, gt, geo, d, base, x, y, scale); break;
      default: general_element_apply<5>(b, g, bt, gt, geo, d, base, x, y, scale); break;
    }
  }
}

// ---------------------------------------------------------------------------------------------

ElasticOperator::ElasticOperator(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                                 const ElasticOperatorOptions& options)
    : impl_(std::make_unique<Impl>()) {
  if (mesh.shape != mesh::ElementShape::hexahedron) {
    // Tetrahedra: the kernels below are written for GLL hexahedra (sum factorisation, brick
    // cache), so K is assembled once and applied as a sparse matrix.
    Impl& impl = *impl_;
    impl.n_dofs = dofs.n_dofs();
    SparseMatrix assembled = fem::assemble_stiffness(mesh, dofs, materials);
    impl.matrix.swap(assembled);  // Eigen 3.4's SparseMatrix assignment would copy it
    impl.matrix.makeCompressed();  // apply_add reads rows as outer[row] .. outer[row + 1]
    impl.info.kernel = "assembled";
    impl.info.n_elements = mesh.n_elements();
    impl.info.n_dofs = impl.n_dofs;
    impl.info.element_multiply_adds = impl.matrix.nonZeros() / std::max<Index>(1, mesh.n_elements());
    return;
  }
  Impl& impl = *impl_;
  impl.order = mesh.order;
  impl.m = mesh.order + 1;
  impl.n = mesh.nodes_per_element();
  impl.n_elements = mesh.n_elements();
  impl.n_dofs = dofs.n_dofs();
  const int n = impl.n;
  if (static_cast<Index>(dofs.dof_node.size()) != mesh.n_nodes()) {
    throw InputError("DOF map has " + std::to_string(dofs.dof_node.size()) + " entries for a mesh of " +
                     std::to_string(mesh.n_nodes()) + " nodes");
  }
  if (static_cast<Index>(mesh.element_region.size()) != impl.n_elements) {
    throw InputError("mesh has " + std::to_string(mesh.element_region.size()) + " element regions for " +
                     std::to_string(impl.n_elements) + " elements");
  }
  impl.dof_base.resize(mesh.connectivity.size());
  for (std::size_t i = 0; i < mesh.connectivity.size(); ++i) {
    const Index node = mesh.connectivity[i];
    if (node < 0 || node >= mesh.n_nodes()) {
      throw InputError("element " + std::to_string(i / n) + " refers to node " + std::to_string(node) + " of a mesh of " +
                       std::to_string(mesh.n_nodes()) + " nodes");
    }
    impl.dof_base[i] = 3 * dofs.dof_node[node];
  }
  impl.region = mesh.element_region;
  for (Index e = 0; e < impl.n_elements; ++e) {
    if (impl.region[e] < 0 || impl.region[e] >= static_cast<int>(materials.size())) {
      throw InputError("element " + std::to_string(e) + " has region " + std::to_string(impl.region[e]) + " but " +
                       std::to_string(materials.size()) + " materials are given");
    }
  }

  // Chunks of consecutive elements; greedy colouring so that chunks of one colour share no DOF node.
  const int threads = std::max(1, omp_get_max_threads());
  Index chunk = options.chunk_elements;
  if (chunk <= 0) {
    chunk = threads == 1 ? 4096 : (impl.n_elements + 16 * threads - 1) / (16 * threads);
    chunk = std::clamp<Index>((chunk + kLanes - 1) / kLanes * kLanes, 64, 4096);
  }
  {
    // Chunks within each run of elements between cuts (no cut: one run, chunks from element 0).
    std::vector<Index> runs{0};
    for (Index cut : options.element_cuts) {
      if (cut < runs.back() || cut > impl.n_elements) {
        throw InputError("elastic operator: element cut " + std::to_string(cut) + " out of order or outside 0.." +
                         std::to_string(impl.n_elements));
      }
      if (cut > runs.back() && cut < impl.n_elements) runs.push_back(cut);
    }
    runs.push_back(impl.n_elements);
    for (std::size_t r = 0; r + 1 < runs.size(); ++r)
      for (Index begin = runs[r]; begin < runs[r + 1]; begin += chunk) impl.chunk_begin.push_back(begin);
    impl.chunk_begin.push_back(impl.n_elements);
  }
  const Index n_chunks = static_cast<Index>(impl.chunk_begin.size()) - 1;
  {
    // DOF node -> chunks touching it (chunks visited in order, so each list is sorted).
    const Index n_nodes = dofs.n_dof_nodes;
    std::vector<Index> count(n_nodes + 1, 0), last(n_nodes, -1);
    for (Index c = 0; c < n_chunks; ++c)
      for (std::size_t i = impl.chunk_begin[c] * static_cast<std::size_t>(n); i < impl.chunk_begin[c + 1] * static_cast<std::size_t>(n); ++i) {
        const Index node = impl.dof_base[i] / 3;
        if (last[node] != c) {
          last[node] = c;
          ++count[node + 1];
        }
      }
    for (Index r = 0; r < n_nodes; ++r) count[r + 1] += count[r];
    std::vector<Index> chunks_of(count[n_nodes]);
    std::vector<Index> next(count.begin(), count.end() - 1);
    std::fill(last.begin(), last.end(), -1);
    for (Index c = 0; c < n_chunks; ++c)
      for (std::size_t i = impl.chunk_begin[c] * static_cast<std::size_t>(n); i < impl.chunk_begin[c + 1] * static_cast<std::size_t>(n); ++i) {
        const Index node = impl.dof_base[i] / 3;
        if (last[node] != c) {
          last[node] = c;
          chunks_of[next[node]++] = c;
        }
      }
    impl.colour_chunks = greedy_colouring(
        n_chunks, n_nodes,
        [&](Index c, auto&& visit) {
          for (std::size_t i = impl.chunk_begin[c] * static_cast<std::size_t>(n);
               i < impl.chunk_begin[c + 1] * static_cast<std::size_t>(n); ++i) {
            visit(impl.dof_base[i] / 3);
          }
        },
        [&](Index node, auto&& visit) {
          for (Index k = count[node]; k < count[node + 1]; ++k) visit(chunks_of[k]);
        });
  }

  // Brick kernel: one matrix per distinct brick.
  impl.brick = options.brick_kernel && mesh.axis_aligned_bricks && impl.n_elements > 0;
  if (impl.brick) {
    // One matrix per distinct (hx, hy, hz, region), sizes equal within 1e-10 taken as equal.
    std::map<std::array<int, 4>, int> ids;
    std::array<DistinctSizes, 3> distinct;
    std::vector<std::array<double, 4>> shapes;
    std::vector<int> element_matrix(impl.n_elements);
    for (Index e = 0; e < impl.n_elements && impl.brick; ++e) {
      const std::array<double, 3> size = brick_size(mesh, e);
      if (!(size[0] > 0.0 && size[1] > 0.0 && size[2] > 0.0)) {
        impl.brick = false;  // not a brick in the generator's orientation: use the general kernel
        break;
      }
      std::array<int, 4> key;
      for (int c = 0; c < 3; ++c) key[c] = distinct[c].index(size[c]);
      key[3] = mesh.element_region[e];
      const auto inserted = ids.emplace(key, static_cast<int>(ids.size()));
      if (inserted.second) {
        shapes.push_back({distinct[0].value(key[0]), distinct[1].value(key[1]), distinct[2].value(key[2]),
                          double(mesh.element_region[e])});
      }
      element_matrix[e] = inserted.first->second;
    }
    const double bytes = static_cast<double>(shapes.size()) * 9.0 * n * n * sizeof(double);
    if (impl.brick && bytes > 1e9) impl.brick = false;
    if (impl.brick) {
      const fem::HexBasis basis(mesh.order);
      std::vector<double> coords(3 * n);
      MatrixX stiffness;
      impl.matrices.reserve(shapes.size());
      for (const auto& shape : shapes) {
        fem::brick_coordinates(basis, shape[0], shape[1], shape[2], coords.data());
        fem::element_stiffness(basis, coords.data(), materials[static_cast<int>(shape[3])], stiffness);
        impl.matrices.push_back(make_brick_matrix(mesh.order, stiffness, true));
        BrickMatrix& matrix = impl.matrices.back();
        matrix.fixed_layout = options.fixed_order_kernel &&
                              ((mesh.order == 1 && has_fixed_layout<1>(matrix)) || (mesh.order == 2 && has_fixed_layout<2>(matrix)));
      }
      // Batches: within a chunk, elements of one brick in order, kLanes at a time.
      impl.chunk_batch_begin.push_back(0);
      std::vector<std::vector<Index>> by_matrix(impl.matrices.size());
      for (Index c = 0; c < n_chunks; ++c) {
        for (auto& list : by_matrix) list.clear();
        for (Index e = impl.chunk_begin[c]; e < impl.chunk_begin[c + 1]; ++e) by_matrix[element_matrix[e]].push_back(e);
        for (std::size_t k = 0; k < by_matrix.size(); ++k) {
          const std::vector<Index>& list = by_matrix[k];
          for (std::size_t start = 0; start < list.size(); start += kLanes) {
            const int count = static_cast<int>(std::min<std::size_t>(kLanes, list.size() - start));
            impl.batch_matrix.push_back(static_cast<int>(k));
            impl.batch_count.push_back(count);
            for (int l = 0; l < kLanes; ++l) impl.batch_elements.push_back(l < count ? list[start + l] : list[start]);
            // Lattice batch (order 1): node (i, j, k) of lane l is node (0, j, k) of lane 0 plus
            // i + l nodes, and the batch is the same brick for all lanes (checked above).
            bool lattice = mesh.order == 1 && count == kLanes && impl.matrices[k].butterflies.size() > 0;
            const Index* first = impl.dof_base.data() + static_cast<std::size_t>(list[start]) * n;
            for (int l = 0; l < kLanes && lattice; ++l) {
              const Index* dofs_l = impl.dof_base.data() + static_cast<std::size_t>(list[start + l]) * n;
              for (int a = 0; a < n && lattice; ++a) lattice = dofs_l[a] == first[a & ~1] + 3 * (l + (a & 1));
            }
            impl.batch_lattice.push_back(lattice ? 1 : 0);
          }
        }
        impl.chunk_batch_begin.push_back(static_cast<Index>(impl.batch_count.size()));
      }
      bool blocked = true;
      for (const BrickMatrix& matrix : impl.matrices) blocked = blocked && !matrix.butterflies.empty();
      impl.info.kernel = blocked ? "brick-blocked" : "brick-dense";
      impl.batches_function = select_brick_batches();
      impl.info.instruction_set = instruction_set_name(impl.batches_function);
      impl.info.n_element_matrices = static_cast<int>(impl.matrices.size());
      impl.info.n_batches = static_cast<Index>(impl.batch_count.size());
      for (char lattice : impl.batch_lattice) impl.info.n_lattice_batches += lattice;
      for (int matrix : impl.batch_matrix) impl.info.n_fixed_order_batches += impl.matrices[matrix].fixed_layout ? 1 : 0;
      impl.info.element_multiply_adds = impl.matrices.front().multiply_adds();
    }
  }
  if (!impl.brick) {
    impl.info.kernel = "general";
    impl.stiffness.clear();
    for (const fem::Material& material : materials) impl.stiffness.push_back(material.stiffness);
    const int m = impl.m;
    const Rule1D gll = gauss_lobatto(m);
    const Rule1D gauss = gauss_legendre(m);
    impl.interpolation.resize(m * m);
    impl.derivative.resize(m * m);
    impl.interpolation_transpose.resize(m * m);
    impl.derivative_transpose.resize(m * m);
    for (int q = 0; q < m; ++q) lagrange_basis(gll.points, gauss.points[q], &impl.interpolation[q * m], &impl.derivative[q * m]);
    for (int q = 0; q < m; ++q)
      for (int i = 0; i < m; ++i) {
        impl.interpolation_transpose[i * m + q] = impl.interpolation[q * m + i];
        impl.derivative_transpose[i * m + q] = impl.derivative[q * m + i];
      }
    impl.weights.resize(n);
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) impl.weights[i + m * (j + m * k)] = gauss.weights[i] * gauss.weights[j] * gauss.weights[k];
    // Geometry of every Gauss point, and the check that every Jacobian is positive.
    impl.geometry.resize(static_cast<std::size_t>(impl.n_elements) * n * 10);
    std::vector<double> coords(3 * n);
    for (Index e = 0; e < impl.n_elements; ++e) {
      const Index* nodes = mesh.element_nodes(e);
      for (int a = 0; a < n; ++a)
        for (int c = 0; c < 3; ++c) coords[3 * a + c] = mesh.nodes[nodes[a]][c];
      double* geometry = impl.geometry.data() + static_cast<std::size_t>(e) * n * 10;
      const double* b = impl.interpolation.data();
      const double* g = impl.derivative.data();
      const double* w = impl.weights.data();
      double determinant = 0.0;
      switch (m) {
        case 2: determinant = general_element_geometry<2>(b, g, w, coords.data(), geometry); break;
        case 3: determinant = general_element_geometry<3>(b, g, w, coords.data(), geometry); break;
        case 4: determinant = general_element_geometry<4>(b, g, w, coords.data(), geometry); break;
        default: determinant = general_element_geometry<5>(b, g, w, coords.data(), geometry); break;
      }
      if (!(determinant > 0.0)) {
        throw InputError("element " + std::to_string(e) + ": Jacobian determinant " + format_number(determinant) +
                         " <= 0 at a Gauss point (inverted or degenerate element)");
      }
    }
    impl.info.element_multiply_adds = 42LL * m * m * m * m + 81LL * n;  // contractions + pointwise, roughly
  }
  impl.info.n_elements = impl.n_elements;
  impl.info.n_dofs = impl.n_dofs;
  impl.info.n_chunks = n_chunks;
  impl.info.n_colours = static_cast<int>(impl.colour_chunks.size());
}

ElasticOperator::~ElasticOperator() = default;
ElasticOperator::ElasticOperator(ElasticOperator&&) noexcept = default;
ElasticOperator& ElasticOperator::operator=(ElasticOperator&&) noexcept = default;

Index ElasticOperator::n_dofs() const { return impl_->n_dofs; }
const ElasticOperatorInfo& ElasticOperator::info() const { return impl_->info; }

void ElasticOperator::apply(const VectorX& x, VectorX& y) const {
  y.setZero(impl_->n_dofs);
  apply_add(1.0, x, y);
}

bool ElasticOperator::can_apply_elements(Index begin, Index end) const {
  const Impl& impl = *impl_;
  if (impl.matrix.rows() > 0 || begin < 0 || begin > end || end > impl.n_elements) return false;
  const auto is_chunk_start = [&](Index element) {
    return std::binary_search(impl.chunk_begin.begin(), impl.chunk_begin.end(), element);
  };
  return is_chunk_start(begin) && is_chunk_start(end);
}

void ElasticOperator::apply_add_elements(double scale, const VectorX& x, VectorX& y, Index begin, Index end) const {
  if (!can_apply_elements(begin, end)) {
    throw InputError("elastic operator (" + impl_->info.kernel + "): elements " + std::to_string(begin) + ".." +
                     std::to_string(end) + " are not a range of whole chunks");
  }
  const auto chunk_of = [&](Index element) {
    return static_cast<Index>(std::lower_bound(impl_->chunk_begin.begin(), impl_->chunk_begin.end(), element) -
                              impl_->chunk_begin.begin());
  };
  apply_chunks(scale, x, y, chunk_of(begin), chunk_of(end));
}

void ElasticOperator::apply_add(double scale, const VectorX& x, VectorX& y) const {
  apply_chunks(scale, x, y, 0, static_cast<Index>(impl_->chunk_begin.size()) - 1);
}

void ElasticOperator::apply_chunks(double scale, const VectorX& x, VectorX& y, Index first_chunk, Index end_chunk) const {
  const Impl& impl = *impl_;
  if (x.size() != impl.n_dofs || y.size() != impl.n_dofs) {
    throw InputError("elastic operator of " + std::to_string(impl.n_dofs) + " DOFs applied to vectors of " +
                     std::to_string(x.size()) + " and " + std::to_string(y.size()));
  }
  const double* in = x.data();
  double* out = y.data();
  if (impl.matrix.rows() > 0) {
    const Index* outer = impl.matrix.outerIndexPtr();
    const Index* inner = impl.matrix.innerIndexPtr();
    const double* values = impl.matrix.valuePtr();
    const bool parallel = omp_get_max_threads() > 1 && impl.n_dofs >= kParallelMinimumDofs;
#pragma omp parallel for schedule(static) if (parallel)
    for (Index row = 0; row < impl.n_dofs; ++row) {
      double sum = 0.0;
      for (Index k = outer[row]; k < outer[row + 1]; ++k) sum += values[k] * in[inner[k]];
      out[row] += scale * sum;
    }
    return;
  }
  const Index n_chunks = static_cast<Index>(impl.chunk_begin.size()) - 1;
  const std::size_t scratch_size = impl.scratch_size();
  auto run_chunk = [&](Index c, double* scratch) {
    if (impl.brick) {
      impl.brick_chunk(c, in, out, scale, scratch, scratch + scratch_size / 2);
    } else {
      impl.general_chunk(c, in, out, scale, scratch);
    }
  };
  // Small problems run on one thread: starting and synchronising threads would cost more.
  if (omp_get_max_threads() == 1 || n_chunks <= 1 || impl.n_dofs < kParallelMinimumDofs) {
    std::vector<double> scratch(scratch_size);
    for (Index c = first_chunk; c < end_chunk; ++c) run_chunk(c, scratch.data());
    return;
  }
  const bool all = first_chunk == 0 && end_chunk == n_chunks;
#pragma omp parallel
  {
    std::vector<double> scratch(scratch_size);
    for (const std::vector<Index>& chunks : impl.colour_chunks) {
      // A colour's chunks are in increasing order: those of the range are one run of them.
      const std::size_t from = all ? 0 : std::lower_bound(chunks.begin(), chunks.end(), first_chunk) - chunks.begin();
      const std::size_t to = all ? chunks.size() : std::lower_bound(chunks.begin(), chunks.end(), end_chunk) - chunks.begin();
#pragma omp for schedule(static)
      for (std::size_t k = from; k < to; ++k) run_chunk(chunks[k], scratch.data());
    }
  }
}

}  // namespace crackle::fem
