#include "reduction/reduction.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include <Eigen/Geometry>

#include "core/errors.hpp"
#include "core/fingerprint.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "io/cache_file.hpp"
#include "modal/cache.hpp"
#include "linalg/cholmod_factor.hpp"
#include "modal/stiffness_factors.hpp"
#include "modal/modal.hpp"

namespace crackle::reduced {
namespace {

/// Modes asked in the first eigen-solve of an automatic count; doubled until the highest is above the target.
constexpr int kFirstModeCount = 12;
/// Right-hand sides of one blocked static solve (n_free x kSolveBlock doubles, twice, in memory).
constexpr Index kSolveBlock = 32;
/// File magic and key seed; version 4: keyed by fem::System::fingerprint (3: output rows of relative
/// points and frames).
constexpr char kMagic[8] = {'C', 'R', 'K', 'R', 'E', 'D', 'U', '4'};
const std::string kCachePrefix = "reduction";

/// One pair row of B: weights over free DOFs (sparse, at most 6 entries).
struct Row {
  std::vector<Index> free;
  std::vector<double> weight;
  double dot(const VectorX& x) const {
    double sum = 0.0;
    for (std::size_t k = 0; k < free.size(); ++k) sum += weight[k] * x[free[k]];
    return sum;
  }
  void add_to(VectorX& x, double scale) const {
    for (std::size_t k = 0; k < free.size(); ++k) x[free[k]] += scale * weight[k];
  }
};

/// Rows of B (pairs x directions) then of C (outputs), over the free DOFs.
void build_rows(const fem::System& system, bool friction, const std::vector<OutputPoint>& outputs,
                std::vector<Row>& pair_rows, std::vector<Row>& output_rows, VectorX& areas) {
  const fem::Constraints& constraints = system.constraints();
  const mesh::DofMap& dofs = system.dofs();
  auto add_entry = [&](Row& row, Index node, int c, double w) {
    const Index free = constraints.free_index[dofs.dof(node, c)];
    if (free >= 0 && w != 0.0) {
      row.free.push_back(free);
      row.weight.push_back(w);
    }
  };
  const std::vector<mesh::CrackPair> pairs =
      system.variant() == mesh::Variant::open ? split_pairs(system.mesh()) : std::vector<mesh::CrackPair>{};
  areas.resize(static_cast<Index>(pairs.size()));
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const mesh::CrackPair& pair = pairs[i];
    areas[static_cast<Index>(i)] = pair.area;
    std::vector<Vec3> directions = {pair.normal.normalized()};
    if (friction) {
      const auto [t1, t2] = pair_tangents(directions[0]);
      directions.push_back(t1);
      directions.push_back(t2);
    }
    for (const Vec3& d : directions) {
      Row row;
      for (int c = 0; c < 3; ++c) {
        add_entry(row, pair.minus, c, d[c]);
        add_entry(row, pair.plus, c, -d[c]);
      }
      pair_rows.push_back(std::move(row));
    }
  }
  for (const OutputPoint& point : outputs) {
    for (int r = 0; r < 3; ++r) {
      Row row;
      for (int c = 0; c < 3; ++c) {
        const double w = point.frame(r, c);
        if (point.minus_node < 0) {
          add_entry(row, point.node, c, w);
        } else {
          add_entry(row, point.minus_node, c, w);
          add_entry(row, point.node, c, -w);
        }
      }
      output_rows.push_back(std::move(row));
    }
  }
}

SparseMatrix diagonal(const VectorX& values) {
  SparseMatrix matrix(values.size(), values.size());
  matrix.reserve(Eigen::VectorXi::Ones(values.size()));
  for (Index i = 0; i < values.size(); ++i) matrix.insert(i, i) = values[i];
  matrix.makeCompressed();
  return matrix;
}

/// Modes to ask for so that the highest lies above `target_hz`, from the n computed (ascending)
/// frequencies: the mode count of a body grows as a power of the frequency (Weyl: f^1 for a
/// beam's bending, f^2 for a plate, f^3 for a solid), N(f) = n (f / f_n)^alpha with alpha fitted
/// over the upper half of the spectrum (clamped to [1, 3]), plus 20 % and 2 spare modes.
Index modes_below(const VectorX& frequencies_hz, double target_hz) {
  const Index n = frequencies_hz.size();
  if (n < 4 || !(frequencies_hz[n / 2 - 1] > 0.0)) return 2 * std::max<Index>(n, 1);
  const double ratio = frequencies_hz[n - 1] / frequencies_hz[n / 2 - 1];
  const double alpha = ratio > 1.0 ? std::clamp(std::log(static_cast<double>(n) / (n / 2)) / std::log(ratio), 1.0, 3.0)
                                   : 3.0;
  const double estimate = n * std::pow(target_hz / frequencies_hz[n - 1], alpha);
  return static_cast<Index>(std::ceil(1.2 * estimate)) + 2;
}

/// Lowest modes of (K, M): a fixed count, or every mode up to `target_hz` (solving for more as needed).
/// `factor`: the caller's factor of K itself (a held body), which every solve then shares.
modal::ModeSet lowest_modes(const SparseMatrix& stiffness, const SparseMatrix& mass, const ReductionOptions& options,
                            int n_rigid, linalg::CholmodFactor* factor) {
  modal::ModalOptions settings;
  settings.solver = modal::Solver::arpack;
  settings.lumped_mass = true;
  if (factor) {
    settings.factor = factor;
    settings.shift = factor->shift();
  }
  const Index n_free = stiffness.rows();
  if (options.modes > 0) {
    settings.modes = options.modes;
    return modal::solve_modes(stiffness, mass, settings, n_rigid);
  }
  if (!(options.max_frequency_hz > 0.0)) {
    throw InputError("reduced model: expected a mode count or a positive maximum frequency, got neither");
  }
  const double target = options.max_frequency_hz * std::max(1.0, options.frequency_margin);
  settings.modes = static_cast<int>(std::min<Index>(kFirstModeCount, n_free - 1));
  for (;;) {
    modal::ModeSet modes = modal::solve_modes(stiffness, mass, settings, n_rigid);
    if (modes.n_modes() > 0 && modes.frequencies_hz[modes.n_modes() - 1] > target) return modes;
    if (settings.modes >= n_free / 2) return modes;  // all the body has (small test meshes)
    const Index wanted = std::max<Index>(settings.modes + 4, modes_below(modes.frequencies_hz, target));
    settings.modes = static_cast<int>(std::min<Index>({wanted, 8 * Index{settings.modes}, n_free / 2}));
  }
}

/// The elastic static flexibility G_el = sum over the elastic modes of phi phi^T / omega^2 applied to
/// blocks of right-hand sides: K^-1 for a held body (one CHOLMOD factor). A free body (rigid modes Psi,
/// mass-normalised) has K singular: G_el b is the solution x orthogonal (in M) to Psi of K x = P^T b,
/// P^T = I - M Psi Psi^T (the load balanced by the rigid-body inertia), found by the fixed point
/// (K + sigma M) x_{k+1} = P^T b + sigma M x_k, whose elastic error shrinks by sigma/(omega^2 + sigma)
/// per iteration (sigma = 1e-2 omega_1^2: about 1e-2).
class StaticFlexibility {
 public:
  StaticFlexibility(const SparseMatrix& stiffness, const SparseMatrix& mass, const MatrixX& rigid_shapes,
                    double lowest_elastic_omega)
      : mass_(mass.diagonal()),
        rigid_(rigid_shapes),
        shift_(rigid_shapes.cols() > 0 ? kShiftFraction * lowest_elastic_omega * lowest_elastic_omega : 0.0),
        own_(std::make_unique<linalg::CholmodFactor>(stiffness, mass, -shift_, "reduced model: static solve with K")),
        factor_(*own_) {}
  /// A held body with the caller's factor of K itself (shared with the eigen-solve).
  StaticFlexibility(const SparseMatrix& mass, linalg::CholmodFactor& stiffness_factor)
      : mass_(mass.diagonal()), shift_(0.0), factor_(stiffness_factor) {}

