#pragma once
/// \file A file cache of solved mode sets, so that the uncracked solve (which does not depend on
/// the crack) is done once for all the cases of a parameter study that share a mesh.
#include <cstdint>
#include <filesystem>
#include <optional>

#include "modal/modal.hpp"

namespace crackle::modal {

/// Fingerprint of an eigenproblem: K and M over the free DOFs (pattern and values) and the options
/// that change the result. Two problems with equal keys have the same modes.
std::uint64_t problem_key(const SparseMatrix& stiffness, const SparseMatrix& mass, const ModalOptions& options);

/// The cached mode set of this key in `directory`, if one was stored; nullopt otherwise (also for
/// a damaged or foreign file, which is then simply recomputed).
std::optional<ModeSet> load_cached_modes(const std::filesystem::path& directory, std::uint64_t key, Index n_free);

/// Stores a mode set atomically (several processes may store the same key at once).
void store_cached_modes(const std::filesystem::path& directory, std::uint64_t key, const ModeSet& modes);

}  // namespace crackle::modal
