#pragma once
/// \file Modal analysis of the two linear limits of a cracked body (MODEL.md sec. 5): the
/// uncracked body (crack faces tied) and the open-crack body (faces free).
///
/// For each variant: K phi = omega^2 M phi over the free DOFs (Dirichlet DOFs eliminated, eq. 5),
/// K from eq. (25a), M consistent (25c) or lumped. Open modes are paired to uncracked modes by the
/// modal assurance criterion on the nodes both variants share, and each pair gets the bilinear
/// frequency f_b = 2 f_u f_o / (f_u + f_o) of a breathing crack.
#include <filesystem>
#include <optional>
#include <string>
#include <functional>
#include <vector>


#include "core/defaults.hpp"
#include "core/types.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "fem/system.hpp"
#include "mesh/mesh.hpp"
#include "modal/eigensolver.hpp"

namespace crackle::modal {

class StiffnessFactors;

/// Weighting of the modal assurance criterion.
enum class MacWeighting {
  mass,   ///< MAC = (a^T M b)^2 / ((a^T M a)(b^T M b)), M the uncracked mass (default)
  plain,  ///< MAC = (a^T b)^2 / ((a^T a)(b^T b))
};
inline constexpr Words<MacWeighting, 2> kMacWeightingWords{{{"mass", MacWeighting::mass}, {"plain", MacWeighting::plain}}};

struct ModalOptions {
  int modes = defaults::kModes;  ///< ELASTIC modes per variant (rigid-body modes are found in addition)
  /// Variants to solve; empty: uncracked and open if the mesh has a crack, else uncracked only.
  std::vector<mesh::Variant> variants;
  Solver solver = Solver::slepc;
  Factorization factorization = Factorization::automatic;  ///< SLEPc backend only
  bool lumped_mass = false;   ///< diagonal GLL-lumped mass instead of the consistent one
  double tolerance = 1e-10;   ///< relative residual tolerance of the eigen-iteration
  int max_iterations = 1000;
  /// Shift sigma [rad^2/s^2]. Default: -shift_fraction * lambda_ref, negative so that
  /// K - sigma M is positive definite even for free bodies (rigid-body modes at lambda = 0).
  std::optional<double> shift;
  double shift_fraction = 1e-10;
  /// ARPACK only: the caller's factor of K - shift M (EigenOptions::factor); `shift` must be its shift.
  CholmodFactor* factor = nullptr;
  /// ARPACK only: where run_modal takes (and leaves) the factor of K of variant `factors_variant`
  /// when that body is held (StiffnessFactors), shared with later solves on the same K (the reduced
  /// model's); null: each solve factorises K - sigma M on its own (and drops it).
  StiffnessFactors* factors = nullptr;
  mesh::Variant factors_variant = mesh::Variant::open;
  /// A mode is rigid when |f| < rigid_tolerance * f_ref, f_ref = sqrt(lambda_ref) / (2 pi),
  /// lambda_ref = tr K / tr M (the mean eigenvalue of the discrete pencil), and its eigenvalue is
  /// at least 1e6 times below the largest one computed (see solve_modes).
  double rigid_tolerance = 1e-6;
  MacWeighting mac = MacWeighting::mass;
  /// If not empty: each variant's solve is looked up in (and stored into) this folder, keyed by a
  /// fingerprint of what K and M are made from and of the options (modal/cache.hpp). A parameter
  /// study shares it between cases whose body (for the open variant: body and crack) is the same.
  std::filesystem::path cache_directory;
};

/// Statistics of one eigen-solve.
struct SolveReport {
  std::string solver;         ///< "slepc" or "arpack"
  std::string factorization;  ///< "cholmod" or "mumps"
  int n_ranks = 1;
  int iterations = 0;         ///< of the last attempt
  int attempts = 1;           ///< solves needed (more when unexpected zero-energy modes showed up)
  int n_eigenpairs = 0;       ///< eigenpairs computed in the last attempt
  double shift = 0.0;         ///< sigma [rad^2/s^2]
  double reference_eigenvalue = 0.0;  ///< lambda_ref = tr K / tr M [rad^2/s^2]
  double factorization_s = 0.0;       ///< all attempts
  double iterations_s = 0.0;          ///< all attempts
  double solve_s = 0.0;  ///< whole backend calls (factorisation, iterations, set-up, clean-up)
  double postprocess_s = 0.0;  ///< normalisation, Rayleigh–Ritz, orthogonality and residual checks
  bool from_cache = false;     ///< read from ModalOptions::cache_directory instead of solved
};

/// Modes of one eigenproblem over its free DOFs.
struct ModeSet {
  VectorX frequencies_hz;  ///< elastic modes, ascending [Hz]
  MatrixX shapes;          ///< free DOFs x elastic modes, mass-normalised (phi^T M phi = 1)
  int n_rigid_expected = -1;      ///< from the topology (-1: not given)
  VectorX rigid_frequencies_hz;   ///< signed: sign(lambda) sqrt|lambda| / (2 pi), near 0
  MatrixX rigid_shapes;           ///< free DOFs x rigid modes, mass-normalised
  double orthogonality_error = 0.0;  ///< max |Phi^T M Phi - I| over all returned modes
  /// The same for the backend's vectors before the Rayleigh–Ritz step (a check of the solver).
  double backend_orthogonality_error = 0.0;
  double max_residual = 0.0;  ///< max ||K phi - lambda M phi|| / (max(|lambda|, lambda_ref 1e-12) ||M phi||)
  SolveReport report;
  int n_rigid() const { return static_cast<int>(rigid_frequencies_hz.size()); }
  int n_modes() const { return static_cast<int>(frequencies_hz.size()); }
};

/// Factorisation and weighting from their names ("cholmod", "mass", ...); InputError naming `key`
/// and the accepted values otherwise.
Factorization parse_factorization(const std::string& name, const std::string& key = "modal.factorization");
MacWeighting parse_mac_weighting(const std::string& name, const std::string& key = "modal.mac");

/// Solves K phi = omega^2 M phi (K, M over free DOFs) for `options.modes` elastic modes plus the
/// rigid-body ones. `n_rigid_expected` rigid modes are requested in addition; if more zero-energy
/// modes than that turn up, it solves again with more. InputError if the modes wanted exceed the
/// DOFs; SolverError if the eigen-solve fails.
ModeSet solve_modes(const SparseMatrix& stiffness, const SparseMatrix& mass,
                    const ModalOptions& options, int n_rigid_expected = 0);

/// Rigid-body modes the topology allows: per connected piece of elements (through the DOF map),
/// 6 minus the rank of the piece's rigid motions restricted to its fixed DOFs.
int count_rigid_body_modes(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                           const fem::Constraints& constraints);
/// Connected pieces of the mesh under a DOF map (2 when an open crack cuts the body in two).
int count_pieces(const mesh::Mesh& mesh, const mesh::DofMap& dofs);

/// One variant: its DOFs, constraints and modes.
struct VariantResult {
  mesh::Variant variant = mesh::Variant::uncracked;
  mesh::DofMap dofs;
  fem::Constraints constraints;
  /// Over the free DOFs (consistent or lumped), for the mass-weighted MAC; empty where the modes came
  /// from the cache and the MAC too (nothing needed it).
  SparseMatrix mass;
  ModeSet modes;
  int n_pieces = 1;
  double assembly_s = 0.0;
  std::uint64_t cache_key = 0;  ///< problem_key (modal/cache.hpp) where a cache directory was given, else 0