  /// Overwrites `block` (n_free x columns) by G_el block.
  void apply(MatrixX& block) {
    MatrixX solution(block.rows(), block.cols());
    if (rigid_.cols() == 0) {
      factor_.solve(block.data(), solution.data(), block.cols());
      block = solution;
      return;
    }
    block -= mass_.asDiagonal() * (rigid_ * (rigid_.transpose() * block));  // P^T b
    factor_.solve(block.data(), solution.data(), block.cols());
    for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
      MatrixX rhs = block + shift_ * (mass_.asDiagonal() * solution);
      MatrixX next(block.rows(), block.cols());
      factor_.solve(rhs.data(), next.data(), block.cols());
      const double change = (next - solution).norm(), size = next.norm();
      solution = std::move(next);
      if (!(change > kTolerance * size)) break;
    }
    block = solution - rigid_ * (rigid_.transpose() * (mass_.asDiagonal() * solution));
  }

 private:
  static constexpr double kShiftFraction = 1e-2;
  static constexpr double kTolerance = 1e-13;
  static constexpr int kMaxIterations = 30;
  VectorX mass_;
  MatrixX rigid_;
  double shift_;
  std::unique_ptr<linalg::CholmodFactor> own_;
  linalg::CholmodFactor& factor_;
};

void mix(std::uint64_t& hash, const void* data, std::size_t bytes) { fingerprint_mix(hash, data, bytes); }

}  // namespace

