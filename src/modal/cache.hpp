#pragma once
/// \file A file cache of solved mode sets, keyed by a fingerprint of K and M: the uncracked solve
/// (which does not depend on the crack) is done once for all the cases of a parameter study that
/// share a mesh, the open one once for the cases that also share the crack.
#include <cstdint>
#include <filesystem>
#include <optional>

#include "modal/modal.hpp"

namespace crackle::modal {

/// Adds `bytes` bytes to a 64-bit fingerprint (start from kFingerprintSeed): FNV-1a over 8-byte words
/// with a final fold of the high bits, the tail byte by byte. Shared by the file caches of modes and
/// of reduced models.
inline constexpr std::uint64_t kFingerprintSeed = 1469598103934665603ull;
void fingerprint_mix(std::uint64_t& hash, const void* data, std::size_t bytes);

/// Fingerprint of an eigenproblem: K and M over the free DOFs (pattern and values) and the options
/// that change the result. Two problems with equal keys have the same modes.
std::uint64_t problem_key(const SparseMatrix& stiffness, const SparseMatrix& mass, const ModalOptions& options);

/// The cached mode set of this key in `directory`, if one was stored; nullopt otherwise (also for
/// a damaged or foreign file, which is then simply recomputed).
std::optional<ModeSet> load_cached_modes(const std::filesystem::path& directory, std::uint64_t key, Index n_free);

/// Stores a mode set atomically (several processes may store the same key at once).
void store_cached_modes(const std::filesystem::path& directory, std::uint64_t key, const ModeSet& modes);

}  // namespace crackle::modal
