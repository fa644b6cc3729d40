// FNV-1a (Fowler, Noll, Vo), 64-bit: a change of any input byte changes the hash. Not a
// cryptographic hash; for keys and checks against accidents (a scene's fingerprint, a cached
// module's name and contents), not against an adversary.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace vkray {

class Fnv1a {
public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ull;
    }
  }
  // Bulk data, a 64-bit word at a time: 8 times fewer steps than bytes(). The xor-shift after each
  // multiply carries a word's high bits down, which the multiply alone never does; each step is a
  // bijection of the state for a fixed word and of the word for a fixed state, so inputs that
  // differ in one word always hash apart.
  void words(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, sizeof w);
      h_ = (h_ ^ w) * 0x100000001b3ull;
      h_ ^= h_ >> 32;
    }
    bytes(p + i, n - i);
  }
  void u64(std::uint64_t v) { bytes(&v, sizeof v); }
  std::uint64_t value() const { return h_; }

private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

} // namespace vkray