std::vector<mesh::CrackPair> split_pairs(const mesh::Mesh& mesh) {
  std::vector<mesh::CrackPair> pairs;
  for (const mesh::CrackPair& pair : mesh.crack_pairs) {
    if (!pair.on_front()) pairs.push_back(pair);
  }
  return pairs;
}

std::pair<Vec3, Vec3> pair_tangents(const Vec3& normal) {
  Index axis = 0;
  normal.cwiseAbs().minCoeff(&axis);
  const Vec3 first = Vec3::Unit(axis).cross(normal).normalized();
  return {first, normal.cross(first).normalized()};
}

std::optional<Index> Reduction::modes_up_to(double f_hz) const {
  const double omega_limit = 2.0 * kPi * f_hz;
  if (omega.size() == 0 || !(omega[omega.size() - 1] > omega_limit)) return std::nullopt;
  Index count = 0;
  while (count < omega.size() && omega[count] <= omega_limit) ++count;
  return count;
}

VectorX Reduction::modal_coordinates(const VectorX& free_field, Index modes) const {
  if (free_field.size() != shapes.rows() || modes > shapes.cols()) {
    throw InputError("reduced model: a field of " + std::to_string(free_field.size()) + " free DOFs projected on " +
                     std::to_string(modes) + " modes; the reduction has " + std::to_string(shapes.rows()) +
                     " free DOFs and " + std::to_string(shapes.cols()) + " modes");
  }
  return shapes.leftCols(modes).transpose() * mass.cwiseProduct(free_field);
}

