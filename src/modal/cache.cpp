#include "modal/cache.hpp"

#include <string>

#include <nlohmann/json.hpp>

#include "core/fingerprint.hpp"
#include "io/cache_file.hpp"

namespace crackle::modal {
namespace {

constexpr char kMagic[8] = {'C', 'R', 'K', 'M', 'O', 'D', 'E', '3'};  ///< 3: keyed by the inputs of K and M
const std::string kPrefix = "modes";
constexpr char kMacMagic[8] = {'C', 'R', 'K', 'M', 'A', 'C', '0', '1'};
const std::string kMacPrefix = "mac";

void mix(std::uint64_t& hash, const void* data, std::size_t bytes) { fingerprint_mix(hash, data, bytes); }

}  // namespace

std::uint64_t problem_key(std::uint64_t system_fingerprint, const ModalOptions& options) {
  std::uint64_t hash = kFingerprintSeed;
  mix(hash, kMagic, sizeof kMagic);
  mix(hash, &system_fingerprint, sizeof system_fingerprint);
  const std::int64_t settings[4] = {options.modes, static_cast<std::int64_t>(options.solver), options.max_iterations,
                                    options.lumped_mass ? 1 : 0};
  mix(hash, settings, sizeof settings);
  const double tolerances[3] = {options.tolerance, options.shift_fraction, options.rigid_tolerance};
  mix(hash, tolerances, sizeof tolerances);
  return hash;
}

std::optional<ModeSet> load_cached_modes(const std::filesystem::path& directory, std::uint64_t key, Index n_free) {
  io::CacheReader in(directory, kPrefix, kMagic, key);
  std::string header;
  if (!in.get_text(header)) return std::nullopt;
  ModeSet modes;
  MatrixX frequencies, rigid_frequencies;
  if (!in.get_matrix(frequencies) || !in.get_matrix(modes.shapes) || !in.get_matrix(rigid_frequencies) ||
      !in.get_matrix(modes.rigid_shapes)) {
    return std::nullopt;
  }
  if (modes.shapes.rows() != n_free) return std::nullopt;
  modes.frequencies_hz = frequencies.col(0);
  modes.rigid_frequencies_hz = rigid_frequencies.size() ? VectorX(rigid_frequencies.col(0)) : VectorX();
  try {
    const nlohmann::json json = nlohmann::json::parse(header);
    modes.n_rigid_expected = json.at("n_rigid_expected");
    modes.orthogonality_error = json.at("orthogonality_error");
    modes.backend_orthogonality_error = json.at("backend_orthogonality_error");
    modes.max_residual = json.at("max_residual");
    const nlohmann::json& report = json.at("report");
    modes.report.solver = report.at("solver");
    modes.report.factorization = report.at("factorization");
    modes.report.n_ranks = report.at("n_ranks");
    modes.report.iterations = report.at("iterations");
    modes.report.attempts = report.at("attempts");
    modes.report.n_eigenpairs = report.at("n_eigenpairs");
    modes.report.shift = report.at("shift");
    modes.report.reference_eigenvalue = report.at("reference_eigenvalue");
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
  modes.report.from_cache = true;  // no solve time was spent here
  return modes;
}

void store_cached_modes(const std::filesystem::path& directory, std::uint64_t key, const ModeSet& modes) {
  const nlohmann::json header = {
      {"n_rigid_expected", modes.n_rigid_expected},
      {"orthogonality_error", modes.orthogonality_error},
      {"backend_orthogonality_error", modes.backend_orthogonality_error},
      {"max_residual", modes.max_residual},
      {"report",
       {{"solver", modes.report.solver},
        {"factorization", modes.report.factorization},
        {"n_ranks", modes.report.n_ranks},
        {"iterations", modes.report.iterations},
        {"attempts", modes.report.attempts},
        {"n_eigenpairs", modes.report.n_eigenpairs},
        {"shift", modes.report.shift},
        {"reference_eigenvalue", modes.report.reference_eigenvalue}}}};
  io::CacheWriter out(kMagic, key);
  out.put_text(header.dump());
  out.put_matrix(modes.frequencies_hz);
  out.put_matrix(modes.shapes);
  out.put_matrix(modes.rigid_frequencies_hz);
  out.put_matrix(modes.rigid_shapes);
  out.store(directory, kPrefix);
}

std::uint64_t mac_key(std::uint64_t uncracked_key, std::uint64_t open_key, MacWeighting weighting) {
  std::uint64_t hash = kFingerprintSeed;
  mix(hash, kMacMagic, sizeof kMacMagic);
  const std::uint64_t parts[3] = {uncracked_key, open_key, static_cast<std::uint64_t>(weighting)};
  mix(hash, parts, sizeof parts);
  return hash;
}

std::optional<MatrixX> load_cached_mac(const std::filesystem::path& directory, std::uint64_t key, Index rows, Index cols) {
  io::CacheReader in(directory, kMacPrefix, kMacMagic, key);
  MatrixX mac;
  if (!in.get_matrix(mac) || mac.rows() != rows || mac.cols() != cols) return std::nullopt;
  return mac;
}

void store_cached_mac(const std::filesystem::path& directory, std::uint64_t key, const MatrixX& mac) {
  io::CacheWriter out(kMacMagic, key);
  out.put_matrix(mac);
  out.store(directory, kMacPrefix);
}

}  // namespace crackle::modal
