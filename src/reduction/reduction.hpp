#pragma once
/// \file Building a ReducedSystem from a finite-element system (HYBRID.md §2): the lowest modes of
/// the variant with the lumped mass of the full transient, and the residual flexibility seen by the
/// crack pairs, the load and the outputs (probe DOFs), from static solves with one CHOLMOD factor of K.
///
/// What is computed once and kept (a `Reduction`, also what the file cache stores) are the static
/// images \f$B K^{-1} B^T\f$, \f$C K^{-1} B^T\f$, \f$B K^{-1}\hat f\f$, \f$C K^{-1}\hat f\f$ and the modal
/// images \f$B\Phi\f$, \f$C\Phi\f$, \f$\Phi^T\hat f\f$ of every mode computed. The residual flexibility of
/// any m of them follows without a solve: \f$G_{res} = K^{-1} - \Phi_m\Omega_m^{-2}\Phi_m^T\f$, so
/// \f$R = B K^{-1}B^T - B\Phi_m \Omega_m^{-2} (B\Phi_m)^T\f$ and likewise for the other images. Never an
/// n_DOF x n_c block: the static solves go one column at a time and only the rows B and C are kept.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/types.hpp"
#include "fem/system.hpp"
#include "reduced/system.hpp"

namespace crackle::modal {
class StiffnessFactors;
}

namespace crackle::reduced {

/// Which modes to compute.
struct ReductionOptions {
  /// Modes to keep; 0: every mode below `max_frequency_hz` (found by solving for more until the
  /// highest computed mode is above it).
  int modes = 0;
  double max_frequency_hz = 0.0;  ///< [Hz], used when modes == 0
  /// Computed modes reach at least this multiple of max_frequency_hz (modes == 0 only), so that a
  /// cached reduction also serves later cases asking a little more (a study over frequency).
  double frequency_margin = 1.5;
  bool friction = false;  ///< 3 rows per pair (normal, two tangents) instead of 1
};

/// One output point of the reduction: three rows of C. A node point reads the node's displacement
/// along the rows of `frame` (the identity: components x, y, z). A relative point (`minus_node` >= 0,
/// a crack-opening probe) reads the pair's relative displacement u_minus - u_node along the rows of
/// `frame` (n+, t1, t2: the normal gap less g0 and the two tangential slips, MODEL.md eqs. 9-10), so a
/// frictionless model, whose B has normal rows only, still has the slips as outputs.
struct OutputPoint {
  Index node = 0;
  Index minus_node = -1;
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
};

/// The expensive part of a reduction, for M computed modes and c pair rows, o outputs.
struct Reduction {
  VectorX omega;             ///< omega_r of all computed modes [rad/s], ascending (M): rigid-body modes (0) first
  MatrixX pair_modes;        ///< B Phi (c x M)
  MatrixX output_modes;      ///< C Phi (o x M)
  VectorX load_modal;        ///< Phi^T f_hat (M) for the load shape given (unit amplitude in the pipeline)
  MatrixX pair_static;       ///< B K^-1 B^T (c x c) [m/N]
  MatrixX output_static;     ///< C K^-1 B^T (o x c)
  VectorX pair_static_load;  ///< B K^-1 f_hat (c)
  VectorX output_static_load;  ///< C K^-1 f_hat (o)
  VectorX pair_area;         ///< area of each split pair [m^2]
  MatrixX shapes;            ///< Phi over the free DOFs (n_free x M), mass-normalised (initial states)
  VectorX mass;              ///< the lumped mass over the free DOFs (n_free) that normalises Phi
  bool friction = false;
  double modes_s = 0.0;        ///< eigen-solve time [s]
  double flexibility_s = 0.0;  ///< factorisation and static solves [s]

