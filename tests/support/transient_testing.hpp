#pragma once
/// \file Helpers of the transient tests: dense modal reference solutions, frequency estimation
/// (compiled once in crackle_test_support).
#include <cmath>
#include <complex>
#include <memory>
#include <vector>

#include "contact/contact_force.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "mesh/mesh.hpp"
#include "transient/solver.hpp"

namespace crackle::transient::testing {

/// The crack contact plugged into a problem on the open DOF map, as the run pipeline does; the term
/// is returned for queries (pairs closed, slipping, forces).
std::shared_ptr<contact::ContactForce> plug_contact(const mesh::Mesh& mesh, TransientProblem& problem,
                                                    const contact::ContactOptions& options);

/// Lowest modes of K phi = omega^2 M phi, M the lumped mass, over the free DOFs (dense solve:
/// small meshes only). Modes are returned over all DOFs (zero at held ones), M-normalised.
struct DenseModes {
  VectorX omega;   ///< ascending [rad/s]
  MatrixX shapes;  ///< columns
};

DenseModes dense_modes(const SparseMatrix& stiffness, const VectorX& lumped_mass, const fem::Constraints& constraints,
                       int count);

/// Largest omega of the same problem.
double dense_omega_max(const SparseMatrix& stiffness, const VectorX& lumped_mass, const fem::Constraints& constraints);

/// |DFT| of a Hann-windowed signal (mean removed) at frequency f [Hz].
double windowed_dft(const std::vector<double>& signal, double dt, double frequency);

/// Frequency of the DFT peak in [low, high] [Hz]: scan on the resolution grid 1/T, then refine
/// the peak by golden-section search of the continuous (windowed) DFT.
double dominant_frequency(const std::vector<double>& signal, double dt, double low, double high);

/// Frequency from upward zero crossings of (signal - mean), linearly interpolated [Hz].
double zero_crossing_frequency(const std::vector<double>& signal, double dt);

}  // namespace crackle::transient::testing
