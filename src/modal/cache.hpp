#pragma once
/// \file A file cache of solved mode sets, keyed by what K and M are made from: the uncracked solve
/// (which does not depend on the crack) is done once for all the cases of a parameter study that
/// share a mesh, the open one once for the cases that also share the crack.
#include <cstdint>
#include <filesystem>
#include <optional>

#include "modal/modal.hpp"

namespace crackle::modal {

/// Fingerprint of an eigenproblem: the system's (fem::System::fingerprint: what K, M and the free
/// DOFs are made from, and the code that makes them), the mass (lumped or consistent) and the options
/// that change the result. Two problems with equal keys have the same modes; the key needs no
/// assembled matrix, so a cached solve costs no assembly of K.
std::uint64_t problem_key(std::uint64_t system_fingerprint, const ModalOptions& options);

/// The cached mode set of this key in `directory`, if one was stored; nullopt otherwise (also for
/// a damaged or foreign file, which is then simply recomputed).
std::optional<ModeSet> load_cached_modes(const std::filesystem::path& directory, std::uint64_t key, Index n_free);

/// Stores a mode set atomically (several processes may store the same key at once).
void store_cached_modes(const std::filesystem::path& directory, std::uint64_t key, const ModeSet& modes);

/// Fingerprint of the open-to-uncracked MAC matrix: the two variants' problem keys and the weighting.
/// A run whose two mode sets both come from the cache reads its MAC too, and so assembles no mass
/// matrix at all (the mass-weighted MAC is its only use there).
std::uint64_t mac_key(std::uint64_t uncracked_key, std::uint64_t open_key, MacWeighting weighting);

/// The cached MAC matrix of this key (`rows` uncracked x `cols` open modes), if one was stored.
std::optional<MatrixX> load_cached_mac(const std::filesystem::path& directory, std::uint64_t key, Index rows, Index cols);

/// Stores a MAC matrix atomically.
void store_cached_mac(const std::filesystem::path& directory, std::uint64_t key, const MatrixX& mac);

}  // namespace crackle::modal
