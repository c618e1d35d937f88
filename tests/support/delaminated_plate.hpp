#pragma once
/// bench_reduced's body for the reduced-model tests: a steel plate 0.2 x 0.2 x 0.01 m clamped on x-,
/// n x n x 2 cells of p = 1, with a mid-plane delamination (z = 0.005) over its free half
/// x in [0.1, 0.2] ((n/2)(n + 1) split pairs), reduced with a unit z load on the free end's top edge
/// (compiled once in crackle_test_support).
#include "contact/contact.hpp"
#include "reduction/reduction.hpp"

namespace crackle::reduced::testing {

/// The plate's reduction (`modes` open modes; 3 rows per pair with `contact.friction_coefficient` > 0)
/// and the automatic penalties for `contact`.
struct DelaminatedPlate {
  Reduction reduction;
  contact::PenaltyChoice penalty;
};

DelaminatedPlate delaminated_plate(int cells, int modes, const contact::ContactOptions& contact = {});

}  // namespace crackle::reduced::testing
