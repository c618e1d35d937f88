#pragma once
/// \file Linear operators as actions (STYLE.md, MFEM `Operator::Mult`): an assembled sparse matrix
/// and a matrix-free element operator are interchangeable behind `apply`.
#include "core/types.hpp"

namespace crackle::linalg {

/// A square linear map y = A x over the DOFs of one DOF map.
class LinearOperator {
 public:
  virtual ~LinearOperator() = default;
  virtual Index n_rows() const = 0;
  /// y += scale A x (x and y of size n_rows(); y is not cleared).
  virtual void apply_add(double scale, const VectorX& x, VectorX& y) const = 0;
  /// y = A x.
  virtual void apply(const VectorX& x, VectorX& y) const {
    y.setZero(n_rows());
    apply_add(1.0, x, y);
  }
};

/// An assembled matrix (CSR) as an operator.
class CsrOperator final : public LinearOperator {
 public:
  explicit CsrOperator(SparseMatrix matrix) : matrix_(std::move(matrix)) {}
  Index n_rows() const override { return static_cast<Index>(matrix_.rows()); }
  void apply_add(double scale, const VectorX& x, VectorX& y) const override { y.noalias() += scale * (matrix_ * x); }
  void apply(const VectorX& x, VectorX& y) const override { y.noalias() = matrix_ * x; }
  const SparseMatrix& matrix() const { return matrix_; }

 private:
  SparseMatrix matrix_;
};

}  // namespace crackle::linalg
