#include "core/fingerprint.hpp"

#include <cstring>

namespace crackle {

void fingerprint_mix(std::uint64_t& hash, const void* data, std::size_t bytes) {
  constexpr std::uint64_t kPrime = 1099511628211ull;
  const auto* p = static_cast<const unsigned char*>(data);
  const std::size_t words = bytes / sizeof(std::uint64_t);
  for (std::size_t i = 0; i < words; ++i) {
    std::uint64_t word;
    std::memcpy(&word, p + i * sizeof word, sizeof word);
    hash ^= word;
    hash *= kPrime;
    hash ^= hash >> 32;
  }
  for (std::size_t i = words * sizeof(std::uint64_t); i < bytes; ++i) {
    hash ^= p[i];
    hash *= kPrime;
  }
}

}  // namespace crackle
