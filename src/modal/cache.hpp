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

}  // namespace crackle::modal