Reduction compute_reduction(const fem::System& system, const ReductionOptions& options,
                            const std::vector<OutputPoint>& outputs, const fem::LoadShape& load,
                            modal::StiffnessFactors* factors) {
  const fem::Constraints& constraints = system.constraints();
  const int n_rigid = modal::count_rigid_body_modes(system.mesh(), system.dofs(), constraints);
  Reduction reduction;
  reduction.friction = options.friction;
  Stopwatch clock;
  const SparseMatrix stiffness = fem::restrict_to_free(system.assemble_stiffness(), constraints);
  const SparseMatrix mass = diagonal(fem::restrict_to_free(system.lumped_mass(), constraints));
  // A held body: one factor of K serves the eigen-solves (shift 0) and the static images (the
  // caller's, when it has one: the modal stage's). A free body (or a held one whose K turns out
  // singular: a mechanism) factors K - sigma M per use.
  modal::StiffnessFactors own_factors;
  linalg::CholmodFactor* stiffness_factor =
      n_rigid == 0 ? (factors ? factors : &own_factors)->factor(system.variant(), stiffness) : nullptr;
  const modal::ModeSet modes = lowest_modes(stiffness, mass, options, n_rigid, stiffness_factor);
  reduction.modes_s = clock.seconds();
  // Rigid-body modes first (omega = 0), then the elastic ones.
  const Index n_zero = modes.n_rigid();
  reduction.shapes.resize(stiffness.rows(), n_zero + modes.n_modes());
  reduction.shapes << modes.rigid_shapes, modes.shapes;
  reduction.omega = VectorX::Zero(reduction.shapes.cols());
  reduction.omega.tail(modes.n_modes()) = 2.0 * kPi * modes.frequencies_hz;
  reduction.mass = mass.diagonal();

  Stopwatch flexibility_clock;
  std::vector<Row> pair_rows, output_rows;
  build_rows(system, options.friction, outputs, pair_rows, output_rows, reduction.pair_area);
  const Index m = reduction.shapes.cols(), c = static_cast<Index>(pair_rows.size());
  const Index o = static_cast<Index>(output_rows.size());
  reduction.pair_modes.resize(c, m);
  reduction.output_modes.resize(o, m);
  for (Index r = 0; r < m; ++r) {
    const VectorX phi = reduction.shapes.col(r);
    for (Index i = 0; i < c; ++i) reduction.pair_modes(i, r) = pair_rows[i].dot(phi);
    for (Index i = 0; i < o; ++i) reduction.output_modes(i, r) = output_rows[i].dot(phi);
  }
  const VectorX load_free = fem::restrict_to_free(load.dense(system.n_dofs()), constraints);
  reduction.load_modal = reduction.shapes.transpose() * load_free;

  // Static images: one solve per pair row (kSolveBlock rows at once) and one for the load, only rows
  // B and C kept.
  const double lowest = modes.n_modes() > 0 ? reduction.omega[n_zero] : 0.0;
  std::optional<StaticFlexibility> flexibility_storage;
  if (stiffness_factor && modes.rigid_shapes.cols() == 0) {
    flexibility_storage.emplace(mass, *stiffness_factor);
  } else {
    flexibility_storage.emplace(stiffness, mass, modes.rigid_shapes, lowest);
  }
  StaticFlexibility& flexibility = *flexibility_storage;
  const Index n_free = stiffness.rows();
  reduction.pair_static.resize(c, c);
  reduction.output_static.resize(o, c);
  for (Index first = 0; first < c; first += kSolveBlock) {
    poll_interrupt();
    const Index columns = std::min<Index>(kSolveBlock, c - first);
    MatrixX block = MatrixX::Zero(n_free, columns);
    for (Index k = 0; k < columns; ++k) {
      VectorX column = VectorX::Zero(n_free);
      pair_rows[first + k].add_to(column, 1.0);
      block.col(k) = column;
    }
    flexibility.apply(block);
    for (Index k = 0; k < columns; ++k) {
      const VectorX column = block.col(k);
      for (Index i = 0; i < c; ++i) reduction.pair_static(i, first + k) = pair_rows[i].dot(column);
      for (Index i = 0; i < o; ++i) reduction.output_static(i, first + k) = output_rows[i].dot(column);
    }
  }
  reduction.pair_static = 0.5 * (reduction.pair_static + reduction.pair_static.transpose()).eval();
  MatrixX load_block = load_free;
  flexibility.apply(load_block);
  const VectorX solution = load_block.col(0);
  reduction.pair_static_load.resize(c);
  reduction.output_static_load.resize(o);
  for (Index i = 0; i < c; ++i) reduction.pair_static_load[i] = pair_rows[i].dot(solution);
  for (Index i = 0; i < o; ++i) reduction.output_static_load[i] = output_rows[i].dot(solution);
  reduction.flexibility_s = flexibility_clock.seconds();
  return reduction;
}

ReducedSystem reduced_system(const Reduction& reduction, Index modes, double load_scale) {
  if (modes < 0 || modes > reduction.n_computed_modes()) {
    throw InputError("reduced model: " + std::to_string(modes) + " modes asked, " +
                     std::to_string(reduction.n_computed_modes()) + " computed");
  }
  ReducedSystem system;
  system.omega = reduction.omega.head(modes);
  system.friction = reduction.friction;
  system.pair_area = reduction.pair_area;
  system.initial_gap = VectorX::Zero(reduction.pair_area.size());
  system.pair_modes = reduction.pair_modes.leftCols(modes);
  system.output_modes = reduction.output_modes.leftCols(modes);
  system.load_modal = load_scale * reduction.load_modal.head(modes);
  // Rigid-body modes (omega 0) hold no static flexibility: the static images are elastic only.
  VectorX inverse_square = VectorX::Zero(modes);
  for (Index r = 0; r < modes; ++r) inverse_square[r] = system.omega[r] > 0.0 ? 1.0 / (system.omega[r] * system.omega[r]) : 0.0;
  const MatrixX pair_scaled = system.pair_modes * inverse_square.asDiagonal();
  const MatrixX output_scaled = system.output_modes * inverse_square.asDiagonal();
  system.residual = reduction.pair_static - pair_scaled * system.pair_modes.transpose();
  system.residual = 0.5 * (system.residual + system.residual.transpose()).eval();
  system.output_residual_pairs = reduction.output_static - output_scaled * system.pair_modes.transpose();
  const VectorX load_unit = reduction.load_modal.head(modes);
  system.load_residual = load_scale * (reduction.pair_static_load - pair_scaled * load_unit);
  system.output_residual_load = load_scale * (reduction.output_static_load - output_scaled * load_unit);
  return system;
}

