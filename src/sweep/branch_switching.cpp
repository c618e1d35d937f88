#include "sweep/branch_switching.hpp"

#include <cmath>

#include <Eigen/LU>
#include <Eigen/SVD>

#include "core/errors.hpp"

namespace crackle::sweep {
namespace {

/// The odd-harmonic block of the nu = 2 Jacobian at a period-one state `gaps` (in nu = 2 harmonics).
/// At a period-one orbit the contact stiffness has period T, so the odd and the even harmonics of
/// Omega/2 decouple: the block is singular where the nu = 2 branch crosses the period-one one.
MatrixX odd_block(const HarmonicBalance& two, double omega, const VectorX& gaps, const std::vector<Index>& odd) {
  const MatrixX jacobian = two.jacobian(omega, gaps);
  MatrixX block(odd.size(), odd.size());
  for (std::size_t i = 0; i < odd.size(); ++i)
    for (std::size_t j = 0; j < odd.size(); ++j) block(i, j) = jacobian(odd[i], odd[j]);
  return block;
}

/// Sign of a determinant (+1, -1; 0 when singular).
int determinant_sign(const MatrixX& matrix) {
  const Eigen::PartialPivLU<MatrixX> lu(matrix);
  double sign = lu.permutationP().determinant();
  for (Index i = 0; i < matrix.rows(); ++i) sign *= lu.matrixLU()(i, i) > 0.0 ? 1.0 : (lu.matrixLU()(i, i) < 0.0 ? -1.0 : 0.0);
  return static_cast<int>(sign);
}

}  // namespace

std::vector<Index> odd_unknowns(Index rows, int harmonics) {
  std::vector<Index> odd;
  for (int k = 1; k <= harmonics; k += 2)
    for (int component : {2 * k - 1, 2 * k})
      for (Index i = 0; i < rows; ++i) odd.push_back(component * rows + i);
  return odd;
}

VectorX odd_part(const Solution& solution, const std::vector<Index>& odd) {
  VectorX part(odd.size());
  for (std::size_t i = 0; i < odd.size(); ++i) part[i] = solution.gaps[odd[i]];
  return part;
}

double period_two_share(const Solution& solution, Index rows) {
  const Index components = solution.gaps.size() / rows;
  double odd = 0.0, total = 0.0;
  for (Index component = 1; component < components; ++component) {
    const double part = solution.gaps.segment(component * rows, rows).squaredNorm();
    total += part;
    if (((component + 1) / 2) % 2 == 1) odd += part;  // components 2k-1, 2k hold harmonic k
  }
  return total > 0.0 ? std::sqrt(odd / total) : 0.0;
}

std::optional<Solution> period_two_start(const reduced::ReducedSystem& system, const HarmonicBalance& one,
                                         const HarmonicBalance& two, const std::vector<BranchPoint>& branch,
                                         const ContinuationOptions& continuation) {
  const Index rows = system.n_rows();
  const std::vector<Index> odd = odd_unknowns(rows, two.n_harmonics());
  const auto embedded = [&](const Solution& period_one) {
    return period_doubled_guess(system, period_one, Stability(), two.n_harmonics(), 0.0);
  };
  const auto sign_at = [&](const Solution& period_one) {
    return determinant_sign(odd_block(two, period_one.omega, embedded(period_one), odd));
  };
  std::size_t after = 0;
  int previous = branch.empty() ? 0 : sign_at(branch.front().solution);
  for (std::size_t i = 1; i < branch.size() && after == 0; ++i) {
    const int sign = sign_at(branch[i].solution);
    if (sign != previous) after = i;
    previous = sign;
  }
  if (after == 0) return std::nullopt;
  // bisection in Omega between the two period-one points around the sign change
  Solution low = branch[after - 1].solution, high = branch[after].solution;
  const int low_sign = sign_at(low);
  for (int step = 0; step < 12; ++step) {
    try {
      Solution middle = one.solve(0.5 * (low.omega + high.omega), 0.5 * (low.gaps + high.gaps));
      (sign_at(middle) == low_sign ? low : high) = std::move(middle);
    } catch (const SolverError&) {
      break;  // a fold in between: the bracket so far
    }
  }
  Solution base;
  base.omega = high.omega;
  base.gaps = embedded(high);
  const Eigen::JacobiSVD<MatrixX> svd(odd_block(two, base.omega, base.gaps, odd), Eigen::ComputeFullV);
  const VectorX null = svd.matrixV().col(svd.matrixV().cols() - 1);
  VectorX direction = VectorX::Zero(base.gaps.size());
  for (std::size_t i = 0; i < odd.size(); ++i) direction[odd[i]] = null[i];
  const double size = high.gaps.cwiseAbs().maxCoeff();
  for (double step : {0.05, 0.02, 0.1, 0.01}) {
    try {
      Solution solution = branch_off(two, base, direction, step * size, continuation);
      if (period_two_share(solution, rows) > 10.0 * kJoinedShare) return solution;
    } catch (const SolverError&) {
    }
  }
  return std::nullopt;
}

}  // namespace crackle::sweep
