#include "modal/cache.hpp"

#include <cstring>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "core/fingerprint.hpp"
#include "io/files.hpp"

namespace crackle::modal {
namespace {

constexpr char kMagic[8] = {'C', 'R', 'K', 'M', 'O', 'D', 'E', '3'};  ///< 3: keyed by the inputs of K and M

void mix(std::uint64_t& hash, const void* data, std::size_t bytes) { fingerprint_mix(hash, data, bytes); }

std::filesystem::path cache_file(const std::filesystem::path& directory, std::uint64_t key) {
  char name[40];
  std::snprintf(name, sizeof name, "modes-%016llx.bin", static_cast<unsigned long long>(key));
  return directory / name;
}

void put_matrix(std::string& out, const MatrixX& matrix) {
  const std::int64_t size[2] = {matrix.rows(), matrix.cols()};
  out.append(reinterpret_cast<const char*>(size), sizeof size);
  out.append(reinterpret_cast<const char*>(matrix.data()), sizeof(double) * matrix.size());
}

bool get_matrix(std::istream& in, MatrixX& matrix) {
  std::int64_t size[2];
  if (!in.read(reinterpret_cast<char*>(size), sizeof size) || size[0] < 0 || size[1] < 0) return false;
  matrix.resize(size[0], size[1]);
  return static_cast<bool>(in.read(reinterpret_cast<char*>(matrix.data()), sizeof(double) * matrix.size()));
}

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
  std::ifstream in(cache_file(directory, key), std::ios::binary);
  if (!in) return std::nullopt;
  char magic[sizeof kMagic];
  std::uint64_t stored_key = 0;
  std::int64_t header_bytes = 0;
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0) return std::nullopt;
  if (!in.read(reinterpret_cast<char*>(&stored_key), sizeof stored_key) || stored_key != key) return std::nullopt;
  if (!in.read(reinterpret_cast<char*>(&header_bytes), sizeof header_bytes) || header_bytes <= 0) return std::nullopt;
  std::string header(static_cast<std::size_t>(header_bytes), '\0');
  if (!in.read(header.data(), header_bytes)) return std::nullopt;
  ModeSet modes;
  MatrixX frequencies, rigid_frequencies;
  if (!get_matrix(in, frequencies) || !get_matrix(in, modes.shapes) || !get_matrix(in, rigid_frequencies) ||
      !get_matrix(in, modes.rigid_shapes)) {
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
  io::ensure_directory(directory);
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
  const std::string header_text = header.dump();
  std::string out(kMagic, sizeof kMagic);
  out.append(reinterpret_cast<const char*>(&key), sizeof key);
  const std::int64_t header_bytes = static_cast<std::int64_t>(header_text.size());
  out.append(reinterpret_cast<const char*>(&header_bytes), sizeof header_bytes);
  out += header_text;
  put_matrix(out, modes.frequencies_hz);
  put_matrix(out, modes.shapes);
  put_matrix(out, modes.rigid_frequencies_hz);
  put_matrix(out, modes.rigid_shapes);
  io::write_file_atomic(cache_file(directory, key), out);
}

}  // namespace crackle::modal
