#include "linalg/gmres.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace crackle::linalg {

GmresReport gmres(const LinearAction& apply, const LinearAction& precondition, const VectorX& b, VectorX& x,
                  double tolerance, int max_iterations, int restart) {
  const Index n = b.size();
  GmresReport report;
  if (x.size() != n) x = VectorX::Zero(n);
  const double b_norm = b.norm();
  if (b_norm == 0.0) {
    x.setZero();
    report.converged = true;
    return report;
  }
  restart = static_cast<int>(std::max<Index>(1, std::min<Index>(restart, n)));
  MatrixX basis(n, restart + 1);
  MatrixX hessenberg = MatrixX::Zero(restart + 1, restart);
  VectorX cs(restart), sn(restart), g(restart + 1);
  VectorX w(n), z(n);
  while (true) {
    apply(x, w);
    w = b - w;
    const double beta = w.norm();
    report.relative_residual = beta / b_norm;
    if (report.relative_residual <= tolerance) {
      report.converged = true;
      return report;
    }
    if (report.iterations >= max_iterations || !std::isfinite(beta)) return report;
    basis.col(0) = w / beta;
    hessenberg.setZero();
    g.setZero();
    g[0] = beta;
    int j = 0;
    for (; j < restart && report.iterations < max_iterations; ++j) {
      precondition(basis.col(j), z);
      apply(z, w);
      // classical Gram-Schmidt twice (matrix-vector products, as stable as modified Gram-Schmidt)
      for (int pass = 0; pass < 2; ++pass) {
        const VectorX h = basis.leftCols(j + 1).transpose() * w;
        w.noalias() -= basis.leftCols(j + 1) * h;
        hessenberg.col(j).head(j + 1) += h;
      }
      const double h_next = w.norm();
      hessenberg(j + 1, j) = h_next;
      if (h_next > 0.0) basis.col(j + 1) = w / h_next;
      for (int i = 0; i < j; ++i) {  // the previous rotations on the new column
        const double a = hessenberg(i, j), c = hessenberg(i + 1, j);
        hessenberg(i, j) = cs[i] * a + sn[i] * c;
        hessenberg(i + 1, j) = -sn[i] * a + cs[i] * c;
      }
      const double a = hessenberg(j, j), c = hessenberg(j + 1, j);
      const double r = std::hypot(a, c);
      cs[j] = r > 0.0 ? a / r : 1.0;
      sn[j] = r > 0.0 ? c / r : 0.0;
      hessenberg(j, j) = r;
      hessenberg(j + 1, j) = 0.0;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      ++report.iterations;
      if (std::abs(g[j + 1]) <= tolerance * b_norm || h_next == 0.0) {
        ++j;
        break;
      }
    }
    const VectorX y =
        hessenberg.topLeftCorner(j, j).triangularView<Eigen::Upper>().solve(g.head(j));
    precondition(basis.leftCols(j) * y, z);
    x += z;
  }
}

}  // namespace crackle::linalg