std::uint64_t reduction_key(const fem::System& system, const std::vector<OutputPoint>& outputs,
                            const fem::LoadShape& load, bool friction) {
  std::uint64_t hash = kFingerprintSeed;
  mix(hash, kMagic, sizeof kMagic);
  // What K, the lumped M and the free DOFs are made from (no assembly of K for the key).
  const std::uint64_t system_fingerprint = system.fingerprint();
  mix(hash, &system_fingerprint, sizeof system_fingerprint);
  const int variant = static_cast<int>(system.variant());
  mix(hash, &variant, sizeof variant);
  for (const mesh::CrackPair& pair : split_pairs(system.mesh())) {
    mix(hash, &pair.minus, sizeof pair.minus);
    mix(hash, &pair.plus, sizeof pair.plus);
    mix(hash, pair.normal.data(), 3 * sizeof(double));
    mix(hash, &pair.area, sizeof pair.area);
  }
  const std::int64_t n_outputs = static_cast<std::int64_t>(outputs.size());
  mix(hash, &n_outputs, sizeof n_outputs);
  for (const OutputPoint& point : outputs) {
    mix(hash, &point.node, sizeof point.node);
    mix(hash, &point.minus_node, sizeof point.minus_node);
    mix(hash, point.frame.data(), 9 * sizeof(double));
  }
  mix(hash, load.dofs.data(), sizeof(Index) * load.dofs.size());
  mix(hash, load.values.data(), sizeof(double) * load.values.size());
  const char with_friction = friction ? 1 : 0;
  mix(hash, &with_friction, 1);
  return hash;
}

std::optional<Reduction> load_cached_reduction(const std::filesystem::path& directory, std::uint64_t key) {
  io::CacheReader in(directory, kCachePrefix, kMagic, key);
  Reduction reduction;
  char friction = 0;
  double times[2] = {0.0, 0.0};
  if (!in.get(friction) || !in.get(times)) return std::nullopt;
  reduction.friction = friction != 0;
  reduction.modes_s = times[0];
  reduction.flexibility_s = times[1];
  if (!in.get_matrix(reduction.omega) || !in.get_matrix(reduction.pair_modes) || !in.get_matrix(reduction.output_modes) ||
      !in.get_matrix(reduction.load_modal) || !in.get_matrix(reduction.pair_static) ||
      !in.get_matrix(reduction.output_static) || !in.get_matrix(reduction.pair_static_load) ||
      !in.get_matrix(reduction.output_static_load) || !in.get_matrix(reduction.pair_area) ||
      !in.get_matrix(reduction.shapes) || !in.get_matrix(reduction.mass)) {
    return std::nullopt;
  }
  const Index m = reduction.omega.size(), c = reduction.pair_static.rows(), o = reduction.output_static.rows();
  if (reduction.pair_modes.rows() != c || reduction.pair_modes.cols() != m || reduction.output_modes.cols() != m ||
      reduction.output_modes.rows() != o || reduction.load_modal.size() != m || reduction.pair_static.cols() != c ||
      reduction.output_static.cols() != c || reduction.pair_static_load.size() != c ||
      reduction.output_static_load.size() != o || reduction.shapes.cols() != m ||
      reduction.mass.size() != reduction.shapes.rows()) {
    return std::nullopt;
  }
  return reduction;
}

void store_cached_reduction(const std::filesystem::path& directory, std::uint64_t key, const Reduction& reduction) {
  io::CacheWriter out(kMagic, key);
  out.put(static_cast<char>(reduction.friction ? 1 : 0));
  const double times[2] = {reduction.modes_s, reduction.flexibility_s};
  out.put(times);
  for (const MatrixX& matrix :
       {MatrixX(reduction.omega), reduction.pair_modes, reduction.output_modes, MatrixX(reduction.load_modal),
        reduction.pair_static, reduction.output_static, MatrixX(reduction.pair_static_load),
        MatrixX(reduction.output_static_load), MatrixX(reduction.pair_area), reduction.shapes,
        MatrixX(reduction.mass)}) {
    out.put_matrix(matrix);
  }
  out.store(directory, kCachePrefix);
}

}  // namespace crackle::reduced