  VariantResult() = default;
  VariantResult(const VariantResult&) = default;
  VariantResult& operator=(const VariantResult&) = default;
  /// Moves swap the mass matrix in: Eigen 3.4's SparseMatrix has no move constructor, so the
  /// implicit move copied it (hundreds of MB at order 4, when ModalResult::variants grows or a result
  /// is handed on). A member added above must be added to both.
  VariantResult(VariantResult&& other) noexcept;
  VariantResult& operator=(VariantResult&& other) noexcept;
};

/// An open mode paired to an uncracked mode.
struct ModePair {
  int uncracked_mode = 0;  ///< 0-based index among the elastic uncracked modes
  int open_mode = 0;       ///< 0-based index among the elastic open modes
  double f_uncracked_hz = 0.0;
  double f_open_hz = 0.0;
  double ratio = 0.0;  ///< f_open / f_uncracked
  double mac = 0.0;
  double f_bilinear_hz = 0.0;  ///< 2 f_u f_o / (f_u + f_o)
  /// MAC >= kPairingMac: the open mode is the uncracked mode's partner. Below it, the partner is
  /// not among the open modes computed (open-only local modes took their places: ask for more
  /// modes) and ratio and f_bilinear mean nothing.
  bool paired = true;
};

/// Smallest MAC of a pair taken as the same mode shape (correlation practice: 0.9 and above is a
/// clear match, below 0.5 a different shape).
constexpr double kPairingMac = 0.5;

struct ModalResult {
  ModalOptions options;
  std::vector<VariantResult> variants;
  std::vector<ModePair> pairs;  ///< one per uncracked elastic mode, in its order
  MatrixX mac;                  ///< MAC[uncracked][open] of the elastic modes
  double total_s = 0.0;
  /// The variant's result, or nullptr if it was not solved.
  const VariantResult* find(mesh::Variant variant) const;
  VariantResult* find(mesh::Variant variant);
  /// The size of the modal problem: the most free DOFs of any variant solved (0 when none was).
  /// The frequencies' refinement estimates are Richardson extrapolations in this size.
  Index free_dofs() const;
};

/// Assembles and solves every variant, pairs open to uncracked modes.
/// `materials[mesh.element_region[e]]` is the material of element e.
ModalResult run_modal(const mesh::Mesh& mesh, const fem::Materials& materials,
                      const std::vector<fem::DirichletCondition>& conditions,
                      const ModalOptions& options);

/// The same over systems already built (fem::System, shared with the other solvers of a run): one
/// per variant of options.variants (or uncracked, then open when the mesh has a crack), found by
/// `system_for`.
ModalResult run_modal(const std::function<const fem::System&(mesh::Variant)>& system_for, const ModalOptions& options);

/// MAC matrix between the columns of `a` and `b` (same rows); weight nullptr: plain MAC.
MatrixX mac_matrix(const MatrixX& a, const MatrixX& b, const SparseMatrix* weight);

/// Open-variant shapes (free open DOFs) carried to the free DOFs of the uncracked variant: each
/// uncracked DOF node takes the value of the open mesh node of the same index, i.e. the original
/// (not duplicated) node, which sits on one side of the crack.
MatrixX open_on_uncracked_dofs(const MatrixX& open_shapes, const VariantResult& open,
                               const VariantResult& uncracked);

/// Pairs each uncracked mode to a distinct open mode, greedily by largest MAC; pairs below
/// kPairingMac are marked unpaired.
std::vector<ModePair> pair_modes(const VectorX& f_uncracked, const VectorX& f_open, const MatrixX& mac);

/// Displacement of every mesh node (3 per node, node-major) of elastic mode `mode`, zero at
/// constrained DOFs; duplicated crack nodes of the uncracked variant take their original's value.
std::vector<double> nodal_shape(const mesh::Mesh& mesh, const VariantResult& variant, int mode);

/// Terminal table: mode, f_uncracked, f_open, ratio, MAC, f_bilinear (or the frequencies of the
/// single variant solved).
std::string modal_table(const ModalResult& result);

/// True on the rank that writes files (rank 0, or any process without MPI).
inline bool is_output_rank() { return mpi_rank() == 0; }

}  // namespace crackle::modal
