// Folded SPIR-V kept on disk between runs. Folding a specialization into the trace kernel's SPIR-V
// (vk/spirv_fold.h) takes 60-200 ms of SPIRV-Tools on a CPU, every run, for a result that depends
// only on the module and the constants: a third of a warm `vkray render`'s pipeline step on
// lavapipe, whose own caches keep the machine code but not the module it was made from. The cache
// keeps each folded module in a file named by a hash of what went in (the module, the constants,
// the SPIRV-Tools version and this format), checks a hash of what comes out when it reads one back,
// and keeps the most recently used files only. Any failure is a miss: the module is folded again.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace vkray::vulkan {

class Specialization;

class FoldCache {
public:
  // `dir` is created on the first store; an empty path disables the cache (every load misses and
  // stores do nothing). At most `maxFiles` modules are kept; the least recently used go first.
  explicit FoldCache(std::filesystem::path dir, std::size_t maxFiles = 64);

  // The key of a module folded with these constants.
  static std::uint64_t key(std::span<const std::uint32_t> code, const Specialization& specialization);
  // The folded module stored under `key`, or empty when there is none or it does not check out.
  std::vector<std::uint32_t> load(std::uint64_t key) const;
  // Stores a folded module (atomically: a reader sees the whole file or none); failures are
  // ignored, since a module that is not kept only costs the next run its folding.
  void store(std::uint64_t key, std::span<const std::uint32_t> folded) const;

  std::filesystem::path fileFor(std::uint64_t key) const;

private:
  void evict() const;

  std::filesystem::path dir_;
  std::size_t maxFiles_;
};

} // namespace vkray::vulkan
