#pragma once
/// \file Basic numeric types shared by every module.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>

namespace crackle {

/// Index of a node, element or degree of freedom. 32-bit, like the PETSc build Debian ships.
using Index = std::int32_t;

/// pi and 2 pi (C++17 has no std::numbers).
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2.0 * kPi;

using Vec3 = Eigen::Vector3d;
using VectorX = Eigen::VectorXd;
using MatrixX = Eigen::MatrixXd;

/// Sparse matrices are stored row-major (CSR), the layout PETSc and CHOLMOD (transposed) take.
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

/// Coordinate axes; also the displacement components.
enum Axis : int { kX = 0, kY = 1, kZ = 2 };

/// Name of an axis: "x", "y" or "z".
inline const char* axis_name(int axis) {
  static constexpr const char* names[3] = {"x", "y", "z"};
  return names[axis];
}

}  // namespace crackle
