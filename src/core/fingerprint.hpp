#pragma once
/// \file 64-bit fingerprints of data for the file caches (modes, reduced models): FNV-1a over 8-byte
/// words with a fold of the high bits, the tail byte by byte.
#include <cstddef>
#include <cstdint>

namespace crackle {

inline constexpr std::uint64_t kFingerprintSeed = 1469598103934665603ull;

/// Adds `bytes` bytes to a fingerprint (start from kFingerprintSeed).
void fingerprint_mix(std::uint64_t& hash, const void* data, std::size_t bytes);

}  // namespace crackle