namespace crackle::reduced {

struct FieldRecovery::Impl {
  const fem::System& system;
  MatrixX shapes;         ///< Phi_m over the free DOFs
  VectorX inverse_square; ///< 1 / omega_r^2 of the retained elastic modes, 0 for rigid ones
  MatrixX rigid;          ///< every rigid-body mode of the reduction (for the elastic flexibility)
  double lowest_elastic = 0.0;
  VectorX mass;
  VectorX load;           ///< f_hat over the free DOFs, scaled
  std::vector<Row> pair_rows;
  bool residual_flexibility = true;
  std::unique_ptr<StaticFlexibility> flexibility;  ///< made at the first static part
};

FieldRecovery::FieldRecovery(const fem::System& system, const Reduction& reduction, Index modes,
                             const fem::LoadShape& load, double load_scale, bool with_pairs,
                             bool residual_flexibility)
    : impl_(new Impl{system, {}, {}, {}, 0.0, {}, {}, {}, residual_flexibility, nullptr}) {
  if (modes < 0 || modes > reduction.n_computed_modes() || reduction.shapes.rows() != system.constraints().n_free()) {
    throw InputError("reduced model: field recovery of " + std::to_string(modes) + " modes over " +
                     std::to_string(system.constraints().n_free()) + " free DOFs; the reduction has " +
                     std::to_string(reduction.n_computed_modes()) + " modes over " +
                     std::to_string(reduction.shapes.rows()) + " free DOFs");
  }
  Impl& d = *impl_;
  d.shapes = reduction.shapes.leftCols(modes);
  d.inverse_square = VectorX::Zero(modes);
  for (Index r = 0; r < modes; ++r) {
    const double w = reduction.omega[r];
    if (w > 0.0) d.inverse_square[r] = 1.0 / (w * w);
  }
  Index n_rigid = 0;
  while (n_rigid < reduction.omega.size() && !(reduction.omega[n_rigid] > 0.0)) ++n_rigid;
  d.rigid = reduction.shapes.leftCols(n_rigid);
  d.lowest_elastic = n_rigid < reduction.omega.size() ? reduction.omega[n_rigid] : 0.0;
  d.mass = reduction.mass;
  d.load = load_scale * fem::restrict_to_free(load.dense(system.n_dofs()), system.constraints());
  if (with_pairs) {
    std::vector<Row> no_outputs;
    VectorX areas;
    build_rows(system, reduction.friction, {}, d.pair_rows, no_outputs, areas);
  }
}

FieldRecovery::~FieldRecovery() = default;
FieldRecovery::FieldRecovery(FieldRecovery&&) noexcept = default;
FieldRecovery& FieldRecovery::operator=(FieldRecovery&&) noexcept = default;

bool FieldRecovery::factored() const { return impl_->flexibility != nullptr; }

VectorX FieldRecovery::displacement(const VectorX& modal_displacement, const VectorX& pair_forces,
                                    double load_value) {
  Impl& d = *impl_;
  if (modal_displacement.size() != d.shapes.cols() ||
      (pair_forces.size() != 0 && pair_forces.size() != static_cast<Index>(d.pair_rows.size()))) {
    throw InputError("reduced model: field of " + std::to_string(modal_displacement.size()) + " modal coordinates and " +
                     std::to_string(pair_forces.size()) + " pair forces; the recovery has " +
                     std::to_string(d.shapes.cols()) + " modes and " + std::to_string(d.pair_rows.size()) + " pair rows");
  }
  VectorX free_field = d.shapes * modal_displacement;
  if (d.residual_flexibility) {
    // b = B^T p + f_hat a, then G_res b = G_el b - Phi_m Omega_m^-2 Phi_m^T b.
    VectorX rhs = load_value * d.load;
    for (Index i = 0; i < pair_forces.size(); ++i) d.pair_rows[i].add_to(rhs, pair_forces[i]);
    if (rhs.squaredNorm() > 0.0) {
      const VectorX modal_part = d.shapes * d.inverse_square.cwiseProduct(d.shapes.transpose() * rhs);
      if (!d.flexibility) {
        const fem::Constraints& constraints = d.system.constraints();
        const SparseMatrix stiffness = fem::restrict_to_free(d.system.assemble_stiffness(), constraints);
        d.flexibility = std::make_unique<StaticFlexibility>(stiffness, diagonal(d.mass), d.rigid, d.lowest_elastic);
      }
      MatrixX block = rhs;
      d.flexibility->apply(block);
      free_field += block.col(0) - modal_part;
    }
  }
  const fem::Constraints& constraints = d.system.constraints();
  VectorX field = constraints.values;
  if (field.size() != d.system.n_dofs()) field = VectorX::Zero(d.system.n_dofs());
  for (Index k = 0; k < constraints.n_free(); ++k) field[constraints.free_dofs[k]] = free_field[k];
  return field;
}

}  // namespace crackle::reduced
