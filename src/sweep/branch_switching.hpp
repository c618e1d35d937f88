#pragma once
/// \file Switching from the period-one branch of a harmonic-balance sweep onto the period-two branch
/// born at its first period doubling (HYBRID.md sec. 5): where the doubling is in the truncated
/// balance, the first nu = 2 solution past it, and the measures that say when a nu = 2 branch has
/// rejoined the period-one one.
#include <optional>
#include <vector>

#include "core/types.hpp"
#include "reduced/system.hpp"
#include "sweep/harmonic_balance.hpp"

namespace crackle::sweep {

/// A nu = 2 point whose period-two share is below this has rejoined the period-one branch.
inline constexpr double kJoinedShare = 1e-3;

/// Indices of the unknowns on the odd harmonics of Omega/2 in the gap layout of a nu = 2 solver
/// with `rows` pair rows and `harmonics` harmonics of Omega/2.
std::vector<Index> odd_unknowns(Index rows, int harmonics);

/// The gaps on the odd harmonics of Omega/2 of a nu = 2 solution (`odd` from odd_unknowns).
VectorX odd_part(const Solution& solution, const std::vector<Index>& odd);

/// Share of the odd harmonics of Omega/2 in the gap response of a nu = 2 solution: 0 on the
/// period-one branch, up to 1.
double period_two_share(const Solution& solution, Index rows);

/// The first nu = 2 solution (of `two`) on the branch born at the first period doubling of `branch`
/// (points of `one`, nu = 1). The doubling of the truncated harmonic balance is where the odd block of
/// the nu = 2 Jacobian turns singular along the period-one branch (its determinant changes sign; the
/// monodromy's doubling of the sampled orbit converges to it with H): found between branch points and
/// refined by bisection in Omega; from there Keller's corrector along the block's null vector
/// (branch_off) at a few steps. None if the sign does not change or no step reaches a solution with a
/// period-two share above 10 kJoinedShare.
std::optional<Solution> period_two_start(const reduced::ReducedSystem& system, const HarmonicBalance& one,
                                         const HarmonicBalance& two, const std::vector<BranchPoint>& branch,
                                         const ContinuationOptions& continuation);

}  // namespace crackle::sweep