  Index n_computed_modes() const { return static_cast<Index>(omega.size()); }
  /// Number of computed modes with frequency <= f_hz; nullopt when the computed set might miss some
  /// (its highest mode is not above f_hz).
  std::optional<Index> modes_up_to(double f_hz) const;
  /// Modal coordinates \f$\Phi_m^T M u\f$ of a field u over the free DOFs, first `modes` modes: the
  /// state of the reduced model nearest to u in the mass norm (exact for u in the span of those modes).
  VectorX modal_coordinates(const VectorX& free_field, Index modes) const;
};

/// The split crack pairs of the mesh (minus != plus), in mesh order: those that carry force.
std::vector<mesh::CrackPair> split_pairs(const mesh::Mesh& mesh);

/// The orthonormal tangents (a_1, a_2) of a pair's plane normal to n+ used for the friction rows.
std::pair<Vec3, Vec3> pair_tangents(const Vec3& normal);

/// Computes modes and static images of `system`. A body (or a piece of it, e.g. a block cut off by the
/// crack) free to move keeps its rigid-body modes as modes of frequency 0, first in the mode list, and
/// the static images are those of the elastic flexibility (rigid motions projected out, HYBRID.md §2). Pairs: every split crack pair of the mesh when the variant is open,
/// none otherwise. Outputs: 3 rows per point of `outputs` (see OutputPoint; a held DOF
/// gives a zero entry). `load`: the load shape f_hat. `factors`: where the factor of a held body's K
/// is looked up (the modal stage's) and left for the next reduction of the same K; null: made and
/// dropped here.
Reduction compute_reduction(const fem::System& system, const ReductionOptions& options,
                            const std::vector<OutputPoint>& outputs, const fem::LoadShape& load,
                            modal::StiffnessFactors* factors = nullptr);

/// The ReducedSystem of the first m computed modes (m <= n_computed_modes()) with the residual
/// flexibility of the rest; the load images scaled by `load_scale`. Contact (penalties, gap,
/// friction coefficient) and damping are left for the caller to fill.
ReducedSystem reduced_system(const Reduction& reduction, Index modes, double load_scale);

/// Fingerprint of a reduction's inputs that do not depend on the mode count: K and the lumped
/// mass over the free DOFs, the pair rows, the output rows (nodes, relative pairs and frames), the
/// load shape and the friction flag.
std::uint64_t reduction_key(const fem::System& system, const std::vector<OutputPoint>& outputs,
                            const fem::LoadShape& load, bool friction);

/// The cached reduction of this key in `directory`, or nullopt (absent, damaged or foreign file).
std::optional<Reduction> load_cached_reduction(const std::filesystem::path& directory, std::uint64_t key);
/// Stores a reduction atomically under its key.
void store_cached_reduction(const std::filesystem::path& directory, std::uint64_t key, const Reduction& reduction);

/// Displacement fields of a reduced model over all DOFs of its system (HYBRID.md §2), for snapshots:
/// \f$u = \Phi_m q + G_{res}(B^T p + \hat f a)\f$, \f$G_{res} = G_{el} - \sum_{r \le m,\ \omega_r > 0}
/// \phi_r\phi_r^T/\omega_r^2\f$ (G_el = K^-1, or the elastic flexibility of a free body as in
/// compute_reduction). Cheap to make; the CHOLMOD factor of K is made once, at the first field with a
/// static part, also when the reduction came from the cache. Borrows `system`.
class FieldRecovery {
 public:
  /// The first `modes` modes of `reduction`; pair rows as compute_reduction made them (none when
  /// `with_pairs` is false: the open body without contact); `load` the unit load shape, scaled by
  /// `load_scale`; `residual_flexibility` false: u = Phi_m q only (the model without static correction).
  FieldRecovery(const fem::System& system, const Reduction& reduction, Index modes, const fem::LoadShape& load,
                double load_scale, bool with_pairs, bool residual_flexibility);
  ~FieldRecovery();
  FieldRecovery(FieldRecovery&&) noexcept;
  FieldRecovery& operator=(FieldRecovery&&) noexcept;

  /// u over the system's DOFs (held DOFs at their prescribed values) for modal coordinates q (m),
  /// pair-row forces p (c, or empty without pairs) and load value a [m].
  VectorX displacement(const VectorX& modal_displacement, const VectorX& pair_forces, double load_value);
  /// Whether the factor of K has been made (the first displacement() with a static part makes it).
  bool factored() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace crackle::reduced
